//! The draft map: rows and protocol facts written as YAML, every item citing its line.
//!
//! The draft is marked `draft:` with the list of what the reviewer must confirm (protocol facts
//! the manual did not print where the reader looked, written as placeholders so that the file
//! loads); `check` accepts it as a draft and the generator refuses it until a reviewer removes
//! the mark.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use crate::Reading;
use crate::protocol::Protocol;
use crate::row::{Notation, Row};

/// The function codes drivemap speaks (a draft lists only these; others are reported).
const SPOKEN: &[u8] = &[0x03, 0x04, 0x06, 0x08, 0x10];

/// What the draft is made of.
pub struct DraftInput<'a> {
    /// The drive id of the draft.
    pub id: &'a str,
    /// Rows left out (by manual file and line), with why: the rows the front end refused.
    pub left_out: &'a BTreeMap<(String, usize), String>,
    /// What was read from each manual.
    pub readings: &'a [(Reading, Protocol)],
    /// The command line that made it, recorded in the file's header.
    pub command: &'a str,
}

/// A YAML double-quoted string.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A snake_case identifier from printed text (`Accel / Decel Time 1` → `accel_decel_time_1`).
pub fn ident(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('_') && !out.is_empty() {
            out.push('_');
        }
    }
    let out = out.trim_end_matches('_').to_string();
    let out: String = out.chars().take(60).collect();
    let out = out.trim_end_matches('_').to_string();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        format!("r_{out}")
    } else {
        out
    }
}

fn unique(base: String, taken: &mut BTreeSet<String>) -> String {
    let mut id = base.clone();
    let mut n = 2;
    while !taken.insert(id.clone()) {
        id = format!("{base}_{n}");
        n += 1;
    }
    id
}

fn num(v: f64) -> String {
    let s = format!("{v}");
    if s.contains('e') {
        format!("{v:.6}")
    } else {
        s
    }
}

/// The prefix of a parameter number that names its table (`Cn-44` → `Cn`, `b1-01` → `b`).
fn table_prefix(row: &Row) -> String {
    match &row.param {
        Some(p) => p.chars().take_while(|c| c.is_ascii_alphabetic()).collect(),
        None => String::from("registers"),
    }
}

/// Rows split into tables: a new table where the parameter prefix changes or rows stop for a
/// while.
fn tables<'r>(rows: &[&'r Row]) -> Vec<Vec<&'r Row>> {
    let mut out: Vec<Vec<&Row>> = Vec::new();
    for r in rows {
        let same = out.last().and_then(|t| t.last()).is_some_and(|last| {
            table_prefix(last) == table_prefix(r)
                && r.line <= last.line + 60
                && last.table == r.table
        });
        if same {
            out.last_mut().expect("a table").push(r);
        } else {
            out.push(vec![r]);
        }
    }
    out
}

/// What [`write()`] wrote.
pub struct Written {
    /// The draft map.
    pub yaml: String,
    /// What the reviewer must confirm (also under `draft.to_confirm`).
    pub to_confirm: Vec<String>,
    /// Each register's id with the manual file and line of its row.
    pub registers: Vec<(String, String, usize)>,
}

/// Writes the draft.
pub fn write(input: &DraftInput<'_>) -> Written {
    let mut registers = Vec::new();
    let mut to_confirm = Vec::new();
    let mut y = String::new();
    let _ = writeln!(y, "# A DRAFT made by `{}`.", input.command);
    let _ = writeln!(
        y,
        "# Every register cites the manual line it was read from; a field the line does not show is\n\
         # left out. Review every row against the manual (`drivemap coverage` lists the rows no\n\
         # register cites), then delete `draft:`: the generator refuses a draft."
    );
    let _ = writeln!(y, "schema: 2");
    let decimal = input
        .readings
        .iter()
        .flat_map(|(r, _)| &r.rows)
        .filter(|r| r.notation == Notation::Decimal)
        .count()
        * 2
        > input
            .readings
            .iter()
            .map(|(r, _)| r.rows.len())
            .sum::<usize>();
    if decimal {
        let _ = writeln!(y, "address_format: decimal");
    }
    let mut body = String::new();
    let _ = writeln!(body, "drive:");
    let _ = writeln!(body, "  id: {}", input.id);
    let _ = writeln!(
        body,
        "  vendor: {}  # not read from the manual",
        quote("to be confirmed")
    );
    to_confirm.push("drive.vendor: not read from the manual".to_string());
    let _ = writeln!(body, "  models: [{}]", quote(input.id));
    to_confirm.push("drive.models: not read from the manual (the drive id is written)".to_string());
    let _ = writeln!(body, "  manuals:");
    for (reading, _) in input.readings {
        let _ = writeln!(
            body,
            "    - {{file: {}, title: {}}}",
            quote(&reading.file),
            quote(&reading.title)
        );
    }
    to_confirm.push("drive.manuals[].title: the first line of text of each manual".to_string());
    write_protocol(&mut body, input, &mut to_confirm);
    let _ = writeln!(body, "groups:");
    let mut taken_ids = BTreeSet::new();
    let mut taken_groups = BTreeSet::new();
    for (reading, _) in input.readings {
        let rows: Vec<&Row> = reading
            .rows
            .iter()
            .filter(|r| !r.reserved && r.address.is_some())
            .filter(|r| !input.left_out.contains_key(&(reading.file.clone(), r.line)))
            .collect();
        for table in tables(&rows) {
            let first = table[0];
            let prefix = table_prefix(first);
            let gid = unique(
                match &first.table {
                    Some((_, heading)) => ident(heading),
                    None => ident(&format!("{prefix}_{}", first.line)),
                },
                &mut taken_groups,
            );
            let _ = writeln!(body, "  - id: {gid}");
            let name = match &first.param {
                Some(_) => format!(
                    "{prefix} rows of lines {}-{}",
                    first.line,
                    table[table.len() - 1].line
                ),
                None => format!(
                    "Registers of lines {}-{}",
                    first.line,
                    table[table.len() - 1].line
                ),
            };
            match &first.table {
                // The table's heading names the group, and is cited.
                Some((line, heading)) => {
                    let _ = writeln!(body, "    name: {}", quote(heading));
                    let _ = writeln!(body, "    table: {}", quote(heading));
                    let _ = writeln!(
                        body,
                        "    source: {}",
                        quote(&format!("{}:{line}", reading.file))
                    );
                }
                None => {
                    let _ = writeln!(body, "    name: {}", quote(&name));
                    let _ = writeln!(
                        body,
                        "    source: {}",
                        quote(&format!("{}:{}", reading.file, first.line))
                    );
                }
            }
            let _ = writeln!(body, "    registers:");
            for r in table {
                let id = write_register(&mut body, &reading.file, r, &mut taken_ids);
                if r.access.is_none() {
                    to_confirm.push(format!(
                        "{id}.access: unknown ({}:{} prints no access; read-only until a reviewer writes it)",
                        reading.file, r.line
                    ));
                }
                registers.push((id, reading.file.clone(), r.line));
            }
        }
    }
    let _ = writeln!(y, "draft:");
    let _ = writeln!(y, "  by: {}", quote("drivemap import"));
    if !to_confirm.is_empty() {
        let _ = writeln!(y, "  to_confirm:");
        for c in &to_confirm {
            let _ = writeln!(y, "    - {}", quote(c));
        }
    }
    y.push_str(&body);
    Written {
        yaml: y,
        to_confirm,
        registers,
    }
}

fn write_protocol(y: &mut String, input: &DraftInput<'_>, to_confirm: &mut Vec<String>) {
    let _ = writeln!(y, "protocol:");
    // The first manual that prints a fact is cited for it.
    let find = |f: &dyn Fn(&Protocol) -> bool| input.readings.iter().find(|(_, p)| f(p));
    let mut transports: BTreeMap<&str, String> = BTreeMap::new();
    for (r, p) in input.readings {
        for (t, line) in &p.transports {
            transports
                .entry(t)
                .or_insert_with(|| format!("{}:{line}", r.file));
        }
    }
    if transports.is_empty() {
        let _ = writeln!(
            y,
            "  transports: [rtu]  # placeholder: no transport named where the reader looked"
        );
        to_confirm.push("protocol.transports: not found; rtu written as a placeholder".into());
    } else {
        let names: Vec<&str> = transports.keys().copied().collect();
        let cites: Vec<&str> = transports.values().map(String::as_str).collect();
        let _ = writeln!(
            y,
            "  transports: [{}]  # {}",
            names.join(", "),
            cites.join(", ")
        );
    }
    match find(&|p| p.function_codes.keys().any(|c| SPOKEN.contains(c))) {
        Some((r, p)) => {
            let spoken: BTreeMap<u8, usize> = p
                .function_codes
                .iter()
                .filter(|(c, _)| SPOKEN.contains(c))
                .map(|(c, l)| (*c, *l))
                .collect();
            for (c, line) in p.function_codes.iter().filter(|(c, _)| !SPOKEN.contains(c)) {
                to_confirm.push(format!(
                    "protocol.function_codes: the manual names function {c:02X}h ({}:{line}), which drivemap does not speak; left out",
                    r.file
                ));
            }
            let codes: Vec<String> = spoken.keys().map(|c| format!("0x{c:02X}")).collect();
            let lines: BTreeSet<usize> = spoken.values().copied().collect();
            let first = lines.iter().next().copied().unwrap_or(1);
            let _ = writeln!(
                y,
                "  function_codes: {{codes: [{}], source: {}}}",
                codes.join(", "),
                quote(&format!("{}:{first}", r.file))
            );
            if lines.len() > 1 {
                let _ = writeln!(
                    y,
                    "  # function codes read from lines {}",
                    lines
                        .iter()
                        .map(usize::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
        }
        None => {
            let _ = writeln!(y, "  function_codes: [0x03, 0x06, 0x10]  # placeholder");
            to_confirm.push(
                "protocol.function_codes: not found; 03h/06h/10h written as placeholders".into(),
            );
        }
    }
    for (key, get, limit) in [
        (
            "max_read",
            (|p: &Protocol| p.max_read.clone()) as fn(&Protocol) -> _,
            125,
        ),
        ("max_write", |p: &Protocol| p.max_write.clone(), 123),
    ] {
        match input
            .readings
            .iter()
            .find_map(|(r, p)| get(p).map(|c| (r, c)))
        {
            Some((r, c)) => {
                let _ = writeln!(
                    y,
                    "  {key}: {{value: {}, source: {}}}",
                    c.value,
                    quote(&format!("{}:{}", r.file, c.line))
                );
            }
            None => {
                let _ = writeln!(y, "  {key}: {limit}  # placeholder: the Modbus limit");
                to_confirm.push(format!(
                    "protocol.{key}: not found; the Modbus limit {limit} written as a placeholder"
                ));
            }
        }
    }
    match input
        .readings
        .iter()
        .find_map(|(r, p)| p.slave_range.clone().map(|c| (r, c)))
    {
        Some((r, c)) => {
            let _ = writeln!(
                y,
                "  slave_address: {{min: {}, max: {}, source: {}}}",
                c.value.0,
                c.value.1,
                quote(&format!("{}:{}", r.file, c.line))
            );
        }
        None => {
            let _ = writeln!(
                y,
                "  slave_address: {{min: 1, max: 247}}  # placeholder: the Modbus range"
            );
            to_confirm.push("protocol.slave_address: not found; the Modbus range 1-247 written as a placeholder".into());
        }
    }
    if let Some((r, p)) = find(&|p| p.format.is_some())
        && let Some(f) = &p.format
    {
        // The schema takes serial settings whole: with the baud rates, or not at all.
        match &p.bauds {
            Some(b) => {
                let rates: Vec<String> = b.value.0.iter().map(u32::to_string).collect();
                let default = b
                    .value
                    .1
                    .map(|d| format!(" default_baud: {d},"))
                    .unwrap_or_default();
                let _ = writeln!(
                    y,
                    "  serial: {{baud_rates: [{rates}],{default} parities: [{parity}], default_parity: {parity}, data_bits: {data}, stop_bits: {stop}, source: {source}}}  # baud rates: line {line}",
                    rates = rates.join(", "),
                    parity = f.value.parity,
                    data = f.value.data_bits,
                    stop = f.value.stop_bits,
                    source = quote(&format!("{}:{}", r.file, f.line)),
                    line = b.line
                );
            }
            None => to_confirm.push(format!(
                "protocol.serial: the character format is printed ({}:{}: {} data bits, parity {}, {} stop bit(s)) but no baud rate was read; not written",
                r.file, f.line, f.value.data_bits, f.value.parity, f.value.stop_bits
            )),
        }
    }
    if let Some((r, p)) = find(&|p| p.broadcast.is_some())
        && let Some(line) = p.broadcast
    {
        // The rules (which functions, which registers) are not read: the runtime refuses every
        // broadcast until a reviewer writes them.
        let _ = writeln!(
            y,
            "  broadcast: {{unknown: {}, source: {}}}",
            quote(
                "the manual names a broadcast; its functions and registers are to be read by the reviewer"
            ),
            quote(&format!("{}:{line}", r.file))
        );
        to_confirm.push(format!(
            "protocol.broadcast: the manual names one ({}:{line}); its functions and registers are not read",
            r.file
        ));
    }
    if let Some((r, p)) = find(&|p| !p.exceptions.is_empty()) {
        let _ = writeln!(y, "  exceptions:");
        for e in &p.exceptions {
            let _ = writeln!(
                y,
                "    - {{code: 0x{:02X}, name: {}, description: {}, source: {}}}",
                e.code,
                quote(&e.name),
                quote(e.description.as_deref().unwrap_or(&e.name)),
                quote(&format!("{}:{}", r.file, e.line))
            );
        }
    } else {
        to_confirm.push("protocol.exceptions: no exception table found".into());
    }
}

/// Writes one row as a register of a group (indented for `registers:`); returns its id.
pub fn write_register(y: &mut String, file: &str, r: &Row, taken: &mut BTreeSet<String>) -> String {
    let base = if r.name.chars().any(char::is_alphabetic) {
        ident(&r.name)
    } else {
        ident(r.param.as_deref().unwrap_or("register"))
    };
    let id = unique(base, taken);
    let _ = writeln!(y, "      - id: {id}");
    if let Some(p) = &r.param {
        let _ = writeln!(y, "        param: {}", quote(p));
    }
    let _ = writeln!(y, "        name: {}", quote(&r.name));
    let address = r.address.unwrap_or_default();
    match r.notation {
        Notation::Hex => {
            let _ = writeln!(y, "        address: 0x{address:04X}");
        }
        Notation::Decimal => {
            let _ = writeln!(y, "        address: {address}");
        }
    }
    if let Some(a) = r.access {
        let _ = writeln!(y, "        access: {a}");
    }
    if let Some(u) = &r.unit {
        let _ = writeln!(y, "        unit: {}", quote(u));
    }
    if let Some(s) = r.scale {
        let _ = writeln!(y, "        scale: {}", num(s));
    }
    if let Some(p) = r.pair {
        let _ = writeln!(
            y,
            "        pair: {{order: {}}}  # the other word's row: line {}",
            if p.high_first {
                "high_first"
            } else {
                "low_first"
            },
            p.other_line
        );
    }
    if r.signed == Some(true) || r.min.is_some_and(|m| m < 0.0) || r.max.is_some_and(|m| m < 0.0) {
        let _ = writeln!(y, "        signed: true");
    }
    if let Some(m) = r.min {
        let _ = writeln!(y, "        min: {}", num(m));
    }
    if let Some(m) = r.max {
        let _ = writeln!(y, "        max: {}", num(m));
    }
    if let Some(d) = r.default {
        let _ = writeln!(y, "        default: {}", num(d));
    }
    let codes: Vec<_> = r
        .values
        .iter()
        .filter(|c| (0..=i64::from(u16::MAX)).contains(&c.value))
        .collect();
    if !codes.is_empty() {
        let _ = writeln!(y, "        values:");
        let mut taken_codes = BTreeSet::new();
        for c in codes {
            let cid = unique(ident(&c.name), &mut taken_codes);
            let _ = writeln!(
                y,
                "          - {{value: {}, id: {cid}, name: {}, source: {}}}",
                c.value,
                quote(&c.name),
                quote(&format!("{file}:{}", c.line))
            );
        }
    }
    if !r.fields.is_empty() {
        let _ = writeln!(y, "        fields:");
        let mut taken_fields = BTreeSet::new();
        for f in &r.fields {
            let fid = unique(ident(&f.name), &mut taken_fields);
            let bits = if f.first == f.last {
                format!("bit: {}", f.first)
            } else {
                format!("bits: [{}, {}]", f.first, f.last)
            };
            let _ = writeln!(
                y,
                "          - {{id: {fid}, name: {}, {bits}, source: {}}}",
                quote(&f.name),
                quote(&format!("{file}:{}", f.line))
            );
        }
    }
    if !r.notes.is_empty() {
        let _ = writeln!(y, "        notes:");
        for n in &r.notes {
            let _ = writeln!(y, "          - {}", quote(&format!("import: {n}")));
        }
    }
    let _ = writeln!(
        y,
        "        source: {}",
        quote(&format!("{file}:{}", r.line))
    );
    id
}
