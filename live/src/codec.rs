//! Raw words ↔ engineering values by the map, at run time.
//!
//! The same rules the generated code compiles in: decimal scales and raw range checks from the
//! IR, relative scales through the reference's value, selected scales through the selector's
//! code, enumeration codes (listed, or inside a printed code range), bit fields with reserved
//! bits kept 0. Conversions call [`drivemap_runtime::scale`], as generated code does.

use std::fmt;

use drivemap_codegen::ir::{Drive, RawLimits, Register, ValueKind};
use drivemap_codegen::model::{Field, Reference, Scale};
use drivemap_codegen::numbers::Dec;
use drivemap_codegen::validate::field_span;
use drivemap_runtime::ValueError;
use drivemap_runtime::scale::{self, Decimal, RawRange};

use crate::intern::intern;
use crate::settings::LiveSettings;

/// A decoded register value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A plain word (`u16`, or `i16` when signed).
    Word(i64),
    /// An engineering value; `decimals` is the resolution of the scale in use, for display.
    Quantity {
        value: f64,
        unit: String,
        decimals: usize,
    },
    /// An enumeration code and, when the manual lists it, its id and meaning.
    Code {
        code: u16,
        id: Option<String>,
        name: Option<String>,
    },
    /// Bit fields.
    Bits { raw: u16, fields: Vec<FieldValue> },
}

/// One field of a bit-field register.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldValue {
    pub id: String,
    pub name: String,
    pub lsb: u8,
    pub width: u8,
    pub value: u16,
    /// Meaning of a multi-bit field's code, when listed.
    pub label: Option<String>,
}

impl Value {
    /// The number a value stands for (engineering value, word or code).
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Word(w) => Some(*w as f64),
            Value::Quantity { value, .. } => Some(*value),
            Value::Code { code, .. } => Some(f64::from(*code)),
            Value::Bits { raw, .. } => Some(f64::from(*raw)),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Word(w) => write!(f, "{w}"),
            Value::Quantity {
                value,
                unit,
                decimals,
            } => {
                write!(f, "{value:.decimals$}")?;
                if !unit.is_empty() {
                    write!(f, " {unit}")?;
                }
                Ok(())
            }
            Value::Code {
                code,
                name: Some(name),
                ..
            } => write!(f, "{code}: {name}"),
            Value::Code {
                code, name: None, ..
            } => write!(f, "{code} (not listed)"),
            Value::Bits { raw, fields } => {
                let on: Vec<String> = fields
                    .iter()
                    .filter(|fv| fv.value != 0)
                    .map(|fv| match (&fv.label, fv.width) {
                        (_, 1) => fv.id.clone(),
                        (Some(l), _) => format!("{}={l}", fv.id),
                        (None, _) => format!("{}={}", fv.id, fv.value),
                    })
                    .collect();
                write!(f, "{raw:04X}h")?;
                if !on.is_empty() {
                    write!(f, " [{}]", on.join(", "))?;
                }
                Ok(())
            }
        }
    }
}

/// How a register's word converts under given settings.
enum Conversion {
    Decimal {
        scale: Decimal,
        range: RawRange,
    },
    Relative {
        full_scale: f64,
        reference: f64,
        setting: &'static str,
    },
}

fn decimal_of(dec: Dec) -> Decimal {
    Decimal::new(dec.mantissa as i64, dec.exponent)
}

fn raw_range(l: RawLimits) -> RawRange {
    RawRange {
        min: l.min as i64,
        max: l.max as i64,
    }
}

/// The raw range of a fixed-scale register for the chosen variant.
fn variant_range(drive: &Drive, r: &Register, factor: Dec, settings: &LiveSettings) -> RawRange {
    let word = RawLimits::word(r.def.signed);
    let option = r
        .def
        .by_variant
        .keys()
        .find(|k| settings.has_variant(drive, k));
    let (min, max) = match option {
        Some(k) => r.limits_for(k),
        None => r.limits(),
    };
    raw_range(r.raw_limits(factor, min, max).unwrap_or(word))
}

fn label(r: &Register) -> &'static str {
    intern(r.def.param.as_deref().unwrap_or(&r.def.id))
}

fn relative(
    drive: &Drive,
    r: &Register,
    reference: &Reference,
    full_scale: f64,
    settings: &LiveSettings,
) -> Result<Conversion, ValueError> {
    let (key, setting): (&str, &'static str) = match reference {
        Reference::Register(name) => match drive.find(name) {
            Some(t) => (t.id(), label(t)),
            None => (name, intern(name)),
        },
        Reference::External(q) => (&q.external, intern(&q.external)),
    };
    let reference = *settings
        .references
        .get(key)
        .ok_or_else(|| ValueError::MissingSetting {
            register: intern(r.id()),
            setting,
        })?;
    Ok(Conversion::Relative {
        full_scale,
        reference,
        setting,
    })
}

fn conversion(
    drive: &Drive,
    r: &Register,
    settings: &LiveSettings,
) -> Result<(Conversion, usize), ValueError> {
    let one = Dec {
        mantissa: 1,
        exponent: 0,
    };
    match r.kind() {
        ValueKind::Quantity(Scale::Relative(rel)) => Ok((
            relative(drive, r, &rel.relative_to, rel.full_scale, settings)?,
            2,
        )),
        ValueKind::Quantity(Scale::Selected(sel)) => {
            let selector = drive.find(&sel.selected_by);
            let setting = selector
                .map(label)
                .unwrap_or_else(|| intern(&sel.selected_by));
            let code = selector
                .and_then(|s| settings.selectors.get(&s.def.id))
                .copied()
                .ok_or_else(|| ValueError::MissingSetting {
                    register: intern(r.id()),
                    setting,
                })?;
            let case = sel
                .cases
                .iter()
                .find(|c| c.when.contains(&code))
                .ok_or_else(|| ValueError::UnsupportedSetting {
                    register: intern(r.id()),
                    setting,
                    code,
                })?;
            match &case.scale {
                Scale::Factor(f) => {
                    let dec = Dec::from_f64(*f).unwrap_or(one);
                    let range = raw_range(
                        r.raw_limits(dec, case.min, case.max)
                            .unwrap_or(RawLimits::word(r.def.signed)),
                    );
                    Ok((
                        Conversion::Decimal {
                            scale: decimal_of(dec),
                            range,
                        },
                        dec.exponent as usize,
                    ))
                }
                Scale::Relative(rel) => Ok((
                    relative(drive, r, &rel.relative_to, rel.full_scale, settings)?,
                    2,
                )),
                Scale::Selected(_) => Err(ValueError::UnsupportedSetting {
                    register: intern(r.id()),
                    setting,
                    code,
                }),
            }
        }
        _ => {
            let dec = r.factor().unwrap_or(one);
            Ok((
                Conversion::Decimal {
                    scale: decimal_of(dec),
                    range: variant_range(drive, r, dec, settings),
                },
                dec.exponent as usize,
            ))
        }
    }
}

fn field_values(fields: &[Field], raw: u16) -> Vec<FieldValue> {
    fields
        .iter()
        .filter_map(|f| {
            let (lsb, width) = field_span(f)?;
            let mask = ((1u32 << width) - 1) as u16;
            let value = (raw >> lsb) & mask;
            let label = f
                .values
                .iter()
                .find(|v| v.value == value)
                .map(|v| v.name.clone());
            Some(FieldValue {
                id: f.id.clone(),
                name: f.name.clone(),
                lsb,
                width,
                value,
                label,
            })
        })
        .collect()
}

/// The mask of bits that carry a field.
pub fn field_mask(fields: &[Field]) -> u16 {
    fields
        .iter()
        .filter_map(field_span)
        .fold(0u16, |m, (lsb, width)| {
            m | ((((1u32 << width) - 1) << lsb) as u16)
        })
}

/// Decodes a raw word read from the drive.
pub fn decode(
    drive: &Drive,
    r: &Register,
    raw: u16,
    settings: &LiveSettings,
) -> Result<Value, ValueError> {
    match r.kind() {
        ValueKind::Word => Ok(Value::Word(scale::word_to_int(raw, r.def.signed))),
        ValueKind::Enum(values) => {
            let v = values.iter().find(|v| v.value == raw);
            Ok(Value::Code {
                code: raw,
                id: v.map(|v| v.id.clone()),
                name: v.map(|v| v.name.clone()),
            })
        }
        ValueKind::Bits(fields) => {
            let raw = raw & field_mask(fields);
            Ok(Value::Bits {
                raw,
                fields: field_values(fields, raw),
            })
        }
        ValueKind::Quantity(_) | ValueKind::UnitQuantity => {
            let unit = r.def.unit.clone().unwrap_or_default();
            let (conv, decimals) = conversion(drive, r, settings)?;
            let value = match conv {
                Conversion::Decimal { scale: s, .. } => scale::decode_decimal(raw, r.def.signed, s),
                Conversion::Relative {
                    full_scale,
                    reference,
                    ..
                } => scale::decode_relative(raw, r.def.signed, full_scale, reference),
            };
            Ok(Value::Quantity {
                value,
                unit,
                decimals,
            })
        }
    }
}

/// Encodes an engineering number (a value in the register's unit, a code, or a raw word for
/// words and bit fields), checking the range first.
pub fn encode(
    drive: &Drive,
    r: &Register,
    value: f64,
    settings: &LiveSettings,
) -> Result<u16, ValueError> {
    let id = intern(r.id());
    let unit = intern(r.def.unit.as_deref().unwrap_or(""));
    match r.kind() {
        ValueKind::Word => {
            let one = Dec {
                mantissa: 1,
                exponent: 0,
            };
            if value.fract() != 0.0 || !value.is_finite() {
                return Err(ValueError::NotFinite {
                    register: id,
                    value,
                });
            }
            scale::encode_int(
                id,
                unit,
                value as i64,
                variant_range(drive, r, one, settings),
            )
        }
        ValueKind::Enum(values) => {
            let listed = values.iter().any(|v| f64::from(v.value) == value);
            let in_range = value.fract() == 0.0
                && (r.def.min.is_some() || r.def.max.is_some())
                && r.def.min.is_none_or(|m| value >= m)
                && r.def.max.is_none_or(|m| value <= m);
            if listed || in_range {
                Ok(value as u16)
            } else {
                Err(ValueError::UnknownCode {
                    register: id,
                    code: if (0.0..=65535.0).contains(&value) {
                        value as u16
                    } else {
                        u16::MAX
                    },
                })
            }
        }
        ValueKind::Bits(fields) => {
            let mask = field_mask(fields);
            if value.fract() != 0.0 || !(0.0..=65535.0).contains(&value) {
                return Err(ValueError::NotFinite {
                    register: id,
                    value,
                });
            }
            let raw = value as u16;
            if raw & !mask != 0 {
                return Err(ValueError::OutOfRange {
                    register: id,
                    value,
                    min: 0.0,
                    max: f64::from(mask),
                    unit: "(reserved bits set)",
                });
            }
            Ok(raw)
        }
        ValueKind::Quantity(_) | ValueKind::UnitQuantity => match conversion(drive, r, settings)?.0
        {
            Conversion::Decimal { scale: s, range } => {
                scale::encode_decimal(id, unit, value, s, range)
            }
            Conversion::Relative {
                full_scale,
                reference,
                setting,
            } => scale::encode_relative(
                id,
                setting,
                unit,
                value,
                full_scale,
                reference,
                RawRange::word(r.def.signed),
            ),
        },
    }
}

/// Why a value typed by a user cannot be written.
#[derive(Debug, Clone, PartialEq)]
pub enum InputError {
    /// The text is not a value of this register; the message says what is expected.
    Parse(String),
    /// The value does not convert (out of range, unknown code, missing setting).
    Value(ValueError),
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InputError::Parse(m) => f.write_str(m),
            InputError::Value(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for InputError {}

fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    if let Some(hex) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        return u16::from_str_radix(hex, 16).ok().map(f64::from);
    }
    if let Some(hex) = t.strip_suffix('h').or_else(|| t.strip_suffix('H')) {
        if hex.chars().all(|c| c.is_ascii_hexdigit()) && !hex.is_empty() {
            return u16::from_str_radix(hex, 16).ok().map(f64::from);
        }
    }
    t.parse::<f64>().ok()
}

/// Fields of a bit-field register as a user names them: the bits they set and the bits they
/// cover. Bits outside `mask` were not named.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldInput {
    pub value: u16,
    pub mask: u16,
}

/// Parses `run,reverse` or `run=1,direction=reverse` (a field's value by number, id or printed
/// meaning, `on`/`off`, `true`/`false`) for a bit-field register; `None` for a plain number,
/// which is the whole word.
pub fn field_input(r: &Register, text: &str) -> Result<Option<FieldInput>, InputError> {
    match r.kind() {
        ValueKind::Bits(fields) if parse_number(text).is_none() => {
            parse_fields(r, fields, text.trim()).map(Some)
        }
        _ => Ok(None),
    }
}

fn parse_fields(r: &Register, fields: &[Field], text: &str) -> Result<FieldInput, InputError> {
    let mut input = FieldInput { value: 0, mask: 0 };
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, v) = part.split_once('=').unwrap_or((part, "1"));
        let name = name.trim();
        let f = fields.iter().find(|f| f.id == name).ok_or_else(|| {
            let ids: Vec<&str> = fields.iter().map(|f| f.id.as_str()).collect();
            InputError::Parse(format!(
                "`{name}` is not a field of {}; fields: {}",
                r.id(),
                ids.join(", ")
            ))
        })?;
        let (lsb, width) = field_span(f).unwrap_or((0, 1));
        let v = v.trim();
        let code = f
            .values
            .iter()
            .find(|e| e.id == v || e.name.eq_ignore_ascii_case(v))
            .map(|e| e.value)
            .or_else(|| match v.to_ascii_lowercase().as_str() {
                "true" | "on" => Some(1),
                "false" | "off" => Some(0),
                _ => v.parse::<u16>().ok(),
            })
            .ok_or_else(|| {
                let known: Vec<String> = f
                    .values
                    .iter()
                    .map(|e| format!("{} ({})", e.id, e.name))
                    .collect();
                InputError::Parse(if known.is_empty() {
                    format!("`{v}` is not a value of field {name}; give a number, on or off")
                } else {
                    format!(
                        "`{v}` is not a value of field {name}; values: {}",
                        known.join(", ")
                    )
                })
            })?;
        if u32::from(code) >= 1u32 << width {
            return Err(InputError::Parse(format!(
                "{code} does not fit field {name} ({width} bit(s))"
            )));
        }
        let mask = (((1u32 << width) - 1) << lsb) as u16;
        input.value = (input.value & !mask) | (code << lsb);
        input.mask |= mask;
    }
    Ok(input)
}

/// Parses a value as a user types it — `48`, `48.5 Hz`, an enumeration code, id or printed
/// meaning, bit fields as `run,reverse` or `run=1,mode=2`, or a raw `0x0003` — and encodes it.
pub fn parse_value(
    drive: &Drive,
    r: &Register,
    text: &str,
    settings: &LiveSettings,
) -> Result<u16, InputError> {
    let text = text.trim();
    let value = match r.kind() {
        ValueKind::Enum(values) => {
            let lower = text.to_ascii_lowercase();
            match values
                .iter()
                .find(|v| v.id == lower || v.name.eq_ignore_ascii_case(text))
            {
                Some(v) => f64::from(v.value),
                None => parse_number(text).ok_or_else(|| {
                    let ids: Vec<&str> = values.iter().map(|v| v.id.as_str()).collect();
                    InputError::Parse(format!(
                        "`{text}` is not a code of {}; expected a number or one of: {}",
                        r.id(),
                        ids.join(", ")
                    ))
                })?,
            }
        }
        ValueKind::Bits(fields) => match parse_number(text) {
            Some(n) => n,
            None => f64::from(parse_fields(r, fields, text)?.value),
        },
        _ => {
            let unit = r.def.unit.as_deref().unwrap_or("");
            let number = text
                .strip_suffix(unit)
                .filter(|_| !unit.is_empty())
                .unwrap_or(text);
            parse_number(number).ok_or_else(|| {
                InputError::Parse(if unit.is_empty() {
                    format!("`{text}` is not a number")
                } else {
                    format!("`{text}` is not a number of {unit}")
                })
            })?
        }
    };
    encode(drive, r, value, settings).map_err(InputError::Value)
}
