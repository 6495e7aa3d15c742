//! Conversions between raw register words and engineering values.
//!
//! Engineering values are `f64`. Raw words are integers in units of the register's increment
//! ("n019 reads 600 for 60.0 s"). Decimal scales are kept as an integer mantissa and a power of
//! ten, never as a binary fraction: decoding divides an exact integer by an exact power of ten
//! (one correctly rounded operation), encoding multiplies back and rounds to the nearest integer.
//! Every raw value of a 16-bit register therefore round-trips exactly (6000 × 0.1 s decodes to
//! the `f64` nearest 600.0 and encodes back to 6000); the test below checks all 65536 words for
//! every decimal scale the maps use.
//!
//! Range checks compare raw integers: the generator converts the manual's limits to raw words
//! with exact decimal arithmetic, so a limit is never missed by a rounding error.

use core::fmt;

use crate::width::Width;

/// Why a value cannot be converted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ValueError {
    /// The register holds text ([`crate::text`]): it has no number to give or take.
    #[error("{register} holds text, not a number")]
    Text {
        /// The register's id.
        register: &'static str,
    },
    /// The value lies outside the register's range for the drive's variant.
    #[error("{register}: {value} {unit} is out of range {min} ..= {max} {unit}")]
    OutOfRange {
        /// The register's id.
        register: &'static str,
        /// The value given.
        value: f64,
        /// The lowest value of the range.
        min: f64,
        /// The highest value of the range.
        max: f64,
        /// The value's unit.
        unit: &'static str,
    },
    /// The manual prints no range for the register, and the value does not fit its word (or
    /// its pair of words: `bits` is 16 or 32).
    #[error(
        "{register}: {value} {unit} does not fit the register's {bits}-bit {} ({min} ..= {max} {unit}); the manual prints no range for it",
        word_or_value(*.bits)
    )]
    WordOverflow {
        /// The register's id.
        register: &'static str,
        /// The bits of the register's value: 16 or 32.
        bits: u32,
        /// The value given.
        value: f64,
        /// The lowest value that fits.
        min: f64,
        /// The highest value that fits.
        max: f64,
        /// The value's unit.
        unit: &'static str,
    },
    /// The value lies above a limit the manual states through another quantity (a reference
    /// at most the maximum output frequency n011).
    #[error("{register}: {value} {unit} is above {max} {unit}, {percent} % of {reference}")]
    AboveLimit {
        /// The register's id.
        register: &'static str,
        /// The value given.
        value: f64,
        /// The limit.
        max: f64,
        /// The value's unit.
        unit: &'static str,
        /// The limit as a percentage of `reference`.
        percent: f64,
        /// The quantity the limit is stated through.
        reference: &'static str,
    },
    /// A value that is not a whole number of the register's steps: sent as given or refused,
    /// never rounded silently ([`Rounding::Nearest`] asks for the nearest).
    #[error(
        "{register}: {value} {unit} is between {below} and {above} {unit}; the register counts {step} {unit}"
    )]
    NotAStep {
        /// The register's id.
        register: &'static str,
        /// The value given.
        value: f64,
        /// The register's value just below.
        below: f64,
        /// The register's value just above.
        above: f64,
        /// The register's step.
        step: f64,
        /// The value's unit.
        unit: &'static str,
    },
    /// A value that is not a whole number of counts of a ratio scale ("60.0 Hz = 3600"): sent
    /// as given or refused, never rounded silently. `below` and `below + 1` are the two counts
    /// around it; the message gives their exact values and the step by `ratio` (printed as
    /// decimals where their expansion is finite, see [`crate::ratio::Fraction`]).
    #[error(
        "{register}: {value} {unit} is not a whole number of counts (the register counts {} {unit}); the nearest legal values are {} and {} {unit}",
        .ratio.step(),
        .ratio.exact(*.below),
        .ratio.exact(*.below + 1)
    )]
    NotACount {
        /// The register's id.
        register: &'static str,
        /// The value given.
        value: f64,
        /// The count just below the value (the one above is `below + 1`).
        below: i64,
        /// The register's scale.
        ratio: crate::ratio::Ratio,
        /// The value's unit.
        unit: &'static str,
    },
    /// A plain word given a fraction.
    #[error("{register}: {value} is not a whole number")]
    NotWhole {
        /// The register's id.
        register: &'static str,
        /// The value given.
        value: f64,
    },
    /// NaN or infinite.
    #[error("{register}: {value} is not a finite number")]
    NotFinite {
        /// The register's id.
        register: &'static str,
        /// The value given.
        value: f64,
    },
    /// An enumeration value that the manual does not list cannot be written.
    #[error("{register}: code {code} is not one of the codes the manual lists")]
    UnknownCode {
        /// The register's id.
        register: &'static str,
        /// The code given.
        code: u16,
    },
    /// The conversion depends on a setting the caller has not provided.
    #[error(
        "{register}: converting needs the value of {setting}; read it from the drive or set it in Settings"
    )]
    MissingSetting {
        /// The register's id.
        register: &'static str,
        /// The setting the conversion needs (the parameter number when printed).
        setting: &'static str,
    },
    /// The register's limit through another quantity cannot be checked: the quantity is not
    /// known. A limit that cannot be checked refuses the value.
    #[error(
        "{register}: its limit is a percentage of {setting}, which is not known; read it from the drive or set it in Settings (a value whose limit cannot be checked is not sent)"
    )]
    LimitNotKnown {
        /// The register's id.
        register: &'static str,
        /// The quantity the limit is stated through.
        setting: &'static str,
    },
    /// A selecting parameter holds a code for which the map defines no scale.
    #[error("{register}: {setting} = {code} selects no scale the manual defines")]
    UnsupportedSetting {
        /// The register's id.
        register: &'static str,
        /// The selecting parameter.
        setting: &'static str,
        /// The code it holds.
        code: u16,
    },
    /// A reference quantity is zero or negative, so a relative value cannot be computed.
    #[error("{register}: reference {setting} = {value} cannot scale a relative value")]
    BadReference {
        /// The register's id.
        register: &'static str,
        /// The reference quantity.
        setting: &'static str,
        /// Its value.
        value: f64,
    },
}

fn word_or_value(bits: u32) -> &'static str {
    if bits > 16 { "value" } else { "word" }
}

/// A decimal scale factor: engineering = raw × `mantissa` / 10^`exponent`.
///
/// `0.1` is `Decimal { mantissa: 1, exponent: 1 }`; `5` is `Decimal { mantissa: 5, exponent: 0 }`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Decimal {
    /// The digits.
    pub mantissa: i64,
    /// The power of ten that divides them.
    pub exponent: u32,
}

impl Decimal {
    /// The factor 1.
    pub const ONE: Decimal = Decimal {
        mantissa: 1,
        exponent: 0,
    };

    /// A scale of `mantissa` × 10^-`exponent`.
    pub const fn new(mantissa: i64, exponent: u32) -> Self {
        Decimal { mantissa, exponent }
    }

    fn power(self) -> f64 {
        // Powers of ten up to 10^22 are exact in f64; the maps use at most 10^4.
        const POWERS: [f64; 23] = [
            1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
            1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
        ];
        match POWERS.get(self.exponent as usize) {
            Some(p) => *p,
            None => f64::INFINITY,
        }
    }

    /// The factor as an `f64` (for display only; conversions do not use it).
    pub fn as_f64(self) -> f64 {
        self.mantissa as f64 / self.power()
    }

    /// Engineering value of a raw integer.
    pub fn decode(self, raw: i64) -> f64 {
        (raw * self.mantissa) as f64 / self.power()
    }

    /// Nearest raw integer for an engineering value; `None` if not finite or out of `i64`.
    pub fn encode(self, value: f64) -> Option<i64> {
        if !value.is_finite() {
            return None;
        }
        round(value * self.power() / self.mantissa as f64)
    }

    /// The decimal a float was written as: its shortest round-trip form, as Rust's `Display`
    /// prints it (YAML's `0.1` is `Decimal::new(1, 1)`, `6000.0` is `Decimal::new(6000, 0)`).
    ///
    /// Without allocating: below 2^53 the fewest decimal places `e` at which an integer `m`
    /// gives back `x` as `m / 10^e` (both exact in `f64`, so the division is correctly
    /// rounded, as parsing the decimal text is) is the shortest form; from 2^53 on every
    /// `f64` is a whole number and is taken as it is; a shortest mantissa beyond 2^53 is read
    /// from the `Display` text in a stack buffer. `None` when `x` is not finite, needs more than
    /// 22 decimal places, or its mantissa does not fit an `i64`.
    pub fn from_f64(x: f64) -> Option<Decimal> {
        if !x.is_finite() {
            return None;
        }
        const EXACT: f64 = 9_007_199_254_740_992.0; // 2^53
        if x.abs() >= EXACT {
            // A whole number; `i64` holds it when below 2^63 (the cast saturates beyond).
            const LIMIT: f64 = 9_223_372_036_854_775_808.0; // 2^63
            return (x.abs() < LIMIT).then(|| Decimal::new(x as i64, 0));
        }
        let mut power = 1.0f64;
        for exponent in 0..=22u32 {
            let m = x * power;
            let Some(whole) = round(m) else { break };
            if (whole as f64) / power == x && (whole as f64).abs() < EXACT {
                return Some(Decimal::new(whole, exponent).normalized());
            }
            power *= 10.0;
        }
        Self::from_display(x)
    }

    /// [`Decimal::from_f64`] through the float's shortest `Display` text, written into a
    /// buffer on the stack (for the rare float whose shortest mantissa is beyond 2^53).
    fn from_display(x: f64) -> Option<Decimal> {
        struct Buf {
            bytes: [u8; 48],
            len: usize,
        }
        impl fmt::Write for Buf {
            fn write_str(&mut self, s: &str) -> fmt::Result {
                let end = self.len + s.len();
                self.bytes
                    .get_mut(self.len..end)
                    .ok_or(fmt::Error)?
                    .copy_from_slice(s.as_bytes());
                self.len = end;
                Ok(())
            }
        }
        let mut buf = Buf {
            bytes: [0; 48],
            len: 0,
        };
        fmt::write(&mut buf, format_args!("{x}")).ok()?;
        let text = buf.bytes.get(..buf.len)?;
        let (neg, digits) = match text.split_first() {
            Some((b'-', rest)) => (true, rest),
            _ => (false, text),
        };
        let mut mantissa: i64 = 0;
        let mut exponent = 0u32;
        let mut fraction = false;
        for &b in digits {
            match b {
                b'.' => fraction = true,
                b'0'..=b'9' => {
                    mantissa = mantissa.checked_mul(10)?.checked_add(i64::from(b - b'0'))?;
                    if fraction {
                        exponent += 1;
                    }
                }
                _ => return None,
            }
        }
        let mantissa = if neg { -mantissa } else { mantissa };
        // Beyond 10^-22 the factor is no longer exact as an `f64` power of ten.
        let d = Decimal::new(mantissa, exponent).normalized();
        (d.exponent <= 22).then_some(d)
    }

    /// The same decimal with no trailing zeros in the mantissa (`Decimal::new(10, 2)` is
    /// `Decimal::new(1, 1)`).
    pub const fn normalized(mut self) -> Decimal {
        while self.exponent > 0 && self.mantissa % 10 == 0 {
            self.mantissa /= 10;
            self.exponent -= 1;
        }
        self
    }

    /// Whether the factor is above zero (a usable scale).
    pub const fn is_positive(self) -> bool {
        self.mantissa > 0
    }

    /// Both mantissas at the larger exponent, in `i128`; `None` on overflow.
    fn aligned(self, by: Decimal) -> Option<(i128, i128)> {
        let e = if self.exponent > by.exponent {
            self.exponent
        } else {
            by.exponent
        };
        let up = |d: Decimal| -> Option<i128> {
            10i128
                .checked_pow(e - d.exponent)?
                .checked_mul(i128::from(d.mantissa))
        };
        Some((up(self)?, up(by)?))
    }

    /// `self / by` if it is a whole number (exact integer arithmetic: `6000 / 0.1` is 60000).
    pub fn div_exact(self, by: Decimal) -> Option<i128> {
        let (a, b) = self.aligned(by)?;
        if b == 0 || a % b != 0 {
            return None;
        }
        Some(a / b)
    }

    /// `self / by` rounded toward negative infinity.
    pub fn div_floor(self, by: Decimal) -> Option<i128> {
        let (a, b) = self.aligned(by)?;
        if b == 0 {
            return None;
        }
        Some(a.div_euclid(b))
    }
}

/// The raw integer of an engineering value at a decimal scale, if it is a whole number of
/// increments (`raw_of(6000.0, 0.1)` is 60000; `raw_of(0.05, 0.1)` is `None`). Exact: the value
/// is taken as the decimal it was written as ([`Decimal::from_f64`]).
pub fn raw_of(value: f64, scale: Decimal) -> Option<i128> {
    Decimal::from_f64(value)?.div_exact(scale)
}

impl fmt::Display for Decimal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.as_f64())
    }
}

/// The nearest integer, halves away from zero (`f64::round`, which needs `std`); `None` when
/// not finite or beyond ±9·10^15, where every `f64` is already an integer and `i64` arithmetic on
/// scales could overflow.
pub fn round(x: f64) -> Option<i64> {
    if !(-9.0e15..=9.0e15).contains(&x) {
        return None;
    }
    // Exact: below 2^53 a float minus its truncation loses nothing.
    let whole = x as i64;
    let fraction = x - whole as f64;
    Some(if fraction >= 0.5 {
        whole + 1
    } else if fraction <= -0.5 {
        whole - 1
    } else {
        whole
    })
}

/// Interprets a raw word as signed (two's complement) or unsigned.
pub const fn word_to_int(raw: u16, signed: bool) -> i64 {
    if signed {
        raw as i16 as i64
    } else {
        raw as i64
    }
}

/// Limits of a register in raw integers, with the engineering values for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawRange {
    /// The lowest raw value.
    pub min: i64,
    /// The highest raw value.
    pub max: i64,
}

/// The refusal of `value` outside `range`, whose limits are `min` and `max` in engineering
/// units: [`ValueError::WordOverflow`] when the range is the word's own (the manual printed none),
/// else [`ValueError::OutOfRange`].
pub(crate) fn outside(
    register: &'static str,
    unit: &'static str,
    value: f64,
    range: RawRange,
    min: f64,
    max: f64,
) -> ValueError {
    let full = |w: Width| range == w.range(true) || range == w.range(false);
    let pair = Width::Pair(crate::width::WordOrder::HighFirst);
    if full(Width::Word) || full(pair) {
        ValueError::WordOverflow {
            register,
            bits: if full(pair) { 32 } else { 16 },
            value,
            min,
            max,
            unit,
        }
    } else {
        ValueError::OutOfRange {
            register,
            value,
            min,
            max,
            unit,
        }
    }
}

impl RawRange {
    /// `min ..= max`.
    pub const fn new(min: i64, max: i64) -> RawRange {
        RawRange { min, max }
    }

    /// The whole range of an unsigned or signed 16-bit word.
    pub const fn word(signed: bool) -> RawRange {
        if signed {
            RawRange {
                min: i16::MIN as i64,
                max: i16::MAX as i64,
            }
        } else {
            RawRange {
                min: 0,
                max: u16::MAX as i64,
            }
        }
    }

    /// Whether `raw` lies in the range.
    pub const fn contains(&self, raw: i64) -> bool {
        raw >= self.min && raw <= self.max
    }
}

/// What to do with a value that is not a whole number of a register's steps (35.75 Hz to a
/// register that counts 0.1 Hz).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Rounding {
    /// Refuse it, naming the two nearest values the register can carry
    /// ([`ValueError::NotAStep`]). The default: a value is sent as given or not at all.
    #[default]
    Exact,
    /// Send the nearest value the register can carry (halves away from zero). The range is
    /// still checked on the value given, before rounding.
    Nearest,
}

/// Encodes an engineering value with a decimal scale, exactly ([`Rounding::Exact`]): the raw
/// integer ([`Width::from_int`] makes it the register's bits).
pub fn encode_decimal(
    register: &'static str,
    unit: &'static str,
    value: f64,
    scale: Decimal,
    range: RawRange,
) -> Result<i64, ValueError> {
    encode_decimal_with(register, unit, value, scale, range, Rounding::Exact)
}

/// Encodes an engineering value with a decimal scale: the range is checked on the value given,
/// then a value that is not a whole number of steps is refused or rounded as `rounding` says.
/// A value accepted exactly decodes back to itself ([`Decimal::decode`] of the raw integer
/// equals it).
pub fn encode_decimal_with(
    register: &'static str,
    unit: &'static str,
    value: f64,
    scale: Decimal,
    range: RawRange,
    rounding: Rounding,
) -> Result<i64, ValueError> {
    if !value.is_finite() {
        return Err(ValueError::NotFinite { register, value });
    }
    let (min, max) = (scale.decode(range.min), scale.decode(range.max));
    let raw = match scale.encode(value) {
        Some(raw) if value >= min && value <= max && range.contains(raw) => raw,
        _ => return Err(outside(register, unit, value, range, min, max)),
    };
    let back = scale.decode(raw);
    if rounding == Rounding::Exact && back != value {
        let (below, above) = if value < back {
            (scale.decode(raw - 1), back)
        } else {
            (back, scale.decode(raw + 1))
        };
        return Err(ValueError::NotAStep {
            register,
            value,
            below,
            above,
            step: scale.as_f64(),
            unit,
        });
    }
    Ok(raw)
}

/// Decodes a raw word with a decimal scale.
pub fn decode_decimal(raw: u16, signed: bool, scale: Decimal) -> f64 {
    scale.decode(word_to_int(raw, signed))
}

/// Engineering value of a raw integer scaled relative to a reference quantity:
/// `full_scale` raw = 100 % of `reference` ("30000 = 100 % of Cn-02").
pub fn decode_relative(raw: i64, full_scale: f64, reference: f64) -> f64 {
    raw as f64 * reference / full_scale
}

/// Encodes a value relative to a reference quantity, exactly ([`Rounding::Exact`]); the raw
/// integer.
pub fn encode_relative(
    register: &'static str,
    setting: &'static str,
    unit: &'static str,
    value: f64,
    full_scale: f64,
    reference: f64,
    range: RawRange,
) -> Result<i64, ValueError> {
    encode_relative_with(
        register,
        setting,
        unit,
        value,
        full_scale,
        reference,
        range,
        Rounding::Exact,
    )
}

/// Encodes a value relative to a reference quantity: the range is checked on the value given,
/// then a value that is not a whole number of steps (`reference / full_scale`) is refused or
/// rounded as `rounding` says; the raw integer.
// The register's names for messages (register, setting, unit), the value, the scale's
// three numbers and the rounding: plain values the plan already holds apart.
#[allow(clippy::too_many_arguments)]
pub fn encode_relative_with(
    register: &'static str,
    setting: &'static str,
    unit: &'static str,
    value: f64,
    full_scale: f64,
    reference: f64,
    range: RawRange,
    rounding: Rounding,
) -> Result<i64, ValueError> {
    if !value.is_finite() {
        return Err(ValueError::NotFinite { register, value });
    }
    if !(reference.is_finite() && reference > 0.0) {
        return Err(ValueError::BadReference {
            register,
            setting,
            value: reference,
        });
    }
    let raw = round(value * full_scale / reference).map_or(f64::NAN, |r| r as f64);
    let min = range.min as f64 * reference / full_scale;
    let max = range.max as f64 * reference / full_scale;
    if !(raw >= range.min as f64 && raw <= range.max as f64) || value < min || value > max {
        return Err(outside(register, unit, value, range, min, max));
    }
    let raw = raw as i64;
    let back = decode_relative(raw, full_scale, reference);
    if rounding == Rounding::Exact && back != value {
        let (below, above) = if value < back {
            (decode_relative(raw - 1, full_scale, reference), back)
        } else {
            (back, decode_relative(raw + 1, full_scale, reference))
        };
        return Err(ValueError::NotAStep {
            register,
            value,
            below,
            above,
            step: reference / full_scale,
            unit,
        });
    }
    Ok(raw)
}

/// Checks a plain integer against the raw range.
pub fn encode_int(
    register: &'static str,
    unit: &'static str,
    raw: i64,
    range: RawRange,
) -> Result<i64, ValueError> {
    if !range.contains(raw) {
        let (min, max) = (range.min as f64, range.max as f64);
        return Err(outside(register, unit, raw as f64, range, min, max));
    }
    Ok(raw)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    /// The decimal of a float's shortest `Display` text, parsed as text (what
    /// [`Decimal::from_f64`] computes without allocating).
    fn from_text(x: f64) -> Option<Decimal> {
        let text = std::format!("{x}");
        let (neg, digits) = match text.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, text.as_str()),
        };
        let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
        let frac = frac.trim_end_matches('0');
        let mantissa: i64 = std::format!("{int}{frac}").parse().ok()?;
        let mantissa = if neg { -mantissa } else { mantissa };
        Some(Decimal::new(mantissa, frac.len() as u32).normalized())
    }

    #[test]
    fn from_f64_agrees_with_the_shortest_text() {
        let mut values = std::vec![0.0, -0.0, 1e-7, 0.3, 2.675, 655.35, 1e15 + 0.5, 123456.789];
        for e in 0..7 {
            for k in (-20_000i64..20_000).step_by(7) {
                values.push(k as f64 / 10f64.powi(e));
            }
        }
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            values.push((x >> 11) as f64 / (1u64 << 20) as f64 - 4096.0);
        }
        for v in values {
            assert_eq!(Decimal::from_f64(v), from_text(v), "{v}");
        }
    }

    #[test]
    fn whole_numbers_beyond_two_to_the_53_are_taken_as_they_are() {
        let big = 2f64.powi(60);
        assert_eq!(Decimal::from_f64(big), Some(Decimal::new(1 << 60, 0)));
        assert_eq!(Decimal::from_f64(-big), Some(Decimal::new(-(1 << 60), 0)));
        assert_eq!(Decimal::from_f64(1e19), None, "beyond i64");
        assert_eq!(Decimal::from_f64(f64::NAN), None);
        assert_eq!(Decimal::from_f64(f64::INFINITY), None);
        assert_eq!(Decimal::from_f64(1e-30), None, "more than 22 places");
    }

    #[test]
    fn decimals_are_exact() {
        let tenth = Decimal::from_f64(0.1).unwrap();
        assert_eq!(tenth, Decimal::new(1, 1));
        assert_eq!(raw_of(6000.0, tenth), Some(60000));
        assert_eq!(raw_of(0.3, tenth), Some(3));
        assert_eq!(raw_of(0.05, tenth), None);
        assert_eq!(raw_of(-100.0, tenth), Some(-1000));
        assert_eq!(
            raw_of(65.535, Decimal::from_f64(0.001).unwrap()),
            Some(65535)
        );
        assert_eq!(raw_of(400.0, Decimal::from_f64(0.01).unwrap()), Some(40000));
        assert_eq!(Decimal::from_f64(5.0).unwrap(), Decimal::new(5, 0));
        assert_eq!(Decimal::new(7, 1).div_floor(Decimal::new(2, 1)), Some(3));
        assert_eq!(Decimal::new(-7, 1).div_floor(Decimal::new(2, 1)), Some(-4));
        assert_eq!(Decimal::new(1, 0).div_exact(Decimal::new(0, 0)), None);
        assert_eq!(
            Decimal::new(1, 0).div_exact(Decimal::new(1, 40)),
            None,
            "overflow"
        );
    }

    #[test]
    fn every_word_round_trips_through_decimal_scales() {
        for scale in [
            Decimal::new(1, 0),
            Decimal::new(1, 1),
            Decimal::new(1, 2),
            Decimal::new(1, 3),
            Decimal::new(5, 1),
            Decimal::new(10, 0),
        ] {
            for signed in [false, true] {
                for raw in 0..=u16::MAX {
                    let value = decode_decimal(raw, signed, scale);
                    let range = RawRange::word(signed);
                    let back = encode_decimal("t", "", value, scale, range).unwrap();
                    assert_eq!(
                        Width::Word.from_int(back),
                        u32::from(raw),
                        "scale {scale} signed {signed} raw {raw} value {value}"
                    );
                }
            }
        }
    }

    #[test]
    fn six_thousand_tenths_is_exactly_six_hundred_seconds() {
        let s = Decimal::new(1, 1);
        assert_eq!(decode_decimal(6000, false, s), 600.0);
        assert_eq!(
            encode_decimal("t", "s", 600.0, s, RawRange { min: 0, max: 60000 }),
            Ok(6000)
        );
        assert_eq!(decode_decimal(60000, false, s), 6000.0);
    }

    #[test]
    fn a_value_beyond_the_word_is_not_called_out_of_the_printed_range() {
        // A register with no printed range at 0.01 Hz per count: the word's own limit.
        let e = encode_decimal("f", "Hz", 700.0, Decimal::new(1, 2), RawRange::word(false));
        assert_eq!(
            e.unwrap_err().to_string(),
            "f: 700 Hz does not fit the register's 16-bit word (0 ..= 655.35 Hz); the manual prints no range for it"
        );
        let e = encode_decimal(
            "f",
            "Hz",
            700.0,
            Decimal::new(1, 2),
            RawRange { min: 0, max: 40000 },
        );
        assert!(matches!(e, Err(ValueError::OutOfRange { .. })));
    }

    #[test]
    fn out_of_range_and_nan_are_refused() {
        let s = Decimal::new(1, 1);
        let r = RawRange { min: 0, max: 60000 };
        assert!(matches!(
            encode_decimal("accel", "s", 6000.1, s, r),
            Err(ValueError::OutOfRange { max, .. }) if max == 6000.0
        ));
        assert!(matches!(
            encode_decimal("accel", "s", f64::NAN, s, r),
            Err(ValueError::NotFinite { .. })
        ));
        assert!(matches!(
            encode_decimal("accel", "s", -0.1, s, r),
            Err(ValueError::OutOfRange { .. })
        ));
    }

    #[test]
    fn relative_scale_matches_the_tds_v8_example() {
        // 5DC0h = 24000 = 80 % of Cn-02; with Cn-02 = 60 Hz that is 48 Hz.
        assert_eq!(decode_relative(0x5DC0, 30000.0, 60.0), 48.0);
        assert_eq!(
            encode_relative(
                "f",
                "Cn-02",
                "Hz",
                48.0,
                30000.0,
                60.0,
                RawRange::word(false)
            ),
            Ok(0x5DC0)
        );
        assert!(matches!(
            encode_relative(
                "f",
                "Cn-02",
                "Hz",
                48.0,
                30000.0,
                0.0,
                RawRange::word(false)
            ),
            Err(ValueError::BadReference { .. })
        ));
    }
}
