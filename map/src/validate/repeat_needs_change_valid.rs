//! `repeat_needs_change` (on a register or its group): the register is writable, and the value
//! written in between is one the register accepts, since writers send it through the same write
//! gate as any value: a listed code (or one inside the printed code range) of an enumeration, a
//! word without reserved bits of a bit-field register, a whole number of increments inside the
//! limits of every variant of a quantity or word, and 0 where the scale depends on a setting
//! (0 is 0 in every scale; another value would need the settings to encode).

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register, ValueKind};
use crate::names::field_span;
use drivemap_core::scale::{RawRange, raw_of};

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        let Some((rule, path)) = &r.repeat_needs_change else {
            continue;
        };
        let rid = Some(r.id());
        if !r.writable() {
            out.push(drive.error(
                path,
                rid,
                "`repeat_needs_change` on a read-only register: only a written value can need a change before it is repeated",
            ));
            continue;
        }
        if let Err(why) = legal(r, rule.between) {
            out.push(drive.error(
                &path.key("between"),
                rid,
                format!(
                    "`repeat_needs_change.between: {}` is not a value `{}` accepts ({why}); writers send it through the write gate, so give a legal value",
                    rule.between,
                    r.id()
                ),
            ));
        }
    }
}

/// Whether `v` may be written to `r`, and why not.
fn legal(r: &Register, v: f64) -> Result<(), Illegal> {
    if !v.is_finite() {
        return Err(Illegal::NotFinite);
    }
    let d = &r.def;
    match r.kind() {
        ValueKind::Enum(values) => {
            let listed = values.iter().any(|x| f64::from(x.value) == v);
            let in_range = v.fract() == 0.0
                && (d.min.is_some() || d.max.is_some())
                && d.min.unwrap_or(0.0) <= v
                && v <= d.max.unwrap_or(65535.0);
            if listed || in_range {
                Ok(())
            } else {
                let codes: Vec<String> = values.iter().map(|x| x.value.to_string()).collect();
                Err(Illegal::NotACode {
                    codes: codes.join(", "),
                })
            }
        }
        ValueKind::Bits(fields) => {
            let mask = fields
                .iter()
                .filter_map(field_span)
                .fold(0u32, |m, (lsb, w)| m | (((1u32 << w) - 1) << lsb));
            if v.fract() != 0.0 || !(0.0..=65535.0).contains(&v) {
                Err(Illegal::NotAWord)
            } else if (v as u32) & !mask != 0 {
                Err(Illegal::ReservedBits { mask })
            } else {
                Ok(())
            }
        }
        // Refused on text by `strings_valid`; no number is legal.
        ValueKind::Text(_) => Err(Illegal::NotAWord),
        ValueKind::Quantity(_) | ValueKind::UnitQuantity | ValueKind::Word => {
            let Some(factor) = r.factor() else {
                return if v == 0.0 {
                    Ok(())
                } else {
                    Err(Illegal::ScaleFromSetting)
                };
            };
            let Some(raw) = raw_of(v, factor) else {
                return Err(Illegal::NotAStep);
            };
            let word = RawRange::word(d.signed);
            if raw < i128::from(word.min) || raw > i128::from(word.max) {
                return Err(Illegal::OutsideWord);
            }
            let mut limits = vec![(None, r.limits())];
            for k in d.by_variant.keys() {
                limits.push((Some(k.as_str()), r.limits_for(k)));
            }
            for (variant, (min, max)) in limits {
                if min.is_some_and(|m| v < m) || max.is_some_and(|m| v > m) {
                    let of = variant
                        .map(|k| format!(" of variant {k}"))
                        .unwrap_or_default();
                    return Err(Illegal::OutsideRange {
                        of,
                        min: min.map_or("-".into(), |m| m.to_string()),
                        max: max.map_or("-".into(), |m| m.to_string()),
                    });
                }
            }
            Ok(())
        }
    }
}

/// Why a `between` value is not one the register accepts (said inside the diagnostic at
/// `repeat_needs_change.between`).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
enum Illegal {
    #[error("not a finite number")]
    NotFinite,
    #[error("not one of its codes {codes}")]
    NotACode { codes: String },
    #[error("not a 16-bit word")]
    NotAWord,
    #[error("it sets reserved bits (fields cover {mask:04X}h)")]
    ReservedBits { mask: u32 },
    #[error("its scale depends on a setting, so only 0 converts without it")]
    ScaleFromSetting,
    #[error("not a whole number of its increments")]
    NotAStep,
    #[error("outside its word")]
    OutsideWord,
    /// `of` is empty for the base limits, else " of variant `<k>`".
    #[error("outside the range{of} {min}..={max}")]
    OutsideRange {
        of: String,
        min: String,
        max: String,
    },
}
