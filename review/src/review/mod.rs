//! Reviewing a map against its manuals: citations checked by what the cited line says
//! ([`verify_citations`]), manual rows no item cites ([`coverage()`]), the text of a cited line
//! ([`Manuals::quote`]).
//!
//! Validation (`drivemap_map`'s checks) decides whether a map can be built; review decides whether
//! it says what the manual says. Its findings are warnings (`drivemap check`, errors with
//! `--strict`) and a coverage report (`drivemap coverage`); it needs the manuals' text.

mod citations;
mod coverage;
mod matching;
mod others;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use drivemap_map::Loc;
use drivemap_map::facts::parse_citation;

pub use citations::{CitationCheck, Item, Verdict, verify_citations};
pub use coverage::{CoverageReport, TableSummary, UncitedRow, coverage};

/// The largest manual read (bytes); a larger file is treated as missing.
pub const MAX_MANUAL_BYTES: u64 = 32 * 1024 * 1024;

/// The text of the manuals, by file name, read on demand from one directory.
#[derive(Debug, Clone, Default)]
pub struct Manuals {
    dir: Option<PathBuf>,
    files: HashMap<String, Option<Vec<String>>>,
}

impl Manuals {
    /// Manuals in `dir`, read when first asked for.
    pub fn new(dir: &Path) -> Manuals {
        Manuals {
            dir: Some(dir.to_path_buf()),
            files: HashMap::new(),
        }
    }

    /// Manuals held in memory (tests).
    pub fn from_texts<'a>(texts: impl IntoIterator<Item = (&'a str, &'a str)>) -> Manuals {
        Manuals {
            dir: None,
            files: texts
                .into_iter()
                .map(|(name, text)| (name.to_owned(), Some(split_lines(text))))
                .collect(),
        }
    }

    /// Reads the manuals a map names; the ones missing stay missing.
    pub fn load_for(&mut self, map: &drivemap_map::Map) {
        for file in map.meta().text_manuals() {
            self.load(file);
        }
    }

    /// Reads one manual by file name, if not read yet.
    pub fn load(&mut self, file: &str) {
        if self.files.contains_key(file) {
            return;
        }
        let text = self.dir.as_ref().and_then(|dir| {
            // A manual is named by its file name only: no path may escape the directory.
            if file.contains(['/', '\\']) || file == ".." {
                return None;
            }
            let path = dir.join(file);
            let len = std::fs::metadata(&path).ok()?.len();
            (len <= MAX_MANUAL_BYTES)
                .then(|| std::fs::read(&path).ok())
                .flatten()
                .map(|b| split_lines(&String::from_utf8_lossy(&b)))
        });
        self.files.insert(file.to_owned(), text);
    }

    /// The lines of a loaded manual.
    pub fn lines(&self, file: &str) -> Option<&[String]> {
        self.files.get(file)?.as_deref()
    }

    /// Line `n` (1-based) of a loaded manual.
    pub fn line(&self, file: &str, n: usize) -> Option<&str> {
        self.lines(file)?.get(n.checked_sub(1)?).map(String::as_str)
    }

    /// The text a `file:line` citation points at, trimmed, tabs as ` | `; `None` when the
    /// manual is not at hand or the line does not exist.
    pub fn quote(&self, citation: &str) -> Option<String> {
        let (file, n) = parse_citation(citation)?;
        self.line(file, n).map(quote_text)
    }

    /// Whether any manual is loaded.
    pub fn any(&self) -> bool {
        self.files.values().any(Option::is_some)
    }
}

/// A manual line as quoted in messages: trimmed, tab-separated cells joined by ` | `, runs of
/// spaces collapsed, at most 160 characters.
pub fn quote_text(line: &str) -> String {
    let cells: Vec<String> = line
        .split('\t')
        .map(|c| c.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter(|c| !c.is_empty())
        .collect();
    let text = cells.join(" | ");
    if text.chars().count() > 160 {
        let cut: String = text.chars().take(159).collect();
        format!("{cut}…")
    } else {
        text
    }
}

fn split_lines(text: &str) -> Vec<String> {
    text.lines().map(str::to_owned).collect()
}

/// Findings about a map's protocol that are worth a word but never refuse the map: a slave range
/// the manual gives beyond the Modbus serial-line specification's unicast addresses 1-247 (ACN
/// CM.01 1-250; some manuals print 01H-FEH). The map records the manual's range; the warning
/// says what a standard master or gateway may do with 248-255.
pub fn protocol_warnings(map: &drivemap_map::Map) -> Vec<Warning> {
    let s = &map.protocol().slave_address;
    // Numbers with neither a source nor an `unknown` (map/src/validate/protocol_stated.rs).
    let mut out: Vec<Warning> = map
        .protocol_warnings()
        .into_iter()
        .map(|d| Warning {
            loc: d.loc,
            register: d.register,
            message: d.message,
        })
        .collect();
    let (s_min, s_max) = s.range();
    if s.unknown.is_none() && s_max > 247 {
        let above = if s_min > 247 { s_min } else { 248 };
        out.push(Warning {
            loc: map.locate("protocol.slave_address.max"),
            register: None,
            message: format!(
                "slave addresses {above}..={} are the manual's, but the Modbus serial-line \
                 specification reserves 248-255 (unicast 1-247): a standard master or gateway \
                 may not reach them",
                s_max
            ),
        });
    }
    out
}

/// A warning of review: where, which register, what.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Warning {
    /// Where in the map.
    pub loc: Loc,
    /// The register's id, when the warning is about one.
    pub register: Option<String>,
    /// What review found.
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: warning", self.loc)?;
        if let Some(r) = &self.register {
            write!(f, " in register `{r}`")?;
        }
        write!(f, ": {}", self.message)
    }
}
