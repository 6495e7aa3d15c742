//! The Rust names the generator gives to map items. Validation uses the same functions to find
//! collisions before emission.

use crate::ir::Register;
use crate::model::{Field, VariantAxis};
use crate::validate::pascal_case;

/// The zero-sized type of a register: `accel_time_1` → `AccelTime1`.
pub fn register_type(r: &Register) -> String {
    pascal_case(r.id())
}

/// The enumeration of a register's codes: `run_source` → `RunSourceValue`.
pub fn value_enum(r: &Register) -> String {
    format!("{}Value", pascal_case(r.id()))
}

/// The bit-field struct of a register: `inverter_status` → `InverterStatusBits`.
pub fn bits_type(r: &Register) -> String {
    format!("{}Bits", pascal_case(r.id()))
}

/// The enumeration of a multi-bit field's codes: `InverterStatusSettingError`.
pub fn field_enum(r: &Register, f: &Field) -> String {
    format!("{}{}", pascal_case(r.id()), pascal_case(&f.id))
}

/// The enumeration of a variant axis: `voltage_class` → `VoltageClass`.
pub fn axis_enum(axis: &VariantAxis) -> String {
    pascal_case(&axis.id)
}

/// Type names the generator always emits.
pub const FIXED_TYPES: &[&str] = &["Settings"];
