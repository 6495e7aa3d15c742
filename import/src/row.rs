//! The row grammar: a manual line → a register row, or a line the reader could not use.
//!
//! A row starts with its key: an address (`0101h`, `0x0300`, `19Eh` glued to what follows), a
//! parameter number of one of the manual's schemes ([`crate::scheme`]), or both in either order;
//! under a table header that names an address column, a decimal address (`40001`, `1102`). After
//! the key comes the body, read cell by cell when the line has cells (tabs, wide gaps, `|`) and
//! left to right when OCR glued it into one run (`1A2hb8-01Energy Saving Gain0 to 100%80`):
//! the name, then a resolution (`0.01 Hz`), a range (`0.0~400.0`), a default, and enumeration
//! codes (`0 Ramp To Stop`). Lines below a row that list codes are the row's codes.
//!
//! Nothing is guessed: a field the line does not show is left out; a key with no name is
//! reported, not proposed.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::LazyLock;

use regex::Regex;

use crate::columns::{Column, Layout, Role, Split, access_word, modicon, param_cell, scale_of};
use crate::scheme::{glued_address, param_prefix, shape};
use crate::text::{Num, Range, cells, find_range, hex_address, resolution_cell, unit_cell};

/// One enumeration code as printed.
#[derive(Debug, Clone, PartialEq)]
pub struct Code {
    /// The code.
    pub value: i64,
    /// What it means, as printed.
    pub name: String,
    /// 1-based line number of the code's line.
    pub line: usize,
}

/// A bit or bits of a register, from a bit table (`Address  Bits  Function`).
#[derive(Debug, Clone, PartialEq)]
pub struct BitField {
    /// The first bit.
    pub first: u8,
    /// The last bit (the first, for one bit).
    pub last: u8,
    /// What the bits mean, as printed.
    pub name: String,
    /// The 1-based line of the bit's row.
    pub line: usize,
}

/// How the manual printed an address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Notation {
    /// `0101h`, `0x0101`, `0h0101`, or digits under a Hex column.
    Hex,
    /// Decimal digits under an Address or Register column.
    Decimal,
}

/// A register row read from a manual line.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// 1-based line number of the row.
    pub line: usize,
    /// The address, as a number (in the manual's notation).
    pub address: Option<u16>,
    /// The address as printed (`0101h`, `40001`).
    pub address_printed: Option<String>,
    /// How the address is printed.
    pub notation: Notation,
    /// The parameter number, as printed.
    pub param: Option<String>,
    /// The name, as printed (footnote marks dropped, a wrapped name joined).
    pub name: String,
    /// `r`, `w` or `rw` where the row prints it.
    pub access: Option<&'static str>,
    /// The unit, in the map's spelling (`sec` → `s`).
    pub unit: Option<String>,
    /// Engineering value per count: the printed resolution, else the range's decimals.
    pub scale: Option<f64>,
    /// The lower end of the printed range.
    pub min: Option<f64>,
    /// The upper end of the printed range.
    pub max: Option<f64>,
    /// The printed default.
    pub default: Option<f64>,
    /// Enumeration codes, from the row and the lines under it.
    pub values: Vec<Code>,
    /// Bits, when the row heads a bit table.
    pub fields: Vec<BitField>,
    /// What the row prints that the draft does not carry (a ratio scale, a second range).
    pub notes: Vec<String>,
    /// The row prints `Reserved` / `Not used` as its name.
    pub reserved: bool,
    /// The heading of the row's table (`List of Monitor Data Registers`) and its line, when a
    /// short heading stands just above the table's header.
    pub table: Option<(usize, String)>,
    /// `Some(true)` when a type column prints a signed type (`INT16`, `S16`), `Some(false)` for
    /// an unsigned one; a negative range makes the register signed too.
    pub signed: Option<bool>,
    /// A 32-bit value printed as two rows (`... (HIGH)` and `... (LOW)`): the order of its words
    /// and the line of the other word's row.
    pub pair: Option<Pair>,
}

/// A 32-bit value the manual prints as a HIGH and a LOW row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pair {
    /// The word at the lower address is the high word.
    pub high_first: bool,
    /// The 1-based line of the other word's row.
    pub other_line: usize,
}

impl Row {
    /// Adds a bit (or bits) of a bit table; reserved bits are left out (reserved bits are
    /// written as 0, as the schema says).
    fn push_bits(&mut self, first: u8, last: u8, name: String, line: usize) {
        if !is_reserved(&name) {
            self.fields.push(BitField {
                first,
                last,
                name,
                line,
            });
        }
    }

    /// Whether `line` (the row's own line) shows the row's parameter number or address as
    /// printed: the rule `check` applies to a register's citation.
    pub fn shown_by(&self, line: &str) -> bool {
        self.param.as_deref().is_some_and(|p| line.contains(p))
            || self
                .address_printed
                .as_deref()
                .is_some_and(|a| line.contains(a))
    }
}

/// A line that looked like a row but could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unread {
    /// The 1-based line.
    pub line: usize,
    /// The line, trimmed.
    pub text: String,
    /// Why it was not read as a row.
    pub why: String,
}

/// What a table header says about the rows under it.
#[derive(Debug, Clone, Copy, Default)]
struct Header {
    /// The first column is headed `Address`, `Register`, `Addr` or `Reg`: a decimal number
    /// starting a row under it is an address.
    address_first: bool,
    /// A column is headed `Bit` or `Bits`: rows under it list a register's bits.
    bits: bool,
    /// A column is headed `Hex`: the number after a parameter number is its address in hex,
    /// printed without a mark (`dr.02 1102 44354 44355`).
    hex_column: bool,
}

const HEADER_WORDS: &[&str] = &[
    "address",
    "addr",
    "register",
    "reg.",
    "parameter",
    "param",
    "no.",
    "name",
    "function",
    "description",
    "unit",
    "units",
    "range",
    "setting range",
    "default",
    "factory",
    "initial",
    "access",
    "r/w",
    "attribute",
    "resolution",
    "bit",
    "bits",
    "hex",
];

fn header(line: &str) -> Option<Header> {
    let cs = cells(line);
    let words: Vec<String> = if cs.len() >= 2 {
        cs.iter().map(|c| c.to_lowercase()).collect()
    } else {
        line.split_whitespace().map(str::to_lowercase).collect()
    };
    let hits = words
        .iter()
        .filter(|w| {
            HEADER_WORDS
                .iter()
                .any(|h| w.as_str() == *h || w.starts_with(&format!("{h} ")))
        })
        .count();
    if hits < 2 || line.chars().any(|c| c.is_ascii_digit()) {
        return None;
    }
    let first = words.first().map(String::as_str).unwrap_or("");
    Some(Header {
        address_first: first.starts_with("addr")
            || first.starts_with("reg")
            || first.contains("address"),
        bits: words
            .iter()
            .any(|w| w == "bit" || w == "bits" || w.starts_with("bit ")),
        hex_column: words.iter().any(|w| w == "hex" || w.starts_with("hex ")),
    })
}

/// A heading line: a few words of text on their own, starting with a capital, no digits, no
/// cells.
fn is_heading(line: &str) -> bool {
    let t = line.trim();
    let words = t.split_whitespace().count();
    (1..=6).contains(&words)
        && t.starts_with(|c: char| c.is_uppercase())
        && !t.chars().any(|c| c.is_ascii_digit())
        && cells(line).len() == 1
        && !t.ends_with(['.', ':', ','])
}

fn access_cell(cell: &str) -> Option<&'static str> {
    match cell.to_ascii_lowercase().as_str() {
        "r" | "ro" | "read" | "read only" | "read-only" => Some("r"),
        "w" | "wo" | "write" | "write only" | "write-only" => Some("w"),
        "r/w" | "rw" | "read/write" | "read-write" => Some("rw"),
        _ => None,
    }
}

fn is_reserved(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n.starts_with("reserved") || n.starts_with("not used") || n == "unused" || n == "-"
}

/// Reads every row of `lines` (the whole manual, or a slice of it: line numbers stay the
/// manual's), with the parameter schemes learnt from the whole manual.
pub fn read_rows(
    lines: &[&str],
    first_line: usize,
    schemes: &BTreeSet<String>,
) -> (Vec<Row>, Vec<Unread>) {
    let r = read_tables(
        lines,
        first_line,
        schemes,
        &BTreeMap::new(),
        &BTreeSet::new(),
    );
    (r.rows, r.unread)
}

/// What [`read_tables`] read.
#[derive(Debug, Clone, Default)]
pub struct Tables {
    /// The register rows, in manual order.
    pub rows: Vec<Row>,
    /// Lines that looked like rows but were not read as one, with why.
    pub unread: Vec<Unread>,
    /// The tables read by their header's columns.
    pub layouts: Vec<Layout>,
    /// The lines taken by the rows: a row's own, its codes', bits' (reserved ones too) and the
    /// rest of a wrapped name, and table headers.
    pub taken: BTreeSet<usize>,
}

/// A table's lines for deciding its columns: the lines after its header up to the next header
/// (at most 300).
fn table_lines<'a>(lines: &[&'a str], from: usize) -> Vec<&'a str> {
    lines[from.min(lines.len())..]
        .iter()
        .take(300)
        .take_while(|l| header(l).is_none() && Layout::header(l, 0).is_none())
        .copied()
        .collect()
}

/// Reads every row of `lines` like [`read_rows`]; tables with a header are read by their
/// columns, `columns` naming the columns of the tables whose header is on a given line (the
/// user's `--columns`); `ruled` are the lines printed as `|` tables.
pub fn read_tables(
    lines: &[&str],
    first_line: usize,
    schemes: &BTreeSet<String>,
    columns: &BTreeMap<usize, Vec<Role>>,
    ruled: &BTreeSet<usize>,
) -> Tables {
    let mut rows: Vec<Row> = Vec::new();
    let mut unread = Vec::new();
    let mut layouts: Vec<Layout> = Vec::new();
    let mut layout: Option<Layout> = None;
    let mut words_layout: Option<Layout> = None;
    let mut header_ctx = Header::default();
    let mut last_attached = 0usize;
    // The last short heading line (`Status word`), and the heading of the current table: a bit
    // table's heading names its register when the row does not.
    let mut heading: Option<(usize, String)> = None;
    let mut table_heading: Option<String> = None;
    let mut table: Option<(usize, String)> = None;
    // The lines a row or its codes took, and the lines of prose between tables.
    let mut used: BTreeSet<usize> = BTreeSet::new();
    // Tables printed one cell per line (text as PDF extraction gives it) are read first.
    let vertical = vertical_tables(lines, first_line, &table);
    let mut skip: BTreeSet<usize> = BTreeSet::new();
    for v in vertical {
        skip.extend(v.lines.iter().copied());
        used.extend(v.lines.iter().copied());
        rows.extend(v.rows);
        unread.extend(v.unread);
        layouts.push(v.layout);
    }
    for (i, raw) in lines.iter().enumerate() {
        let line_no = first_line + i;
        let line = raw.trim_end();
        if line.trim().is_empty() || skip.contains(&line_no) {
            continue;
        }
        let old_header = header(line);
        let new_layout = Layout::header(line, line_no)
            .or_else(|| {
                // A header the reader cannot read at all, named by the user.
                columns
                    .contains_key(&line_no)
                    .then(|| Layout::header_as_named(line, line_no))?
            })
            .map(|mut l| {
                // Titles wrapped onto the next line.
                if let Some(next) = lines.get(i + 1)
                    && l.continue_titles(next)
                {
                    skip.insert(line_no + 1);
                    used.insert(line_no + 1);
                }
                l
            });
        // A header whose titles are separated by single blanks (text copied from a page, PDF
        // text without its layout): read by words, its rows by their tokens' shapes.
        let words = new_layout
            .is_none()
            .then(|| word_header(line, line_no))
            .flatten()
            .map(|mut w| {
                // Hex and Modicon numbering, and undecided titles, from the rows' tokens.
                let rows: Vec<String> = table_lines(lines, i + 1)
                    .iter()
                    .filter_map(|l| word_row(l, &w))
                    .collect();
                w.decide(&rows.iter().map(String::as_str).collect::<Vec<_>>());
                if let Some(named) = columns.get(&line_no) {
                    w.name_columns(named);
                }
                w
            })
            // Left to the row grammar: bit tables, address lists, and headers it reads alike.
            .filter(|w| {
                old_header.is_none_or(|h| !h.bits && !h.hex_column)
                    && !header_ctx.hex_column
                    && !header_ctx.bits
                    && w.columns.iter().any(|c| {
                        !matches!(
                            c.role,
                            Role::Address | Role::Reference | Role::Param | Role::Name
                        )
                    })
                    && (w.needs_columns() || columns.contains_key(&line_no))
            });
        if words.is_some() || (new_layout.is_some() && words_layout.is_some()) {
            words_layout = words.clone();
        }
        if let Some(w) = words {
            layouts.push(w);
            layout = None;
            header_ctx = Header::default();
            table = heading.take().filter(|(l, _)| line_no <= l + 3);
            table_heading = table.as_ref().map(|(_, t)| t.clone());
            used.insert(line_no);
            continue;
        }
        if old_header.is_some() || new_layout.is_some() {
            words_layout = None;
            header_ctx = old_header.unwrap_or_default();
            let h_heading = heading.take().filter(|(l, _)| line_no <= l + 3);
            let named = columns.contains_key(&line_no);
            layout = new_layout.filter(|_| !header_ctx.bits).map(|mut l| {
                l.decide(&table_lines(lines, i + 1));
                if let Some(named) = columns.get(&line_no) {
                    l.name_columns(named);
                }
                // The table's caption: its heading, or the short line just above its header.
                let caption = lines[..i]
                    .iter()
                    .rev()
                    .take(2)
                    .find(|l| !l.trim().is_empty())
                    .filter(|l| l.len() < 100)
                    .map(|l| l.to_lowercase())
                    .unwrap_or_default();
                let context = h_heading
                    .as_ref()
                    .map(|(_, t)| t.to_lowercase())
                    .unwrap_or(caption);
                if l.bits.is_none() {
                    l.bits = bit_space(&context);
                }
                l
            });
            // A tab-separated table (OCR text) whose columns the row grammar reads as well is
            // left to it.
            layout = layout.filter(|l| {
                l.split == Split::Blanks || ruled.contains(&line_no) || named || l.needs_columns()
            });
            if let Some(l) = &layout {
                layouts.push(l.clone());
                header_ctx.address_first = false;
            }
            table = h_heading;
            table_heading = table.as_ref().map(|(_, t)| t.clone());
            used.insert(line_no);
            continue;
        }
        if is_heading(line) {
            heading = Some((line_no, line.trim().to_string()));
        }
        let synthetic = words_layout
            .as_ref()
            .and_then(|w| word_row(line, w).map(|s| (s, w)));
        // Under a header read by words, a line without a key just after a row continues its
        // last cell (a description wrapping): it is part of the row, not its name.
        if words_layout.is_some()
            && synthetic.is_none()
            && !rows.is_empty()
            && line_no <= last_attached + 3
            && !row_shaped(line)
        {
            used.insert(line_no);
            last_attached = line_no;
            continue;
        }
        let read_as = match (&synthetic, &layout) {
            (Some((s, w)), _) => Some((s.as_str(), *w)),
            (None, Some(l)) => Some((line, l)),
            (None, None) => None,
        };
        if let Some((line_as, l)) = read_as {
            match layout_row(line_as, line_no, l, &table) {
                LayoutLine::Row(row) => {
                    used.insert(line_no);
                    last_attached = line_no;
                    if row.name.is_empty() {
                        unread.push(Unread {
                            line: line_no,
                            text: line.trim().to_string(),
                            why: "a row key with no name after it".into(),
                        });
                    } else {
                        rows.push(*row);
                    }
                    continue;
                }
                LayoutLine::Reported(u) => {
                    used.insert(line_no);
                    unread.push(u);
                    continue;
                }
                LayoutLine::NotKeyed => {
                    if let Some(row) = rows.last_mut()
                        && line_no <= last_attached + 3
                        && !row.reserved
                        && layout_continuation(line, line_no, l, row, last_attached)
                    {
                        used.insert(line_no);
                        last_attached = line_no;
                        continue;
                    }
                }
            }
        }
        if header_ctx.hex_column
            && let Some(records) = address_records(line, line_no, schemes, &table)
        {
            last_attached = line_no;
            used.insert(line_no);
            rows.extend(records);
            continue;
        }
        match read_key(line, schemes, header_ctx) {
            Some(key) => {
                let mut row = Row {
                    line: line_no,
                    address: key.address,
                    address_printed: key.address_printed,
                    notation: key.notation,
                    param: key.param,
                    name: String::new(),
                    access: None,
                    unit: None,
                    scale: None,
                    min: None,
                    max: None,
                    default: None,
                    values: Vec::new(),
                    fields: Vec::new(),
                    notes: if key.references.is_empty() {
                        Vec::new()
                    } else {
                        vec![format!("also printed: {}", key.references.join(", "))]
                    },
                    reserved: false,
                    table: table.clone(),
                    signed: None,
                    pair: None,
                };
                if header_ctx.bits
                    && let Some((first, last, name)) = bit_cells(key.body)
                {
                    // The row heads a bit table: its first bit is on its own line.
                    match table_heading.take() {
                        Some(t) => {
                            row.name = t;
                            row.notes.push(BY_HEADING.into());
                        }
                        None => {
                            row.name = format!(
                                "Register {}",
                                row.address_printed.as_deref().unwrap_or("?")
                            );
                            row.notes.push(
                                "the manual prints no name for the register; named by its address"
                                    .into(),
                            );
                        }
                    }
                    row.push_bits(first, last, name, line_no);
                    last_attached = line_no;
                    used.insert(line_no);
                    rows.push(row);
                    continue;
                }
                read_body(key.body, &mut row);
                used.insert(line_no);
                if row.name.is_empty() {
                    unread.push(Unread {
                        line: line_no,
                        text: line.trim().to_string(),
                        why: "a row key with no name after it".into(),
                    });
                    continue;
                }
                row.reserved = is_reserved(&row.name);
                last_attached = line_no;
                rows.push(row);
            }
            None => {
                let Some(row) = rows.last_mut() else { continue };
                if line_no > last_attached + 6 || row.reserved {
                    continue;
                }
                if !row.fields.is_empty() {
                    if let Some((first, last, name)) = bit_cells(line) {
                        row.push_bits(first, last, name, line_no);
                        last_attached = line_no;
                        used.insert(line_no);
                    }
                    continue;
                }
                if line_no == row.line + 1 {
                    let before = row.name.len();
                    name_continuation(line, row);
                    if row.name.len() != before {
                        used.insert(line_no);
                    }
                }
                if continuation_codes(line, line_no, row) {
                    last_attached = line_no;
                    used.insert(line_no);
                }
            }
        }
    }
    // A heading names a bit table's register only when the table has one register; a heading
    // over several (`List of Control Data Registers`) names the table.
    const BY_HEADING: &str = "named by the heading of its bit table";
    for i in 0..rows.len() {
        let shared = rows[i].notes.iter().any(|n| n == BY_HEADING)
            && rows
                .iter()
                .filter(|r| r.table.is_some() && r.table == rows[i].table && !r.fields.is_empty())
                .count()
                > 1;
        if shared {
            let r = &mut rows[i];
            r.name = format!("Register {}", r.address_printed.as_deref().unwrap_or("?"));
            r.notes.retain(|n| n != BY_HEADING);
            r.notes
                .push("the manual prints no name for the register; named by its address".into());
        }
    }
    let (rows, mut unread) = pairs(rows, unread);
    // Every line shaped like a row is a row, part of one, or reported with why.
    for (i, raw) in lines.iter().enumerate() {
        let line_no = first_line + i;
        if !used.contains(&line_no) && row_shaped(raw) && !unread.iter().any(|u| u.line == line_no)
        {
            unread.push(Unread {
                line: line_no,
                text: shorten(raw.trim()),
                why: "a number and a name, but not a row of a register table the reader found (prose, a heading, or a table without a header)".into(),
            });
        }
    }
    Tables {
        rows,
        unread,
        layouts,
        taken: used,
    }
}

/// A line shortened for a report (at most 120 characters).
fn shorten(s: &str) -> String {
    // Escaped: a manual's text may hold control characters.
    let mut out: String = s
        .chars()
        .take(120)
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if s.chars().count() > 120 {
        out.push('…');
    }
    out
}

/// Whether a line is shaped like a register row: it starts with an address-like token (a
/// number of up to six digits, a marked hex number, a parameter-like token with a digit) and a
/// name (a word of two letters or more) follows.
pub fn row_shaped(line: &str) -> bool {
    static RE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(
            r"^\s*\|?\s*(?:0x[0-9A-Fa-f]{1,4}|[0-9A-Fa-f]{2,4}[hH]|\d{1,6}|[A-Za-z]{1,3}\d{1,4}(?:[-.]\d{1,4})?|\d{1,3}[-.]\d{1,3})\b[\s|:]*(?:\S+\s+){0,3}?[A-Za-z][a-z]+",
        )
        .expect("pattern")
    });
    RE.is_match(line)
}

/// The coil or discrete-input space a table heading names.
fn bit_space(text: &str) -> Option<&'static str> {
    if text.contains("coil") {
        Some("coil")
    } else if text.contains("discrete input") || text.contains("input status") {
        Some("discrete input")
    } else {
        None
    }
}

/// The HIGH and LOW rows of a 32-bit value (`Energy (HIGH)` at 0014h, `Energy (LOW)` at 0015h)
/// made one row with a pair; the other word's row is reported as part of it.
fn pairs(rows: Vec<Row>, mut unread: Vec<Unread>) -> (Vec<Row>, Vec<Unread>) {
    let mut out: Vec<Row> = Vec::with_capacity(rows.len());
    let mut iter = rows.into_iter().peekable();
    while let Some(mut row) = iter.next() {
        let word = word_of(&row.name);
        if let (Some((first_high, base)), Some(next)) = (word, iter.peek())
            && let Some((next_high, next_base)) = word_of(&next.name)
            && next_high != first_high
            && crate::compare::name_key(&next_base) == crate::compare::name_key(&base)
            && row.address.is_some()
            && next.address == row.address.and_then(|a| a.checked_add(1))
        {
            let next = iter.next().expect("peeked");
            row.name = base;
            row.pair = Some(Pair {
                high_first: first_high,
                other_line: next.line,
            });
            row.notes.push(format!(
                "a 32-bit value: the {} word at {} (line {})",
                if first_high { "low" } else { "high" },
                next.address_printed.as_deref().unwrap_or("?"),
                next.line
            ));
            if row.scale.is_none() {
                row.scale = next.scale;
                row.unit = row.unit.clone().or(next.unit.clone());
            }
            unread.push(Unread {
                line: next.line,
                text: next.name.clone(),
                why: format!(
                    "the {} word of a 32-bit value; part of the row at line {}",
                    if first_high { "low" } else { "high" },
                    row.line
                ),
            });
        }
        out.push(row);
    }
    (out, unread)
}

/// A name that marks one word of a 32-bit value: whether it is the high word, and the name
/// without the mark (`Output power (HIGH)`, `Trip frequency (low)`, `Power [LOW WORD]`,
/// `Control word MSW`).
fn word_of(name: &str) -> Option<(bool, String)> {
    static RE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(
            r"(?i)\s*[(\[]?\s*\b(high|low|upper|lower|hi|lo|msw|lsw)(?:\s+word)?\b\s*[)\]]?\s*$",
        )
        .expect("pattern")
    });
    let m = RE.captures(name)?;
    let high = matches!(
        m[1].to_ascii_lowercase().as_str(),
        "high" | "upper" | "hi" | "msw"
    );
    let base = name[..m.get(0).expect("match").start()].trim();
    // `(frequency (low)`: an unclosed parenthesis the mark closed.
    let base = if base.matches('(').count() > base.matches(')').count() {
        format!("{base})")
    } else {
        base.to_string()
    };
    (!base.is_empty()).then_some((high, clean_name(&base)))
}

struct Key<'a> {
    address: Option<u16>,
    address_printed: Option<String>,
    notation: Notation,
    param: Option<String>,
    body: &'a str,
    /// Modicon references printed after the address (`40769 40770`: the same register as RTU
    /// and TCP `4xxxx` numbers), kept as a note.
    references: Vec<String>,
}

fn known_param<'a>(s: &'a str, schemes: &BTreeSet<String>) -> Option<(&'a str, &'a str)> {
    param_prefix(s).filter(|(p, _)| schemes.contains(&shape(p)))
}

fn read_key<'a>(line: &'a str, schemes: &BTreeSet<String>, header: Header) -> Option<Key<'a>> {
    let t = line.trim_start();
    let mut key = Key {
        address: None,
        address_printed: None,
        notation: Notation::Hex,
        param: None,
        body: t,
        references: Vec::new(),
    };
    if let Some((address, printed, rest)) = glued_address(t) {
        key.address = Some(address);
        key.address_printed = Some(printed.to_string());
        let rest_t = rest.trim_start();
        if let Some((p, after)) = known_param(rest_t, schemes) {
            key.param = Some(p.to_string());
            key.body = after;
        } else {
            // An address alone is followed by a separate word (`0000H  Run`) or a capital glued
            // to it (`FFDDhACCEPT`), not lower-case letters or digits.
            if rest.starts_with(|c: char| c.is_lowercase() || c.is_ascii_digit()) {
                return None;
            }
            key.body = rest;
        }
    } else if let Some((p, rest)) = known_param(t, schemes) {
        key.param = Some(p.to_string());
        key.body = rest;
        let rest_t = rest.trim_start();
        let first = rest_t.split_whitespace().next().unwrap_or("");
        if let Some(a) = hex_address(first) {
            key.address = Some(a);
            key.address_printed = Some(first.to_string());
            key.body = &rest_t[first.len()..];
        } else if let Some((a, printed, after)) = glued_address(rest_t)
            && !after.starts_with(|c: char| c.is_ascii_lowercase())
        {
            key.address = Some(a);
            key.address_printed = Some(printed.to_string());
            key.body = after;
        } else if header.address_first
            && let Some(a) = decimal_address(first)
        {
            key.address = Some(a);
            key.address_printed = Some(first.to_string());
            key.notation = Notation::Decimal;
            key.body = &rest_t[first.len()..];
        }
    } else if header.address_first && !line.starts_with(char::is_whitespace) {
        let first = t.split_whitespace().next()?;
        let a = decimal_address(first)?;
        key.address = Some(a);
        key.address_printed = Some(first.to_string());
        key.notation = Notation::Decimal;
        let rest = t[first.len()..].trim_start();
        if let Some((p, after)) = known_param(rest, schemes) {
            key.param = Some(p.to_string());
            key.body = after;
        } else {
            key.body = rest;
        }
    } else {
        return None;
    }
    // Modicon references (`40769`, `(40769`, `|40770`) between the address and the name.
    if key.address.is_some() && key.notation == Notation::Hex {
        loop {
            let b = key.body.trim_start();
            let tok = b.split_whitespace().next().unwrap_or("");
            let digits = tok.trim_matches(['(', ')', '|']);
            if key.references.len() < 2
                && digits.len() == 5
                && digits.starts_with('4')
                && digits.chars().all(|c| c.is_ascii_digit())
            {
                key.references.push(digits.to_string());
                key.body = &b[tok.len()..];
            } else {
                break;
            }
        }
    }
    // A key is followed by a name (`1'st Step Time` is one), or by a bit under a Bits header;
    // prose (`n003 = 1`, `0101h.`) is not a row.
    let b = key.body.trim_start();
    // A name may start with an ordinal (`1'st Step Time`): a digit run glued to letters.
    let first_token = b.split_whitespace().next().unwrap_or("");
    let named = b.starts_with(|c: char| c.is_alphabetic() || c == '(' || c == '"')
        || (first_token.starts_with(|c: char| c.is_ascii_digit())
            && first_token.chars().any(char::is_alphabetic)
            && resolution_cell(first_token).is_none());
    let bit = header.bits && bit_cells(b).is_some();
    if !named && !bit {
        return None;
    }
    Some(key)
}

/// A bit table's cells: a bit (`3`) or bits (`4~7`, `8-F`? no: decimal only) and what it means.
fn bit_cells(s: &str) -> Option<(u8, u8, String)> {
    let mut cs = cells(s);
    if cs.first().is_some_and(|c| clean_name(c).is_empty()) {
        // A footnote mark between the address and the bit (`0000H (*1)  0  Run`).
        cs.remove(0);
    }
    let (bit, name) = match cs.as_slice() {
        [bit, name, ..] => (*bit, *name),
        _ => return None,
    };
    let (first, last) = match bit.split_once(['~', '-', '–']) {
        Some((a, b)) => (a.trim().parse::<u8>().ok()?, b.trim().parse::<u8>().ok()?),
        None => {
            let b = bit.parse::<u8>().ok()?;
            (b, b)
        }
    };
    if first > last || last > 31 || !name.starts_with(|c: char| c.is_alphanumeric() || c == '(') {
        return None;
    }
    Some((first, last, clean_name(name)))
}

/// A line of an address list: parameter numbers, each followed by its address in hex without a
/// mark and other numbers (decimal forms of the same address), one or several records a line
/// (`dr.02 1102 44354 44355 dr21 1115 44373 44374`). The rows have no name of their own.
fn address_records(
    line: &str,
    line_no: usize,
    schemes: &BTreeSet<String>,
    table: &Option<(usize, String)>,
) -> Option<Vec<Row>> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for tok in line.split_whitespace() {
        let tok = tok.trim_matches(|c: char| c == '|' || c == '(' || c == ')');
        if tok.is_empty() {
            continue;
        }
        match known_param(tok, schemes) {
            Some((p, "")) => out.push((p.to_string(), Vec::new())),
            _ => {
                let last = out.last_mut()?;
                if tok.chars().all(|c| c.is_ascii_hexdigit()) && last.1.len() < 3 {
                    last.1.push(tok.to_string());
                } else {
                    return None;
                }
            }
        }
    }
    if out.is_empty() {
        return None;
    }
    let mut rows = Vec::new();
    for (param, numbers) in out {
        let hex = numbers.first()?;
        let address = u16::from_str_radix(hex, 16).ok()?;
        let mut notes =
            vec!["the address list prints no name; named by its parameter number".to_string()];
        if numbers.len() > 1 {
            notes.push(format!("also printed: {}", numbers[1..].join(", ")));
        }
        rows.push(Row {
            line: line_no,
            address: Some(address),
            address_printed: Some(hex.clone()),
            notation: Notation::Hex,
            name: param.clone(),
            param: Some(param),
            access: None,
            unit: None,
            scale: None,
            min: None,
            max: None,
            default: None,
            values: Vec::new(),
            fields: Vec::new(),
            notes,
            reserved: false,
            table: table.clone(),
            signed: None,
            pair: None,
        });
    }
    Some(rows)
}

fn decimal_address(tok: &str) -> Option<u16> {
    if tok.is_empty() || tok.len() > 5 || !tok.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    tok.parse().ok()
}

#[derive(Debug)]
enum Cell<'a> {
    Range(Range),
    Resolution(Num, Option<&'static str>),
    Unit(&'static str),
    Number(Num),
    Dash,
    Access(&'static str),
    Text(&'a str),
}

fn classify(cell: &str) -> Cell<'_> {
    if matches!(cell, "-" | "—" | "–" | "--") {
        return Cell::Dash;
    }
    if let Some(a) = access_cell(cell) {
        return Cell::Access(a);
    }
    if let Some(n) = Num::parse(cell) {
        return Cell::Number(n);
    }
    if let Some(u) = unit_cell(cell) {
        return Cell::Unit(u);
    }
    if cell.starts_with(|c: char| c.is_ascii_digit() || "+-−±.".contains(c))
        && let Some(r) = find_range(cell)
        && r.start <= 1
    {
        return Cell::Range(r);
    }
    if let Some((n, u)) = resolution_cell(cell)
        && u.is_some()
    {
        return Cell::Resolution(n, u);
    }
    Cell::Text(cell)
}

fn set_range(
    row: &mut Row,
    r: &Range,
    decimals: &mut Option<u32>,
    unit: &mut Option<&'static str>,
) {
    row.min = Some(r.min.value);
    row.max = Some(r.max.value);
    *decimals = Some(r.min.decimals.max(r.max.decimals));
    if unit.is_none() {
        *unit = r.unit;
    }
}

fn read_body(body: &str, row: &mut Row) {
    static RATIO: LazyLock<Regex> =
        LazyLock::new(|| Regex::new(r"\b\d+\s*/\s*\d+\s*%").expect("pattern"));
    let cs = cells(body);
    let mut unit: Option<&'static str> = None;
    let mut step: Option<f64> = None;
    let mut decimals: Option<u32> = None;
    if cs.len() >= 2 {
        let mut pending_code: Option<i64> = None;
        let mut seen_range = false;
        for cell in &cs {
            match classify(cell) {
                Cell::Text(t) if row.name.is_empty() => row.name = clean_name(t),
                Cell::Text(t) => {
                    if let Some(code) = pending_code.take()
                        && t.starts_with(|c: char| c.is_alphabetic() || c == '(')
                    {
                        row.values.push(Code {
                            value: code,
                            name: t.to_string(),
                            line: row.line,
                        });
                    } else if !seen_range
                        && let Some(r) = find_range(t)
                        && t.starts_with(|c: char| c.is_ascii_digit())
                    {
                        set_range(row, &r, &mut decimals, &mut unit);
                        seen_range = true;
                        row.notes.push(format!("range read from \"{t}\""));
                    }
                }
                Cell::Range(r) if !seen_range => {
                    set_range(row, &r, &mut decimals, &mut unit);
                    seen_range = true;
                }
                Cell::Range(r) => row.notes.push(format!(
                    "a second range {}..{} is printed",
                    r.min.value, r.max.value
                )),
                Cell::Resolution(n, u) => {
                    step = Some(n.value);
                    unit = u;
                }
                Cell::Unit(u) if unit.is_none() => unit = Some(u),
                Cell::Unit(_) | Cell::Dash => {}
                Cell::Access(a) => row.access = Some(a),
                Cell::Number(n) => {
                    if seen_range || !row.values.is_empty() {
                        row.default = Some(n.value);
                    } else if n.decimals == 0 && n.value >= 0.0 && n.value < 65536.0 {
                        if let Some(code) = pending_code.replace(n.value as i64) {
                            // Two numbers in a row: the first was a resolution without a unit
                            // (`0.01` reads as a number) or noise; keep the later one as a code.
                            let _ = code;
                        }
                    } else if resolution_cell(cell).is_some() && step.is_none() {
                        step = Some(n.value);
                    }
                }
            }
        }
        if let Some(code) = pending_code
            && row.values.is_empty()
            && !seen_range
        {
            // A lone number after the name, with no code text: a default, as printed.
            row.default = Some(code as f64);
        }
    } else {
        read_glued(body.trim(), row, &mut unit, &mut decimals);
    }
    if let Some((first, rest)) = glued_columns(&row.name) {
        let (first, rest) = (first.to_string(), rest.to_string());
        if let (_, Some((s, u))) = name_resolution(&rest)
            && step.is_none()
        {
            step = Some(s);
            unit = Some(u);
        }
        row.notes
            .push(format!("printed next to the name: \"{rest}\""));
        row.name = first;
    }
    if let (name, Some((s, u))) = name_resolution(&row.name) {
        row.name = name;
        if step.is_none() {
            step = Some(s);
            unit = Some(u);
        }
    }
    if RATIO.is_match(body) {
        row.notes
            .push("a ratio scale is printed; the draft carries no scale".into());
        step = None;
        unit = unit.filter(|u| *u != "%");
    }
    if !row.values.is_empty() && row.min.is_none() {
        unit = None;
        decimals = None;
    }
    row.unit = unit.map(str::to_string);
    row.scale = match (step, unit, decimals) {
        (Some(s), _, _) => Some(s),
        (None, Some(_), Some(d)) => Some(10f64.powi(-(d as i32))),
        (None, None, Some(d)) if d > 0 => Some(10f64.powi(-(d as i32))),
        _ => None,
    };
}

/// A body OCR glued into one run: `Energy Saving Gain0 to 100%80`,
/// `Slip Compensation Selection0Disabled0`, `Acceleration Time 1`.
fn read_glued(
    body: &str,
    row: &mut Row,
    unit: &mut Option<&'static str>,
    decimals: &mut Option<u32>,
) {
    static CODE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(
            r"^(?P<name>.*?[a-z.)])(?P<code>\d{1,2})(?P<text>[A-Z][a-z][^\d]*?)(?P<def>\d+(?:\.\d+)?)?$",
        )
        .expect("pattern")
    });
    if let Some(r) = find_range(body) {
        let name = body[..r.start].trim();
        // A resolution printed between the name and the range (`Gain 0.01 0.00~2.55`).
        let (name, step) = match name.rsplit_once(' ') {
            Some((head, last)) if resolution_cell(last).is_some() && !head.is_empty() => {
                (head.trim(), resolution_cell(last))
            }
            _ => (name, None),
        };
        row.name = clean_name(name);
        set_range(row, &r, decimals, unit);
        if let Some((n, u)) = step {
            row.scale = Some(n.value);
            if u.is_some() {
                *unit = u;
            }
        }
        let after = body[r.end..].trim();
        let lead: String = after
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '.')
            .collect();
        if let Some(n) = Num::parse(&lead) {
            row.default = Some(n.value);
        }
        if !after.is_empty() && lead.is_empty() {
            row.notes
                .push(format!("printed after the range: \"{after}\""));
        }
        return;
    }
    if let Some(c) = CODE.captures(body) {
        row.name = clean_name(&c["name"]);
        if let Ok(v) = c["code"].parse() {
            row.values.push(Code {
                value: v,
                name: c["text"].trim().to_string(),
                line: row.line,
            });
        }
        if let Some(d) = c.name("def").and_then(|d| Num::parse(d.as_str())) {
            row.default = Some(d.value);
        }
        return;
    }
    row.name = clean_name(body);
}

/// A resolution printed in the name (`Output Current (0.1A) (U-03)`): the name without it, and
/// the step and unit.
fn name_resolution(name: &str) -> (String, Option<(f64, &'static str)>) {
    // `(0.1A)` anywhere in the name, or `0.1A/1` ("0.1 A per count") at its end.
    static PAREN: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"\s*\((?:in\s+)?(\d[\d.]*\s*[^()\d\s][^()]{0,5})\)").expect("pattern")
    });
    static PER_COUNT: LazyLock<Regex> =
        LazyLock::new(|| Regex::new(r"\s+(\d[\d.]*\s*[^\d\s/]{1,4})\s*/\s*1$").expect("pattern"));
    for re in [&*PAREN, &*PER_COUNT] {
        for c in re.captures_iter(name) {
            if let Some((n, Some(u))) = resolution_cell(&c[1]) {
                let m = c.get(0).expect("whole match");
                let rest = format!("{}{}", &name[..m.start()], &name[m.end()..]);
                return (clean_name(&rest), Some((n.value, u)));
            }
        }
    }
    (name.to_string(), None)
}

/// Two columns OCR glued together (`Motor SpeedMotor Speed (in 0.1 Hz)`): the first, and the
/// rest. The seam is a word of two letters or more running into a capital (`SpeedMotor`,
/// `VqOutput`, `(Iq)Motor`); `kWatts` is one word.
fn glued_columns(s: &str) -> Option<(&str, &str)> {
    let b = s.as_bytes();
    for i in 1..b.len().saturating_sub(1) {
        let (prev, cur, next) = (b[i - 1], b[i], b[i + 1]);
        if !cur.is_ascii_uppercase() || !next.is_ascii_alphabetic() {
            continue;
        }
        let word_start = s[..i].rfind([' ', '/', '-']).map_or(0, |p| p + 1);
        let word = &s[word_start..i];
        let seam = (prev.is_ascii_lowercase()
            && word.len() >= 2
            && word.chars().any(|c| c.is_ascii_lowercase()))
            || prev == b')';
        if seam {
            return Some((s[..i].trim(), s[i..].trim()));
        }
    }
    None
}

fn clean_name(s: &str) -> String {
    static FOOTNOTE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"\(\s*(?:\*|※|Note\s*)\d*\s*\)|(?:^|\s)[*※]\d+\b|\*+$").expect("pattern")
    });
    let s = FOOTNOTE.replace_all(s, "");
    let s = s.trim().trim_matches(|c: char| c == '|' || c == '*');
    let s = s.trim_end_matches(['(', ',', ':', ';']);
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The rest of a name the table wraps onto the next line (`Password / Initialization` then
/// `Selection`; `Slip Compensation Primary Delay` then `Time`): the first cell of words only
/// (no digits: OCR noise such as `012/11` is not a name) that is not the text of a code.
fn name_continuation(line: &str, row: &mut Row) {
    let cs = cells(line);
    let mut previous_is_code = false;
    for cell in &cs {
        let words_only = cell.chars().filter(|c| c.is_alphabetic()).count() >= 3
            && !cell.chars().any(|c| c.is_ascii_digit())
            && cell.starts_with(|c: char| c.is_alphabetic());
        if words_only && !previous_is_code {
            // Not a row's own echo (OCR prints some rows twice: `Reverse Fromott Selection`
            // under `Reverse Prohibit Selection`), not a reserved row, not after a description.
            let first = |t: &str| t.split_whitespace().next().unwrap_or("").to_lowercase();
            let echo = first(cell) == first(&row.name);
            if !echo
                && !is_reserved(cell)
                && !row.name.ends_with(['.', ':', ')'])
                && !row.name.contains([':', ';'])
                && access_cell(cell).is_none()
                && unit_cell(cell).is_none()
            {
                row.name = format!("{} {}", row.name, clean_name(cell));
            }
            return;
        }
        previous_is_code = Num::parse(cell).is_some_and(|n| n.decimals == 0 && n.value <= 255.0);
    }
}

/// Codes listed under a row: `0  Ramp To Stop`, `1: Coast`, `2 = External`. Returns whether the
/// line gave one.
fn continuation_codes(line: &str, line_no: usize, row: &mut Row) -> bool {
    static INLINE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"^\s*(?P<code>\d{1,3})\s*[:=]\s*(?P<text>[A-Za-z(].*)$").expect("pattern")
    });
    // A quantity with decimals has no codes.
    if row.scale.is_some_and(|s| s < 1.0) {
        return false;
    }
    let mut found = None;
    if let Some(c) = cells(line)
        .into_iter()
        .find_map(|cell| INLINE.captures(cell))
    {
        found = Some((c["code"].parse::<i64>().ok(), c["text"].trim().to_string()));
    } else {
        let cs = cells(line);
        for pair in cs.windows(2) {
            if let (Some(n), true) = (
                Num::parse(pair[0])
                    .filter(|n| n.decimals == 0 && n.value >= 0.0 && n.value <= 255.0),
                pair[1].starts_with(|c: char| c.is_alphabetic() || c == '('),
            ) {
                found = Some((Some(n.value as i64), pair[1].to_string()));
            }
        }
    }
    let Some((Some(value), name)) = found else {
        return false;
    };
    if row.values.iter().any(|c| c.value == value) {
        return false;
    }
    if let (Some(min), Some(max)) = (row.min, row.max)
        && ((value as f64) < min || (value as f64) > max)
    {
        return false;
    }
    row.values.push(Code {
        value,
        name,
        line: line_no,
    });
    true
}

/// What a line under a table header is, read by the header's columns.
enum LayoutLine {
    /// A register row.
    Row(Box<Row>),
    /// A row that is not proposed (a coil, a block of registers printed as one row), with why.
    Reported(Unread),
    /// No key in the address or parameter column.
    NotKeyed,
}

/// A number printed for a column of a row: the address, as a register of this table.
enum AddressKey {
    Register(u16, Notation, Option<String>),
    OtherSpace(&'static str),
    Block,
}

fn address_key(cell: &str, col: &Column) -> Option<AddressKey> {
    let tok = cell.split_whitespace().next()?;
    let tok = tok.trim_matches(['(', ')', '|']);
    static BLOCK: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"^\S+\s*(?:…|\.\.\.|\.\.|–|-|~|to)\s*\S*\d").expect("pattern")
    });
    if BLOCK.is_match(cell.trim()) && !cell.trim().contains(char::is_alphabetic) {
        return Some(AddressKey::Block);
    }
    if cell.trim().ends_with(['…', '.']) && cell.trim().contains("..") || cell.contains('…') {
        return Some(AddressKey::Block);
    }
    // One number with the other notation in brackets (`40 (28)`, `0028h (40)`): the pair says
    // which is decimal and which hex.
    static BRACKETED: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"^([0-9A-Fa-f]{1,5})[hH]?\s*[(\[]\s*(?:0x)?([0-9A-Fa-f]{1,5})[hH]?\s*[)\]]$")
            .expect("pattern")
    });
    if let Some(c) = BRACKETED.captures(cell.trim()) {
        let (a, b) = (&c[1], &c[2]);
        let dec = |t: &str| t.parse::<u32>().ok();
        let hex = |t: &str| u32::from_str_radix(t, 16).ok();
        if dec(a).is_some() && dec(a) == hex(b) {
            return Some(AddressKey::Register(
                u16::try_from(dec(a)?).ok()?,
                Notation::Decimal,
                Some(format!("printed with its hex form: {}", cell.trim())),
            ));
        }
        if hex(a).is_some() && hex(a) == dec(b) {
            return Some(AddressKey::Register(
                u16::try_from(hex(a)?).ok()?,
                Notation::Hex,
                Some(format!("printed with its decimal form: {}", cell.trim())),
            ));
        }
    }
    if let Some((space, register)) = modicon(tok)
        && (col.modicon || space != '4')
        && !col.hex
    {
        return Some(match space {
            '4' => AddressKey::Register(
                register,
                Notation::Decimal,
                Some(format!(
                    "printed as the Modicon reference {tok} (4xxxx numbering: 40001 is register 0)"
                )),
            ),
            '3' => AddressKey::OtherSpace("an input register (3xxxx, read with 04h)"),
            '1' => AddressKey::OtherSpace("a discrete input (1xxxx)"),
            _ => AddressKey::OtherSpace("a coil (0xxxx)"),
        });
    }
    if let Some(a) = hex_address(tok) {
        return Some(AddressKey::Register(a, Notation::Hex, None));
    }
    if col.hex && tok.len() <= 4 && tok.chars().all(|c| c.is_ascii_hexdigit()) {
        return Some(AddressKey::Register(
            u16::from_str_radix(tok, 16).ok()?,
            Notation::Hex,
            None,
        ));
    }
    if tok.len() <= 5 && tok.chars().all(|c| c.is_ascii_digit()) {
        return Some(AddressKey::Register(
            tok.parse().ok()?,
            Notation::Decimal,
            None,
        ));
    }
    None
}

/// A register row read by the columns of its table's header.
fn layout_row(
    line: &str,
    line_no: usize,
    layout: &Layout,
    table: &Option<(usize, String)>,
) -> LayoutLine {
    let cells = layout.assign(line);
    let cell = |role: Role| layout.find(role).and_then(|i| cells[i]);
    let mut row = Row {
        line: line_no,
        address: None,
        address_printed: None,
        notation: Notation::Hex,
        param: None,
        name: String::new(),
        access: None,
        unit: None,
        scale: None,
        min: None,
        max: None,
        default: None,
        values: Vec::new(),
        fields: Vec::new(),
        notes: Vec::new(),
        reserved: false,
        table: table.clone(),
        signed: None,
        pair: None,
    };
    let reported = |why: String| {
        LayoutLine::Reported(Unread {
            line: line_no,
            text: shorten(line.trim()),
            why,
        })
    };
    if let Some(i) = layout.find(Role::Address)
        && let Some(c) = cells[i]
    {
        match address_key(c, &layout.columns[i]) {
            Some(AddressKey::Register(a, notation, note)) => {
                row.address = Some(a);
                row.address_printed = c.split_whitespace().next().map(str::to_string);
                row.notation = notation;
                row.notes.extend(note);
            }
            Some(AddressKey::OtherSpace(what)) => {
                return reported(format!(
                    "{what}: not a holding register; the map has no space for it yet, so it is reported, not proposed"
                ));
            }
            Some(AddressKey::Block) => {
                return reported(
                    "a block of registers printed as one row (its registers are not named one by one); not proposed".into(),
                );
            }
            None => {}
        }
    }
    // A name printed under the number's title (`0500H  Save parameters  -`): the row leaves
    // the number out and its cells shift left.
    let mut shifted_name = None;
    if let Some(c) = cell(Role::Param) {
        match param_cell(c) {
            Some(p) => row.param = Some(p.to_string()),
            None if row.address.is_none() => return LayoutLine::NotKeyed,
            None => shifted_name = Some(c),
        }
    }
    if row.address.is_none() && row.param.is_none() {
        return LayoutLine::NotKeyed;
    }
    if let Some(space) = layout.bits {
        return reported(format!(
            "a {space} (the table at line {} lists {space}s): not a holding register; the map has no space for it yet, so it is reported, not proposed",
            layout.line
        ));
    }
    if let Some(c) = cell(Role::Reference) {
        if let Some((space, _)) = modicon(c.split_whitespace().next().unwrap_or(""))
            && space != '4'
        {
            return reported(format!(
                "printed with the reference {c} of another space than the holding registers; not proposed"
            ));
        }
        row.notes.push(format!("also printed as {c}"));
    }
    if let Some(c) = cell(Role::Name) {
        row.name = clean_name(c);
    }
    if let Some(c) = shifted_name
        && (row.name.is_empty() || row.name == "-")
        && c.chars().filter(|c| c.is_alphabetic()).count() >= 3
    {
        row.name = clean_name(c);
    }
    row.reserved = is_reserved(&row.name);
    let mut unit: Option<&'static str> = None;
    let mut step: Option<f64> = None;
    let mut decimals: Option<u32> = None;
    let debracket = |c: &str| c.replace(['[', ']'], " ").trim().to_string();
    for (col, c) in layout.columns.iter().zip(&cells) {
        let Some(c) = c else { continue };
        let dash = matches!(*c, "-" | "—" | "–" | "--" | "n/a" | "N/A" | "None" | "none");
        match col.role {
            Role::Access => match access_word(c) {
                Some(a) => row.access = Some(a),
                None if dash => {}
                None => row.notes.push(format!("access printed as \"{c}\"")),
            },
            Role::Unit if !dash => {
                let d = debracket(c);
                if let Some(u) = unit_cell(&d) {
                    unit = Some(u);
                } else if let Some((n, u)) = resolution_cell(&d) {
                    step = Some(n.value);
                    unit = u.or(unit);
                }
            }
            Role::Step if !dash => {
                let d = debracket(c);
                if let Some((n, u)) = resolution_cell(&d) {
                    step = Some(n.value);
                    if u.is_some() {
                        unit = u;
                    }
                } else {
                    row.notes.push(format!("{} printed as \"{c}\"", col.title));
                }
            }
            Role::Factor | Role::Exponent if !dash => match scale_of(col.role, c) {
                Some(s) => step = Some(s),
                None => row.notes.push(format!("{} printed as \"{c}\"", col.title)),
            },
            Role::Range if !dash => {
                if let Some(r) = find_range(c) {
                    set_range(&mut row, &r, &mut decimals, &mut unit);
                } else {
                    for code in inline_codes(c, line_no) {
                        row.values.push(code);
                    }
                }
            }
            Role::Min if !dash => match Num::parse(c) {
                Some(n) => {
                    row.min = Some(n.value);
                    decimals = Some(decimals.unwrap_or(0).max(n.decimals));
                }
                None => row.notes.push(format!("minimum printed as \"{c}\"")),
            },
            Role::Max if !dash => match Num::parse(c) {
                Some(n) => {
                    row.max = Some(n.value);
                    decimals = Some(decimals.unwrap_or(0).max(n.decimals));
                }
                None => row.notes.push(format!("maximum printed as \"{c}\"")),
            },
            Role::Default if !dash => match Num::parse(c) {
                Some(n) => row.default = Some(n.value),
                None => row.notes.push(format!("default printed as \"{c}\"")),
            },
            Role::Type if !dash => {
                let t = c.to_ascii_lowercase();
                let signed = (t.contains("int") && !t.contains("uint") && !t.contains("unsigned"))
                    || t.starts_with('s')
                    || t.starts_with('i')
                    || (t.contains("signed") && !t.contains("unsigned"));
                let unsigned = t.contains("uint") || t.starts_with('u') || t.contains("unsigned");
                if signed && !t.contains("float") && !t.contains("real") {
                    row.signed = Some(true);
                } else if unsigned {
                    row.signed = Some(false);
                }
                if t.contains("32") || t.contains("float") || t.contains("real") {
                    row.notes
                        .push(format!("printed as the type {c} (two registers)"));
                }
            }
            Role::Size if !dash && c.trim() != "1" => {
                row.notes.push(format!("{} printed as \"{c}\"", col.title));
            }
            Role::Description => {
                for code in inline_codes(c, line_no) {
                    row.values.push(code);
                }
            }
            _ => {}
        }
    }
    if !row.values.is_empty() && row.min.is_none() {
        unit = None;
        decimals = None;
    }
    // Limits printed in counts (`0  65000` beside `0.01 Hz`): whole numbers that no register
    // holds at the scale but that fit one as counts are counts; read as such, with a note.
    if let (Some(s), Some(max)) = (step, row.max)
        && s < 1.0
        && decimals == Some(0)
        && max > 65535.0 * s
        && max <= 65535.0
        && row.min.is_none_or(|m| m >= -32768.0)
    {
        let round = |v: f64| (v * s * 1e6).round() / 1e6;
        row.max = Some(round(max));
        row.min = row.min.map(round);
        row.notes.push(format!(
            "limits printed in counts ({} to {}); read as counts of {s}",
            num_text(row.min.unwrap_or(0.0) / s),
            num_text(max)
        ));
        decimals = None;
    }
    row.unit = unit.map(str::to_string);
    row.scale = match (step, unit, decimals) {
        // A count of one with no unit is a plain word.
        (Some(1.0), None, _) => None,
        (Some(s), _, _) => Some(s),
        (None, Some(_), Some(d)) => Some(10f64.powi(-(d as i32))),
        (None, None, Some(d)) if d > 0 => Some(10f64.powi(-(d as i32))),
        _ => None,
    };
    LayoutLine::Row(Box::new(row))
}

/// Codes printed in one cell (`0: Stop, 1: Run`, `0 = off`).
fn inline_codes(cell: &str, line_no: usize) -> Vec<Code> {
    static RE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"(?:^|[,;]\s*)(\d{1,3})\s*[:=]\s*([A-Za-z(][^,;]*)").expect("pattern")
    });
    RE.captures_iter(cell)
        .filter_map(|c| {
            Some(Code {
                value: c[1].parse().ok()?,
                name: c[2].trim().to_string(),
                line: line_no,
            })
        })
        .collect()
}

/// A line under a row of a column-read table that carries no key: the rest of a wrapped name
/// (text in the name column), or codes (in the name, range or description column). Returns
/// whether the line was taken.
fn layout_continuation(
    line: &str,
    line_no: usize,
    layout: &Layout,
    row: &mut Row,
    last_attached: usize,
) -> bool {
    let cells = layout.assign(line);
    let mut taken = false;
    for (col, c) in layout.columns.iter().zip(&cells) {
        let Some(c) = c else { continue };
        let codes = inline_codes(c, line_no);
        if !codes.is_empty() {
            for code in codes {
                if !row.values.iter().any(|v| v.value == code.value) {
                    row.values.push(code);
                }
            }
            taken = true;
            continue;
        }
        match col.role {
            Role::Name
                if line_no == last_attached + 1
                    && row.values.is_empty()
                    && c.chars().filter(|c| c.is_alphabetic()).count() >= 2
                    && !c.starts_with(|c: char| c.is_ascii_digit()) =>
            {
                row.name = clean_name(&format!("{} {c}", row.name));
                taken = true;
            }
            Role::Description | Role::Unit | Role::Type | Role::Step => taken = true,
            _ => return false,
        }
    }
    if taken && !row.values.is_empty() && row.min.is_none() {
        row.unit = None;
        row.scale = None;
    }
    taken
}

/// A table printed one cell per line, as read.
struct Vertical {
    /// The lines it takes (header and records), 1-based.
    lines: BTreeSet<usize>,
    rows: Vec<Row>,
    unread: Vec<Unread>,
    layout: Layout,
}

/// Whether a line is a lone column title (one cell, a known title, no digit).
fn lone_title(line: &str) -> Option<Role> {
    let t = line.trim();
    if t.is_empty() || t.len() > 40 || t.chars().any(|c| c.is_ascii_digit()) || cells(t).len() != 1
    {
        return None;
    }
    crate::columns::title_role(t)
}

/// Whether a cell fits a column of a role, by its shape.
fn fits(role: Role, cell: &str) -> bool {
    let c = cell.trim();
    let dash = matches!(c, "-" | "—" | "–" | "--");
    match role {
        Role::Access => access_word(c).is_some() || dash,
        Role::Unit => unit_cell(&c.replace(['[', ']'], " ")).is_some() || dash,
        Role::Step | Role::Factor | Role::Exponent => {
            resolution_cell(&c.replace(['[', ']'], " ")).is_some()
                || Num::parse(c).is_some()
                || dash
        }
        Role::Range => find_range(c).is_some() || dash,
        Role::Min | Role::Max | Role::Default | Role::Size => Num::parse(c).is_some() || dash,
        Role::Type => {
            let t = c.to_ascii_lowercase();
            [
                "int", "uint", "word", "float", "real", "bool", "u16", "s16", "u32", "s32", "i16",
                "i32",
            ]
            .iter()
            .any(|w| t.contains(w))
                || dash
        }
        Role::Name | Role::Description => {
            c.chars().filter(|c| c.is_alphabetic()).count() >= 2
                && access_word(c).is_none()
                && unit_cell(c).is_none()
        }
        _ => false,
    }
}

/// Tables printed one cell per line: a run of three or more lone column titles (`Register`,
/// `Name`, `Unit`, `Access`), then records that each start with a key under the first title
/// (an address or a parameter number) and give the other cells on the lines after it, in the
/// titles' order; a cell that does not fit its column's shape is left empty, and a name may
/// wrap over several lines.
fn vertical_tables(
    lines: &[&str],
    first_line: usize,
    table: &Option<(usize, String)>,
) -> Vec<Vertical> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        // A run of lone titles.
        let start = i;
        let mut roles = Vec::new();
        let mut titles = Vec::new();
        while i < lines.len()
            && let Some(r) = lone_title(lines[i])
        {
            roles.push(r);
            titles.push(lines[i].trim().to_string());
            i += 1;
        }
        if roles.len() < 3 || !matches!(roles[0], Role::Address | Role::Param) || i >= lines.len() {
            i = start + 1;
            continue;
        }
        // Titles the reader does not know, right after the known ones (`Allotment for bits`):
        // columns it leaves undecided.
        while i < lines.len() && roles.len() < 12 {
            let t = lines[i].trim();
            let words = t.split_whitespace().count();
            if t.is_empty()
                || t.chars().any(|c| c.is_ascii_digit())
                || !(1..=4).contains(&words)
                || t.len() > 30
                || hex_address(t).is_some()
                || access_word(t).is_some()
                || t == "-"
            {
                break;
            }
            roles.push(Role::Undecided);
            titles.push(t.to_string());
            i += 1;
        }
        let header_line = first_line + start;
        let columns: Vec<Column> = titles
            .iter()
            .zip(&roles)
            .enumerate()
            .map(|(n, (t, r))| Column {
                title: t.clone(),
                role: *r,
                start: n,
                end: n,
                hex: false,
                modicon: false,
            })
            .collect();
        let mut layout = Layout {
            line: header_line,
            columns,
            split: Split::Tabs,
            bits: None,
        };
        let key_col = layout.columns[0].clone();
        let is_key = |l: &str| {
            let t = l.trim();
            !t.contains(char::is_whitespace)
                && match key_col.role {
                    Role::Address => {
                        hex_address(t).is_some()
                            || (t.len() <= 6 && t.chars().all(|c| c.is_ascii_digit()))
                    }
                    _ => param_cell(t).is_some() && t.chars().any(|c| c.is_ascii_alphabetic()),
                }
        };
        // The records: from a key to the next key.
        let mut records: Vec<(usize, Vec<&str>)> = Vec::new();
        let mut taken = BTreeSet::new();
        for n in start..i {
            taken.insert(first_line + n);
        }
        let mut blanks = 0;
        while i < lines.len() {
            let l = lines[i].trim();
            if l.is_empty() {
                blanks += 1;
                if blanks >= 2 {
                    break;
                }
                i += 1;
                continue;
            }
            blanks = 0;
            // A key like the first (hex with its mark, or decimal), and a decimal one above the
            // last (a resolution `1` under a decimal-numbered table is not a key).
            let like_first = records.first().is_none_or(|(_, f)| {
                let marked = |t: &str| hex_address(t).is_some();
                marked(f[0]) == marked(l)
                    && (marked(l)
                        || records.last().is_some_and(|(_, r)| {
                            r.len() >= 2 && l.parse::<u32>().ok() > r[0].parse::<u32>().ok()
                        }))
            });
            if is_key(l) && like_first {
                records.push((i, vec![l]));
            } else if let Some(r) = records.last_mut()
                && l.len() <= 60
            {
                r.1.push(l);
            } else {
                break;
            }
            taken.insert(first_line + i);
            i += 1;
        }
        if records.is_empty() {
            i = start + 1;
            continue;
        }
        // Decide hex and Modicon numbering from the keys, as for a table on one line.
        let keys: Vec<String> = records.iter().map(|(_, c)| c[0].to_string()).collect();
        layout.decide(&keys.iter().map(String::as_str).collect::<Vec<_>>());
        // A `Parameter` title over names (the cell after the key is words, not a number).
        if !layout.columns.iter().any(|c| c.role == Role::Name)
            && let Some(k) = layout.columns.iter().position(|c| c.role == Role::Param)
            && k > 0
        {
            let wordy = records
                .iter()
                .filter(|(_, c)| {
                    c.get(1)
                        .is_some_and(|t| t.contains(' ') || param_cell(t).is_none())
                })
                .count();
            if wordy * 10 >= records.len() * 9 {
                layout.columns[k].role = Role::Name;
            }
        }
        let mut v = Vertical {
            lines: taken,
            rows: Vec::new(),
            unread: Vec::new(),
            layout: layout.clone(),
        };
        for (at, cells_of) in records {
            // Cells to columns in order: a cell goes to the next column its shape fits; text
            // that fits no later column continues the name.
            let mut placed: Vec<String> = vec![String::new(); layout.columns.len()];
            placed[0] = cells_of[0].to_string();
            let mut col = 1;
            for c in &cells_of[1..] {
                let next = (col..layout.columns.len()).find(|k| fits(layout.columns[*k].role, c));
                match next {
                    Some(k) => {
                        placed[k] = c.to_string();
                        col = k + 1;
                    }
                    None => {
                        // Text that fits no later column: the name wrapping, while nothing after
                        // the name is filled; else a column the reader left undecided (or the
                        // description), never the name.
                        let name = layout.columns.iter().position(|c| c.role == Role::Name);
                        let target = if name.is_some_and(|n| col <= n + 1) {
                            name
                        } else {
                            (col..layout.columns.len()).find(|k| {
                                matches!(
                                    layout.columns[*k].role,
                                    Role::Undecided | Role::Description
                                )
                            })
                        };
                        if let Some(k) = target {
                            placed[k] = format!("{} {c}", placed[k]).trim().to_string();
                        }
                    }
                }
            }
            let line_no = first_line + at;
            let synthetic = placed.join("\t");
            match layout_row(&synthetic, line_no, &layout, table) {
                LayoutLine::Row(mut row) => {
                    if row.name.is_empty() {
                        v.unread.push(Unread {
                            line: line_no,
                            text: cells_of.join(" "),
                            why: "a row key with no name after it".into(),
                        });
                    } else {
                        row.notes
                            .push("read from a table printed one cell per line".into());
                        v.rows.push(*row);
                    }
                }
                LayoutLine::Reported(u) => v.unread.push(u),
                LayoutLine::NotKeyed => {}
            }
        }
        out.push(v);
    }
    out
}

/// A header whose titles are separated by single blanks: its roles, matched greedily over one to
/// three words (`Modbus register` `Access` `Information`), a name column put after the keys when
/// no title names one. `None` unless most words are known titles and the first is an address or
/// a parameter number.
fn word_header(line: &str, line_no: usize) -> Option<Layout> {
    let t = line.trim();
    if t.is_empty() || t.len() > 120 || t.chars().any(|c| c.is_ascii_digit()) || t.ends_with('.') {
        return None;
    }
    let words: Vec<&str> = t.split_whitespace().collect();
    if words.len() < 2 || words.len() > 14 {
        return None;
    }
    let mut roles: Vec<(String, Role)> = Vec::new();
    let mut known_words = 0;
    let mut i = 0;
    while i < words.len() {
        // A title of two words is one title when neither word names another column on its own
        // (`Modbus register`, `Data resolution`, `Register No.`; not `Register Access`).
        let suffix = |w: &str| {
            matches!(
                w.to_lowercase().trim_end_matches(['.', ':']),
                "no" | "number" | "nr" | "value" | "values" | "(hex)" | "(dec)"
            )
        };
        let mut matched = None;
        for n in (1..=2).rev() {
            if i + n <= words.len() {
                let title = words[i..i + n].join(" ");
                let Some(r) = crate::columns::title_role(&title) else {
                    continue;
                };
                let alone = |w: &str| crate::columns::title_role(w);
                let consistent = n == 1
                    || (alone(words[i]).is_none_or(|x| x == r)
                        && (suffix(words[i + 1]) || alone(words[i + 1]).is_none_or(|x| x == r)));
                if consistent {
                    matched = Some((title, r, n));
                    break;
                }
            }
        }
        match matched {
            Some((title, r, n)) => {
                roles.push((title, r));
                known_words += n;
                i += n;
            }
            None => {
                roles.push((words[i].to_string(), Role::Undecided));
                i += 1;
            }
        }
    }
    let known = roles.iter().filter(|(_, r)| *r != Role::Undecided).count();
    if known < 2 || known_words * 10 < words.len() * 7 {
        return None;
    }
    if !matches!(roles[0].1, Role::Address | Role::Param) {
        return None;
    }
    // Undecided titles are used for nothing; a description with no name column is the name.
    if !roles.iter().any(|(_, r)| *r == Role::Name) {
        match roles.iter().position(|(_, r)| *r == Role::Description) {
            Some(d) if d == 1 => roles[d].1 = Role::Name,
            _ => {
                let at = roles
                    .iter()
                    .position(|(_, r)| !matches!(r, Role::Address | Role::Param | Role::Reference))
                    .unwrap_or(roles.len());
                roles.insert(at, ("(name)".to_string(), Role::Name));
            }
        }
    }
    // Two number columns: the second is a reference.
    if roles.len() > 1 && roles[0].1 == Role::Address && roles[1].1 == Role::Address {
        roles[1].1 = Role::Reference;
    }
    Some(Layout {
        line: line_no,
        columns: roles
            .into_iter()
            .enumerate()
            .map(|(n, (title, role))| Column {
                title,
                role,
                start: n,
                end: n,
                hex: false,
                modicon: false,
            })
            .collect(),
        split: Split::Tabs,
        bits: None,
    })
}

/// A row under a header read by words, as cells joined by tabs for [`layout_row`]: the keys (one
/// token each), the name up to the first token that can only be a later column (an access, a
/// parameter number, a range, a bracketed unit, a resolution with its unit), then each token in
/// the next column its shape fits; what fits none is description.
fn word_row(line: &str, layout: &Layout) -> Option<String> {
    let toks: Vec<&str> = line.split_whitespace().collect();
    let offset = |t: &str| t.as_ptr() as usize - line.as_ptr() as usize;
    let roles: Vec<Role> = layout.columns.iter().map(|c| c.role).collect();
    let name_at = roles.iter().position(|r| *r == Role::Name)?;
    if toks.len() <= name_at {
        return None;
    }
    let mut cells = vec![String::new(); roles.len()];
    for k in 0..name_at {
        let t = toks[k];
        let ok = match roles[k] {
            Role::Address | Role::Reference => {
                hex_address(t).is_some() || (t.len() <= 6 && t.chars().all(|c| c.is_ascii_digit()))
            }
            Role::Param => param_cell(t).is_some(),
            r => fits(r, t),
        };
        if !ok {
            return None;
        }
        cells[k] = t.to_string();
    }
    let later: Vec<Role> = roles[name_at + 1..].to_vec();
    let anchor = |j: usize| {
        let t = toks[j];
        let rest = &line[offset(t)..];
        (later.contains(&Role::Access) && access_word(t).is_some())
            || (later.contains(&Role::Param)
                && param_cell(t).is_some()
                && t.chars().any(|c| c.is_ascii_alphabetic())
                && t.chars().any(|c| c.is_ascii_digit()))
            || (later.contains(&Role::Range)
                && rest.starts_with(|c: char| c.is_ascii_digit() || "+-−±".contains(c))
                && find_range(rest).is_some_and(|r| r.start == 0))
            || (t.starts_with('[') && unit_cell(t.trim_matches(['[', ']'])).is_some())
            || (resolution_cell(&t.replace(['[', ']'], " ")).is_some_and(|(_, u)| u.is_some())
                && t.chars().next().is_some_and(|c| c.is_ascii_digit()))
    };
    let mut j = name_at + 1;
    while j < toks.len() && !anchor(j) {
        j += 1;
    }
    cells[name_at] = toks[name_at..j].join(" ");
    let mut col = name_at + 1;
    let mut t = j;
    let mut last: Option<usize> = None;
    while t < toks.len() {
        // A bracketed unit after a number belongs to it (`0.01 [Hz]`).
        if let Some(k) = last
            && toks[t].starts_with('[')
            && unit_cell(toks[t].trim_matches(['[', ']'])).is_some()
            && matches!(
                roles[k],
                Role::Step | Role::Unit | Role::Min | Role::Max | Role::Default
            )
        {
            cells[k] = format!("{} {}", cells[k], toks[t]);
            t += 1;
            continue;
        }
        let rest = &line[offset(toks[t])..];
        // A range takes the tokens it spans.
        if let Some(k) = (col..roles.len()).find(|k| roles[*k] == Role::Range)
            && rest.starts_with(|c: char| c.is_ascii_digit() || "+-−±".contains(c))
            && let Some(r) = find_range(rest).filter(|r| r.start == 0)
        {
            let end = offset(toks[t]) + r.end;
            cells[k] = line[offset(toks[t])..end].trim().to_string();
            col = k + 1;
            last = Some(k);
            while t < toks.len() && offset(toks[t]) < end {
                t += 1;
            }
            continue;
        }
        let tok = toks[t];
        match (col..roles.len()).find(|k| {
            !matches!(roles[*k], Role::Description | Role::Undecided) && fits(roles[*k], tok)
        }) {
            Some(k) => {
                cells[k] = tok.to_string();
                col = k + 1;
                last = Some(k);
            }
            None => {
                last = None;
                if let Some(d) = roles.iter().position(|r| *r == Role::Description) {
                    cells[d] = format!("{} {tok}", cells[d]).trim().to_string();
                }
            }
        }
        t += 1;
    }
    Some(cells.join("\t"))
}

/// A number for a note (`65000`, `0.5`).
fn num_text(v: f64) -> String {
    let r = (v * 1e6).round() / 1e6;
    format!("{r}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> (Vec<Row>, Vec<Unread>) {
        let lines: Vec<&str> = text.lines().collect();
        let schemes = crate::scheme::learn(&lines);
        read_rows(&lines, 1, &schemes)
    }

    #[test]
    fn a_tabbed_table_with_a_unit_column() {
        let (rows, _) = read(
            "Address\tParameter\tName\tUnit\tSetting Range\n\
             032BH\tCn-44\tPID Integral Upper Bound\t1%\t0~109%\n\
             032CH\tCn-45\tPID Primary Delay Time Constant\t0.1s\t0.0~2.5s\n\
             032DH\tCn-46\tResistance, Motor winding\t0.00 1Ω\t0.000~65.535Ω\n\
             032EH\tCn-47\tSlip Compensation Gain\t0.01\t0.00~2.55\n",
        );
        assert_eq!(rows.len(), 4);
        let r = &rows[1];
        assert_eq!(
            (r.address, r.param.as_deref(), r.name.as_str()),
            (
                Some(0x032C),
                Some("Cn-45"),
                "PID Primary Delay Time Constant"
            )
        );
        assert_eq!(
            (r.unit.as_deref(), r.scale, r.min, r.max),
            (Some("s"), Some(0.1), Some(0.0), Some(2.5))
        );
        assert_eq!(rows[2].scale, Some(0.001));
        assert_eq!((rows[3].unit.as_deref(), rows[3].scale), (None, Some(0.01)));
        assert_eq!(
            (rows[0].unit.as_deref(), rows[0].scale, rows[0].max),
            (Some("%"), Some(1.0), Some(109.0))
        );
    }

    #[test]
    fn glued_rows_and_codes() {
        let (rows, _) = read(
            "1A0hb7-01Droop Control Gain0.0 to 100.0\n\
             1A2hb8-01Energy Saving Gain0 to 100%80\n\
             1A3hb8-02Energy Saving Frequency0.0 to 400.0 Hz0.0\n\
             212hC3-04Slip Compensation Selection0Disabled0\n\
             during Regeneration1Enabled\n",
        );
        assert_eq!(rows.len(), 4);
        assert_eq!(
            (
                rows[1].name.as_str(),
                rows[1].unit.as_deref(),
                rows[1].default
            ),
            ("Energy Saving Gain", Some("%"), Some(80.0))
        );
        assert_eq!(
            (rows[2].scale, rows[2].max, rows[2].default),
            (Some(0.1), Some(400.0), Some(0.0))
        );
        assert_eq!(
            rows[3].values.first().map(|c| (c.value, c.name.as_str())),
            Some((0, "Disabled"))
        );
        assert_eq!(rows[3].default, Some(0.0));
    }

    #[test]
    fn codes_listed_under_a_row() {
        let (rows, _) = read(
            "n004\t0104h\tReference Source\t0\tKeypad\t0\n\
             \t\t\t1\tTerminal\n\
             n005\t0105h\tStopping Method Selection\t0\tRamp To Stop\t0\n\
             \t\t\t1\tCoast To Stop\n\
             n006\t0106h\tReverse Prohibit\t0\tEnabled\t0\n\
             n007\t0107h\tStop Key\t0\tEnabled\t0\n",
        );
        assert_eq!(rows.len(), 4);
        let codes: Vec<_> = rows[1]
            .values
            .iter()
            .map(|c| (c.value, c.name.as_str(), c.line))
            .collect();
        assert_eq!(codes, vec![(0, "Ramp To Stop", 3), (1, "Coast To Stop", 4)]);
        assert_eq!(rows[1].default, Some(0.0));
    }

    #[test]
    fn a_name_wrapped_onto_the_next_line() {
        let (rows, _) = read(
            "n001\t0101h\tPassword / Initialization\t0\tAll locked\t1\n\
             11001\t010111\tSelection\t1\tAll open\n\
             n002\t0102h\tReverse Prohibit Selection\t0\tEnabled\t0\n\
             11002\t010211\tReverse Fromott Selection\t1\tDisabled\n\
             n003\t0103h\tStop Key\t0\tEnabled\t0\n\
             \t\tReserved\n\
             n004\t0104h\tOperator\t0\tOn\t0\n",
        );
        let names: Vec<&str> = rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "Password / Initialization Selection",
                "Reverse Prohibit Selection",
                "Stop Key",
                "Operator"
            ]
        );
        assert_eq!(
            rows[0].values.iter().map(|c| c.value).collect::<Vec<_>>(),
            [0, 1]
        );
        assert_eq!(
            rows[1].values.iter().map(|c| c.value).collect::<Vec<_>>(),
            [0, 1]
        );
    }

    #[test]
    fn prose_is_not_a_row() {
        let (rows, _) = read(
            "n003 = 1 selects the terminals\nn001 Password\nn002 Control\nn003 Run\nn004 Reference\n\
             The value 0101h. is written\n",
        );
        assert_eq!(
            rows.iter().map(|r| r.line).collect::<Vec<_>>(),
            vec![2, 3, 4, 5]
        );
    }

    #[test]
    fn decimal_addresses_under_an_address_header() {
        let (rows, _) = read(
            "Register   Name                 Range        Default\n\
             40101      Acceleration time    0.1 to 600.0 s   5.0\n\
             40102      Deceleration time    0.1 to 600.0 s   5.0\n",
        );
        assert_eq!(rows.len(), 2);
        // A register column of Modicon references only: 40001 is register 0.
        assert_eq!(
            (
                rows[0].address,
                rows[0].notation,
                rows[0].address_printed.as_deref()
            ),
            (Some(100), Notation::Decimal, Some("40101"))
        );
        assert_eq!(
            (rows[0].unit.as_deref(), rows[0].scale, rows[0].default),
            (Some("s"), Some(0.1), Some(5.0))
        );
    }

    #[test]
    fn one_cell_per_line_with_a_parameter_title_over_names_and_an_unknown_title() {
        let (rows, _) = read(
            "Address\nParameter\nScale\nUnit\nR/W\nBit assignment\n\
             0x0010\nDrive type\n-\n-\nR\nB : model B\n\
             0x0011\nSpeed\nreference\n0.01\nHz\nR/W\n",
        );
        let got: Vec<_> = rows
            .iter()
            .map(|r| {
                (
                    r.address,
                    r.name.as_str(),
                    r.access,
                    r.unit.as_deref(),
                    r.scale,
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (Some(0x10), "Drive type", Some("r"), None, None),
                (
                    Some(0x11),
                    "Speed reference",
                    Some("rw"),
                    Some("Hz"),
                    Some(0.01)
                ),
            ]
        );
    }

    #[test]
    fn a_header_with_single_blanks_read_by_words() {
        let (rows, _) = read(
            "Modbus register Access Data resolution Remarks\n\
             40001 Output frequency R 0.01 [Hz] Filtered value.\n\
             40002 Trip counter R 1 [times] Since power-on.\n\
             40003 Frequency reference R/W 0.01 [Hz] Written by the master,\n\
             kept until power-off.\n",
        );
        let got: Vec<_> = rows
            .iter()
            .map(|r| {
                (
                    r.address,
                    r.name.as_str(),
                    r.access,
                    r.unit.as_deref(),
                    r.scale,
                    r.default,
                )
            })
            .collect();
        // A resolution column is never a default; a unit the reader does not know is left out.
        assert_eq!(
            got,
            [
                (
                    Some(0),
                    "Output frequency",
                    Some("r"),
                    Some("Hz"),
                    Some(0.01),
                    None
                ),
                (Some(1), "Trip counter", Some("r"), None, None, None),
                (
                    Some(2),
                    "Frequency reference",
                    Some("rw"),
                    Some("Hz"),
                    Some(0.01),
                    None
                ),
            ]
        );
    }

    #[test]
    fn titles_wrapped_onto_a_second_header_line() {
        let (rows, _) = read(
            "Register   Function name          Function   R/W   Setting range      Data\n\
             No.                               code                                resolution\n\
             0011h      Trip counter           d080       R     0 to 65530         1\n\
             0012h      Output frequency       d001       R     0.00 to 400.00     0.01 [Hz]\n",
        );
        let got: Vec<_> = rows
            .iter()
            .map(|r| {
                (
                    r.address,
                    r.param.as_deref(),
                    r.name.as_str(),
                    r.scale,
                    r.default,
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (Some(0x11), Some("d080"), "Trip counter", None, None),
                (
                    Some(0x12),
                    Some("d001"),
                    "Output frequency",
                    Some(0.01),
                    None
                ),
            ]
        );
    }
}
