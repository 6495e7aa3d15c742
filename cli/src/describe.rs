//! How map items are written in text: numbers, addresses, scales, ranges, defaults, bit spans.
//! Shared by `drivemap doc` and `drivemap diff` so both print an item the same way.

use drivemap_codegen::ir::{Drive, Register, ValueKind};
use drivemap_codegen::model::{
    Access, Condition, DefaultValue, Dependency, Field, ModbusTable, Reference, Scale,
    TransportName, WriteRestriction,
};

/// A number as the manual prints it (`6000`, `0.1`, `-100`).
pub fn num(v: f64) -> String {
    format!("{v}")
}

/// A communication address (`0200h`).
pub fn address(a: u16) -> String {
    format!("{a:04X}h")
}

/// A function code (`03h`).
pub fn function(f: u8) -> String {
    format!("{f:02X}h")
}

/// Access as the schema writes it.
pub fn access(a: Access) -> &'static str {
    match a {
        Access::Read => "r",
        Access::Write => "w",
        Access::ReadWrite => "rw",
    }
}

/// The Modbus table.
pub fn table(t: ModbusTable) -> &'static str {
    match t {
        ModbusTable::Holding => "holding",
        ModbusTable::Input => "input",
    }
}

/// When writes are accepted.
pub fn write_restriction(w: WriteRestriction) -> &'static str {
    match w {
        WriteRestriction::None => "any time",
        WriteRestriction::Stopped => "only while stopped",
        WriteRestriction::PrgMode => "only in PRG mode",
    }
}

/// A transport name.
pub fn transport(t: TransportName) -> String {
    t.to_string()
}

/// A list of transports, or `all` when unrestricted.
pub fn transports(t: Option<&[TransportName]>) -> String {
    match t {
        None => "all".into(),
        Some(list) => list
            .iter()
            .map(|t| transport(*t))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// What kind of value a register holds.
pub fn kind(r: &Register) -> &'static str {
    match r.kind() {
        ValueKind::Word if r.def.signed => "signed word",
        ValueKind::Word => "word",
        ValueKind::Quantity(_) | ValueKind::UnitQuantity => "quantity",
        ValueKind::Enum(_) => "enumeration",
        ValueKind::Bits(_) => "bit fields",
    }
}

/// A register as a user names it: id, and the parameter number when printed.
pub fn register(r: &Register) -> String {
    match &r.def.param {
        Some(p) => format!("{} ({p})", r.def.id),
        None => r.def.id.clone(),
    }
}

/// The register or quantity a relative scale refers to.
pub fn reference(drive: &Drive, r: &Reference) -> String {
    match r {
        Reference::Register(name) => match drive.find(name) {
            Some(t) if t.def.param.as_deref() == Some(name.as_str()) => {
                format!("{name} ({})", t.def.name)
            }
            Some(t) => match &t.def.param {
                Some(p) => format!("{p} ({})", t.def.name),
                None => format!("{} ({})", t.def.id, t.def.name),
            },
            None => name.clone(),
        },
        Reference::External(q) => format!("external {} in {}", q.external, q.unit),
    }
}

/// A fixed or relative scale; a selected scale lists its cases.
pub fn scale(drive: &Drive, s: &Scale) -> String {
    match s {
        Scale::Factor(f) => num(*f),
        Scale::Relative(rel) => format!(
            "{} = 100 % of {}",
            num(rel.full_scale),
            reference(drive, &rel.relative_to)
        ),
        Scale::Selected(sel) => {
            let cases: Vec<String> = sel
                .cases
                .iter()
                .map(|c| format!("{} → {}", codes(&c.when), scale(drive, &c.scale)))
                .collect();
            format!("selected by {}: {}", sel.selected_by, cases.join("; "))
        }
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
    match (f.bit, f.bits) {
        (Some(b), _) => format!("bit {b}"),
        (None, Some([lo, hi])) => format!("bits {lo}–{hi}"),
        (None, None) => "no bits".into(),
    }
}

/// The condition under which an alternative address applies, in the library's one wording.
pub fn condition(c: &Condition) -> String {
    c.to_string()
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
    }
}
