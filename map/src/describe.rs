//! How map items are written in text: numbers, addresses, access, scales, ranges, defaults,
//! conditions, bit spans. The one wording of each, used by the rustdoc of generated items
//! (`generate/docs.rs`), the Markdown reference of `drivemap doc` (`drivemap-review`'s `reference`),
//! the semantic diff of `drivemap diff` (`drivemap-review`'s `diff`) and the command line's messages, so
//! that all of them print an item the same way (a scale as `0.01 Hz`, a condition as
//! `o2-09 is 1`, a range as `0 ..= 400 Hz`).
//!
//! What the lowered plan decides (access, table, transports, write restriction, value kind) is
//! described from the plan's [`drivemap_core`] types; scales, limits and defaults as the manual
//! prints them (decimal, in engineering units, with their citations) from the map.
//!
//! A register's facts are worded here once, into the facts view ([`crate::facts`]); printers
//! read a register's rows there rather than calling these functions on the map (see
//! `map/README.md` for the few that still word a register themselves, and why). A scale is
//! worded by kind where its kind is decided, on its typed form
//! ([`ScaleData::describe`](crate::facts::data::ScaleData::describe)); the scale of a register
//! ([`RegisterRef::scale_text`](crate::RegisterRef::scale_text)) and [`kind`] read it and the
//! plan's [`ValueShape`] without matching on the kind.

use drivemap_core::plan::{RegisterPlan, ValueShape};
use drivemap_core::register::{Access, Table, WriteRestriction};
use drivemap_core::rule::Transports;
use drivemap_core::text::ByteOrder;
use drivemap_core::width::{Width, WordOrder};

use crate::ir::{Drive, Register};
use crate::model::{Condition, DefaultValue, Dependency, DisplayStep, Field, Scale, UnknownItem};
use crate::names::field_span;
/// `accel_time_1` → `AccelTime1`: how generated code names map items.
pub use crate::names::pascal_case;

/// A register whose drive executes a written value only when it differs from the previous
/// write: `a value is executed only when it differs from the previous write, so 0 is written
/// before any other value (`004_...:1115`)`.
pub fn repeat_needs_change(rule: &crate::model::RepeatNeedsChange) -> String {
    format!(
        "a value is executed only when it differs from the previous write, so {} is written before any other value (`{}`)",
        num(rule.between),
        rule.source
    )
}

/// The functions a register accepts where the map restricts them: `accepts only 03h, 06h;
/// another function is answered with exception 01h (illegal function) (`m.txt:12`)`.
pub fn function_codes(f: &crate::model::RegisterFunctions) -> String {
    let codes: Vec<String> = f.codes.iter().map(|c| format!("{c:02X}h")).collect();
    let refusal = match f.refusal() {
        0x02 => "02h (illegal data address)".to_string(),
        0x01 => "01h (illegal function)".to_string(),
        other => format!("{other:02X}h"),
    };
    format!(
        "accepts only {}; another function is answered with exception {refusal} (`{}`)",
        codes.join(", "),
        f.source
    )
}

/// What a word read means when it differs from what a write means: `0 Unlock, 1 Lock`.
pub fn read_values(values: &[crate::model::EnumValue]) -> String {
    values
        .iter()
        .map(|v| format!("{} {}", v.value, v.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A number as the manual prints it (`6000`, `0.1`, `-100`).
pub fn num(v: f64) -> String {
    format!("{v}")
}

/// A communication address (`0200h`).
pub fn address(a: u16) -> String {
    format!("{a:04X}h")
}

/// An address in the notation the map gives its addresses: the plain number in a map that
/// numbers registers in decimal (`address_format: decimal`, `45`), else `002Dh`.
pub fn address_as(format: crate::model::AddressFormat, a: u16) -> String {
    match format {
        crate::model::AddressFormat::Decimal => a.to_string(),
        crate::model::AddressFormat::Hex => address(a),
    }
}

/// A function code (`03h`).
pub fn function(f: u8) -> String {
    format!("{f:02X}h")
}

/// Function codes: `03h, 06h, 10h`.
pub fn functions(f: &[u8]) -> String {
    f.iter()
        .map(|f| function(*f))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A span of addresses: `0100h`, or `0100h – 0105h`.
pub fn address_span(first: u16, last: u16) -> String {
    if first == last {
        address(first)
    } else {
        format!("{} – {}", address(first), address(last))
    }
}

/// A span of addresses in the notation the map gives its addresses ([`address_as`]): `45 – 48`
/// in a map that numbers registers in decimal, else [`address_span`]'s `002Dh – 0030h`.
pub fn address_span_as(format: crate::model::AddressFormat, first: u16, last: u16) -> String {
    match format {
        crate::model::AddressFormat::Hex => address_span(first, last),
        crate::model::AddressFormat::Decimal if first == last => first.to_string(),
        crate::model::AddressFormat::Decimal => format!("{first} – {last}"),
    }
}

/// The registers one request may carry: `at most 16 per read, 16 per write`.
pub fn per_request(max_read: u16, max_write: u16) -> String {
    format!("at most {max_read} per read, {max_write} per write")
}

/// The coils and discrete inputs one request may carry, for the limits a map states: `at most
/// 32 per read (01h/02h), 16 per write (0Fh)`.
pub fn bits_per_request(max_read: Option<u16>, max_write: Option<u16>) -> String {
    let parts: Vec<String> = [
        max_read.map(|n| format!("{n} per read (01h/02h)")),
        max_write.map(|n| format!("{n} per write (0Fh)")),
    ]
    .into_iter()
    .flatten()
    .collect();
    format!("at most {}", parts.join(", "))
}

/// What a limit's map entry says beyond its number: `. max_read 8 not printed: <why>
/// (`file:line`)`, `. max_read (`file:line`)`, or nothing for a plain number; without the
/// citation when `with_source` is false (the caller gives it elsewhere).
pub fn limit_citation(name: &str, l: &crate::model::Limit, with_source: bool) -> String {
    let src = match &l.source {
        Some(s) if with_source => format!(" (`{s}`)"),
        _ => String::new(),
    };
    match &l.unknown {
        Some(why) => match l.value {
            Some(v) => format!(". {name} {v} not printed: {}{src}", why.trim()),
            None => format!(
                ". {name} {}{src}",
                not_printed(why, &format!("the Modbus limit ({})", fallback_limit(name)))
            ),
        },
        None if !src.is_empty() => format!(". {name}{src}"),
        None => String::new(),
    }
}

/// A fact the manual does not print, in `doc`'s words: `not printed in the manual: <why>;
/// used instead: <fallback>`.
pub fn not_printed(why: &str, fallback: &str) -> String {
    format!(
        "not printed in the manual: {}; used instead: {fallback}",
        why.trim()
    )
}

/// The Modbus limit standing in for an unprinted `max_read` (125), `max_write` (123),
/// `max_read_bits` (2000) or `max_write_bits` (1968).
fn fallback_limit(name: &str) -> u16 {
    match name {
        "max_read" => drivemap_core::stated::MODBUS_MAX_READ,
        "max_read_bits" => drivemap_core::stated::MODBUS_MAX_READ_BITS,
        "max_write_bits" => drivemap_core::stated::MODBUS_MAX_WRITE_BITS,
        _ => drivemap_core::stated::MODBUS_MAX_WRITE,
    }
}

/// A broadcast whose rules the manual does not print: `broadcast exists, rules not printed:
/// <why>`.
pub fn broadcast_not_printed(why: &str) -> String {
    format!("broadcast exists, rules not printed: {}", why.trim())
}

/// Access: `read-only`, `write-only`, `read/write`.
pub fn access(a: Access) -> &'static str {
    match a {
        Access::Read => "read-only",
        Access::Write => "write-only",
        Access::ReadWrite => "read/write",
    }
}

/// The Modbus table.
pub fn table(t: Table) -> &'static str {
    match t {
        Table::Holding => "holding",
        Table::Input => "input",
        Table::Coil => "coil",
        Table::DiscreteInput => "discrete input",
    }
}

/// When writes are accepted.
pub fn write_restriction(w: WriteRestriction) -> &'static str {
    match w {
        WriteRestriction::None => "any time",
        WriteRestriction::Stopped => "only while the motor is stopped",
        WriteRestriction::PrgMode => "only in PRG (program) mode",
    }
}

/// The transports a register exists on: `RTU`, `TCP`, or `all`.
pub fn transports(t: Transports) -> String {
    match (t.rtu, t.tcp) {
        (true, true) => "all".into(),
        (true, false) => "RTU".into(),
        (false, true) => "TCP".into(),
        (false, false) => "none".into(),
    }
}

/// How many registers a value takes: `one register`, or a 32-bit pair and its word order.
pub fn width(w: Width) -> String {
    match w {
        Width::Word => "one register".into(),
        Width::Pair(WordOrder::HighFirst) => "32-bit pair, high word first".into(),
        Width::Pair(WordOrder::LowFirst) => "32-bit pair, low word first".into(),
        Width::Text(n) => format!("text in {n} registers ({} characters)", 2 * u16::from(n)),
    }
}

/// A string register's layout: `text in 8 registers (16 characters), high byte first`, and
/// the manual's example when the map gives one (escaped: `example "Q2-0400"`).
pub fn text(registers: u8, order: ByteOrder, example: Option<&str>) -> String {
    let order = match order {
        ByteOrder::HighFirst => "high byte first",
        ByteOrder::LowFirst => "low byte first",
    };
    let mut out = format!("{}, {order}", width(Width::Text(registers)));
    if let Some(e) = example {
        out.push_str(", example \"");
        let _ = drivemap_core::text::write_escaped(&mut out, e.as_bytes());
        out.push('"');
    }
    out
}

/// What kind of value a register holds.
pub fn kind(plan: &RegisterPlan) -> &'static str {
    let pair = plan.info.width != Width::Word;
    match plan.conversion.shape() {
        ValueShape::Word { signed: true } if pair => "signed 32-bit pair",
        ValueShape::Word { .. } if pair => "32-bit pair",
        ValueShape::Word { signed: true } => "signed word",
        ValueShape::Word { .. } => "word",
        ValueShape::Number if pair => "32-bit quantity",
        ValueShape::Number => "quantity",
        ValueShape::Codes(_) => "enumeration",
        ValueShape::Bits { .. } => "bit fields",
        ValueShape::Text { .. } => "text",
    }
}

/// A register as a user names it: id, and the parameter number when printed.
pub(crate) fn register(r: &Register) -> String {
    match &r.def.param {
        Some(p) => format!("{} ({p})", r.def.id),
        None => r.def.id.clone(),
    }
}

/// A register named in a map (a selector, a reference): its parameter number when printed,
/// else its id; the name as given when no register has it.
pub(crate) fn setting(drive: &Drive, name: &str) -> String {
    drive
        .selector(name)
        .map(|s| s.prose())
        .unwrap_or_else(|| name.to_owned())
}

/// A scale in engineering units: `0.01 Hz` (per count), `30000 = 100 % of Cn-02 (…)`, or a
/// selected scale with its cases (`selected by C6-01: 0 → 0.01 Hz; 1 → 0.1 Hz`). The wording
/// of each kind is its typed form's ([`ScaleData::describe`](crate::facts::data::ScaleData::describe)).
pub(crate) fn scale(drive: &Drive, s: &Scale, unit: &str) -> String {
    crate::facts::data::scale_of(drive, s).describe(unit)
}

/// A ratio scale: `3600 = 60 Hz (1/60 (≈0.016667) Hz per count, exact)`.
pub(crate) fn ratio(s: &crate::model::RatioScale, unit: &str) -> String {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    match crate::ratio::ratio_of(s) {
        Some(r) => format!("{r}{unit} ({}{unit} per count, exact)", r.step()),
        None => format!("{} = {}{unit}", s.counts, num(s.equals)),
    }
}

/// Selector codes: `0`, `1, 2`.
pub fn codes(when: &[u16]) -> String {
    when.iter()
        .map(u16::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A range in engineering units (`0 ..= 6000 s`); empty when neither limit is given.
pub fn range(min: Option<f64>, max: Option<f64>, unit: &str) -> String {
    if min.is_none() && max.is_none() {
        return String::new();
    }
    let s = format!(
        "{} ..= {} {unit}",
        min.map(num).unwrap_or_else(|| "…".into()),
        max.map(num).unwrap_or_else(|| "…".into())
    );
    s.trim_end().to_owned()
}

/// A limit through another quantity: `at most 100 % of n011 (003_...:102)`.
pub(crate) fn relative_limit(drive: &crate::ir::Drive, l: &crate::model::RelativeLimit) -> String {
    let of = match &l.relative_to {
        crate::model::Reference::Register(name) => setting(drive, name),
        crate::model::Reference::External(q) => format!("{} (external)", q.external),
    };
    format!("at most {} % of {of} ({})", num(l.percent), l.source)
}

/// What a default depends on.
pub fn dependency(d: Dependency) -> &'static str {
    match d {
        Dependency::Capacity => "capacity",
        Dependency::ControlMethod => "control method",
        Dependency::Variant => "variant",
        Dependency::Setting => "setting",
        Dependency::Unknown => "unknown",
    }
}

/// A default value, or what it depends on.
pub fn default(d: &DefaultValue) -> String {
    match d {
        DefaultValue::Value(v) => num(*v),
        DefaultValue::Depends(dep) => match &dep.note {
            Some(n) => format!("depends on {} ({n})", dependency(dep.depends_on)),
            None => format!("depends on {}", dependency(dep.depends_on)),
        },
    }
}

/// The bits of a field: `bit 3` or `bits 12–15`.
pub fn bits(f: &Field) -> String {
    match field_span(f) {
        Some((lsb, width)) => bit_span(lsb, width),
        None => "no bits".into(),
    }
}

/// `width` bits from `lsb`: `bit 3` or `bits 12–15`.
pub fn bit_span(lsb: u8, width: u8) -> String {
    if width == 1 {
        format!("bit {lsb}")
    } else {
        format!("bits {lsb}–{}", u16::from(lsb) + u16::from(width) - 1)
    }
}

/// The condition under which an alternative address applies (`o2-09 is 1`, `variant v440`,
/// `transport TCP`).
pub fn condition(c: &Condition) -> String {
    c.to_string()
}

/// What the manual leaves unknown about an item.
pub fn unknown_item(u: UnknownItem) -> &'static str {
    match u {
        UnknownItem::Range => "range",
        UnknownItem::Default => "default",
        UnknownItem::Unit => "unit",
        UnknownItem::Scale => "scale",
        UnknownItem::Signed => "signedness",
        UnknownItem::Values => "values",
        UnknownItem::Fields => "fields",
        UnknownItem::Access => "access",
    }
}

/// How the keypad shows a value whose register carries more resolution.
pub fn display_steps(steps: &[DisplayStep]) -> String {
    let bands = steps
        .iter()
        .map(|b| format!("from {} in steps of {}", num(b.from), num(b.step)))
        .collect::<Vec<_>>()
        .join(", ");
    format!("the keypad shows it {bands}; the register carries the full resolution")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_ranges_read_like_the_manual() {
        assert_eq!(num(6000.0), "6000");
        assert_eq!(num(0.1), "0.1");
        assert_eq!(address(0x20), "0020h");
        assert_eq!(range(Some(0.0), Some(400.0), "Hz"), "0 ..= 400 Hz");
        assert_eq!(range(None, Some(5.0), ""), "… ..= 5");
        assert_eq!(range(None, None, "Hz"), "");
        assert_eq!(codes(&[1, 2]), "1, 2");
        assert_eq!(functions(&[3, 0x10]), "03h, 10h");
        assert_eq!(address_span(0x100, 0x100), "0100h");
        assert_eq!(address_span(0x100, 0x105), "0100h – 0105h");
        assert_eq!(transports(Transports::RTU), "RTU");
        assert_eq!(transports(Transports::ALL), "all");
        assert_eq!(access(Access::ReadWrite), "read/write");
        assert_eq!(bit_span(3, 1), "bit 3");
        assert_eq!(bit_span(12, 4), "bits 12–15");
    }
}
