//! Raw words ↔ engineering values by the map, at run time.
//!
//! The same plan the generated code holds as `const` data ([`Map::plan`], lowered once per
//! map), converted by the same implementation ([`RegisterPlan::decode_number`] and its
//! siblings in the vocabulary crate): this module only turns the results into values a tool
//! prints and parses what a user types.

use std::fmt;

use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::core::plan::{Conversion, Field, RegisterPlan, ValueShape};
use drivemap_runtime::core::ratio::Fraction;
use drivemap_runtime::core::scale::{Rounding, ValueError};

use crate::settings::{LiveSettings, View};

/// A decoded register value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A plain word (`u16`, or `i16` when signed).
    Word(i64),
    /// An engineering value; `decimals` is the resolution of the scale in use, for display.
    /// `exact` is its exact value for a ratio scale ("60.0 Hz = 3600"), whose steps are not
    /// decimals: displayed by [`Fraction`]'s rule (the decimal when finite, else the fraction
    /// and six decimals), `None` for other scales.
    Quantity {
        /// The value in `unit`.
        value: f64,
        /// The unit as the manual prints it (empty for none).
        unit: String,
        /// The decimals the scale in use resolves, for display.
        decimals: usize,
        /// The exact value under a ratio scale; `None` for other scales.
        exact: Option<Fraction>,
    },
    /// An enumeration code and, when the manual lists it, its id and meaning.
    Code {
        /// The code read.
        code: u16,
        /// The code's id in the map, when the manual lists the code.
        id: Option<String>,
        /// The code's meaning as the manual prints it, when listed.
        name: Option<String>,
    },
    /// A coil or discrete input: on or off.
    Bit(bool),
    /// Bit fields.
    Bits {
        /// The whole word.
        raw: u16,
        /// Each field of the map, in the map's order.
        fields: Vec<FieldValue>,
    },
    /// Text from a string register (`string:`), as read, padding dropped: untrusted bytes,
    /// shown quoted, escaped and shortened ([`Value::text`] for the whole text, escaped).
    Text(Vec<u8>),
}

/// The most characters of a text [`Value`]'s `Display` shows (a table cell, a log line); the
/// rest is cut and marked `…`.
pub const TEXT_SHOWN: usize = 64;

/// One field of a bit-field register.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldValue {
    /// The field's id in the map.
    pub id: String,
    /// The field's name as the manual prints it.
    pub name: String,
    /// Its lowest bit.
    pub lsb: u8,
    /// Its width in bits.
    pub width: u8,
    /// Its value, shifted down to bit 0.
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
            Value::Bit(on) => Some(f64::from(u8::from(*on))),
            Value::Text(_) => None,
        }
    }

    /// The whole text of a string, every byte that is not printable ASCII escaped (`\xNN`;
    /// `\\` and `\"` for a backslash and a quote), unquoted: what a record carries. `None`
    /// for other values.
    pub fn text(&self) -> Option<String> {
        let Value::Text(bytes) = self else {
            return None;
        };
        let mut out = String::new();
        let _ = drivemap_runtime::core::text::write_escaped(&mut out, bytes);
        Some(out)
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Text(bytes) => {
                f.write_str("\"")?;
                drivemap_runtime::core::text::write_escaped(
                    f,
                    &bytes[..bytes.len().min(TEXT_SHOWN)],
                )?;
                f.write_str("\"")?;
                if bytes.len() > TEXT_SHOWN {
                    f.write_str("…")?;
                }
                Ok(())
            }
            Value::Word(w) => write!(f, "{w}"),
            Value::Bit(true) => f.write_str("1 (on)"),
            Value::Bit(false) => f.write_str("0 (off)"),
            Value::Quantity {
                exact: Some(exact),
                unit,
                ..
            } => {
                write!(f, "{exact}")?;
                if !unit.is_empty() {
                    write!(f, " {unit}")?;
                }
                Ok(())
            }
            Value::Quantity {
                value,
                unit,
                decimals,
                exact: None,
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

/// The plan of `r` and a view of `settings` in the plan's slots.
fn planned<'a>(
    drive: &'a Map,
    r: RegisterRef<'_>,
    settings: &'a LiveSettings,
) -> (&'static RegisterPlan, View<'a>) {
    (r.plan(), settings.view(drive))
}

fn field_values(fields: &[Field], raw: u16) -> Vec<FieldValue> {
    fields
        .iter()
        .map(|f| {
            let value = f.get(raw);
            FieldValue {
                id: f.id.to_owned(),
                name: f.name.to_owned(),
                lsb: f.lsb,
                width: f.width,
                value,
                label: f
                    .values
                    .iter()
                    .find(|v| v.code == value)
                    .map(|v| v.name.to_owned()),
            }
        })
        .collect()
}

/// Decodes the words read from a string register (`string:`, all its registers) in the map's
/// byte order, trailing NUL and space padding dropped; an error for any other register.
pub fn decode_text(plan: &RegisterPlan, words: &[u16]) -> Result<Value, ValueError> {
    let Conversion::Text { order } = plan.conversion else {
        return Err(ValueError::Text {
            register: plan.info.id,
        });
    };
    let mut bytes = vec![0u8; 2 * words.len()];
    let len = drivemap_runtime::core::text::decode(words, order, &mut bytes);
    bytes.truncate(len);
    Ok(Value::Text(bytes))
}

/// Decodes a raw value read from the drive (its word, or a 32-bit pair's words joined in the
/// map's order: `plan.info.width.join(words)`), by the register's plan. A register whose read
/// meaning differs from its write form (`read_values`, [`RegisterPlan::read_values`]) gives its
/// read code and meaning; [`decode_written`] gives the write form of a value.
pub fn decode(
    drive: &Map,
    r: RegisterRef<'_>,
    raw: u32,
    settings: &LiveSettings,
) -> Result<Value, ValueError> {
    let plan = r.plan();
    if !plan.read_values.is_empty() {
        // Read meanings are codes of one word (validation refuses them on a pair).
        let raw = raw as u16;
        let label = plan.read_label(raw);
        return Ok(Value::Code {
            code: raw,
            id: label.map(|l| l.id.to_owned()),
            name: label.map(|l| l.name.to_owned()),
        });
    }
    decode_written(drive, r, raw, settings)
}

/// Decodes a word as a write means it (the register's conversion): what `drivemap write`
/// reports it wrote. The same as [`decode`] except for registers with `read_values`.
pub fn decode_written(
    drive: &Map,
    r: RegisterRef<'_>,
    raw: u32,
    settings: &LiveSettings,
) -> Result<Value, ValueError> {
    let (plan, view) = planned(drive, r, settings);
    if plan.info.table.is_bits() {
        return Ok(Value::Bit(raw != 0));
    }
    match plan.conversion.shape() {
        // A string's value is its words' ([`decode_text`]), not one raw number.
        ValueShape::Text { .. } => Err(ValueError::Text {
            register: plan.info.id,
        }),
        ValueShape::Word { .. } => Ok(Value::Word(plan.int(raw))),
        ValueShape::Codes(_) => {
            let raw = raw as u16;
            let label = plan.label(raw);
            Ok(Value::Code {
                code: raw,
                id: label.map(|l| l.id.to_owned()),
                name: label.map(|l| l.name.to_owned()),
            })
        }
        ValueShape::Bits { mask, fields } => {
            let raw = raw as u16 & mask;
            Ok(Value::Bits {
                raw,
                fields: field_values(fields, raw),
            })
        }
        ValueShape::Number => {
            let scale = plan.scale(&view).transpose()?;
            Ok(Value::Quantity {
                value: plan.decode_number(raw, &view)?,
                unit: plan.unit.to_owned(),
                decimals: scale.map_or(0, |s| s.decimals()),
                exact: scale.and_then(|s| s.exact(plan.int(raw))),
            })
        }
    }
}

/// Encodes an engineering number (a value in the register's unit, a code, or a raw word for
/// words and bit fields), checking the range first, by the register's plan: the raw value (a
/// pair's goes out as `plan.info.width.split(raw)`).
pub fn encode(
    drive: &Map,
    r: RegisterRef<'_>,
    value: f64,
    settings: &LiveSettings,
) -> Result<u32, ValueError> {
    encode_with(drive, r, value, settings, Rounding::Exact)
}

/// [`encode`] with a choice for a number between two steps of the register: refused
/// ([`Rounding::Exact`], as `encode`) or the nearest step ([`Rounding::Nearest`]); limits are
/// checked on the value given.
pub fn encode_with(
    drive: &Map,
    r: RegisterRef<'_>,
    value: f64,
    settings: &LiveSettings,
    rounding: Rounding,
) -> Result<u32, ValueError> {
    let (plan, view) = planned(drive, r, settings);
    plan.encode_number_with(value, &view, rounding)
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

/// Whether `text` is written as hexadecimal (`0x32`, `0032h`).
fn is_hex(text: &str) -> bool {
    let t = text.trim();
    t.starts_with("0x")
        || t.starts_with("0X")
        || t.strip_suffix(['h', 'H'])
            .is_some_and(|h| !h.is_empty() && h.chars().all(|c| c.is_ascii_hexdigit()))
}

/// `text` as a message quotes it: escaped, and at most 40 characters (then `...`).
pub fn shorten(text: &str) -> String {
    let escaped: String = text.escape_debug().collect();
    match escaped.char_indices().nth(40) {
        Some((i, _)) => format!("{}...", &escaped[..i]),
        None => escaped,
    }
}

fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    if let Some(hex) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        return u32::from_str_radix(hex, 16).ok().map(f64::from);
    }
    if let Some(hex) = t.strip_suffix('h').or_else(|| t.strip_suffix('H'))
        && hex.chars().all(|c| c.is_ascii_hexdigit())
        && !hex.is_empty()
    {
        return u32::from_str_radix(hex, 16).ok().map(f64::from);
    }
    t.parse::<f64>().ok()
}

/// Fields of a bit-field register as a user names them: the bits they set and the bits they
/// cover. Bits outside `mask` were not named.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldInput {
    /// The bits the named fields set, in place in the word.
    pub value: u16,
    /// The bits the named fields cover.
    pub mask: u16,
}

/// Parses `run,reverse` or `run=1,direction=reverse` (a field's value by number, id or printed
/// meaning, `on`/`off`, `true`/`false`) for a bit-field register; `None` for a plain number,
/// which is the whole word.
pub fn field_input(
    drive: &Map,
    r: RegisterRef<'_>,
    text: &str,
) -> Result<Option<FieldInput>, InputError> {
    debug_assert!(std::ptr::eq(drive, r.map()), "a register of another map");
    match &r.plan().conversion {
        Conversion::Bits { fields, .. } if parse_number(text).is_none() => {
            parse_fields(r, fields, text.trim()).map(Some)
        }
        _ => Ok(None),
    }
}

fn parse_fields(
    r: RegisterRef<'_>,
    fields: &[Field],
    text: &str,
) -> Result<FieldInput, InputError> {
    let mut input = FieldInput { value: 0, mask: 0 };
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, v) = part.split_once('=').unwrap_or((part, "1"));
        let name = name.trim();
        let f = fields.iter().find(|f| f.id == name).ok_or_else(|| {
            let ids: Vec<&str> = fields.iter().map(|f| f.id).collect();
            InputError::Parse(format!(
                "`{name}` is not a field of {}; fields: {}",
                r.id(),
                ids.join(", ")
            ))
        })?;
        let (lsb, width) = (f.lsb, f.width);
        let v = v.trim();
        let code = f
            .values
            .iter()
            .find(|e| e.id == v || e.name.eq_ignore_ascii_case(v))
            .map(|e| e.code)
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
    if input.mask == 0 {
        // `,` names nothing: never taken as "write back what the drive holds".
        let ids: Vec<&str> = fields.iter().map(|f| f.id).collect();
        return Err(InputError::Parse(format!(
            "`{}` names no field of {}: name at least one ({})",
            shorten(text),
            r.id(),
            ids.join(", ")
        )));
    }
    Ok(input)
}

/// Parses a value as a user types it — `48`, `48.5 Hz`, an enumeration code, id or printed
/// meaning, bit fields as `run,reverse` or `run=1,mode=2`, or a raw `0x0003` — and encodes it.
pub fn parse_value(
    drive: &Map,
    r: RegisterRef<'_>,
    text: &str,
    settings: &LiveSettings,
) -> Result<u32, InputError> {
    parse_value_with(drive, r, text, settings, Rounding::Exact)
}

/// [`parse_value`] with a choice for a number between two steps of the register (`--round`).
/// An empty text is refused: it is no value.
pub fn parse_value_with(
    drive: &Map,
    r: RegisterRef<'_>,
    text: &str,
    settings: &LiveSettings,
    rounding: Rounding,
) -> Result<u32, InputError> {
    let text = text.trim();
    if text.is_empty() {
        return Err(InputError::Parse(format!("no value given for {}", r.id())));
    }
    let plan = r.plan();
    if plan.info.table.is_bits() {
        let on = match text.to_ascii_lowercase().as_str() {
            "1" | "on" | "true" => 1.0,
            "0" | "off" | "false" => 0.0,
            _ => {
                return Err(InputError::Parse(format!(
                    "`{}` is not a state of {}, a {}: write on or off (1 or 0)",
                    shorten(text),
                    r.id(),
                    plan.info.table.item()
                )));
            }
        };
        return encode_with(drive, r, on, settings, rounding).map_err(InputError::Value);
    }
    let value = match &plan.conversion {
        Conversion::Enum { values, .. } => {
            let lower = text.to_ascii_lowercase();
            match values
                .iter()
                .find(|v| v.id == lower || v.name.eq_ignore_ascii_case(text))
            {
                Some(v) => f64::from(v.code),
                None => {
                    let codes = || {
                        values
                            .iter()
                            .map(|v| format!("{} ({})", v.code, v.id))
                            .collect::<Vec<_>>()
                            .join(", ")
                    };
                    let n = parse_number(text).ok_or_else(|| {
                        InputError::Parse(format!(
                            "`{}` is not a code of {}; expected a number or one of: {}",
                            shorten(text),
                            r.id(),
                            codes()
                        ))
                    })?;
                    // A code is a whole number of one word: `-1` is no code (not code 0).
                    if !(n.fract() == 0.0 && (0.0..=f64::from(u16::MAX)).contains(&n)) {
                        return Err(InputError::Parse(format!(
                            "`{}` is not a code of {}: the codes the manual lists are {}",
                            shorten(text),
                            r.id(),
                            codes()
                        )));
                    }
                    n
                }
            }
        }
        Conversion::Bits { fields, .. } => match parse_number(text) {
            Some(n) => n,
            None => f64::from(parse_fields(r, fields, text)?.value),
        },
        _ => {
            let unit = plan.unit;
            let number = text
                .strip_suffix(unit)
                .filter(|_| !unit.is_empty())
                .unwrap_or(text);
            if let (Conversion::Ratio { .. }, Rounding::Exact) = (&plan.conversion, rounding) {
                // A ratio's counts are compared with the value as typed (`59.9`, `3599/60`),
                // exactly: no float stands between the text and the count.
                if let Some(exact) = Fraction::parse(number) {
                    let (plan, view) = planned(drive, r, settings);
                    return plan.encode_exact(exact, &view).map_err(InputError::Value);
                }
            }
            // A quantity is a decimal number in its unit: `0032h` or `0x32` would be read as
            // 50 of the unit, which is not what a raw word printed as `0032h` means.
            let raw_word = matches!(plan.conversion, Conversion::Word { .. }) && unit.is_empty();
            if !raw_word && is_hex(number) {
                return Err(InputError::Parse(format!(
                    "`{}` is hexadecimal, but {} takes a decimal number{}: hex is only for words, codes and bit fields",
                    shorten(text),
                    r.id(),
                    if unit.is_empty() {
                        String::new()
                    } else {
                        format!(" of {unit}")
                    }
                )));
            }
            parse_number(number).ok_or_else(|| {
                InputError::Parse(if unit.is_empty() {
                    format!("`{}` is not a number", shorten(text))
                } else {
                    format!("`{}` is not a number of {unit}", shorten(text))
                })
            })?
        }
    };
    encode_with(drive, r, value, settings, rounding).map_err(InputError::Value)
}
