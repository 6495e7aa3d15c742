//! The Rust names the generator gives to map items, and the spans of bit fields. Validation uses
//! the same functions to find collisions and bad spans before emission; they live here, below
//! both, so neither depends on the other.

use crate::ir::Register;
use crate::model::{Field, VariantAxis};

/// The zero-sized type of a register: `accel_time_1` → `AccelTime1`.
pub(crate) fn register_type(r: &Register) -> String {
    pascal_case(r.id())
}

/// The enumeration of a register's codes: `run_source` → `RunSourceValue`.
pub(crate) fn value_enum(r: &Register) -> String {
    format!("{}Value", pascal_case(r.id()))
}

/// The enumeration of what a register's word means when read (`read_values`):
/// `hide_parameter_mode` → `HideParameterModeRead`.
pub(crate) fn read_enum(r: &Register) -> String {
    format!("{}Read", pascal_case(r.id()))
}

/// The bit-field struct of a register: `inverter_status` → `InverterStatusBits`.
pub(crate) fn bits_type(r: &Register) -> String {
    format!("{}Bits", pascal_case(r.id()))
}

/// The enumeration of a multi-bit field's codes: `InverterStatusSettingError`.
pub(crate) fn field_enum(r: &Register, f: &Field) -> String {
    format!("{}{}", pascal_case(r.id()), pascal_case(&f.id))
}

/// The enumeration of a variant axis: `voltage_class` → `VoltageClass`.
pub(crate) fn axis_enum(axis: &VariantAxis) -> String {
    pascal_case(&axis.id)
}

/// Type names the generator always emits.
pub(crate) const FIXED_TYPES: &[&str] = &[
    "Settings",
    "Drive",
    "Reg",
    "ReadOnly",
    "ReadWrite",
    "WriteOnly",
];

/// `accel_time_1` → `AccelTime1`.
pub fn pascal_case(s: &str) -> String {
    s.split('_')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let mut c = p.chars();
            match c.next() {
                Some(first) => first.to_ascii_uppercase().to_string() + c.as_str(),
                None => String::new(),
            }
        })
        .collect()
}

/// (lowest bit, width) of a field, if it is well formed.
pub fn field_span(f: &Field) -> Option<(u8, u8)> {
    match (f.bit, f.bits) {
        (Some(b), None) if b <= 15 => Some((b, 1)),
        (None, Some([lo, hi])) if lo <= hi && hi <= 15 => Some((lo, hi - lo + 1)),
        _ => None,
    }
}
