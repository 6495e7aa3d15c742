//! Citations checked by content: the cited line (or the row it belongs to) must mention the item.
//!
//! - a **register**: its address in a notation the manual uses, its parameter number, or its
//!   printed name (two of its words). A name alone does not verify a line that is another
//!   register's row (it prints that register's address or parameter number and not this one's):
//!   "Acceleration time 2" is not the row of "Acceleration time 1".
//! - a **value**: its code and its label; a **field**: its bit or its name.
//!
//! A row may span two OCR lines: when the cited line is not another register's row, the lines
//! just before and after count as the row. A citation marked `indirect` (with its reason) is not
//! checked, and a page citation (`<manual id>:p<page>`, a manual with no text at hand) is
//! reported as not verifiable by content ([`Verdict::Page`]).

use std::collections::HashMap;

use super::Manuals;
use super::matching::{
    AddressForms, Line, code_found, label_text, name_found, number_found, param_found,
};
use drivemap_map::facts::PlaceKind;
use drivemap_map::facts::{BitField as Field, EnumValue};
use drivemap_map::facts::{parse_citation, parse_page_citation};
use drivemap_map::{Loc, Map, RegisterRef};

/// What a citation is the citation of.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Item {
    /// The register itself (its parameter number, address or name).
    Register,
    /// A code of the register or of one of its fields.
    Value {
        /// The code.
        code: u16,
        /// Its meaning as the map writes it.
        label: String,
    },
    /// A bit field of the register.
    Field {
        /// Its bit or bits (`3`, `4-5`).
        bit: String,
        /// Its name as the map writes it.
        name: String,
    },
    /// A citation outside the registers ([`Map::other_citations`]): of a role, a protocol item, a
    /// reading of a conflict, a gap.
    Other {
        /// `role`, `protocol`, `conflict` or `gap`.
        kind: &'static str,
        /// What it cites (`role `run``, `exception 21h`).
        what: String,
    },
}

/// The outcome of checking one citation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// The cited line mentions the item.
    Verified,
    /// The row the line belongs to (the line before or after) mentions it.
    VerifiedRow(usize),
    /// Marked indirect in the map, with this reason.
    Indirect(String),
    /// The line does not mention it. `row_of`: the register whose row the line is instead.
    Unverified {
        /// The register whose row the line is, when it is another's.
        row_of: Option<String>,
    },
    /// The manual is not at hand or the line does not exist.
    Unchecked,
    /// A page of a manual with no text at hand (`<id>:p<page>`): not verifiable by content.
    Page,
}

/// One citation and what review found.
#[derive(Debug, Clone)]
pub struct CitationCheck {
    /// Where the citation is written in the map.
    pub loc: Loc,
    /// The id of the register it belongs to (empty for a citation outside the registers).
    pub register: String,
    /// What it cites.
    pub item: Item,
    /// `file:line`
    pub source: String,
    /// What the item is expected to show (`Bn-01, 0200h, "Acceleration time 1"`).
    pub expected: String,
    /// The cited line, quoted.
    pub quote: Option<String>,
    /// What review found.
    pub verdict: Verdict,
}

impl CitationCheck {
    /// Whether the cited line or its row mentions the item.
    pub fn verified(&self) -> bool {
        matches!(self.verdict, Verdict::Verified | Verdict::VerifiedRow(_))
    }

    /// The warning for an unverified citation.
    pub fn warning(&self) -> Option<super::Warning> {
        let Verdict::Unverified { row_of } = &self.verdict else {
            return None;
        };
        let what = match &self.item {
            Item::Register => String::new(),
            Item::Value { code, .. } => format!(" of code {code}"),
            Item::Field { bit, .. } => format!(" of bit {bit}"),
            Item::Other { what, .. } => format!(" of {what}"),
        };
        let mut message = format!(
            "citation{what} `{}` does not mention {}: `{}`",
            self.source,
            self.expected,
            self.quote.as_deref().unwrap_or("")
        );
        if let Some(other) = row_of {
            message.push_str(&format!(" (the row of `{other}`)"));
        }
        message.push_str("; fix the line, or mark it `indirect: <reason>`");
        Some(super::Warning {
            loc: self.loc.clone(),
            register: (!self.register.is_empty()).then(|| self.register.clone()),
            message,
        })
    }
}

struct Keys {
    forms: AddressForms,
    alternatives: Vec<AddressForms>,
    param: Option<String>,
    read_param: Option<String>,
}

impl Keys {
    fn of(r: RegisterRef, offsets: Option<(i32, i32)>, decimal: bool) -> Keys {
        let forms = |address: u16| {
            let f = AddressForms::new(address, offsets);
            if decimal { f.with_decimal(address) } else { f }
        };
        Keys {
            forms: forms(r.address()).with_reference(r.modicon()),
            alternatives: r
                .address_alternatives()
                .iter()
                .map(|a| forms(a.address))
                .collect(),
            param: r.param().map(str::to_owned),
            read_param: r.read_param().map(str::to_owned),
        }
    }

    /// The line prints the register's parameter number or one of its addresses.
    fn strong(&self, line: &Line) -> bool {
        self.param.as_deref().is_some_and(|p| param_found(p, line))
            || self
                .read_param
                .as_deref()
                .is_some_and(|p| param_found(p, line))
            || self.forms.found_in(line)
            || self.alternatives.iter().any(|f| f.found_in(line))
    }
}

/// Lines prepared once per manual line asked for.
struct Cache<'m> {
    manuals: &'m Manuals,
    lines: HashMap<(String, usize), Option<Line>>,
}

impl Cache<'_> {
    fn get(&mut self, file: &str, n: usize) -> Option<&Line> {
        let manuals = self.manuals;
        self.lines
            .entry((file.to_owned(), n))
            .or_insert_with(|| manuals.line(file, n).map(Line::new))
            .as_ref()
    }
}

/// How far around a line other registers are looked for when deciding whose row it is.
const WINDOW: usize = 80;

/// Checks every citation of a drive against the manuals: registers, values and fields, then
/// roles, protocol items, readings of conflicts and gaps ([`Map::other_citations`]).
pub fn verify_citations(map: &Map, manuals: &Manuals) -> Vec<CitationCheck> {
    let decimal = map.address_format() == drivemap_map::facts::AddressFormat::Decimal;
    let offsets = map
        .protocol()
        .addressing
        .as_ref()
        .map(|a| (a.rtu_offset, a.tcp_offset));
    let keys: Vec<Keys> = map
        .registers()
        .map(|r| Keys::of(r, offsets, decimal))
        .collect();
    // Registers by manual, sorted by cited line, to find the neighbours of a line.
    let mut by_file: HashMap<&str, Vec<(usize, usize)>> = HashMap::new();
    for (i, r) in map.registers().enumerate() {
        if let Some((file, line)) = r.source().and_then(parse_citation) {
            by_file.entry(file).or_default().push((line, i));
        }
    }
    for list in by_file.values_mut() {
        list.sort_unstable();
    }
    let mut cache = Cache {
        manuals,
        lines: HashMap::new(),
    };
    let mut out = Vec::new();
    // The registers' own citations, from the one list of citation places: each register's row,
    // its values, its read values, each field with its values.
    for place in map.citation_places() {
        let (Some(i), Some(src)) = (place.register, place.source) else {
            continue;
        };
        let Some(r) = map.register_at(i) else {
            continue;
        };
        let value = |v: &EnumValue| {
            let verdict = match &v.indirect {
                Some(reason) => Verdict::Indirect(reason.clone()),
                None => near(manuals, src, |l| value_found(v, l)),
            };
            (
                Item::Value {
                    code: v.value,
                    label: v.name.clone(),
                },
                format!("code {} \"{}\"", v.value, v.name),
                verdict,
            )
        };
        let (item, expected, verdict) = match place.kind {
            PlaceKind::Register => {
                let mut expected = Vec::new();
                if let Some(p) = r.param() {
                    expected.push(p.to_owned());
                }
                if let Some(p) = r.read_param() {
                    expected.push(p.to_owned());
                }
                // In the map's notation (`45` in a decimal-numbered map), and the Modicon
                // reference it records.
                expected.push(drivemap_map::describe::address_as(
                    map.address_format(),
                    r.address(),
                ));
                expected.extend(r.reference().map(str::to_owned));
                expected.push(format!("\"{}\"", r.name()));
                let verdict = match r.indirect() {
                    Some(reason) => Verdict::Indirect(reason.to_owned()),
                    None => register_verdict(map, &keys, &by_file, &mut cache, i, src),
                };
                (Item::Register, expected.join(", "), verdict)
            }
            PlaceKind::Value(vi) => value(&r.values()[vi]),
            PlaceKind::ReadValue(vi) => value(&r.read_values()[vi]),
            PlaceKind::FieldValue { field, value: vi } => value(&r.fields()[field].values[vi]),
            PlaceKind::Field(fi) => {
                let f = &r.fields()[fi];
                let verdict = match &f.indirect {
                    Some(reason) => Verdict::Indirect(reason.clone()),
                    None => near(manuals, src, |l| field_found(f, l)),
                };
                let bit = match (f.bit, f.bits) {
                    (Some(b), _) => b.to_string(),
                    (None, Some([lo, hi])) => format!("{lo}-{hi}"),
                    _ => String::new(),
                };
                (
                    Item::Field {
                        bit: bit.clone(),
                        name: f.name.clone(),
                    },
                    format!("bit {bit} or \"{}\"", f.name),
                    verdict,
                )
            }
            // Read by content with the citations outside the registers, or not at all.
            _ => continue,
        };
        out.push(CitationCheck {
            loc: map.locate_tree_path(&place.path),
            register: r.id().to_owned(),
            item,
            source: src.to_owned(),
            expected,
            quote: manuals.quote(src),
            verdict,
        });
    }
    for o in map.other_citations() {
        let Some(source) = o.source else {
            continue;
        };
        let verdict = match &o.indirect {
            Some(reason) => Verdict::Indirect(reason.clone()),
            None => match &o.rule {
                drivemap_map::facts::CitationRule::Register(i) => {
                    register_verdict(map, &keys, &by_file, &mut cache, *i, &source)
                }
                rule => near(manuals, &source, |l| {
                    super::others::found(rule, map, offsets, l)
                }),
            },
        };
        out.push(CitationCheck {
            loc: map.locate_tree_path(&o.path),
            register: String::new(),
            expected: map.expected(&o.rule),
            quote: manuals.quote(&source),
            item: Item::Other {
                kind: o.kind,
                what: o.what,
            },
            source,
            verdict,
        });
    }
    out
}

pub(crate) fn value_found(v: &EnumValue, line: &Line) -> bool {
    let label = label_text(&v.name);
    name_found(&label, line) && code_found(v.value, &label, line)
}

pub(crate) fn field_found(f: &Field, line: &Line) -> bool {
    let bit = f.bit.or(f.bits.map(|b| b[0]));
    if let Some([lo, hi]) = f.bits {
        // `B0-B7`, OCR `BO-B7`
        let ocr = line.upper.replace('O', "0");
        if ocr.contains(&format!("B{lo}-B{hi}")) || ocr.contains(&format!("B{lo}~B{hi}")) {
            return true;
        }
    }
    bit.is_some_and(|b| number_found(u16::from(b), line)) || name_found(&label_text(&f.name), line)
}

/// A value's or field's citation: the line, else the row it belongs to (the line joined with
/// the one after or before it: a label broken over two OCR lines).
fn near(manuals: &Manuals, source: &str, found: impl Fn(&Line) -> bool) -> Verdict {
    if parse_page_citation(source).is_some() {
        return Verdict::Page;
    }
    let Some((file, n)) = parse_citation(source) else {
        return Verdict::Unchecked;
    };
    let Some(text) = manuals.line(file, n) else {
        return Verdict::Unchecked;
    };
    if found(&Line::new(text)) {
        return Verdict::Verified;
    }
    if let Some(next) = manuals.line(file, n + 1)
        && found(&Line::new(&format!("{text} {next}")))
    {
        return Verdict::VerifiedRow(n + 1);
    }
    if let Some(prev) = n.checked_sub(1).and_then(|m| manuals.line(file, m))
        && found(&Line::new(&format!("{prev} {text}")))
    {
        return Verdict::VerifiedRow(n - 1);
    }
    Verdict::Unverified { row_of: None }
}

fn register_verdict(
    map: &Map,
    keys: &[Keys],
    by_file: &HashMap<&str, Vec<(usize, usize)>>,
    cache: &mut Cache<'_>,
    i: usize,
    source: &str,
) -> Verdict {
    if parse_page_citation(source).is_some() {
        return Verdict::Page;
    }
    let Some((file, n)) = parse_citation(source) else {
        return Verdict::Unchecked;
    };
    let Some(r) = map.register_at(i) else {
        return Verdict::Unchecked;
    };
    let neighbours: Vec<usize> = by_file
        .get(file)
        .map(|list| {
            let lo = list.partition_point(|&(l, _)| l + WINDOW < n);
            let hi = list.partition_point(|&(l, _)| l <= n + WINDOW);
            // Nearest first: the register cited on the line itself names the row.
            let mut near: Vec<(usize, usize)> = list[lo..hi]
                .iter()
                .filter(|&&(_, j)| j != i)
                .filter(|&&(_, j)| {
                    map.register_at(j)
                        .is_some_and(|o| o.address() != r.address())
                })
                .map(|&(l, j)| (l.abs_diff(n), j))
                .collect();
            near.sort_unstable();
            near.into_iter().map(|(_, j)| j).collect()
        })
        .unwrap_or_default();
    // Whose row a line is, other than this register's.
    let other_row = |line: &Line| -> Option<usize> {
        neighbours.iter().copied().find(|&j| keys[j].strong(line))
    };
    let matches = |line: &Line| -> (bool, Option<usize>) {
        if keys[i].strong(line) {
            return (true, None);
        }
        let other = other_row(line);
        (other.is_none() && name_found(r.name(), line), other)
    };
    let Some(line) = cache.get(file, n) else {
        return Verdict::Unchecked;
    };
    let line = line.clone();
    if line.words.is_empty() {
        // A blank line is no row, even beside the right one.
        return Verdict::Unverified { row_of: None };
    }
    let (ok, other) = matches(&line);
    if ok {
        return Verdict::Verified;
    }
    if let Some(j) = other {
        return Verdict::Unverified {
            row_of: map.register_at(j).map(|o| o.label()),
        };
    }
    for m in [n.saturating_sub(1), n + 1] {
        if m == 0 {
            continue;
        }
        if let Some(l) = cache.get(file, m).cloned()
            && matches(&l).0
        {
            return Verdict::VerifiedRow(m);
        }
    }
    Verdict::Unverified { row_of: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MANUAL: &str = "Table 1\n\
        0200H\tBn-01\tAcceleration time 1\t0.1s\n\
        0201H\tBn-02\tDeceleration time 1\t0.1s\n\
        \n\
        0202H\tBn-03\tRun source\t0: Operator 1: Terminals\n";

    fn map(accel: usize, decel: usize, indirect: &str) -> Map {
        let text = format!(
            "drive: {{id: t, vendor: T, models: [T], manuals: [{{file: m.txt, title: M}}]}}\n\
             protocol: {{transports: [rtu], function_codes: [0x03, 0x06], max_read: 1, max_write: 1, slave_address: {{min: 1, max: 31}}}}\n\
             groups:\n\
             \x20 - id: g\n\
             \x20   name: G\n\
             \x20   registers:\n\
             \x20     - {{id: accel, param: Bn-01, name: Acceleration time 1, address: 0x0200, source: \"m.txt:{accel}\"}}\n\
             \x20     - {{id: decel, param: Bn-02, name: Deceleration time 1, address: 0x0201, {indirect}source: \"m.txt:{decel}\"}}\n\
             \x20     - id: run_source\n\
             \x20       param: Bn-03\n\
             \x20       name: Run source\n\
             \x20       address: 0x0202\n\
             \x20       values:\n\
             \x20         - {{value: 0, id: operator, name: Operator, source: \"m.txt:5\"}}\n\
             \x20         - {{value: 1, id: terminals, name: Terminals, source: \"m.txt:5\"}}\n\
             \x20         - {{value: 2, id: network, name: Network, source: \"m.txt:5\"}}\n\
             \x20       source: \"m.txt:5\"\n"
        );
        drivemap_map::Loader::new()
            .load_str("t.yaml", &text)
            .unwrap()
    }

    fn verdicts(drive: &Map) -> Vec<(String, Verdict)> {
        let manuals = Manuals::from_texts([("m.txt", MANUAL)]);
        verify_citations(drive, &manuals)
            .into_iter()
            .map(|c| (c.source.clone(), c.verdict))
            .collect()
    }

    /// A manual that numbers registers in decimal: with `address_format: decimal` its rows are
    /// found by the decimal number (no parameter number, no name on the line).
    #[test]
    fn a_decimal_map_finds_its_registers_by_their_decimal_number() {
        let text = |format: &str| {
            format!(
                "{format}drive: {{id: t, vendor: T, models: [T], manuals: [{{file: d.txt, title: D}}]}}\n\
                 protocol: {{transports: [rtu], function_codes: [0x03], max_read: 1, max_write: 1, slave_address: {{min: 1, max: 31}}}}\n\
                 groups:\n\
                 \x20 - {{id: g, name: G, registers: [{{id: speed, name: Speed reference, access: r, address: 0x07D1, source: \"d.txt:1\"}}]}}\n"
            )
        };
        let manuals = Manuals::from_texts([("d.txt", "2001\tReference\tHz\n")]);
        let verdict = |format: &str| {
            let drive = drivemap_map::Loader::new()
                .load_str("t.yaml", &text(format))
                .unwrap();
            verify_citations(&drive, &manuals)[0].verdict.clone()
        };
        assert_eq!(verdict("address_format: decimal\n"), Verdict::Verified);
        assert_eq!(verdict(""), Verdict::Unverified { row_of: None });
    }

    #[test]
    fn right_rows_verify_and_a_swapped_one_names_the_row_it_points_at() {
        let ok = verdicts(&map(2, 3, ""));
        assert!(
            ok[..2].iter().all(|(_, v)| *v == Verdict::Verified),
            "{ok:?}"
        );
        let swapped = verdicts(&map(3, 3, ""));
        assert_eq!(
            swapped[0].1,
            Verdict::Unverified {
                row_of: Some("decel (Bn-02)".into())
            }
        );
        // The blank line beside the right row is not the row.
        let blank = verdicts(&map(2, 4, ""));
        assert_eq!(blank[1].1, Verdict::Unverified { row_of: None });
    }

    #[test]
    fn an_indirect_citation_is_not_checked_and_codes_need_their_label() {
        let v = verdicts(&map(2, 4, "indirect: \"printed on the next page\", "));
        assert_eq!(v[1].1, Verdict::Indirect("printed on the next page".into()));
        let codes: Vec<&Verdict> = v[3..].iter().map(|(_, v)| v).collect();
        assert_eq!(
            codes,
            [
                &Verdict::Verified,
                &Verdict::Verified,
                &Verdict::Unverified { row_of: None }
            ]
        );
    }

    #[test]
    fn odd_text_does_not_panic() {
        for text in [
            "",
            "é",
            "12éH",
            "0xé",
            "ÀH12 Bn-0é",
            "ΩE4-03",
            "\u{0}\u{ffff}h0200",
            "0h",
        ] {
            let manuals = Manuals::from_texts([("m.txt", text)]);
            let _ = verify_citations(&map(1, 2, ""), &manuals);
            let _ = super::super::coverage(&map(1, 2, ""), &manuals, &[]);
        }
    }
}
