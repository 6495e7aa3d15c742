//! The columns of a register table, by what their headers say and by the shapes of their cells.
//!
//! A table header (`Register | Param | Name | R/W | Unit | Scaling factor | Default`) is read
//! title by title into [`Role`]s; a title the reader does not know is decided from the cells
//! under it (every cell `R`/`R/W` is an access column, every cell a unit is a unit column, every
//! cell a range is a range column), and a column neither its title nor its cells decide is
//! [`Role::Undecided`]: its cells are used for nothing (a number under an unknown title is not
//! taken for a default) and the report names the table and the column, which the user can name
//! with `--columns`. Two number columns (the drive's own register and a `40001`-style
//! reference) are told apart by their cells: a column whose every number is a Modicon reference
//! is the reference. Nothing here knows a vendor.

use std::sync::LazyLock;

use regex::Regex;

use crate::scheme::param_prefix;
use crate::text::{Num, find_range, hex_address, resolution_cell, unit_cell};

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The drive's own register (communication address), hex or decimal.
    Address,
    /// A Modicon reference (`40001`, `400001`) printed beside the drive's own register.
    Reference,
    /// The parameter number (`P1.01`, `F0-00`, `0102`).
    Param,
    /// The name.
    Name,
    /// `R`, `R/W`, `W`.
    Access,
    /// The unit (`Hz`, `[s]`).
    Unit,
    /// The value of one count (`0.01`, `0.1 Hz`): a resolution, a scale, a multiplier.
    Step,
    /// Counts per unit (`100` means a count is 0.01): a scaling factor, a divisor.
    Factor,
    /// A power of ten (`-2` means a count is 0.01): a conversion index.
    Exponent,
    /// The setting range (`0.00 to 400.00`, `-200.0 - 200.0`).
    Range,
    /// The lower limit.
    Min,
    /// The upper limit.
    Max,
    /// The factory default.
    Default,
    /// The data type (`INT16`, `U32`, `float`).
    Type,
    /// The number of registers a row takes.
    Size,
    /// Prose (remarks, information, a description beside the name).
    Description,
    /// A column the user named `skip`.
    Skip,
    /// A column neither its title nor its cells decide.
    Undecided,
}

/// The names `--columns` takes, with their roles.
pub const ROLE_NAMES: &[(&str, Role)] = &[
    ("address", Role::Address),
    ("reference", Role::Reference),
    ("param", Role::Param),
    ("name", Role::Name),
    ("access", Role::Access),
    ("unit", Role::Unit),
    ("resolution", Role::Step),
    ("factor", Role::Factor),
    ("exponent", Role::Exponent),
    ("range", Role::Range),
    ("min", Role::Min),
    ("max", Role::Max),
    ("default", Role::Default),
    ("type", Role::Type),
    ("size", Role::Size),
    ("description", Role::Description),
    ("skip", Role::Skip),
];

/// The `--columns` name of a role (`undecided` for a column nobody named).
pub fn role_name(role: Role) -> &'static str {
    ROLE_NAMES
        .iter()
        .find(|(_, r)| *r == role)
        .map_or("undecided", |(n, _)| n)
}

/// Reads a `--columns` list (`address,name,access,unit,skip`).
pub fn parse_roles(list: &str) -> Result<Vec<Role>, String> {
    list.split(',')
        .map(|w| {
            let w = w.trim().to_ascii_lowercase();
            ROLE_NAMES
                .iter()
                .find(|(n, _)| *n == w)
                .map(|(_, r)| *r)
                .ok_or_else(|| {
                    format!(
                        "`{w}` is not a column role; one of {}",
                        ROLE_NAMES
                            .iter()
                            .map(|(n, _)| *n)
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })
        })
        .collect()
}

/// The role of a column's title, when the title says it. `None`: the title says nothing the
/// reader knows. `Some(Param)` for titles that may head a number or a name (`Parameter`, `Code`)
/// is checked against the cells.
pub fn title_role(title: &str) -> Option<Role> {
    let t = title.to_lowercase();
    let t = t.trim().trim_end_matches([':', '.']);
    let has = |w: &str| t.contains(w);
    let word = |w: &str| {
        t.split(|c: char| !c.is_alphanumeric() && c != '/')
            .any(|x| x == w)
    };
    if has("function code") || has("parameter no") || has("param. no") {
        return Some(Role::Param);
    }
    if has("setting unit") || has("min. unit") || word("step") || word("lsb") {
        return Some(Role::Step);
    }
    if has("conversion index") || has("exponent") {
        return Some(Role::Exponent);
    }
    if has("default") || has("factory") || has("initial") || has("shipping") {
        return Some(Role::Default);
    }
    if has("factor") || has("divisor") || has("divider") {
        return Some(Role::Factor);
    }
    if has("resolution") || has("scal") || has("multiplier") || has("increment") || word("lsb") {
        return Some(Role::Step);
    }
    if has("number of registers") || has("no. of registers") || word("size") || word("words") {
        return Some(Role::Size);
    }
    if has("access")
        || has("r/w")
        || word("rw")
        || has("read/write")
        || has("attribute")
        || word("attr")
    {
        return Some(Role::Access);
    }
    if has("default") || has("factory") || has("initial") || has("shipping") {
        return Some(Role::Default);
    }
    if (has("min") && has("max")) || has("range") || word("limits") {
        return Some(Role::Range);
    }
    if word("min") || word("minimum") || has("lower limit") || has("low limit") {
        return Some(Role::Min);
    }
    if word("max") || word("maximum") || has("upper limit") || has("high limit") {
        return Some(Role::Max);
    }
    if word("unit") || word("units") || has("u.o.m") || word("dimension") {
        return Some(Role::Unit);
    }
    if has("type") || word("format") {
        return Some(Role::Type);
    }
    if has("description")
        || has("remark")
        || has("information")
        || word("notes")
        || word("comment")
        || word("details")
        || word("explanation")
    {
        return Some(Role::Description);
    }
    if has("name")
        || word("function")
        || word("designation")
        || word("item")
        || word("meaning")
        || word("signal")
        || word("variable")
        || word("contents")
        || word("content")
    {
        return Some(Role::Name);
    }
    if has("register")
        || has("address")
        || word("addr")
        || word("reg")
        || word("hex")
        || word("decimal")
        || word("ref")
        || has("reference")
        || has("communication no")
        || word("modbus")
        || word("modicon")
        || word("pdu")
        || word("dec")
    {
        return Some(Role::Address);
    }
    if has("param")
        || word("code")
        || word("no")
        || word("number")
        || word("pnu")
        || word("index")
        || word("id")
    {
        return Some(Role::Param);
    }
    None
}

/// A column: its title, its role, and where it sits on the header line (in characters).
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// The title as printed.
    pub title: String,
    /// What the column holds.
    pub role: Role,
    /// The first character of the title on the line.
    pub start: usize,
    /// One past its last character.
    pub end: usize,
    /// For an address column: its numbers are hex (a cell printed hex or with a hex digit).
    pub hex: bool,
    /// For an address column: every number is a Modicon reference (`40001`): register 0.
    pub modicon: bool,
}

/// How a table separates its cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    /// Tabs (or `|` rules, turned into tabs): the n-th cell is the n-th column.
    Tabs,
    /// Runs of blanks: a cell is in the column it overlaps most.
    Blanks,
}

/// A table's columns, read from its header line.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The 1-based line of the header.
    pub line: usize,
    /// The columns, left to right.
    pub columns: Vec<Column>,
    /// How its cells are separated.
    pub split: Split,
    /// The table is a list of coils or discrete inputs (its heading or header says so).
    pub bits: Option<&'static str>,
}

/// A cell with the character columns it takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell<'a> {
    /// The text, trimmed.
    pub text: &'a str,
    /// First character.
    pub start: usize,
    /// One past the last.
    pub end: usize,
}

/// Cells of a line with where they sit: tab-separated cells keep their empty cells (their index
/// is their column), blank-separated ones their character span.
pub fn positioned(line: &str, split: Split) -> Vec<Option<Cell<'_>>> {
    match split {
        Split::Tabs => {
            let mut at = 0;
            line.split('\t')
                .map(|c| {
                    let start = at;
                    at += c.chars().count() + 1;
                    let t = c.trim();
                    (!t.is_empty()).then_some(Cell {
                        text: t,
                        start,
                        end: start + c.chars().count(),
                    })
                })
                .collect()
        }
        Split::Blanks => {
            let chars: Vec<(usize, char)> = line.char_indices().collect();
            let mut out = Vec::new();
            let mut i = 0;
            while i < chars.len() {
                if chars[i].1.is_whitespace() {
                    i += 1;
                    continue;
                }
                let start = i;
                let mut end = i;
                while end < chars.len() {
                    if chars[end].1 == '\t'
                        || (chars[end].1 == ' ' && end + 1 < chars.len() && chars[end + 1].1 == ' ')
                    {
                        break;
                    }
                    if chars[end].1 == ' ' && end + 1 == chars.len() {
                        break;
                    }
                    end += 1;
                }
                let b0 = chars[start].0;
                let b1 = chars.get(end).map_or(line.len(), |c| c.0);
                out.push(Some(Cell {
                    text: line[b0..b1].trim(),
                    start,
                    end,
                }));
                i = end;
            }
            out
        }
    }
}

impl Layout {
    /// Reads a header line into columns; `None` when the line is not a header: fewer than three
    /// cells, a digit other than in `4x`/`0x` notation, or fewer than two in three titles known.
    pub fn header(line: &str, line_no: usize) -> Option<Layout> {
        let split = if line.contains('\t') {
            Split::Tabs
        } else {
            Split::Blanks
        };
        // Tab-separated titles keep their empty cells: a title over two columns (`Inverter
        // Parameter` over the number and the name) leaves one empty, and the n-th cell is the
        // n-th column.
        let cells: Vec<Cell<'_>> = positioned(line.trim_end(), split)
            .into_iter()
            .enumerate()
            .filter_map(|(i, c)| match (c, split) {
                (Some(c), _) => Some(c),
                (None, Split::Tabs) => Some(Cell {
                    text: "",
                    start: i,
                    end: i,
                }),
                (None, Split::Blanks) => None,
            })
            .collect();
        if cells.iter().filter(|c| !c.text.is_empty()).count() < 3 {
            return None;
        }
        static DIGIT_OK: LazyLock<Regex> =
            LazyLock::new(|| Regex::new(r"(?i)\b[0134]x+\b|\b4xxxx\b|\(\d\)").expect("pattern"));
        if DIGIT_OK
            .replace_all(line, "")
            .chars()
            .any(|c| c.is_ascii_digit())
        {
            return None;
        }
        let columns: Vec<Column> = cells
            .iter()
            .map(|c| Column {
                title: c.text.to_string(),
                role: title_role(c.text).unwrap_or(Role::Undecided),
                start: c.start,
                end: c.end,
                hex: c.text.to_lowercase().contains("hex"),
                modicon: false,
            })
            .collect();
        let known = columns.iter().filter(|c| c.role != Role::Undecided).count();
        let named = columns.iter().any(|c| c.role == Role::Name);
        if known < 2 || (known * 2 < columns.len() && !named) {
            return None;
        }
        if !columns
            .iter()
            .any(|c| matches!(c.role, Role::Address | Role::Param))
        {
            return None;
        }
        let lower = line.to_lowercase();
        let bits = if lower.contains("coil") {
            Some("coil")
        } else if lower.contains("discrete input") || lower.contains("input status") {
            Some("discrete input")
        } else {
            None
        };
        Some(Layout {
            line: line_no,
            columns,
            split,
            bits,
        })
    }

    /// A header the reader did not take for one, whose columns the user named (`--columns`):
    /// its cells as columns, their roles to be named.
    pub fn header_as_named(line: &str, line_no: usize) -> Option<Layout> {
        let split = if line.contains('\t') {
            Split::Tabs
        } else {
            Split::Blanks
        };
        let columns: Vec<Column> = positioned(line, split)
            .into_iter()
            .flatten()
            .map(|c| Column {
                title: c.text.to_string(),
                role: Role::Undecided,
                start: c.start,
                end: c.end,
                hex: false,
                modicon: false,
            })
            .collect();
        (!columns.is_empty()).then_some(Layout {
            line: line_no,
            columns,
            split,
            bits: None,
        })
    }

    /// The cells of a line by column (`None` for an empty one); cells beyond the last column
    /// are joined to it.
    pub fn assign<'a>(&self, line: &'a str) -> Vec<Option<&'a str>> {
        let mut out: Vec<Option<&'a str>> = vec![None; self.columns.len()];
        let cells = positioned(line, self.split);
        match self.split {
            Split::Tabs => {
                for (i, c) in cells.into_iter().enumerate() {
                    if let Some(c) = c {
                        let i = i.min(self.columns.len() - 1);
                        if out[i].is_none() {
                            out[i] = Some(c.text);
                        }
                    }
                }
            }
            Split::Blanks => {
                for c in cells.into_iter().flatten() {
                    let i = self.column_of(c.start, c.end);
                    match out[i] {
                        None => out[i] = Some(c.text),
                        // Two cells in one column: keep the first (the second is reported by
                        // the caller as not placed).
                        Some(_) => {
                            if let Some(next) =
                                (i + 1..self.columns.len()).find(|j| out[*j].is_none())
                                && self.columns[next].start <= c.end + 2
                            {
                                out[next] = Some(c.text);
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// The column a span of characters overlaps most (the nearest when it overlaps none).
    fn column_of(&self, start: usize, end: usize) -> usize {
        let n = self.columns.len();
        let mut best = (0usize, i64::MIN);
        for (i, c) in self.columns.iter().enumerate() {
            // A column reaches up to the next title.
            let c_end = if i + 1 < n {
                self.columns[i + 1].start
            } else {
                usize::MAX / 2
            };
            let c_start = if i == 0 { 0 } else { c.start };
            let overlap = end.min(c_end) as i64 - start.max(c_start) as i64;
            if overlap > best.1 {
                best = (i, overlap);
            }
        }
        best.0
    }

    /// Decides what the titles leave open from the cells of the rows under the header (`rows`:
    /// the lines of the table, as the caller delimits it): an undecided or doubtful title by its
    /// cells' shapes, hex and Modicon address columns, a reference beside an address.
    pub fn decide(&mut self, rows: &[&str]) {
        let per_column: Vec<Vec<&str>> = {
            let mut v: Vec<Vec<&str>> = vec![Vec::new(); self.columns.len()];
            let keys: Vec<usize> = (0..self.columns.len())
                .filter(|i| matches!(self.columns[*i].role, Role::Address | Role::Param))
                .collect();
            for line in rows {
                let cells = self.assign(line);
                // Only the table's rows: a key with a digit in the address or number column.
                let keyed = keys.iter().any(|k| {
                    cells[*k].is_some_and(|c| {
                        c.split_whitespace()
                            .next()
                            .is_some_and(|t| t.chars().any(|d| d.is_ascii_digit()))
                    })
                });
                if !keyed {
                    continue;
                }
                for (i, c) in cells.into_iter().enumerate() {
                    if let Some(c) = c {
                        v[i].push(c);
                    }
                }
            }
            v
        };
        // A `Parameter` column of names is the name column.
        let has_name = self.columns.iter().any(|c| c.role == Role::Name);
        for (i, col) in self.columns.iter_mut().enumerate() {
            let cells = &per_column[i];
            if col.role == Role::Param
                && !has_name
                && !cells.is_empty()
                && cells.iter().filter(|c| param_cell(c).is_none()).count() * 10 >= cells.len() * 9
            {
                col.role = Role::Name;
            }
        }
        let has_name = self.columns.iter().any(|c| c.role == Role::Name);
        for (i, col) in self.columns.iter_mut().enumerate() {
            let cells = &per_column[i];
            // Nine cells in ten: a stray cell (a footnote, a wrapped word) does not hide a column.
            let all = |f: &dyn Fn(&str) -> bool| {
                !cells.is_empty() && cells.iter().filter(|c| f(c)).count() * 10 >= cells.len() * 9
            };
            match col.role {
                Role::Undecided => {
                    col.role = if all(&|c| modicon(c).is_some_and(|(k, _)| k == '4')) {
                        Role::Address
                    } else if all(&|c| {
                        param_cell(c).is_some() && c.chars().any(|d| d.is_ascii_alphabetic())
                    }) {
                        Role::Param
                    } else if all(&|c| access_word(c).is_some()) {
                        Role::Access
                    } else if all(&|c| unit_cell(c.trim_matches(['[', ']'])).is_some() || c == "-")
                    {
                        Role::Unit
                    } else if all(&|c| find_range(c).is_some() || c == "-") {
                        Role::Range
                    } else if all(&|c| resolution_cell(c).is_some_and(|(_, u)| u.is_some())) {
                        Role::Step
                    } else if all(&|c| {
                        c.chars().filter(|c| c.is_alphabetic()).count() >= 3
                            && find_range(c).is_none()
                            && resolution_cell(c).is_none()
                    }) {
                        if has_name {
                            Role::Description
                        } else {
                            Role::Name
                        }
                    } else {
                        Role::Undecided
                    }
                }
                Role::Description if !has_name => col.role = Role::Name,
                _ => {}
            }
            if col.role == Role::Address {
                let numbers: Vec<&str> = cells
                    .iter()
                    .map(|c| c.split_whitespace().next().unwrap_or(""))
                    .filter(|c| !c.is_empty())
                    .collect();
                if numbers.iter().any(|n| {
                    hex_address(n).is_some()
                        || (n.chars().all(|c| c.is_ascii_hexdigit())
                            && n.chars().any(|c| c.is_ascii_alphabetic()))
                }) {
                    col.hex = true;
                }
                col.modicon = !col.hex
                    && !numbers.is_empty()
                    && numbers
                        .iter()
                        .all(|n| modicon(n).is_some_and(|(k, _)| k == '4'));
            }
        }
        // Two address columns: a Modicon one beside the drive's own number is the reference;
        // of two that are not, the first is the address and the other the same number printed
        // again (decimal beside hex).
        let addresses: Vec<usize> = (0..self.columns.len())
            .filter(|i| self.columns[*i].role == Role::Address)
            .collect();
        if addresses.len() >= 2 {
            let own: Vec<usize> = addresses
                .iter()
                .copied()
                .filter(|i| !self.columns[*i].modicon)
                .collect();
            let keep = own.first().copied().unwrap_or(addresses[0]);
            for i in addresses {
                if i != keep {
                    self.columns[i].role = Role::Reference;
                }
            }
        }
        if !self
            .columns
            .iter()
            .any(|c| matches!(c.role, Role::Address | Role::Param))
            && let Some(c) = self.columns.iter_mut().find(|c| c.role == Role::Reference)
        {
            c.role = Role::Address;
        }
    }

    /// Whether the header names a column the row grammar alone cannot read (an access, a
    /// resolution, a factor, a type, limits, a second number, Modicon references): a table
    /// separated by tabs is read by its columns only then, or when the user named them; one
    /// aligned with blanks or ruled with `|` always is.
    pub fn needs_columns(&self) -> bool {
        self.columns.iter().any(|c| {
            matches!(
                c.role,
                Role::Access
                    | Role::Step
                    | Role::Factor
                    | Role::Exponent
                    | Role::Min
                    | Role::Max
                    | Role::Type
                    | Role::Size
                    | Role::Reference
            ) || c.modicon
        })
    }

    /// Takes the second line of a header whose titles wrap (`Register` over `No.`, `Data` over
    /// `resolution`, as PDF tables print them): each of its cells is added to the title it sits
    /// under, and the titles' roles are read again. `false` (and nothing changed) when the line
    /// is not such a line: digits, or a cell under no title.
    pub fn continue_titles(&mut self, line: &str) -> bool {
        if self.split != Split::Blanks || line.trim().is_empty() {
            return false;
        }
        if line.chars().any(|c| c.is_ascii_digit()) {
            return false;
        }
        let cells: Vec<Cell<'_>> = positioned(line, Split::Blanks)
            .into_iter()
            .flatten()
            .collect();
        if cells.is_empty() || cells.len() > self.columns.len() {
            return false;
        }
        // Each cell must start within a title's reach and overlap it.
        let mut targets = Vec::new();
        for c in &cells {
            let i = self.column_of(c.start, c.end);
            let col = &self.columns[i];
            let reach_end = self.columns.get(i + 1).map_or(usize::MAX, |n| n.start);
            if c.end <= col.start.saturating_sub(2) || c.start >= reach_end {
                return false;
            }
            targets.push(i);
        }
        for (c, i) in cells.iter().zip(targets) {
            let col = &mut self.columns[i];
            col.title = format!("{} {}", col.title, c.text);
            if let Some(r) = title_role(&col.title) {
                col.role = r;
            }
            col.hex |= c.text.to_lowercase().contains("hex");
        }
        true
    }

    /// The index of the first column of a role.
    pub fn find(&self, role: Role) -> Option<usize> {
        self.columns.iter().position(|c| c.role == role)
    }

    /// Replaces the roles with the user's (`--columns`), left to right.
    pub fn name_columns(&mut self, roles: &[Role]) {
        for (c, r) in self.columns.iter_mut().zip(roles) {
            c.role = *r;
        }
    }
}

/// An access as printed in an access column.
pub fn access_word(cell: &str) -> Option<&'static str> {
    match cell.trim().to_ascii_lowercase().as_str() {
        "r" | "ro" | "read" | "read only" | "read-only" | "r/-" | "r/o" => Some("r"),
        "w" | "wo" | "write" | "write only" | "write-only" | "-/w" | "w/o" => Some("w"),
        "r/w" | "rw" | "read/write" | "read-write" | "r/w/-" | "w/r" => Some("rw"),
        _ => None,
    }
}

/// A Modicon reference (`40001`, `400001`, `00017`, `10001`, `30001`): its space digit and the
/// 0-based register it names.
pub fn modicon(tok: &str) -> Option<(char, u16)> {
    let t = tok.trim();
    if !t.chars().all(|c| c.is_ascii_digit()) || !(t.len() == 5 || t.len() == 6) {
        return None;
    }
    let space = t.chars().next()?;
    if !matches!(space, '0' | '1' | '3' | '4') {
        return None;
    }
    let n: u32 = t[1..].parse().ok()?;
    if n == 0 || n > 65536 {
        return None;
    }
    Some((space, (n - 1) as u16))
}

/// A scale from a factor or exponent cell, as the column's title means it.
pub fn scale_of(role: Role, cell: &str) -> Option<f64> {
    let n = Num::parse(cell.trim().trim_start_matches(['x', '×', '*']))?;
    match role {
        Role::Exponent if n.decimals == 0 && (-6.0..=6.0).contains(&n.value) => {
            Some(10f64.powi(n.value as i32))
        }
        Role::Factor if n.value >= 1.0 => {
            let r = resolution_cell(cell.trim())?;
            Some(1.0 / r.0.value)
        }
        Role::Factor if n.value > 0.0 => Some(n.value),
        _ => None,
    }
}

/// Whether a token could be a parameter number in a column headed so: short, no blank, with a
/// digit (`P1.01`, `F0-00`, `3-41`, `0102`, `d080`).
pub fn param_cell(cell: &str) -> Option<&str> {
    let t = cell.trim();
    let ok = !t.is_empty()
        && t.len() <= 12
        && !t.contains(char::is_whitespace)
        && t.chars().any(|c| c.is_ascii_digit())
        && t.chars()
            .all(|c| c.is_ascii_alphanumeric() || ".-_/".contains(c));
    (ok && (param_prefix(t).is_some()
        || t.chars().next().is_some_and(|c| c.is_ascii_alphanumeric())))
    .then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn titles() {
        assert_eq!(title_role("Scaling factor"), Some(Role::Factor));
        assert_eq!(title_role("Data resolution"), Some(Role::Step));
        assert_eq!(title_role("R/W"), Some(Role::Access));
        assert_eq!(title_role("Setting range"), Some(Role::Range));
        assert_eq!(title_role("Modbus register"), Some(Role::Address));
        assert_eq!(title_role("Function name"), Some(Role::Name));
        assert_eq!(title_role("Parameter"), Some(Role::Param));
        assert_eq!(title_role("Zugriff"), None);
    }

    #[test]
    fn a_modicon_column_beside_the_drives_own_number() {
        let mut l = Layout::header("Register   Reference   Name            R/W", 1).unwrap();
        l.decide(&[
            "0          40001       Speed setpoint  R/W",
            "1          40002       Ramp time       R",
        ]);
        let roles: Vec<Role> = l.columns.iter().map(|c| c.role).collect();
        assert_eq!(
            roles,
            [Role::Address, Role::Reference, Role::Name, Role::Access]
        );
    }

    #[test]
    fn an_unknown_title_decided_by_its_cells_or_not() {
        let mut l = Layout::header("Address\tName\tMode\tPreset", 1).unwrap();
        l.decide(&["0x10\tSpeed\tR/W\t5", "0x11\tTorque\tR\t0"]);
        assert_eq!(l.columns[2].role, Role::Access);
        assert_eq!(l.columns[3].role, Role::Undecided);
    }

    #[test]
    fn factors_and_exponents() {
        assert_eq!(scale_of(Role::Factor, "100"), Some(0.01));
        assert_eq!(scale_of(Role::Exponent, "-2"), Some(0.01));
        assert_eq!(modicon("40001"), Some(('4', 0)));
        assert_eq!(modicon("400258"), Some(('4', 257)));
        assert_eq!(modicon("00033"), Some(('0', 32)));
        assert_eq!(modicon("1001"), None);
    }
}
