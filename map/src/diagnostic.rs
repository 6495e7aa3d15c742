//! Errors that point at a place in a map: `file:line:column`, the register, the message.

use std::fmt;
use std::sync::Arc;

/// A position in a map file (1-based line and column).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Loc {
    /// The file, as named in diagnostics.
    pub file: Arc<str>,
    /// The line, from 1.
    pub line: usize,
    /// The column, from 1.
    pub col: usize,
}

impl Loc {
    /// A location.
    pub fn new(file: Arc<str>, line: usize, col: usize) -> Self {
        Loc { file, line, col }
    }

    /// Where the character at `offset` of a one-line scalar written here lies: this column,
    /// moved past an opening quote when the file shows one here (a byte of an example frame's
    /// `bytes`).
    pub fn at_offset(&self, offset: usize) -> Loc {
        crate::examples::locate_offset(self, offset)
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// One problem found in a map.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Diagnostic {
    /// Where.
    pub loc: Loc,
    /// The register concerned, by id, if any.
    pub register: Option<String>,
    /// What is wrong (or, for a warning, what to know).
    pub message: String,
}

impl Diagnostic {
    /// A finding at `loc`, naming `register` when it is about one.
    pub fn new(loc: Loc, register: Option<&str>, message: impl Into<String>) -> Self {
        Diagnostic {
            loc,
            register: register.map(str::to_owned),
            message: message.into(),
        }
    }
}

impl Diagnostic {
    /// The same finding printed as a warning (`file:line:col: warning: ...`), for what is
    /// reported but does not stop a map from loading (an earlier schema version read by its
    /// meaning).
    pub fn as_warning(&self) -> String {
        self.to_string().replacen(": error", ": warning", 1)
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: error", self.loc)?;
        if let Some(register) = &self.register {
            write!(f, " in register `{register}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// All problems found in one or more maps, sorted by place.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostics(pub Vec<Diagnostic>);

impl Diagnostics {
    /// No findings.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// How many findings.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// The findings, in the order found.
    pub fn iter(&self) -> impl Iterator<Item = &Diagnostic> {
        self.0.iter()
    }
}

impl From<Vec<Diagnostic>> for Diagnostics {
    fn from(mut list: Vec<Diagnostic>) -> Self {
        list.sort();
        list.dedup();
        Diagnostics(list)
    }
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for d in &self.0 {
            writeln!(f, "{d}")?;
        }
        let n = self.0.len();
        write!(f, "{n} error{}", if n == 1 { "" } else { "s" })
    }
}

impl std::error::Error for Diagnostics {}
