//! Citations outside the registers, checked by content like register citations: roles, every
//! protocol item, the readings of conflicts (of the map and of registers) and gaps. What a line
//! must mention for each kind is listed in `maps/README.md` ("Citations checked by content"),
//! and [`Rule`] says it once in code. The same `indirect: <reason>` escape applies; a
//! protocol limit or function-code list marked `unknown` (not printed) is indirect by nature.
//! As for values and fields, the line just after or before counts as the row when the cited line
//! does not mention the item alone (a statement broken over two OCR lines).

use crate::ir::Drive;
use crate::model::{self, RolePlace};
use crate::source::Path;

/// What one citation outside the registers must mention.
#[derive(Debug, Clone)]
pub enum Rule {
    /// A role at a register: read as that register's own citation (address, parameter number,
    /// name; not another register's row). The index is into [`Drive::registers`].
    Register(usize),
    /// A role at a field: the field's bit or name, one of the role's codes with its label, or
    /// the field's register (its address, parameter number or name).
    Field {
        register: usize,
        field: usize,
        /// The role's codes (`on`, `off`) as numbers.
        codes: Vec<u16>,
    },
    /// Any of these words (lower case), parameter numbers, numbers, or addresses.
    Any {
        words: Vec<String>,
        params: Vec<String>,
        numbers: Vec<String>,
        codes: Vec<u16>,
        addresses: Vec<u16>,
        /// Names of which two words (or all, for a shorter name) must be printed.
        names: Vec<String>,
        /// Registers (indices into [`Drive::registers`]) whose address or parameter number
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
        if let Rule::Any { names, .. } = &mut self {
            if !n.trim().is_empty() {
                names.push(n.to_owned());
            }
        }
        self
    }

    /// What the line is expected to show, for messages.
    pub fn expected(&self, drive: &Drive) -> String {
        match self {
            Rule::Register(i) => {
                let r = &drive.registers[*i].def;
                let mut e: Vec<String> = r.param.iter().cloned().collect();
                e.push(format!("{:04X}h", r.address));
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
                    e.push(format!("{:04X}h", r.address));
                }
                e.extend(names.iter().map(|n| format!("\"{n}\"")));
                e.extend(params.iter().cloned());
                e.extend(addresses.iter().map(|a| format!("{a:04X}h")));
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

/// Every citation of roles, the protocol, conflicts and gaps, with what its line must mention.
pub fn other_citations(drive: &Drive) -> Vec<Other> {
    let mut out = Vec::new();
    roles(drive, &mut out);
    protocol(drive, &mut out);
    conflicts(drive, &mut out);
    gaps(drive, &mut out);
    limits(drive, &mut out);
    functions(drive, &mut out);
    out
}

fn push(
    out: &mut Vec<Other>,
    path: Path,
    what: String,
    kind: &'static str,
    source: &Option<String>,
    indirect: &Option<String>,
    rule: Rule,
) {
    if source.is_some() || indirect.is_some() {
        out.push(Other {
            path,
            what,
            kind,
            source: source.clone(),
            indirect: indirect.clone(),
            indirect_key: true,
            rule,
        });
    }
}

fn roles(drive: &Drive, out: &mut Vec<Other>) {
    for (id, places) in &drive.roles {
        for (i, p) in places.iter().enumerate() {
            let RolePlace {
                register,
                field,
                external,
                source,
                indirect,
                ..
            } = p;
            let rule = match (register, external) {
                (Some(name), _) => {
                    let Some(ri) = drive
                        .find(name)
                        .and_then(|r| drive.registers.iter().position(|x| std::ptr::eq(x, r)))
                    else {
                        continue;
                    };
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
            };
            push(
                out,
                Path::root().key("roles").key(id).index(i).key("source"),
                format!("role `{id}`"),
                "role",
                source,
                indirect,
                rule,
            );
        }
    }
}

fn protocol(drive: &Drive, out: &mut Vec<Other>) {
    let p = &drive.protocol;
    let at = Path::root().key("protocol");
    let model::Protocol {
        transports: _,
        function_codes,
        max_read,
        max_write,
        slave_address,
        broadcast,
        exceptions,
        commands,
        eeprom,
        addressing,
        timing,
        serial,
        source,
        indirect,
        notes: _,
    } = p;
    push(
        out,
        at.key("source"),
        "the protocol".into(),
        "protocol",
        source,
        indirect,
        Rule::any().words(PROTOCOL_WORDS).name("function code"),
    );
    {
        let model::SlaveAddress {
            min: _,
            max: _,
            unknown: _,
            default: _,
            param,
            source,
            indirect,
        } = slave_address;
        push(
            out,
            at.key("slave_address").key("source"),
            "the slave address".into(),
            "protocol",
            source,
            indirect,
            Rule::any()
                .words(&["address", "addresses", "station", "slave", "node"])
                .param(param.as_deref()),
        );
    }
    if let Some(b) = broadcast {
        push(
            out,
            at.key("broadcast").key("source"),
            "the broadcast".into(),
            "protocol",
            &Some(b.source.clone()),
            &b.indirect,
            Rule::any()
                .words(&["broadcast", "broadcasting"])
                .name("all slaves")
                .name("all stations")
                .name("all drives")
                .name("all inverters")
                .name("slave address 0")
                .name("station 0"),
        );
    }
    for (i, e) in exceptions.iter().enumerate() {
        push(
            out,
            at.key("exceptions").index(i).key("source"),
            format!("exception {:02X}h", e.code),
            "protocol",
            &Some(e.source.clone()),
            &e.indirect,
            Rule::any().code(u16::from(e.code)).name(&e.name),
        );
    }
    for (i, c) in commands.iter().enumerate() {
        let mut rule = Rule::any().name(&c.name).name(&c.id.replace('_', " "));
        for w in &c.writes {
            rule = rule.address(w.address);
        }
        push(
            out,
            at.key("commands").index(i).key("source"),
            format!("command `{}`", c.id),
            "protocol",
            &Some(c.source.clone()),
            &c.indirect,
            rule,
        );
    }
    if let Some(e) = eeprom {
        push(
            out,
            at.key("eeprom").key("source"),
            "the EEPROM endurance".into(),
            "protocol",
            &Some(e.source.clone()),
            &e.indirect,
            Rule::any()
                .words(&["eeprom", "nonvolatile", "volatile", "memory"])
                .number(e.endurance),
        );
    }
    if let Some(a) = addressing {
        push(
            out,
            at.key("addressing").key("source"),
            "the addressing".into(),
            "protocol",
            &Some(a.source.clone()),
            &a.indirect,
            Rule::any().words(&[
                "address",
                "addresses",
                "addressing",
                "register",
                "registers",
            ]),
        );
    }
    if let Some(t) = timing {
        let tp = at.key("timing");
        push(
            out,
            tp.key("source"),
            "the timing".into(),
            "protocol",
            &t.source,
            &t.indirect,
            Rule::any().words(TIMING_WORDS),
        );
        for (key, i) in [
            ("frame_gap", &t.frame_gap),
            ("inter_char_timeout", &t.inter_char_timeout),
            ("response_time", &t.response_time),
            ("request_gap", &t.request_gap),
        ] {
            let Some(i) = i else { continue };
            let mut rule = Rule::any().words(TIMING_WORDS);
            for n in [i.ms, i.chars].into_iter().flatten() {
                rule = rule.number(crate::describe::num(n));
            }
            if let Some(b) = i.bits {
                rule = rule.number(b);
            }
            push(
                out,
                tp.key(key).key("source"),
                format!("timing `{key}`"),
                "protocol",
                &i.source,
                &i.indirect,
                rule,
            );
        }
    }
    if let Some(s) = serial {
        let sp = at.key("serial");
        let mut rule = Rule::any().words(&[
            "baud",
            "bps",
            "parity",
            "speed",
            "transmission",
            "stop",
            "data",
        ]);
        for b in &s.baud_rates {
            rule = rule.number(b);
        }
        push(
            out,
            sp.key("source"),
            "the serial line".into(),
            "protocol",
            &(!s.source.is_empty()).then(|| s.source.clone()),
            &s.indirect,
            rule,
        );
        if let Some(f) = &s.formats {
            let parity_words = &["parity", "even", "odd", "none", "stop"];
            push(
                out,
                sp.key("formats").key("source"),
                "the serial formats".into(),
                "protocol",
                &Some(f.source.clone()),
                &f.indirect,
                Rule::any()
                    .words(parity_words)
                    .param(Some(&f.selected_by))
                    .param(
                        drive
                            .find(&f.selected_by)
                            .and_then(|r| r.def.param.as_deref()),
                    ),
            );
            for (i, c) in f.cases.iter().enumerate() {
                let letter = c.parity.letter().to_ascii_lowercase();
                let bits = c.data_bits.unwrap_or(s.data_bits);
                push(
                    out,
                    sp.key("formats").key("cases").index(i).key("source"),
                    format!("serial format {}", c.when),
                    "protocol",
                    &c.source,
                    &c.indirect,
                    Rule::any()
                        .words(parity_words)
                        .words(&[&format!("{bits}{letter}{}", c.stop_bits)]),
                );
            }
        }
    }
    // A list or limit the manual does not print is cited where its working value comes from:
    // indirect by nature, with `unknown` as the reason.
    {
        let model::FunctionCodes {
            codes,
            source,
            unknown,
        } = function_codes;
        let mut rule = Rule::any().name("function code").name("function codes");
        for c in codes {
            rule = rule.code(u16::from(*c));
        }
        if source.is_some() {
            push(
                out,
                at.key("function_codes").key("source"),
                "the function codes".into(),
                "protocol",
                source,
                unknown,
                rule,
            );
            if let Some(o) = out.last_mut() {
                o.indirect_key = false;
            }
        }
    }
    for (key, l) in [("max_read", max_read), ("max_write", max_write)] {
        let model::Limit {
            value,
            source,
            unknown,
        } = l;
        if source.is_some() {
            push(
                out,
                at.key(key).key("source"),
                format!("`{key}`"),
                "protocol",
                source,
                unknown,
                match value {
                    Some(v) => Rule::any().number(v),
                    None => Rule::any(),
                }
                .words(&["quantity", "registers", "words"]),
            );
            if let Some(o) = out.last_mut() {
                o.indirect_key = false;
            }
        }
    }
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

fn conflicts(drive: &Drive, out: &mut Vec<Other>) {
    // A reading of a register's own conflict may also cite the register's row.
    let one =
        |list: &[model::Conflict], base: Path, register: Option<usize>, out: &mut Vec<Other>| {
            for (ci, c) in list.iter().enumerate() {
                for (ri, r) in c.readings.iter().enumerate() {
                    let mut rule = reading_rule(&r.says);
                    if let Some(i) = register {
                        rule = rule.register(i);
                    }
                    push(
                        out,
                        base.index(ci).key("readings").index(ri).key("source"),
                        format!("a reading of conflict \"{}\"", c.topic),
                        "conflict",
                        &Some(r.source.clone()),
                        &r.indirect,
                        rule,
                    );
                }
            }
        };
    one(&drive.conflicts, Path::root().key("conflicts"), None, out);
    for (i, r) in drive.registers.iter().enumerate() {
        one(&r.def.conflicts, r.key_path("conflicts"), Some(i), out);
    }
}

fn gaps(drive: &Drive, out: &mut Vec<Other>) {
    for (i, g) in drive.gaps.iter().enumerate() {
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
        push(
            out,
            Path::root().key("gaps").index(i).key("source"),
            what,
            "gap",
            &Some(g.source.clone()),
            &g.indirect,
            rule,
        );
    }
}

/// A limit through another quantity (`max_relative`): the line prints the percentage, or names
/// the quantity it is taken of (the bounding register's parameter number, address or name, or
/// the external quantity's name).
fn limits(drive: &Drive, out: &mut Vec<Other>) {
    for r in &drive.registers {
        let Some(limit) = &r.def.max_relative else {
            continue;
        };
        let mut rule = Rule::any().number(limit.percent);
        let of = match &limit.relative_to {
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
        push(
            out,
            r.key_path("max_relative").key("source"),
            format!("the limit of {} through {of}", r.id()),
            "limit",
            &Some(limit.source.clone()),
            &None,
            rule,
        );
    }
}

/// A register's (or its group's) `function_codes`: the line mentions one of the listed codes
/// (`10H`, `0x10`), or "function code(s)". A group's list is read once.
fn functions(drive: &Drive, out: &mut Vec<Other>) {
    let mut seen = std::collections::HashSet::new();
    for r in &drive.registers {
        let Some((f, path)) = &r.function_codes else {
            continue;
        };
        if !seen.insert(path.clone()) {
            continue;
        }
        let mut rule = Rule::any()
            .name("function code")
            .name("function codes")
            .words(&["function"]);
        for c in &f.codes {
            rule = rule.code(u16::from(*c));
        }
        push(
            out,
            path.key("source"),
            format!("the function codes of {}", r.id()),
            "functions",
            &Some(f.source.clone()),
            &None,
            rule,
        );
    }
}
