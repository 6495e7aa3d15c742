//! The drive plan printed as `const` data: one row per register, in the order of
//! [`MapPlan::registers`](drivemap_map::MapPlan::registers).
//!
//! Rows are printed here rather than through `prettyplease`, which would spread each row over
//! dozens of lines: a row is the register's identity, then its unit, conversion, envelope and
//! what else the plan says; a list too long for one line (labels, bit fields, scale cases,
//! moves) gets one item per line; and a line longer than [`WIDTH`] continues on the next after a
//! comma ([`wrap`]), so only a string literal longer than that makes a longer line. What a row
//! leaves out is the value of `RegisterInfo::DEFAULT` (a holding word without parameter number,
//! not broadcast-only) or of `RegisterPlan::new` (every transport, no broadcast, no moves);
//! an unsigned word over its whole range is `Conversion::WORD`. Every value printed is a plain
//! literal of the vocabulary crate's types, so a row is exactly the plan the lowering pass
//! decided.

use std::fmt::Write as _;

use drivemap_core::plan::{
    Case, CaseScale, Condition, Conversion, Field, Label, Move, Ranges, RegisterPlan, Relative,
    Setting, VariantOption,
};
use drivemap_core::ratio::Ratio;
use drivemap_core::register::{Access, RegisterInfo, Table, WriteRestriction};
use drivemap_core::roles::{Edge, Target};
use drivemap_core::rule::{Broadcast, Transports};
use drivemap_core::scale::{Decimal, RawRange};
use drivemap_core::text::ByteOrder;
use drivemap_core::width::{Width, WordOrder};

use drivemap_map::MapPlan;

/// The `plan` module of a drive: `pub const REGISTERS: &[RegisterPlan]`.
pub(super) fn module(plan: &MapPlan) -> String {
    let mut rows = String::new();
    for (i, r) in plan.registers.iter().enumerate() {
        let _ = writeln!(rows, "        /* {i} */ {},", row(r));
    }
    let roles = roles(plan);
    // A name used as a type or path of its own: followed by ` {`, `::` or `(`, and not itself a
    // variant of another path (`Target::Field(` uses `Target`, not the type `Field`).
    let names_it = |text: &str, used: &str| {
        text.match_indices(used).any(|(i, _)| {
            !text[..i]
                .chars()
                .next_back()
                .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':')
        })
    };
    let used = |names: &[&'static str]| -> String {
        let found: Vec<&str> = names
            .iter()
            .copied()
            .filter(|n| {
                [" {", "::", "("].iter().any(|end| {
                    let used = format!("{n}{end}");
                    names_it(&rows, &used) || names_it(&roles, &used)
                })
            })
            .collect();
        match found.len() {
            0 => String::new(),
            1 => found[0].to_owned(),
            _ => format!("{{{}}}", found.join(", ")),
        }
    };
    let mut out = String::from(
        "/// The plan of every register: what the lowering pass decided, as data. Sorted by\n\
         /// address, broadcast-only registers last; the register types index it.\n\
         pub mod plan {\n",
    );
    for (path, names) in [
        ("rt::functions", &["Functions"][..]),
        (
            "rt::plan",
            &[
                "Case",
                "CaseScale",
                "Condition",
                "Conversion",
                "Field",
                "Label",
                "Move",
                "Ranges",
                "RegisterPlan",
                "Relative",
                "RelativeLimit",
                "RepeatNeedsChange",
                "Setting",
                "VariantOption",
            ][..],
        ),
        ("rt::ratio", &["Ratio"][..]),
        (
            "rt::register",
            &["Access", "RegisterInfo", "Table", "WriteRestriction"][..],
        ),
        (
            "rt::roles",
            &[
                "Edge",
                "FieldRole",
                "NumberField",
                "Place",
                "Role",
                "Target",
            ][..],
        ),
        ("rt::rule", &["Broadcast", "Transports"][..]),
        ("rt::scale", &["Decimal", "RawRange"][..]),
        ("rt::text", &["ByteOrder"][..]),
        ("rt::width", &["Width", "WordOrder"][..]),
    ] {
        let names = used(names);
        if !names.is_empty() {
            let _ = writeln!(out, "    use super::{path}::{names};");
        }
    }
    out.push_str("\n    /// Every register's plan.\n    pub const REGISTERS: &[super::rt::plan::RegisterPlan] = &[\n");
    out.push_str(&rows);
    out.push_str("    ];\n");
    out.push_str(&roles);
    out.push_str("}\n");
    wrap(&out)
}

/// The longest line printed, but for one holding a string literal longer than that.
pub(super) const WIDTH: usize = 100;

/// Every line of `text` longer than [`WIDTH`] broken after a comma (outside string literals)
/// into lines that fill it, continued one step deeper than the line's indentation; comments
/// stay as they are.
pub(super) fn wrap(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / 16);
    for line in text.lines() {
        if line.len() <= WIDTH || line.trim_start().starts_with("//") {
            out.push_str(line);
            out.push('\n');
            continue;
        }
        let indent = line.len() - line.trim_start().len();
        let cont = " ".repeat(indent + 4);
        let mut current = String::new();
        for piece in comma_pieces(line) {
            if current.is_empty() || current.len() + piece.len() <= WIDTH {
                current.push_str(piece);
            } else {
                out.push_str(current.trim_end());
                out.push('\n');
                current = format!("{cont}{}", piece.trim_start());
            }
        }
        out.push_str(&current);
        out.push('\n');
    }
    out
}

/// `line` cut where a line may break, outside string literals: after `", "` and `"{ "`, and
/// before the `.` of a method called on a `)` (the pieces joined are the line).
fn comma_pieces(line: &str) -> Vec<&str> {
    let bytes = line.as_bytes();
    let mut pieces = Vec::new();
    let (mut start, mut in_string, mut escaped) = (0, false, false);
    for (i, &b) in bytes.iter().enumerate() {
        if in_string {
            match b {
                _ if escaped => escaped = false,
                b'\\' => escaped = true,
                b'"' => in_string = false,
                _ => {}
            }
        } else if b == b'"' {
            in_string = true;
        } else if (b == b',' || b == b'{') && bytes.get(i + 1) == Some(&b' ') {
            pieces.push(&line[start..i + 2]);
            start = i + 2;
        } else if b == b')' && bytes.get(i + 1) == Some(&b'.') {
            pieces.push(&line[start..i + 1]);
            start = i + 1;
        }
    }
    pieces.push(&line[start..]);
    pieces
}

/// `pub const ROLES`: one place per line, the register's id in a comment.
fn roles(plan: &MapPlan) -> String {
    let mut out = String::from(
        "\n    /// Which registers and fields play the standard parts of a drive (the map's `roles`).\n",
    );
    if plan.roles.is_empty() {
        out.push_str(
            "    pub const ROLES: super::rt::roles::Roles = super::rt::roles::Roles::NONE;\n",
        );
        return out;
    }
    out.push_str(
        "    pub const ROLES: super::rt::roles::Roles = super::rt::roles::Roles {\n        places: &[\n",
    );
    for p in plan.roles.places {
        let target = match p.target {
            Target::Register(row) => format!("Target::Register({row})"),
            Target::Field(f) => format!(
                "Target::Field(FieldRole {{ row: {}, lsb: {}, width: {}, on: {}, off: {:?}, edge: {} }})",
                f.row,
                f.lsb,
                f.width,
                list(f.on, |c| c.to_string()),
                f.off,
                match f.edge {
                    Edge::Level => "Edge::Level".to_owned(),
                    Edge::Edge => "Edge::Edge".to_owned(),
                    Edge::NotPrinted(why) => format!("Edge::NotPrinted({})", string(why)),
                }
            ),
            Target::NumberField(f) => format!(
                "Target::NumberField(NumberField {{ row: {}, lsb: {}, width: {}, signed: {}, scale: {} }})",
                f.row,
                f.lsb,
                f.width,
                f.signed,
                decimal(f.scale)
            ),
            Target::External { slot, name } => {
                format!(
                    "Target::External {{ slot: {slot}, name: {} }}",
                    string(name)
                )
            }
        };
        let what = match (p.target, p.target.row()) {
            (Target::NumberField(f), Some(row)) => format!(
                "{}, {} bits {}-{}",
                plan.registers[usize::from(row)].info.id,
                if f.signed { "signed" } else { "unsigned" },
                f.lsb,
                u16::from(f.lsb) + u16::from(f.width) - 1
            ),
            (_, Some(row)) => plan.registers[usize::from(row)].info.id.to_owned(),
            (_, None) => "external quantity".to_owned(),
        };
        let shared = match p.shared_with {
            Some(r) => format!("Some(Role::{r:?})"),
            None => "None".into(),
        };
        let _ = writeln!(
            out,
            "            /* {what} */ Place {{ role: Role::{:?}, target: {target}, transports: {}, source: {}, shared_with: {shared} }},",
            p.role,
            transports(p.transports),
            string(p.source)
        );
    }
    out.push_str("        ],\n");
    out.push_str(&command_profile(plan));
    out.push_str("    };\n");
    out
}

/// The `profile` of `ROLES`: the command profile as data (`None` for a drive run by fields).
fn command_profile(plan: &MapPlan) -> String {
    let Some(p) = plan.roles.profile else {
        return "        profile: None,\n".into();
    };
    let cp = "super::rt::command_profile";
    let id = |row: u16| plan.registers[usize::from(row)].info.id;
    let mut out = format!(
        "        profile: Some(&{cp}::CommandProfile {{\n            name: {},\n            /* {} */ control: {},\n            /* {} */ status: {},\n            states: &[\n",
        string(p.name),
        id(p.control),
        p.control,
        id(p.status),
        p.status
    );
    for (i, s) in p.states.iter().enumerate() {
        let _ = writeln!(
            out,
            "                /* {i} */ {cp}::ProfileState {{ id: {}, mask: {}, value: {}, source: {} }},",
            string(s.id),
            hex(s.mask),
            hex(s.value),
            string(s.source)
        );
    }
    out.push_str("            ],\n            transitions: &[\n");
    for (i, t) in p.transitions.iter().enumerate() {
        let _ = writeln!(
            out,
            "                /* {i} */ {cp}::Transition {{ id: {}, word: {}, keep: {}, edge: {}, from: &{:?}, to: {}, limit_ms: {}, source: {} }},",
            string(t.id),
            hex(t.word),
            hex(t.keep),
            hex(t.edge),
            t.from,
            t.to,
            t.limit_ms,
            string(t.source)
        );
    }
    out.push_str("            ],\n            paths: &[\n");
    for path in p.paths {
        let _ = writeln!(
            out,
            "                {cp}::Path {{ kind: {cp}::PathKind::{:?}, via: &{:?}, to: &{:?} }},",
            path.kind, path.via, path.to
        );
    }
    let _ = write!(
        out,
        "            ],\n            /* {} */ power_on: {},\n            source: {},\n        }}),\n",
        p.state_id(p.power_on),
        p.power_on,
        string(p.source)
    );
    out
}

fn string(s: &str) -> String {
    format!("{s:?}")
}

fn hex(v: u16) -> String {
    format!("0x{v:04X}")
}

fn range(r: RawRange) -> String {
    format!("RawRange::new({}, {})", r.min, r.max)
}

fn float(v: f64) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

fn list<T>(items: &[T], f: impl Fn(&T) -> String) -> String {
    let parts: Vec<String> = items.iter().map(f).collect();
    format!("&[{}]", parts.join(", "))
}

/// The longest list printed on one line; a longer one gets an item per line.
const LIST_WIDTH: usize = 100;

/// A list on one line if short, else one item per line, indented one step from `indent` (the
/// indentation of the line the list starts on).
fn block<T>(items: &[T], indent: usize, f: impl Fn(&T, usize) -> String) -> String {
    let parts: Vec<String> = items.iter().map(|x| f(x, indent + 4)).collect();
    let one_line = format!("&[{}]", parts.join(", "));
    if parts.len() < 2 || (one_line.len() <= LIST_WIDTH && !one_line.contains('\n')) {
        return one_line;
    }
    let mut out = String::from("&[\n");
    for p in parts {
        let _ = writeln!(out, "{:indent$}{p},", "", indent = indent + 4);
    }
    let _ = write!(out, "{:indent$}]", "");
    out
}

fn setting(s: &Setting) -> String {
    format!("Setting {{ slot: {}, label: {} }}", s.slot, string(s.label))
}

fn variant(v: &VariantOption) -> String {
    format!("VariantOption {{ axis: {}, option: {} }}", v.axis, v.option)
}

fn decimal(d: Decimal) -> String {
    format!("Decimal::new({}, {})", d.mantissa, d.exponent)
}

fn ratio(q: Ratio) -> String {
    format!("Ratio::new({}, {})", q.counts, decimal(q.equals))
}

fn ranges(r: &Ranges) -> String {
    if r.by_variant.is_empty() {
        format!("Ranges::fixed({})", range(r.base))
    } else {
        format!(
            "Ranges {{ base: {}, by_variant: {} }}",
            range(r.base),
            list(r.by_variant, |(v, r)| format!(
                "({}, {})",
                variant(v),
                range(*r)
            ))
        )
    }
}

fn relative(r: &Relative) -> String {
    format!(
        "Relative {{ full_scale: {}, reference: {} }}",
        float(r.full_scale),
        setting(&r.reference)
    )
}

fn label(l: &Label) -> String {
    format!(
        "Label {{ code: {}, id: {}, name: {} }}",
        l.code,
        string(l.id),
        string(l.name)
    )
}

fn field(f: &Field, indent: usize) -> String {
    format!(
        "Field {{ id: {}, name: {}, lsb: {}, width: {}, values: {}, source: {} }}",
        string(f.id),
        string(f.name),
        f.lsb,
        f.width,
        block(f.values, indent, |l, _| label(l)),
        string(f.source)
    )
}

fn case(c: &Case) -> String {
    let scale = match &c.scale {
        CaseScale::Decimal { scale, range: r } => format!(
            "CaseScale::Decimal {{ scale: {}, range: {} }}",
            decimal(*scale),
            range(*r)
        ),
        CaseScale::Relative(r) => format!("CaseScale::Relative({})", relative(r)),
    };
    format!(
        "Case {{ codes: {}, scale: {scale} }}",
        list(c.codes, |c| c.to_string())
    )
}

fn conversion(c: &Conversion, indent: usize) -> String {
    match c {
        Conversion::Text { order } => format!(
            "Conversion::Text {{ order: ByteOrder::{} }}",
            match order {
                ByteOrder::HighFirst => "HighFirst",
                ByteOrder::LowFirst => "LowFirst",
            }
        ),
        Conversion::Word { signed, range: r } => {
            format!(
                "Conversion::Word {{ signed: {signed}, range: {} }}",
                ranges(r)
            )
        }
        Conversion::Decimal {
            signed,
            scale,
            range: r,
        } => format!(
            "Conversion::Decimal {{ signed: {signed}, scale: {}, range: {} }}",
            decimal(*scale),
            ranges(r)
        ),
        Conversion::Relative {
            signed,
            relative: r,
        } => format!(
            "Conversion::Relative {{ signed: {signed}, relative: {} }}",
            relative(r)
        ),
        Conversion::Ratio {
            signed,
            ratio: q,
            range: r,
        } => format!(
            "Conversion::Ratio {{ signed: {signed}, ratio: {}, range: {} }}",
            ratio(*q),
            ranges(r)
        ),
        Conversion::Selected {
            signed,
            selector,
            cases,
        } => format!(
            "Conversion::Selected {{ signed: {signed}, selector: {}, cases: {} }}",
            setting(selector),
            block(cases, indent, |c, _| case(c))
        ),
        Conversion::Enum { values, unlisted } => format!(
            "Conversion::Enum {{ values: {}, unlisted: {} }}",
            block(values, indent, |l, _| label(l)),
            match unlisted {
                Some(r) => format!("Some({})", range(*r)),
                None => "None".into(),
            }
        ),
        Conversion::Bits { mask, fields } => format!(
            "Conversion::Bits {{ mask: {}, fields: {} }}",
            hex(*mask),
            block(fields, indent, field)
        ),
    }
}

fn transports(t: Transports) -> &'static str {
    match (t.rtu, t.tcp) {
        (true, true) => "Transports::ALL",
        (true, false) => "Transports::RTU",
        (false, true) => "Transports::TCP",
        (false, false) => "Transports { rtu: false, tcp: false }",
    }
}

fn condition(c: &Condition) -> String {
    match c {
        Condition::Setting { selector, codes } => format!(
            "Condition::Setting {{ selector: {}, codes: {} }}",
            setting(selector),
            list(codes, |c| c.to_string())
        ),
        Condition::Variant(v) => format!("Condition::Variant({})", variant(v)),
        Condition::Transport(t) => format!("Condition::Transport({})", transports(*t)),
    }
}

fn access(a: Access) -> &'static str {
    match a {
        Access::Read => "Access::Read",
        Access::Write => "Access::Write",
        Access::ReadWrite => "Access::ReadWrite",
    }
}

/// The indentation of a row's second and third lines.
const ROW_INDENT: usize = 12;

/// One register's plan as a Rust expression: its identity (the fields that differ from
/// `RegisterInfo::DEFAULT`), its unit, conversion, envelope and the plan's other parts, on one
/// line that [`module`] wraps (`RegisterPlan::word` for a plain unsigned word without unit).
pub(super) fn row(r: &RegisterPlan) -> String {
    let i = &r.info;
    let d = RegisterInfo::DEFAULT;
    let mut info = vec![format!("id: {}", string(i.id))];
    if let Some(p) = i.param {
        info.push(format!("param: Some({})", string(p)));
    }
    info.push(format!("name: {}", string(i.name)));
    info.push(format!("address: {}", hex(i.address)));
    if i.access != d.access {
        info.push(format!("access: {}", access(i.access)));
    }
    if i.table != d.table {
        info.push(format!(
            "table: {}",
            match i.table {
                Table::Holding => "Table::Holding",
                Table::Input => "Table::Input",
                Table::Coil => "Table::Coil",
                Table::DiscreteInput => "Table::DiscreteInput",
            }
        ));
    }
    if i.width != d.width {
        info.push(format!(
            "width: {}",
            match i.width {
                Width::Word => "Width::Word".to_owned(),
                Width::Pair(WordOrder::HighFirst) => "Width::Pair(WordOrder::HighFirst)".into(),
                Width::Pair(WordOrder::LowFirst) => "Width::Pair(WordOrder::LowFirst)".into(),
                Width::Text(n) => format!("Width::Text({n})"),
            }
        ));
    }
    if i.broadcast_only != d.broadcast_only {
        info.push(format!("broadcast_only: {}", i.broadcast_only));
    }
    info.push(format!("source: {}", string(i.source)));
    let info = format!(
        "RegisterInfo {{ {}, ..RegisterInfo::DEFAULT }}",
        info.join(", ")
    );
    let mut s = if r.conversion == Conversion::WORD
        && r.unit.is_empty()
        && r.envelope == RawRange::word(false)
    {
        format!("RegisterPlan::word({info})")
    } else {
        let conversion = if r.conversion == Conversion::WORD {
            "Conversion::WORD".to_owned()
        } else {
            conversion(&r.conversion, ROW_INDENT)
        };
        format!(
            "RegisterPlan::new({info}, {}, {conversion}, {})",
            string(r.unit),
            range(r.envelope),
        )
    };
    if !r.moves.is_empty() || !r.also_at.is_empty() {
        let moves = block(r.moves, ROW_INDENT, |m: &Move, _| {
            format!(
                "Move {{ when: {}, address: {} }}",
                condition(&m.when),
                hex(m.address)
            )
        });
        let _ = write!(s, ".moves({moves}, {})", list(r.also_at, |a| hex(*a)));
    }
    if r.transports != Transports::ALL {
        let _ = write!(s, ".on({})", transports(r.transports));
    }
    match r.broadcast {
        Broadcast::No => {}
        Broadcast::Also => s.push_str(".broadcast(Broadcast::Also)"),
        Broadcast::Only => s.push_str(".broadcast(Broadcast::Only)"),
    }
    match r.restriction {
        WriteRestriction::None => {}
        WriteRestriction::Stopped => s.push_str(".restricted(WriteRestriction::Stopped)"),
        WriteRestriction::PrgMode => s.push_str(".restricted(WriteRestriction::PrgMode)"),
    }
    if let Some(rule) = &r.repeat_needs_change {
        let _ = write!(
            s,
            ".repeat_needs_change(RepeatNeedsChange {{ between: {}, source: {} }})",
            rule.between,
            string(rule.source)
        );
    }
    if r.functions.restricted() {
        let f = &r.functions;
        let _ = write!(
            s,
            ".functions(Functions::only({}, {:#04x}, {}))",
            list(f.codes, |c| format!("{c:#04x}")),
            f.refused_with,
            string(f.source)
        );
    }
    if !r.read_values.is_empty() {
        let _ = write!(
            s,
            ".read_as({})",
            block(r.read_values, ROW_INDENT, |l, _| label(l))
        );
    }
    if let Some(p) = r.read_param {
        let _ = write!(s, ".read_from({})", string(p));
    }
    if let Some(l) = &r.limit {
        let _ = write!(
            s,
            ".limited(RelativeLimit {{ reference: {}, percent: {}, source: {} }})",
            setting(&l.reference),
            float(l.percent),
            string(l.source)
        );
    }
    s
}
