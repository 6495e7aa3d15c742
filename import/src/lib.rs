//! Drafts a register map from a drive manual's text.
//!
//! [`read_manual`] finds the register rows of a manual (OCR text as in `shared/manuals`: columns
//! broken, tables split across pages, rows glued together, or one clean row per line) with a row
//! grammar written from what manuals print ([`row`], [`text`]), learning the manual's parameter
//! number schemes from the manual itself ([`scheme`]). [`draft`] writes the rows as a draft map,
//! every register citing the line it came from; [`compare`] sets rows against an existing map
//! (`drivemap import --merge`, and the figures in `docs/import.md`).
#![doc = include_str!("../README.md")]
#![warn(unreachable_pub, missing_docs, unnameable_types)]

pub mod columns;
pub mod compare;
pub mod draft;
pub mod formula;
pub mod known;
pub mod protocol;
pub mod row;
pub mod scheme;
pub mod text;

use std::collections::BTreeMap;

use row::{Notation, Row, Unread};

/// What was read from one manual.
#[derive(Debug, Clone)]
pub struct Reading {
    /// The manual's file name, as citations name it.
    pub file: String,
    /// The manual's first line of text (a title, as far as the text shows).
    pub title: String,
    /// The register rows read, in manual order (a row printed again is left out).
    pub rows: Vec<Row>,
    /// Lines that looked like rows but were not read as one, with why.
    pub unread: Vec<Unread>,
    /// The parameter number shapes learnt from the manual (`AA-99`, `A999`).
    pub schemes: Vec<String>,
    /// The tables read by their header's columns.
    pub layouts: Vec<columns::Layout>,
    /// The lines the rows took (their own, their codes', bits' and wrapped names').
    pub taken: std::collections::BTreeSet<usize>,
}

/// A Markdown or box-drawn table row (`| 1001 | P1.01 | Maximum frequency |`) as cells separated by
/// tabs, so that every layout reaches the row grammar as cells; other lines unchanged.
fn table_line(line: &str) -> std::borrow::Cow<'_, str> {
    let t = line.trim();
    // Cells separated by spaced bars without a leading one (`0 | 40001 | Speed | R/W`), or a
    // header introduced by a label (`Columns: Register | Name | Access`).
    let spaced = !t.starts_with('|') && t.matches(" | ").count() >= 2;
    if spaced {
        let cells: Vec<&str> = t.split('|').map(str::trim).collect();
        let first = cells[0];
        let first = match first.split_once(':') {
            Some((label, rest)) if label.to_lowercase().contains("column") => rest.trim(),
            _ => first,
        };
        return std::borrow::Cow::Owned(
            std::iter::once(first)
                .chain(cells[1..].iter().copied())
                .collect::<Vec<_>>()
                .join("\t"),
        );
    }
    if t.starts_with('|') && t.matches('|').count() >= 2 {
        let inner = t.trim_matches('|');
        std::borrow::Cow::Owned(
            inner
                .split('|')
                .map(str::trim)
                .collect::<Vec<_>>()
                .join("\t"),
        )
    } else {
        std::borrow::Cow::Borrowed(line)
    }
}

/// The lines `lines` (1-based, inclusive; all when `None`) of `all`, clamped to the text, with
/// the number of the first.
fn line_range<'a>(all: &'a [&'a str], lines: Option<(usize, usize)>) -> (&'a [&'a str], usize) {
    let (first, last) = lines.unwrap_or((1, all.len()));
    let first = first.max(1);
    let last = last.min(all.len());
    if first <= last {
        (&all[first - 1..last], first)
    } else {
        (&all[0..0], first)
    }
}

/// Reads the register rows of one manual; `lines` (1-based, inclusive) limits where rows are
/// read, while the parameter schemes are learnt from the whole text.
pub fn read_manual(file: &str, text: &str, lines: Option<(usize, usize)>) -> Reading {
    read_manual_with(file, text, lines, &BTreeMap::new())
}

/// [`read_manual`], with the columns of some tables named by the user (by the line of their
/// header: `--columns`).
pub fn read_manual_with(
    file: &str,
    text: &str,
    lines: Option<(usize, usize)>,
    columns: &BTreeMap<usize, Vec<columns::Role>>,
) -> Reading {
    let owned: Vec<std::borrow::Cow<'_, str>> = text.lines().map(table_line).collect();
    let all: Vec<&str> = owned.iter().map(|l| l.as_ref()).collect();
    let schemes = scheme::learn(&all);
    let (slice, first) = line_range(&all, lines);
    let ruled: std::collections::BTreeSet<usize> = owned
        .iter()
        .enumerate()
        .filter(|(_, l)| matches!(l, std::borrow::Cow::Owned(_)))
        .map(|(i, _)| i + 1)
        .collect();
    let row::Tables {
        rows,
        mut unread,
        layouts,
        taken,
    } = row::read_tables(slice, first, &schemes, columns, &ruled);
    // A row printed again (a summary table, a record sheet at the end of the manual) is
    // reported, not proposed twice: the first printing is the one a draft cites.
    let mut first_at = std::collections::BTreeMap::new();
    let mut kept = Vec::with_capacity(rows.len());
    for r in rows {
        let key = (r.param.clone(), r.address);
        match first_at.get(&key) {
            Some(line) => unread.push(Unread {
                line: r.line,
                text: r.name.clone(),
                why: format!("printed again (first at line {line}); not proposed twice"),
            }),
            None => {
                first_at.insert(key, r.line);
                kept.push(r);
            }
        }
    }
    let mut rows = kept;
    // A manual that prints its addresses in hex (`0101h`) and a few without a marker (`910`
    // under an Address column) means hex there too; the reading is noted on the row.
    let hex = rows
        .iter()
        .filter(|r| r.address.is_some() && r.notation == Notation::Hex)
        .count();
    let decimal = rows
        .iter()
        .filter(|r| r.notation == Notation::Decimal)
        .count();
    if hex > decimal {
        for r in rows.iter_mut().filter(|r| r.notation == Notation::Decimal) {
            let printed = r.address_printed.clone().unwrap_or_default();
            match u16::from_str_radix(&printed, 16) {
                // One or two digits under an Address column of a hex manual are a byte
                // number of an example frame or a bit, not an address.
                Ok(_) if printed.len() < 3 => r.address = None,
                Ok(a) => {
                    r.address = Some(a);
                    r.notation = Notation::Hex;
                    r.notes.push(format!(
                        "address printed \"{printed}\" without a hex mark; read as hex like the manual's other addresses"
                    ));
                }
                Err(_) => r.address = None,
            }
        }
    }
    // A parameter table addressed by a formula the manual prints: each row with a parameter
    // number and no address gets the formula's address, noted with the formula's line.
    if let Some(f) = formula::find(&all) {
        for r in rows.iter_mut().filter(|r| r.address.is_none()) {
            let Some(a) = r.param.as_deref().and_then(|p| f.address(p)) else {
                continue;
            };
            r.address = Some(a);
            r.notation = Notation::Decimal;
            r.notes.push(format!(
                "address {a} from the formula at line {}: \"{}\"{}",
                f.line,
                f.text,
                if f.modicon() {
                    " (a Modicon reference: the register is the reference less 40001 / 400001; confirm against an example of the manual)"
                } else {
                    ""
                }
            ));
        }
    }
    unread.sort_by_key(|u| u.line);
    let title = all
        .iter()
        .map(|l| l.trim().trim_start_matches('#').trim())
        .find(|l| l.chars().filter(|c| c.is_alphabetic()).count() >= 3 && !l.starts_with("<|"))
        .unwrap_or(file)
        .chars()
        .take(120)
        .collect();
    Reading {
        file: file.to_string(),
        title,
        rows,
        unread,
        schemes: schemes.into_iter().collect(),
        layouts,
        taken,
    }
}

/// A manual to import: its file name (as citations name it) and text.
pub struct Manual<'a> {
    /// The file name citations name.
    pub file: &'a str,
    /// The manual's text.
    pub text: &'a str,
}

/// What `drivemap import` makes of its manuals.
pub struct Import {
    /// What was read from each manual: rows and protocol facts.
    pub readings: Vec<(Reading, protocol::Protocol)>,
    /// The draft map (YAML).
    pub yaml: String,
    /// What the reviewer must confirm (also in the draft's `draft.to_confirm`).
    pub to_confirm: Vec<String>,
    /// Rows read but left out of the draft because the front end refused them, by manual file
    /// and line, with the finding.
    pub left_out: BTreeMap<(String, usize), String>,
    /// Findings of the front end on the draft that no row explains (empty when the draft
    /// checks).
    pub unresolved: Vec<String>,
    /// The draft's registers: id, manual file and line of the row.
    pub registers: Vec<(String, String, usize)>,
}

impl Import {
    /// The registers of the draft read from one manual.
    pub fn proposed(&self, file: &str) -> usize {
        self.registers.iter().filter(|(_, f, _)| f == file).count()
    }
}

/// Reads the manuals and writes the draft map `id`. `lines` limits where rows and protocol facts
/// are read (the same range in each manual).
pub fn import(
    id: &str,
    manuals: &[Manual<'_>],
    lines: Option<(usize, usize)>,
    command: &str,
) -> Import {
    import_with(id, manuals, lines, &BTreeMap::new(), command)
}

/// [`import`], with the columns of tables named by the user: by the line of the table's header
/// (the same line in each manual), the roles of its columns left to right (`--columns`).
pub fn import_with(
    id: &str,
    manuals: &[Manual<'_>],
    lines: Option<(usize, usize)>,
    columns: &BTreeMap<usize, Vec<columns::Role>>,
    command: &str,
) -> Import {
    let readings: Vec<(Reading, protocol::Protocol)> = manuals
        .iter()
        .map(|m| {
            let reading = read_manual_with(m.file, m.text, lines, columns);
            let all: Vec<&str> = m.text.lines().collect();
            let (slice, first) = line_range(&all, lines);
            (reading, protocol::read(slice, first))
        })
        .collect();
    // The front end checks the draft; a row it refuses (two rows at one address, a range that
    // does not fit a register at the scale read) is left out and reported with the finding,
    // never repaired by guessing. Each round removes at least one row, so this ends.
    let mut left_out: BTreeMap<(String, usize), String> = BTreeMap::new();
    let file_name = format!("{id}.yaml");
    loop {
        let written = draft::write(&draft::DraftInput {
            id,
            left_out: &left_out,
            readings: &readings,
            command,
        });
        let findings = match drivemap_map::Loader::new().load_str(&file_name, &written.yaml) {
            Ok(_) => Vec::new(),
            Err(d) => d.0,
        };
        let before = left_out.len();
        for f in &findings {
            let Some(reg) = &f.register else { continue };
            if let Some((_, file, line)) = written.registers.iter().find(|(i, _, _)| i == reg) {
                left_out
                    .entry((file.clone(), *line))
                    .or_insert_with(|| f.message.clone());
            }
        }
        if left_out.len() == before {
            let unresolved = findings.iter().map(|f| f.to_string()).collect();
            return Import {
                readings,
                yaml: written.yaml,
                to_confirm: written.to_confirm,
                left_out,
                unresolved,
                registers: written.registers,
            };
        }
    }
}

/// The `--report`: per manual, every line the reader could not use as a row (with why), every
/// row it did not propose (reserved, no address), and what the reviewer must confirm.
pub fn report(import: &Import) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(out, "# drivemap import report");
    for (r, _) in &import.readings {
        let proposed = import.proposed(&r.file);
        let _ = writeln!(
            out,
            "\n## {}\n\nparameter number schemes learnt: {}\nrows read: {}; registers proposed in the draft: {proposed}; lines reported below: {}\n",
            r.file,
            if r.schemes.is_empty() {
                "none".to_string()
            } else {
                r.schemes.join(", ")
            },
            r.rows.len(),
            r.unread.len()
        );
        for l in &r.layouts {
            let roles: Vec<String> = l
                .columns
                .iter()
                .map(|c| columns::role_name(c.role).to_string())
                .collect();
            let _ = writeln!(
                out,
                "- {}:{}: a table read by its columns: {}",
                r.file,
                l.line,
                l.columns
                    .iter()
                    .zip(&roles)
                    .map(|(c, role)| format!("\"{}\" = {role}", c.title))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            for (n, c) in l.columns.iter().enumerate() {
                if c.role == columns::Role::Undecided {
                    let _ = writeln!(
                        out,
                        "- {}:{}: column {} \"{}\" of this table is not understood (neither its title nor its cells say what it holds); its cells are not used. Name the columns: --columns {}:{}",
                        r.file,
                        l.line,
                        n + 1,
                        c.title,
                        l.line,
                        roles
                            .iter()
                            .map(|r| if r == "undecided" { "?" } else { r.as_str() })
                            .collect::<Vec<_>>()
                            .join(",")
                    );
                }
            }
        }
        for x in r.rows.iter().filter(|x| x.reserved) {
            let _ = writeln!(
                out,
                "- {}:{}: not proposed: printed as {:?}",
                r.file, x.line, x.name
            );
        }
        for x in r.rows.iter().filter(|x| !x.reserved && x.address.is_none()) {
            let _ = writeln!(
                out,
                "- {}:{}: not proposed: parameter {} ({}) has no address on its line",
                r.file,
                x.line,
                x.param.as_deref().unwrap_or("?"),
                x.name
            );
        }
        for ((file, line), why) in import.left_out.iter().filter(|((f, _), _)| *f == r.file) {
            let _ = writeln!(
                out,
                "- {file}:{line}: not proposed: the checked draft refused it: {why}"
            );
        }
        for u in &r.unread {
            let _ = writeln!(out, "- {}:{}: {}: {}", r.file, u.line, u.why, u.text);
        }
    }
    if !import.unresolved.is_empty() {
        let _ = writeln!(out, "\n## Findings of check on the draft\n");
        for u in &import.unresolved {
            let _ = writeln!(out, "- {u}");
        }
    }
    if !import.to_confirm.is_empty() {
        let _ = writeln!(out, "\n## To confirm\n");
        for c in &import.to_confirm {
            let _ = writeln!(out, "- {c}");
        }
    }
    out
}

/// `--merge`: the rows of the manuals set against an existing map's registers.
pub struct Merge<'a> {
    /// Per manual file, its rows against the map's registers.
    pub comparisons: Vec<(&'a str, compare::Comparison<'a>)>,
}

/// Compares every reading with the registers of a map.
pub fn merge<'a>(import: &'a Import, known: &'a [compare::Known]) -> Merge<'a> {
    Merge {
        comparisons: import
            .readings
            .iter()
            .map(|(r, _)| (r.file.as_str(), compare::compare(&r.rows, known, &r.file)))
            .collect(),
    }
}

impl Merge<'_> {
    /// The merge report: rows the map lacks (as YAML registers to paste), then every field where
    /// the map and the manual's row disagree.
    pub fn render(&self, map: &str) -> String {
        use std::fmt::Write as _;
        let mut out = String::new();
        let mut taken = std::collections::BTreeSet::new();
        let new: usize = self
            .comparisons
            .iter()
            .map(|(_, c)| c.new_rows.iter().filter(|r| r.address.is_some()).count())
            .sum();
        let _ = writeln!(out, "# drivemap import --merge {map}");
        // What was read comes first: "0 rows the map lacks" means nothing when no row was read.
        for (file, c) in &self.comparisons {
            let read = c.matched.len() + c.new_rows.len();
            let _ = writeln!(
                out,
                "# {file}: {read} register rows read ({} matching a register of the map), {} registers of the map citing it not found",
                c.matched.len(),
                c.missed.len()
            );
            if read == 0 {
                let _ = writeln!(
                    out,
                    "# {file}: no register row was read, so nothing below says the map agrees with it; see `--report`"
                );
            }
        }
        let _ = writeln!(
            out,
            "# {new} rows the map lacks (registers to review and paste into a group):"
        );
        for (file, c) in &self.comparisons {
            for r in c.new_rows.iter().filter(|r| r.address.is_some()) {
                draft::write_register(&mut out, file, r, &mut taken);
            }
        }
        let disagreeing: usize = self
            .comparisons
            .iter()
            .map(|(_, c)| {
                c.matched
                    .iter()
                    .filter(|m| !m.differences.is_empty())
                    .count()
            })
            .sum();
        let _ = writeln!(
            out,
            "\n# {disagreeing} registers where the map and the manual's row disagree:"
        );
        for (file, c) in &self.comparisons {
            for m in c.matched.iter().filter(|m| !m.differences.is_empty()) {
                let _ = writeln!(out, "#   {} ({file}:{}):", m.known.id, m.row.line);
                for d in &m.differences {
                    let _ = writeln!(
                        out,
                        "#     {}: map {} / manual {}",
                        d.field, d.map, d.manual
                    );
                }
            }
        }
        out
    }
}
