//! Rows of the manual that no item of the map cites.
//!
//! The shapes of register rows are learnt from the lines the map's registers cite: the classes
//! of the first two words of each such line (an address such as `0200H` or `0x0300`, a parameter
//! number shaped like the map's own — `Bn-01`, `n001`, `E4-03`, `UF.8` — or anything else). A
//! manual line of a learnt shape is a row; each parameter number on it (several in two-column
//! tables) is a row key, with the address that follows it, or the address alone when the row
//! prints no parameter number. A key is covered when a register has that parameter number or
//! address, a `gaps` entry covers the address or names the parameter, a `removed` entry names it,
//! or any citation of the map points at the line. The rest are uncited rows.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};

use super::Manuals;
use super::citations::{Verdict, verify_citations};
use drivemap_map::Map;
use drivemap_map::facts::parse_citation;

/// A row of a manual table no item of the map covers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UncitedRow {
    /// The manual's file name.
    pub file: String,
    /// The row's line in it, from 1.
    pub line: usize,
    /// The parameter number or address as printed.
    pub key: String,
    /// The line, quoted.
    pub text: String,
}

/// One table of a manual: a run of rows of a learnt shape.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TableSummary {
    /// The manual's file name.
    pub file: String,
    /// The table's first row's line, from 1.
    pub first_line: usize,
    /// The table's last row's line.
    pub last_line: usize,
    /// The map group citing most of its rows, if any.
    pub group: Option<String>,
    /// Row keys in the manual.
    pub rows: usize,
    /// Keys a register of the map has.
    pub cited: usize,
    /// Keys covered by `gaps`, `removed`, a citation of the line (conflicts, notes), or printed
    /// as reserved or not used.
    pub gaps: usize,
    /// Keys nothing covers.
    pub uncited: usize,
}

/// What `drivemap coverage` reports for one map.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CoverageReport {
    /// The drive's id.
    pub drive: String,
    /// The tables found in the manuals, in file and line order.
    pub tables: Vec<TableSummary>,
    /// The rows nothing covers, in file and line order.
    pub uncited: Vec<UncitedRow>,
    /// Manuals named by the map that are not at hand.
    pub missing_manuals: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Class {
    Address,
    Param,
    /// An address glued to a parameter number (`31AhE4-03Motor`).
    AddressParam,
    Other,
}

/// A parameter number's shape: upper-case letter runs `A`, lower-case `a`, digit runs `9`,
/// other characters kept (`Bn-01` → `Aa-9`, `n001` → `a9`, `UF.8` → `A.9`).
fn shape(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        let k = if c.is_ascii_digit() {
            '9'
        } else if c.is_uppercase() {
            'A'
        } else if c.is_lowercase() {
            'a'
        } else {
            c
        };
        if out.ends_with(k) && matches!(k, '9' | 'A' | 'a') {
            continue;
        }
        out.push(k);
    }
    out
}

fn is_hex_word(s: &str) -> bool {
    !s.is_empty()
        && s.chars().all(|c| c.is_ascii_hexdigit())
        && s.chars().any(|c| c.is_ascii_digit())
}

/// The address a word prints, with what follows it: `0200H`, `0x0300`, `0h03E7`, `1E08`,
/// `31Ah…`. OCR `O`/`Q` are read as `0`.
///
/// In a manual that numbers registers in decimal (`decimal`: the map's `address_format`), a word
/// of decimal digits alone is a register number (`45`).
fn address_prefix(word: &str, decimal: bool) -> Option<(u16, &str)> {
    if decimal && (1..=5).contains(&word.len()) && word.bytes().all(|b| b.is_ascii_digit()) {
        return word.parse().ok().map(|n| (n, ""));
    }
    // An address prints at least one digit (`CODE` is not C0DEh).
    if !word.chars().any(|c| c.is_ascii_digit()) {
        return None;
    }
    let fixed: String = word
        .chars()
        .map(|c| match c {
            'O' | 'Q' | 'o' => '0',
            c => c.to_ascii_uppercase(),
        })
        .collect();
    if fixed.len() != word.len() {
        return None;
    }
    let parse = |h: &str| u16::from_str_radix(h, 16).ok();
    if let Some(h) = fixed
        .strip_prefix("0X")
        .or_else(|| fixed.strip_prefix("0H"))
    {
        if (1..=4).contains(&h.len()) && is_hex_word(h) {
            return Some((parse(h)?, ""));
        }
        return None;
    }
    // `0200H`, `31Ah`; two digits (`10H`, a function code) only glued to a parameter number.
    for len in (2..=4).rev() {
        if fixed.len() > len
            && fixed.as_bytes()[len] == b'H'
            && is_hex_word(&fixed[..len])
            && (len >= 3 || fixed.len() > len + 1)
        {
            return Some((parse(&fixed[..len])?, &word[len + 1..]));
        }
    }
    if fixed.len() == 4 && is_hex_word(&fixed) {
        return Some((parse(&fixed)?, ""));
    }
    None
}

/// The parameter number a word starts with, if its shape is one of the map's.
fn param_prefix<'a>(word: &'a str, shapes: &HashSet<String>) -> Option<&'a str> {
    let bytes = word.as_bytes();
    (1..=word.len())
        .rev()
        .filter(|&end| word.is_char_boundary(end))
        .filter(|&end| bytes[end - 1].is_ascii_digit())
        .filter(|&end| end == word.len() || !bytes[end].is_ascii_digit())
        .map(|end| &word[..end])
        .find(|p| shapes.contains(&shape(p)))
}

fn classify(word: &str, shapes: &HashSet<String>, decimal: bool) -> Class {
    if let Some((_, rest)) = address_prefix(word, decimal) {
        if !rest.is_empty() && param_prefix(rest, shapes).is_some() {
            return Class::AddressParam;
        }
        return Class::Address;
    }
    if param_prefix(word, shapes).is_some_and(|p| p.len() == word.len()) {
        return Class::Param;
    }
    Class::Other
}

fn line_shape(line: &str, shapes: &HashSet<String>, decimal: bool) -> (Class, Class) {
    let mut words = line.split_whitespace();
    let a = words
        .next()
        .map_or(Class::Other, |w| classify(w, shapes, decimal));
    let b = words
        .next()
        .map_or(Class::Other, |w| classify(w, shapes, decimal));
    (a, b)
}

/// The row keys of a line: each parameter number with the address after it (or the only
/// address of the line), or the address alone.
///
/// A word that is a Modicon reference the map records (`references`: its printed spellings with
/// the register's address) is not an address of its own: the row is the register's, keyed by the
/// drive's own number printed beside it, or by the register's address when the row prints only
/// the reference.
fn row_keys(
    line: &str,
    shapes: &HashSet<String>,
    decimal: bool,
    references: &Printed,
) -> Vec<(Option<String>, Option<u16>)> {
    let mut keys: Vec<(Option<String>, Option<u16>)> = Vec::new();
    let mut addresses = Vec::new();
    let mut referenced = Vec::new();
    let words: Vec<&str> = line.split_whitespace().collect();
    for (i, w) in words.iter().enumerate() {
        if let Some(a) = references.address(w) {
            referenced.extend(a);
            continue;
        }
        if let Some((a, rest)) = address_prefix(w, decimal) {
            addresses.push(a);
            if let Some(last) = keys.last_mut()
                && last.1.is_none()
            {
                last.1 = Some(a);
            }
            if let Some(p) = param_prefix(rest, shapes) {
                keys.push((Some(p.to_owned()), Some(a)));
            }
        } else if let Some(p) = param_prefix(w, shapes) {
            // A parameter number is a key at the start of the row, or when its address follows
            // it (two-column tables); elsewhere it is a reference in the text.
            let next_is_address = words
                .get(i + 1)
                .is_some_and(|n| address_prefix(n, decimal).is_some_and(|(_, r)| r.is_empty()));
            if p.len() == w.len() && (i <= 1 || next_is_address) {
                keys.push((Some(p.to_owned()), None));
            }
        }
    }
    if addresses.is_empty() {
        addresses = referenced;
    }
    if keys.is_empty() {
        return addresses
            .first()
            .map(|&a| vec![(None, Some(a))])
            .unwrap_or_default();
    }
    if keys.len() == 1 && keys[0].1.is_none() {
        keys[0].1 = addresses.first().copied();
    }
    let mut seen = HashSet::new();
    keys.retain(|k| seen.insert(k.clone()));
    keys
}

/// A row the manual prints as reserved or unused (OCR breaks tolerated: `Re served`,
/// `Not us sed`): nothing to map.
fn reserved(text: &str) -> bool {
    let t: String = text
        .chars()
        .filter(|c| c.is_alphanumeric())
        .flat_map(char::to_lowercase)
        .collect();
    t.contains("eserv") || t.contains("notus")
}

/// The row ends a reserved range printed over three lines (`0004H (Reserved)` / `to` / `0008H`).
fn ends_reserved_range(lines: &[String], i: usize) -> bool {
    i >= 2 && lines[i - 1].trim_start().to_lowercase().starts_with("to") && reserved(&lines[i - 2])
}

/// A parameter number compared: letters and digits, upper case, leading zeros of numbers
/// dropped (`CM.05` = `CM.5`).
fn norm_param(p: &str) -> String {
    let mut out = String::new();
    let mut in_number = false;
    for c in p.chars() {
        if !c.is_alphanumeric() {
            in_number = false;
            continue;
        }
        if c == '0' && !in_number {
            continue;
        }
        in_number = c.is_ascii_digit();
        out.extend(c.to_uppercase());
    }
    out
}

/// The lines every citation of the map points at ([`citation_places`]).
fn all_citations(map: &Map) -> HashSet<(String, usize)> {
    map.citation_places()
        .into_iter()
        .filter_map(|p| p.source.and_then(parse_citation))
        .map(|(f, l)| (f.to_owned(), l))
        .collect()
}

/// Parameter numbers a `gaps` entry names: `U1-15 .. U1-18` covers U1-15 to U1-18; any other
/// text covers the numbers it prints.
fn gap_covers_param(text: &str, param: &str) -> bool {
    let p = norm_param(param);
    let parts: Vec<&str> = text.split("..").map(str::trim).collect();
    if parts.len() == 2 {
        let split = |s: &str| {
            let n = norm_param(s);
            let digits = n.len() - n.chars().rev().take_while(|c| c.is_ascii_digit()).count();
            (n[..digits].to_owned(), n[digits..].parse::<u32>().ok())
        };
        let (pa, lo) = split(parts[0]);
        let (pb, hi) = split(parts[1]);
        let (pp, n) = split(param);
        if let (Some(lo), Some(hi), Some(n)) = (lo, hi, n)
            && pa == pb
            && pa == pp
            && (lo..=hi).contains(&n)
        {
            return true;
        }
    }
    text.split(|c: char| c.is_whitespace() || c == ',')
        .any(|w| norm_param(w) == p)
}

/// The Modicon references of a map that records them (`reference:`): a word that is one is the
/// reference column of a row, not an address of its own.
#[derive(Debug, Default)]
struct Printed {
    /// Each recorded reference, in its five- and six-digit spellings, with the register's
    /// address.
    recorded: HashMap<String, u16>,
    /// The serial side's addressing offset, when the map records any reference: another word of
    /// a reference's shape is read through it (a row the map leaves out).
    offset: Option<i32>,
}

impl Printed {
    fn of(map: &Map) -> Printed {
        let recorded: HashMap<String, u16> = map
            .registers()
            .filter_map(|r| Some((r.modicon()?, r.address())))
            .flat_map(|(m, a)| {
                let digit = drivemap_map::modicon::digit(m.table);
                let six = format!("{digit}{:05}", u32::from(m.pdu) + 1);
                [
                    (drivemap_map::modicon::Modicon::text(m.table, m.pdu), a),
                    (six, a),
                ]
            })
            .collect();
        let offset = (!recorded.is_empty()).then(|| map.address_offsets().0);
        Printed { recorded, offset }
    }

    /// Whether `word` is a reference, and the address of the map it names (if any).
    fn address(&self, word: &str) -> Option<Option<u16>> {
        if let Some(&a) = self.recorded.get(word) {
            return Some(Some(a));
        }
        let offset = self.offset?;
        let m = drivemap_map::modicon::Modicon::parse(word)?;
        Some(u16::try_from(i32::from(m.pdu) - offset).ok())
    }
}

/// What the map says that the manuals' rows are compared with.
struct Known<'a> {
    map: &'a Map,
    decimal: bool,
    /// The shapes of the map's parameter numbers.
    shapes: HashSet<String>,
    /// Row shapes per manual, from lines that verify by themselves, with how many lines have each.
    learnt: HashMap<String, BTreeMap<(Class, Class), usize>>,
    /// Every line a citation of the map points at.
    cited: HashSet<(String, usize)>,
    /// The registers' parameter numbers (normalised).
    params: HashSet<String>,
    /// The registers' addresses, alternatives included.
    addresses: HashSet<u16>,
    /// The Modicon references the registers record (`reference:`).
    references: Printed,
    /// The `removed` entries' ids (normalised).
    removed: HashSet<String>,
    /// The group citing each line, for naming tables.
    group_of_line: HashMap<(String, usize), usize>,
}

impl<'a> Known<'a> {
    fn new(map: &'a Map, manuals: &Manuals) -> Self {
        let decimal = map.address_format() == drivemap_map::facts::AddressFormat::Decimal;
        let shapes: HashSet<String> = map
            .registers()
            .flat_map(|r| r.param().into_iter().chain(r.read_param()))
            .map(shape)
            .collect();
        let learnt = learn_shapes(map, manuals, &shapes, decimal);
        // A register's group by its place in the map's groups.
        let group_index = |r: drivemap_map::RegisterRef| {
            map.groups().iter().position(|g| std::ptr::eq(g, r.group()))
        };
        Known {
            map,
            decimal,
            shapes,
            learnt,
            cited: all_citations(map),
            params: map
                .registers()
                .flat_map(|r| r.param().into_iter().chain(r.read_param()))
                .map(norm_param)
                .collect(),
            addresses: map
                .registers()
                .flat_map(|r| {
                    std::iter::once(r.address())
                        .chain(r.address_alternatives().iter().map(|a| a.address))
                })
                .collect(),
            references: Printed::of(map),
            removed: map.removed().iter().map(|r| norm_param(&r.id)).collect(),
            group_of_line: map
                .registers()
                .filter_map(|r| {
                    let (f, l) = r.source().and_then(parse_citation)?;
                    Some(((f.to_owned(), l), group_index(r)?))
                })
                .collect(),
        }
    }
}

/// Row shapes per manual, from the registers' citations that verify by themselves: the shape of
/// each cited line (unless neither word is classed), counted.
fn learn_shapes(
    map: &Map,
    manuals: &Manuals,
    shapes: &HashSet<String>,
    decimal: bool,
) -> HashMap<String, BTreeMap<(Class, Class), usize>> {
    let mut learnt: HashMap<String, BTreeMap<(Class, Class), usize>> = HashMap::new();
    for c in verify_citations(map, manuals).iter().filter(|c| {
        matches!(c.item, super::Item::Register) && matches!(c.verdict, Verdict::Verified)
    }) {
        let Some((file, n)) = parse_citation(&c.source) else {
            continue;
        };
        let Some(text) = manuals.line(file, n) else {
            continue;
        };
        let s = line_shape(text, shapes, decimal);
        if s.0 != Class::Other || s.1 != Class::Other {
            *learnt
                .entry(file.to_owned())
                .or_default()
                .entry(s)
                .or_default() += 1;
        }
    }
    learnt
}

/// Learns the row shapes from the registers' verified citations and lists the rows of each
/// cited manual (but those in `skip`: a variant map's base manuals, covered by the base's
/// report), the tables they form, and the rows nothing covers.
pub fn coverage(map: &Map, manuals: &Manuals, skip: &[String]) -> CoverageReport {
    let known = Known::new(map, manuals);
    let mut report = CoverageReport {
        drive: map.id().to_owned(),
        tables: Vec::new(),
        uncited: Vec::new(),
        missing_manuals: Vec::new(),
    };
    let mut files: Vec<&str> = map.meta().text_manuals().collect();
    files.dedup();
    for file in files.into_iter().filter(|f| !skip.iter().any(|s| s == f)) {
        match manuals.lines(file) {
            None => report.missing_manuals.push(file.to_owned()),
            Some(lines) => manual(&known, file, lines, &mut report),
        }
    }
    report
}

/// The table being read: its summary, and how many of its rows each group cites.
type Open = (TableSummary, BTreeMap<usize, usize>);

/// The tables and uncited rows of one manual (`lines` of `file`), added to `report`.
fn manual(known: &Known<'_>, file: &str, lines: &[String], report: &mut CoverageReport) {
    let Some(row_shapes) = known.learnt.get(file) else {
        return;
    };
    // A shape seen on at least two cited rows (or the only one seen).
    let keep: BTreeSet<(Class, Class)> = row_shapes
        .iter()
        .filter(|(_, n)| **n >= 2 || row_shapes.len() == 1)
        .map(|(s, _)| *s)
        .collect();
    let mut table: Option<Open> = None;
    let mut last_group: Option<usize> = None;
    for (i, text) in lines.iter().enumerate() {
        if !keep.contains(&line_shape(text, &known.shapes, known.decimal)) {
            continue;
        }
        let keys = row_keys(text, &known.shapes, known.decimal, &known.references);
        if keys.is_empty() {
            continue;
        }
        let row = Row {
            file,
            lines,
            i,
            n: i + 1,
            text,
        };
        let group_here = known.group_of_line.get(&(file.to_owned(), row.n)).copied();
        if table
            .as_ref()
            .is_some_and(|t| table_ends(t, row.n, group_here, last_group))
        {
            finish(known.map, table.take(), &mut report.tables);
        }
        let (t, groups) =
            table.get_or_insert_with(|| (TableSummary::starting(file, row.n), BTreeMap::new()));
        t.last_line = row.n;
        if let Some(g) = group_here {
            *groups.entry(g).or_default() += 1;
            last_group = Some(g);
        }
        for (param, address) in keys {
            count(known, &row, t, param, address, &mut report.uncited);
        }
    }
    finish(known.map, table.take(), &mut report.tables);
}

impl TableSummary {
    /// A table whose first row is line `n` of `file`, nothing counted yet.
    fn starting(file: &str, n: usize) -> Self {
        TableSummary {
            file: file.to_owned(),
            first_line: n,
            last_line: n,
            group: None,
            rows: 0,
            cited: 0,
            gaps: 0,
            uncited: 0,
        }
    }
}

/// A table ends after a dozen lines without rows, or where the rows start being another
/// group's (the row at line `n` cited by `group_here`, the last cited row by `last_group`).
fn table_ends(
    (t, groups): &Open,
    n: usize,
    group_here: Option<usize>,
    last_group: Option<usize>,
) -> bool {
    n > t.last_line + 12
        || group_here
            .is_some_and(|g| last_group.is_some_and(|l| l != g) && !groups.contains_key(&g))
}

/// Closes a table: named after the group citing most of its rows (the first such group on a
/// tie), and added to `out`.
fn finish(map: &Map, table: Option<Open>, out: &mut Vec<TableSummary>) {
    if let Some((mut t, groups)) = table {
        t.group = groups
            .iter()
            .max_by_key(|(g, n)| (**n, std::cmp::Reverse(**g)))
            .and_then(|(g, _)| map.groups().get(*g))
            .map(|g| g.name.clone());
        out.push(t);
    }
}

/// A row of a manual table: line `n` (index `i` of `lines`) of `file`.
struct Row<'r> {
    file: &'r str,
    lines: &'r [String],
    i: usize,
    n: usize,
    text: &'r str,
}

/// Counts one key of `row` into table `t`: cited by a register, a gap, or uncited (then listed
/// in `uncited`).
fn count(
    known: &Known<'_>,
    row: &Row<'_>,
    t: &mut TableSummary,
    param: Option<String>,
    address: Option<u16>,
    uncited: &mut Vec<UncitedRow>,
) {
    t.rows += 1;
    let by_register = match &param {
        Some(p) => known.params.contains(&norm_param(p)),
        None => address.is_some_and(|a| known.addresses.contains(&a)),
    };
    let key = (param.as_deref(), address);
    if by_register {
        t.cited += 1;
    } else if GAPS.iter().any(|gap| gap(known, row, key)) {
        t.gaps += 1;
    } else {
        t.uncited += 1;
        uncited.push(UncitedRow {
            file: row.file.to_owned(),
            line: row.n,
            // An address in the map's notation: `45` in a decimal-numbered map.
            key: param.unwrap_or_else(|| {
                address
                    .map(|a| drivemap_map::describe::address_as(known.map.address_format(), a))
                    .unwrap_or_default()
            }),
            text: super::quote_text(row.text),
        });
    }
}

/// A row key: its parameter number and address, either may be absent.
type Key<'k> = (Option<&'k str>, Option<u16>);

/// One reason a key no register has is nonetheless covered (counted as a gap).
type Gap = fn(&Known<'_>, &Row<'_>, Key<'_>) -> bool;

/// The reasons a key no register has is covered.
const GAPS: &[Gap] = &[
    gaps_entry,
    removed_param,
    removed_citation,
    line_cited,
    printed_reserved,
];

/// A `gaps` entry covers the address or names the parameter.
fn gaps_entry(known: &Known<'_>, _: &Row<'_>, (param, address): Key<'_>) -> bool {
    known.map.gaps().iter().any(|g| {
        address.is_some_and(|a| g.addresses.is_some_and(|[lo, hi]| (lo..=hi).contains(&a)))
            || param.is_some_and(|p| g.params.as_deref().is_some_and(|t| gap_covers_param(t, p)))
    })
}

/// A `removed` entry names the parameter.
fn removed_param(known: &Known<'_>, _: &Row<'_>, (param, _): Key<'_>) -> bool {
    param.is_some_and(|p| known.removed.contains(&norm_param(p)))
}

/// A removed register's citation is on the row (which may span the lines around the address).
fn removed_citation(known: &Known<'_>, row: &Row<'_>, _: Key<'_>) -> bool {
    known.map.removed().iter().any(|r| {
        parse_citation(&r.source)
            .is_some_and(|(f, l)| f == row.file && l + 1 >= row.n && l <= row.n + 1)
    })
}

/// A citation of the map (a conflict, a note...) points at the line.
fn line_cited(known: &Known<'_>, row: &Row<'_>, _: Key<'_>) -> bool {
    known.cited.contains(&(row.file.to_owned(), row.n))
}

/// The manual prints the row, or the range it ends, as reserved or unused.
fn printed_reserved(_: &Known<'_>, row: &Row<'_>, _: Key<'_>) -> bool {
    reserved(row.text) || ends_reserved_range(row.lines, row.i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_and_keys() {
        assert_eq!(shape("Bn-01"), "Aa-9");
        assert_eq!(shape("n001"), "a9");
        assert_eq!(shape("UF.8"), "A.9");
        let shapes: HashSet<String> = ["Aa-9", "A9-9", "A.9", "a9"].map(String::from).into();
        assert_eq!(address_prefix("0200H", false), Some((0x0200, "")));
        assert_eq!(
            address_prefix("31AhE4-03Motor", false),
            Some((0x031A, "E4-03Motor"))
        );
        assert_eq!(address_prefix("1EOA", false), Some((0x1E0A, "")));
        assert_eq!(address_prefix("6000", false), Some((0x6000, "")));
        assert_eq!(address_prefix("Motor", false), None);
        // A decimal manual's register number; in a hex manual, digits alone are not one.
        assert_eq!(address_prefix("45", true), Some((45, "")));
        assert_eq!(address_prefix("45", false), None);
        assert_eq!(address_prefix("2.", true), None);
        assert_eq!(
            classify("31AhE4-03Motor", &shapes, false),
            Class::AddressParam
        );
        assert_eq!(classify("Bn-01", &shapes, false), Class::Param);
        assert_eq!(
            row_keys(
                "UF.8 1E08 47688 47689 UF.53 1E35 47733 47734",
                &shapes,
                false,
                &Printed::default()
            ),
            vec![
                (Some("UF.8".to_owned()), Some(0x1E08)),
                (Some("UF.53".to_owned()), Some(0x1E35))
            ]
        );
        assert_eq!(
            row_keys(
                "0200H\tBn-01\tAcceleration time 1",
                &shapes,
                false,
                &Printed::default()
            ),
            vec![(Some("Bn-01".to_owned()), Some(0x0200))]
        );
        assert_eq!(
            row_keys("0020H\tStatus", &shapes, false, &Printed::default()),
            vec![(None, Some(0x0020))]
        );
        assert!(gap_covers_param("U1-15 .. U1-18", "U1-16"));
        assert!(!gap_covers_param("U1-15 .. U1-18", "U1-19"));
        assert!(gap_covers_param("n150, n160", "n160"));
        assert_eq!(norm_param("CM.05"), norm_param("CM.5"));
        assert_ne!(norm_param("E4-03"), norm_param("E40-3"));
        assert!(reserved("0025H | Not us | sed"));
    }
}
