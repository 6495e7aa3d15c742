//! Citations outside the registers, checked by content like register citations: roles, every
//! protocol item, the readings of conflicts (of the map and of registers) and gaps. What a line
//! must mention for each kind is listed in `maps/README.md` ("Citations checked by content"),
//! and [`Rule`] says it once in code. The same `indirect: <reason>` escape applies; a
//! protocol limit or function-code list marked `unknown` (not printed) is indirect by nature.
//! As for values and fields, the line just after or before counts as the row when the cited line
//! does not mention the item alone (a statement broken over two OCR lines).

use std::collections::HashSet;

use crate::citations::{CitationPlace, PlaceKind, Reason, citation_places};
use crate::ir::Drive;
use crate::model::{self, RolePlace};
use crate::source::Path;

/// What one citation outside the registers must mention.
#[derive(Debug, Clone)]
pub enum Rule {
    /// A role at a register: read as that register's own citation (address, parameter number,
    /// name; not another register's row). The index is into `Map::registers`.
    Register(usize),
    /// A role at a field: the field's bit or name, one of the role's codes with its label, or
    /// the field's register (its address, parameter number or name).
    Field {
        /// The register (an index into `Map::registers`).
        register: usize,
        /// The field (an index into the register's `fields`).
        field: usize,
        /// The role's codes (`on`, `off`) as numbers.
        codes: Vec<u16>,
    },
    /// Any of these words (lower case), parameter numbers, numbers, or addresses.
    Any {
        /// Words (lower case).
        words: Vec<String>,
        /// Parameter numbers as printed.
        params: Vec<String>,
        /// Numbers as written (`3.5`, `100000`).
        numbers: Vec<String>,
        /// Codes, as numbers.
        codes: Vec<u16>,
        /// Communication addresses, in any notation the manual uses.
        addresses: Vec<u16>,
        /// Names of which two words (or all, for a shorter name) must be printed.
        names: Vec<String>,
        /// Registers (indices into `Map::registers`) whose address or parameter number
        /// counts: a reading of a register's own conflict may cite the register's row.
        registers: Vec<usize>,
    },
}

impl Rule {
    fn any() -> Rule {
        Rule::Any {
            words: Vec::new(),
            params: Vec::new(),
            numbers: Vec::new(),
            codes: Vec::new(),
            addresses: Vec::new(),
            names: Vec::new(),
            registers: Vec::new(),
        }
    }

    fn register(mut self, i: usize) -> Rule {
        if let Rule::Any { registers, .. } = &mut self {
            registers.push(i);
        }
        self
    }

    fn words(mut self, list: &[&str]) -> Rule {
        if let Rule::Any { words, .. } = &mut self {
            words.extend(list.iter().map(|w| w.to_string()));
        }
        self
    }

    fn param(mut self, p: Option<&str>) -> Rule {
        if let (Rule::Any { params, .. }, Some(p)) = (&mut self, p) {
            params.push(p.to_owned());
        }
        self
    }

    fn number(mut self, n: impl ToString) -> Rule {
        if let Rule::Any { numbers, .. } = &mut self {
            numbers.push(n.to_string());
        }
        self
    }

    fn code(mut self, c: u16) -> Rule {
        if let Rule::Any { codes, .. } = &mut self {
            codes.push(c);
        }
        self
    }

    fn address(mut self, a: u16) -> Rule {
        if let Rule::Any { addresses, .. } = &mut self {
            addresses.push(a);
        }
        self
    }

    fn name(mut self, n: &str) -> Rule {
        if let Rule::Any { names, .. } = &mut self
            && !n.trim().is_empty()
        {
            names.push(n.to_owned());
        }
        self
    }

    /// What the line is expected to show, for messages.
    pub(crate) fn expected(&self, drive: &Drive) -> String {
        match self {
            Rule::Register(i) => {
                let r = &drive.registers[*i].def;
                let mut e: Vec<String> = r.param.iter().cloned().collect();
                e.push(crate::describe::address_as(drive.address_format, r.address));
                e.extend(r.reference.iter().cloned());
                e.push(format!("\"{}\"", r.name));
                format!("register {}", e.join(", "))
            }
            Rule::Field {
                register, field, ..
            } => {
                let r = &drive.registers[*register].def;
                let f = &r.fields[*field];
                format!(
                    "field \"{}\" ({}) of {}",
                    f.name,
                    crate::describe::bits(f),
                    r.param.clone().unwrap_or_else(|| r.id.clone())
                )
            }
            Rule::Any {
                words,
                params,
                numbers,
                codes,
                addresses,
                names,
                registers,
            } => {
                let mut e: Vec<String> = Vec::new();
                for i in registers {
                    let r = &drive.registers[*i].def;
                    e.extend(r.param.iter().cloned());
                    e.push(crate::describe::address_as(drive.address_format, r.address));
                    e.extend(r.reference.iter().cloned());
                }
                e.extend(names.iter().map(|n| format!("\"{n}\"")));
                e.extend(params.iter().cloned());
                e.extend(
                    addresses
                        .iter()
                        .map(|a| crate::describe::address_as(drive.address_format, *a)),
                );
                e.extend(codes.iter().map(|c| format!("{c:02X}h")));
                e.extend(numbers.iter().cloned());
                e.extend(words.iter().map(|w| format!("`{w}`")));
                format!("one of {}", e.join(", "))
            }
        }
    }
}

/// One citation outside the registers.
#[derive(Debug, Clone)]
pub struct Other {
    /// Where its `source` is written.
    pub path: Path,
    /// What it is the citation of (`role run`, `protocol slave_address`, `conflict "Range"`,
    /// `gap 0024h – 002Fh`).
    pub what: String,
    /// The kind, for counts: `role`, `protocol`, `conflict`, `gap`.
    pub kind: &'static str,
    /// `file:line`; `None` for an item that carries `indirect` but no citation (an error of
    /// validation).
    pub source: Option<String>,
    /// Why the citation is deliberately indirect, if it is.
    pub indirect: Option<String>,
    /// Whether the reason is an `indirect` key (validated: it needs a reason and a citation),
    /// rather than a limit's `unknown`.
    pub indirect_key: bool,
    /// What its line must show.
    pub rule: Rule,
}

/// What a line citing the protocol as a whole mentions: its protocol, framing or line, not only
/// the word Modbus (which a manual's title prints).
const PROTOCOL_WORDS: &[&str] = &[
    "protocol",
    "protocols",
    "specification",
    "specifications",
    "rtu",
    "tcp",
    "rs485",
    "485",
    "memobus",
];
const TIMING_WORDS: &[&str] = &[
    "time",
    "timing",
    "interval",
    "gap",
    "silent",
    "silence",
    "delay",
    "wait",
    "timeout",
    "ms",
    "msec",
    "character",
    "characters",
    "response",
    "respond",
    "responds",
];

/// Every citation of roles, the protocol, conflicts and gaps (then limits through another
/// quantity and register function-code lists), with what its line must mention: the places of
/// [`citation_places`] outside the registers' own rows, values and fields, each read by
/// `rule_of`, in that order of kinds.
pub(crate) fn other_citations(drive: &Drive) -> Vec<Other> {
    let mut out: Vec<(u8, Other)> = Vec::new();
    let mut functions_seen = HashSet::new();
    for place in citation_places(drive) {
        if place.kind == PlaceKind::RegisterFunctions && !functions_seen.insert(place.path.clone())
        {
            // A group's list, read once.
            continue;
        }
        let Some((rank, kind, what, rule)) = rule_of(drive, &place) else {
            continue;
        };
        let source = match place.kind {
            // An empty `serial.source` is no citation (validation says so).
            PlaceKind::Serial => place.source.filter(|s| !s.is_empty()),
            _ => place.source,
        };
        let indirect = place.reason.text();
        let listed = match place.kind {
            // A list or limit is read where it is cited.
            PlaceKind::FunctionCodes | PlaceKind::Limit(_) => source.is_some(),
            _ => source.is_some() || indirect.is_some(),
        };
        if listed {
            out.push((
                rank,
                Other {
                    path: place.path.clone(),
                    what,
                    kind,
                    source: source.map(str::to_owned),
                    indirect: indirect.map(str::to_owned),
                    indirect_key: matches!(place.reason, Reason::Indirect(_)),
                    rule,
                },
            ));
        }
    }
    // Roles, the protocol, conflicts, gaps, limits, function codes (stable: each kind in map
    // order).
    out.sort_by_key(|(rank, _)| *rank);
    out.into_iter().map(|(_, o)| o).collect()
}

/// What a place outside the registers' own rows, values and fields is, for review: its rank in
/// [`other_citations`], its kind (`role`, `protocol`, `conflict`, `gap`, `limit`, `functions`),
/// what it cites and what its line must mention. `None` for the places review reads otherwise
/// (registers, values, fields) or not by content (variant options, groups, removed registers,
/// pairs, indexed entries, example frames, an exception list the manual does not print).
fn rule_of(drive: &Drive, place: &CitationPlace<'_>) -> Option<(u8, &'static str, String, Rule)> {
    let register = || place.register.map(|i| &drive.registers[i]);
    match place.kind {
        PlaceKind::Role { role, index } => {
            let rule = role_rule(drive, role, index)?;
            Some((0, "role", format!("role `{role}`"), rule))
        }
        PlaceKind::Protocol
        | PlaceKind::SlaveAddress
        | PlaceKind::Broadcast
        | PlaceKind::Exception(_)
        | PlaceKind::Command(_)
        | PlaceKind::Eeprom
        | PlaceKind::Addressing
        | PlaceKind::Timing
        | PlaceKind::TimingInterval(_)
        | PlaceKind::Serial
        | PlaceKind::SerialFormats
        | PlaceKind::SerialFormatCase(_)
        | PlaceKind::FunctionCodes
        | PlaceKind::Limit(_) => {
            let (what, rule) = protocol_rule(drive, place.kind)?;
            Some((1, "protocol", what, rule))
        }
        PlaceKind::ConflictReading { conflict, reading } => {
            // A reading of a register's own conflict may also cite the register's row.
            let list = match register() {
                Some(r) => &r.def.conflicts,
                None => &drive.conflicts,
            };
            let c = &list[conflict];
            let mut rule = reading_rule(&c.readings[reading].says);
            if let Some(i) = place.register {
                rule = rule.register(i);
            }
            let what = format!("a reading of conflict \"{}\"", c.topic);
            Some((2, "conflict", what, rule))
        }
        PlaceKind::Gap(i) => {
            let (what, rule) = gap_rule(&drive.gaps[i]);
            Some((3, "gap", what, rule))
        }
        PlaceKind::RelativeLimit => {
            let (what, rule) = limit_rule(drive, register()?)?;
            Some((4, "limit", what, rule))
        }
        PlaceKind::RegisterFunctions => {
            let r = register()?;
            let (f, _) = r.function_codes.as_ref()?;
            let mut rule = Rule::any()
                .name("function code")
                .name("function codes")
                .words(&["function"]);
            for c in &f.codes {
                rule = rule.code(u16::from(*c));
            }
            let what = format!("the function codes of {}", r.id());
            Some((5, "functions", what, rule))
        }
        PlaceKind::Profile { part, id } => {
            // A state or transition is printed by its name (or a transition by its word); the
            // profile's own line is not read by content.
            let name = id.replace('_', " ");
            let rule = match part {
                "state" | "power on" => Rule::any().name(&name),
                "transition" => {
                    let word = drive
                        .profile
                        .as_ref()
                        .map(crate::command_profile::resolve)
                        .and_then(|p| p.transitions.get(id).and_then(|t| t.word));
                    let rule = Rule::any().name(&name);
                    match word {
                        Some(w) => rule.code(w.0),
                        None => rule,
                    }
                }
                _ => return None,
            };
            Some((6, "profile", format!("profile {part} `{id}`"), rule))
        }
        PlaceKind::ExceptionsUnknown
        | PlaceKind::VariantOption { .. }
        | PlaceKind::Group(_)
        | PlaceKind::Removed(_)
        | PlaceKind::Register
        | PlaceKind::Value(_)
        | PlaceKind::ReadValue(_)
        | PlaceKind::Field(_)
        | PlaceKind::FieldValue { .. }
        | PlaceKind::Pair
        | PlaceKind::Text
        | PlaceKind::RepeatNeedsChange
        | PlaceKind::ByVariant(_)
        | PlaceKind::AddressAlternative(_)
        | PlaceKind::ScaleCase(_)
        | PlaceKind::Indexed
        | PlaceKind::IndexedEntry(_)
        | PlaceKind::Example(_) => None,
    }
}

/// What the line of a protocol item may print besides the item's own figures, by kind of place
/// ([`PlaceKind::name`]): how the item is named (an empty name: worded from the item), words,
/// names. [`protocol_rule`] adds the figures (a parameter number, codes, numbers).
#[rustfmt::skip]
const PROTOCOL_SAYS: &[(&str, &str, &[&str], &[&str])] = &[
    ("protocol", "the protocol", PROTOCOL_WORDS, &["function code"]),
    ("slave address", "the slave address", &["address", "addresses", "station", "slave", "node"], &[]),
    ("broadcast", "the broadcast", &["broadcast", "broadcasting"],
        &["all slaves", "all stations", "all drives", "all inverters", "slave address 0", "station 0"]),
    ("exception", "", &[], &[]),
    ("command", "", &[], &[]),
    ("eeprom", "the EEPROM endurance", &["eeprom", "nonvolatile", "volatile", "memory"], &[]),
    ("addressing", "the addressing", &["address", "addresses", "addressing", "register", "registers"], &[]),
    ("timing", "the timing", TIMING_WORDS, &[]),
    ("timing interval", "", TIMING_WORDS, &[]),
    ("serial", "the serial line", &["baud", "bps", "parity", "speed", "transmission", "stop", "data"], &[]),
    ("serial formats", "the serial formats", PARITY_WORDS, &[]),
    ("serial format case", "", PARITY_WORDS, &[]),
    // A list or limit the manual does not print is cited where its working value comes from:
    // indirect by nature, with `unknown` as the reason.
    ("function codes", "the function codes", &[], &["function code", "function codes"]),
    ("limit", "", &["quantity", "registers", "words"], &[]),
];

/// A protocol item's name and rule: its row of [`PROTOCOL_SAYS`] with the item's figures.
fn protocol_rule(drive: &Drive, kind: PlaceKind<'_>) -> Option<(String, Rule)> {
    let p = &drive.protocol;
    let (_, what, words, names) = PROTOCOL_SAYS.iter().find(|row| row.0 == kind.name())?;
    let mut what = what.to_string();
    let mut rule = Rule::any().words(words);
    for n in *names {
        rule = rule.name(n);
    }
    match kind {
        PlaceKind::SlaveAddress => rule = rule.param(p.slave_address.param.as_deref()),
        PlaceKind::Exception(i) => {
            let e = &p.exceptions[i];
            what = format!("exception {:02X}h", e.code);
            rule = rule.code(u16::from(e.code)).name(&e.name);
        }
        PlaceKind::Command(i) => {
            let c = &p.commands[i];
            what = format!("command `{}`", c.id);
            rule = rule.name(&c.name).name(&c.id.replace('_', " "));
            for w in &c.writes {
                rule = rule.address(w.address);
            }
        }
        PlaceKind::Eeprom => rule = rule.number(p.eeprom.as_ref()?.endurance),
        PlaceKind::TimingInterval(key) => {
            let t = p.timing.as_ref()?;
            let i = match key {
                "frame_gap" => &t.frame_gap,
                "inter_char_timeout" => &t.inter_char_timeout,
                "response_time" => &t.response_time,
                _ => &t.request_gap,
            }
            .as_ref()?;
            what = format!("timing `{key}`");
            for n in [i.ms, i.chars].into_iter().flatten() {
                rule = rule.number(crate::describe::num(n));
            }
            if let Some(b) = i.bits {
                rule = rule.number(b);
            }
        }
        PlaceKind::Serial => {
            for b in &p.serial.as_ref()?.baud_rates {
                rule = rule.number(b);
            }
        }
        PlaceKind::SerialFormats => {
            let f = p.serial.as_ref()?.formats.as_ref()?;
            let param = drive
                .find(&f.selected_by)
                .and_then(|r| r.def.param.as_deref());
            rule = rule.param(Some(&f.selected_by)).param(param);
        }
        PlaceKind::SerialFormatCase(i) => {
            let s = p.serial.as_ref()?;
            let c = &s.formats.as_ref()?.cases[i];
            let letter = c.parity.letter().to_ascii_lowercase();
            let bits = c.data_bits.unwrap_or(s.data_bits);
            what = format!("serial format {}", c.when);
            rule = rule.words(&[&format!("{bits}{letter}{}", c.stop_bits)]);
        }
        PlaceKind::FunctionCodes => {
            for c in &p.function_codes.codes {
                rule = rule.code(u16::from(*c));
            }
        }
        PlaceKind::Limit(key) => {
            let l = match key {
                "max_read" => &p.max_read,
                "max_read_bits" => p.max_read_bits.as_ref()?,
                "max_write_bits" => p.max_write_bits.as_ref()?,
                _ => &p.max_write,
            };
            if key.ends_with("_bits") {
                rule = rule.words(&["coils", "coil", "inputs", "bits"]);
            }
            what = format!("`{key}`");
            if let Some(v) = l.value {
                rule = rule.number(v);
            }
        }
        _ => {}
    }
    Some((what, rule))
}

const PARITY_WORDS: &[&str] = &["parity", "even", "odd", "none", "stop"];

/// What the line of a role's place must mention; `None` for a place at a register the map does
/// not have (validation reports it).
fn role_rule(drive: &Drive, id: &str, index: usize) -> Option<Rule> {
    let places = drive.roles.get(id)?;
    let p = places.get(index)?;
    let RolePlace {
        register,
        field,
        external,
        ..
    } = p;
    Some(match (register, external) {
        (Some(name), _) => {
            let ri = drive
                .find(name)
                .and_then(|r| drive.registers.iter().position(|x| std::ptr::eq(x, r)))?;
            let r = &drive.registers[ri];
            match field
                .as_ref()
                .and_then(|f| r.def.fields.iter().position(|x| x.id == *f))
            {
                Some(fi) => {
                    let f = &r.def.fields[fi];
                    let code = |c: &model::CodeRef| match c {
                        model::CodeRef::Number(n) => Some(*n),
                        model::CodeRef::Id(id) => {
                            f.values.iter().find(|v| v.id == *id).map(|v| v.value)
                        }
                    };
                    let codes =
                        p.on.iter()
                            .flat_map(|c| c.list())
                            .chain(p.off.iter())
                            .filter_map(code)
                            .collect();
                    Rule::Field {
                        register: ri,
                        field: fi,
                        codes,
                    }
                }
                None => Rule::Register(ri),
            }
        }
        (None, Some(name)) => {
            let mut rule = Rule::any().name(&name.replace('_', " "));
            for q in drive.externals() {
                if q.external == *name {
                    rule = rule.name(&q.description);
                }
            }
            rule
        }
        (None, None) => {
            // A place the manual does not print (`unknown`): its line is the one that
            // says so, where the role's printed places are cited, or names the role.
            let printed = places.iter().find_map(|q| {
                let r = drive.find(q.register.as_deref()?)?;
                drive.registers.iter().position(|x| std::ptr::eq(x, r))
            });
            match printed {
                Some(ri) => Rule::Register(ri),
                None => Rule::any().name(&id.replace('_', " ")),
            }
        }
    })
}

/// A reading says what its line says: two of its words, or one of its numbers or codes as
/// printed (`0008H`, `1-31`, `3.5`).
fn reading_rule(says: &str) -> Rule {
    let mut rule = Rule::any().name(says);
    for token in says.split(|c: char| c.is_whitespace() || matches!(c, ';' | '(' | ')')) {
        let t = token.trim_matches(|c: char| !c.is_alphanumeric());
        if t.chars().any(|c| c.is_ascii_digit()) && t.chars().count() >= 2 {
            rule = rule.number(t);
            // A range as the manuals print it: `1-31` is also `1 to 31`, `1 ~ 31`, `1~31`.
            if let Some((a, b)) = t.split_once(['-', '~']) {
                let number = |x: &str| !x.is_empty() && x.parse::<f64>().is_ok();
                if number(a) && number(b) {
                    for sep in [" to ", " ~ ", "~", " - ", "-"] {
                        rule = rule.number(format!("{a}{sep}{b}"));
                    }
                }
            }
        }
    }
    // A quoted word or phrase is what the line prints (`lists "UPPER" before ...`).
    for (i, quoted) in says.split('"').enumerate() {
        if i % 2 == 1 {
            rule = rule.name(quoted);
        }
    }
    rule
}

/// What a gap's line must mention, and how it is named.
fn gap_rule(g: &model::Gap) -> (String, Rule) {
    let mut rule = Rule::any()
        .words(&["reserved", "unused", "missing"])
        .name("not used");
    let mut what = "a gap".to_owned();
    if let Some([first, last]) = g.addresses {
        what = format!("gap {}", crate::describe::address_span(first, last));
        // The gap's own first or last address, or the row just before or after it.
        rule = rule.address(first).address(last);
        if let Some(a) = first.checked_sub(1) {
            rule = rule.address(a);
        }
        if let Some(a) = last.checked_add(1) {
            rule = rule.address(a);
        }
    }
    if let Some(params) = &g.params {
        for p in params.split(|c: char| c.is_whitespace() || c == ',') {
            let p = p.trim_matches('.');
            if p.chars().any(|c| c.is_ascii_digit()) && !p.is_empty() {
                rule = rule.param(Some(p));
            }
        }
    }
    (what, rule)
}

/// A limit through another quantity (`max_relative`): the line prints the percentage, or names
/// the quantity it is taken of (the bounding register's parameter number, address or name, or
/// the external quantity's name).
fn limit_rule(drive: &Drive, r: &crate::ir::Register) -> Option<(String, Rule)> {
    let limit = r.def.max_relative.as_ref()?;
    let mut rule = Rule::any().number(limit.percent);
    let of =
        match &limit.relative_to {
            model::Reference::Register(name) => {
                if let Some(i) = drive.registers.iter().position(|b| {
                    b.def.id == *name || b.def.param.as_deref() == Some(name.as_str())
                }) {
                    rule = rule.register(i).name(&drive.registers[i].def.name);
                }
                name.clone()
            }
            model::Reference::External(q) => {
                rule = rule.name(&q.external.replace('_', " "));
                q.external.clone()
            }
        };
    Some((format!("the limit of {} through {of}", r.id()), rule))
}
