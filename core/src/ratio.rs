//! Exact ratio scales: `counts` raw counts equal `equals` in the register's unit ("60.0 Hz =
//! 3600", 1/60 Hz per count), so a raw value `r` means `r × equals / counts` exactly.
//!
//! Such a step is not a decimal (1/60 Hz has no finite decimal expansion), so the core keeps it
//! as a fraction of integers ([`Ratio`], [`Fraction`]) and never as a binary float:
//!
//! - [`Ratio::exact`] gives the exact rational value of a raw value;
//! - [`Ratio::decode`] gives the `f64` nearest to it (one correctly rounded division of two
//!   integers below 2^53, which the map's validation guarantees for the register's width);
//! - [`Ratio::encode`] accepts an `f64` only when it is the `f64` of a count (the value
//!   [`Ratio::decode`] gives for that count), so `decode(encode(v)) == v` for every legal `v`,
//!   and every `f64` strictly between two counts is refused with the two counts around it;
//! - [`Ratio::encode_exact`] does the same for an exact fraction (a value typed as `59.9` or
//!   `3599/60`), with no float involved.
//!
//! Display rule ([`Fraction`]'s `Display`): a value whose decimal expansion is finite is printed
//! as that decimal, in full; any other as the reduced fraction followed by the value rounded to
//! six decimals (halves away from zero): `3599/60 (≈59.983333)`.

use core::fmt;

use crate::scale::{Decimal, RawRange, Rounding, ValueError, outside};

/// The largest integer every smaller integer of which an `f64` holds exactly (2^53).
pub const EXACT_LIMIT: i128 = 1 << 53;

/// An exact rational number: `num / den`, `den > 0`, reduced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Fraction {
    /// The numerator.
    pub num: i128,
    /// The denominator (positive).
    pub den: i128,
}

const fn gcd(mut a: i128, mut b: i128) -> i128 {
    if a < 0 {
        a = -a;
    }
    if b < 0 {
        b = -b;
    }
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl Fraction {
    /// `num / den` reduced; `None` when `den` is 0.
    pub const fn new(num: i128, den: i128) -> Option<Fraction> {
        if den == 0 {
            return None;
        }
        let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
        let g = gcd(num, den);
        let g = if g == 0 { 1 } else { g };
        Some(Fraction {
            num: num / g,
            den: den / g,
        })
    }

    /// The integer `n`.
    pub const fn int(n: i128) -> Fraction {
        Fraction { num: n, den: 1 }
    }

    /// The `f64` nearest to the fraction when numerator and denominator are below 2^53 (one
    /// correctly rounded division); otherwise the nearest the two conversions allow.
    pub fn to_f64(self) -> f64 {
        self.num as f64 / self.den as f64
    }

    /// The exact value of a finite `f64` (every finite `f64` is a fraction with a power of two
    /// below); `None` for NaN, infinities, and magnitudes or precisions an `i128` fraction
    /// cannot hold (beyond 2^74 or below 2^-74, far outside any register).
    pub fn from_f64(value: f64) -> Option<Fraction> {
        if !value.is_finite() {
            return None;
        }
        if value == 0.0 {
            return Some(Fraction::int(0));
        }
        let bits = value.to_bits();
        let negative = bits >> 63 == 1;
        let exponent = ((bits >> 52) & 0x7ff) as i32;
        let fraction = (bits & ((1 << 52) - 1)) as i128;
        let (mantissa, exponent) = if exponent == 0 {
            (fraction, -1074)
        } else {
            (fraction | (1 << 52), exponent - 1075)
        };
        let mantissa = if negative { -mantissa } else { mantissa };
        if exponent >= 0 {
            if exponent > 74 {
                return None;
            }
            return Some(Fraction::int(mantissa << exponent));
        }
        // Strip trailing zero bits first so small exponents stay in range.
        let shift = (mantissa.trailing_zeros() as i32).min(-exponent);
        let (mantissa, exponent) = (mantissa >> shift, exponent + shift);
        if exponent < -126 {
            return None;
        }
        Fraction::new(mantissa, 1i128 << -exponent)
    }

    /// Parses a decimal (`59.9`, `-0.25`; not `1e3`) or a fraction of two integers (`3599/60`),
    /// exactly; `None` for anything else, and for more than 18 digits (numerator or
    /// denominator of 10^18 or more), which keeps every comparison in an `i128`.
    pub fn parse(text: &str) -> Option<Fraction> {
        const LIMIT: i128 = 1_000_000_000_000_000_000;
        let text = text.trim();
        if let Some((n, d)) = text.split_once('/') {
            let n: i128 = n.trim().parse().ok()?;
            let d: i128 = d.trim().parse().ok()?;
            if n.abs() >= LIMIT || d.abs() >= LIMIT {
                return None;
            }
            return Fraction::new(n, d);
        }
        let (negative, digits) = match text.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, text.strip_prefix('+').unwrap_or(text)),
        };
        let (whole, fraction) = digits.split_once('.').unwrap_or((digits, ""));
        if whole.is_empty() && fraction.is_empty()
            || !whole.bytes().all(|b| b.is_ascii_digit())
            || !fraction.bytes().all(|b| b.is_ascii_digit())
            || whole.len() + fraction.len() > 18
        {
            return None;
        }
        let mut num: i128 = 0;
        for b in whole.bytes().chain(fraction.bytes()) {
            num = num.checked_mul(10)?.checked_add(i128::from(b - b'0'))?;
        }
        let den = 10i128.checked_pow(fraction.len() as u32)?;
        Fraction::new(if negative { -num } else { num }, den)
    }

    /// Whether the decimal expansion is finite (the denominator has no prime factor but 2 and 5).
    pub const fn is_decimal(self) -> bool {
        self.decimal_digits().is_some()
    }

    /// The number of decimals of the finite decimal expansion, if it is finite.
    pub const fn decimal_digits(self) -> Option<u32> {
        let (mut d, mut twos, mut fives) = (self.den, 0u32, 0u32);
        while d % 2 == 0 {
            d /= 2;
            twos += 1;
        }
        while d % 5 == 0 {
            d /= 5;
            fives += 1;
        }
        if d == 1 {
            Some(if twos > fives { twos } else { fives })
        } else {
            None
        }
    }

    /// `self × 10^digits`, rounded to the nearest integer, halves away from zero.
    const fn scaled(self, digits: u32) -> i128 {
        let n = self.num * 10i128.pow(digits);
        let (q, r) = (n / self.den, n % self.den);
        if 2 * r.abs() >= self.den {
            if n < 0 { q - 1 } else { q + 1 }
        } else {
            q
        }
    }
}

fn write_decimal(f: &mut fmt::Formatter<'_>, scaled: i128, digits: u32) -> fmt::Result {
    let sign = if scaled < 0 { "-" } else { "" };
    let abs = scaled.unsigned_abs();
    let power = 10u128.pow(digits);
    if digits == 0 {
        write!(f, "{sign}{abs}")
    } else {
        write!(
            f,
            "{sign}{}.{:0width$}",
            abs / power,
            abs % power,
            width = digits as usize
        )
    }
}

impl fmt::Display for Fraction {
    /// The exact decimal when finite (`59.9`, `0.25`), else the fraction and its value to six
    /// decimals (`3599/60 (≈59.983333)`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.decimal_digits() {
            Some(digits) => write_decimal(f, self.scaled(digits), digits),
            None => {
                write!(f, "{}/{} (≈", self.num, self.den)?;
                write_decimal(f, self.scaled(6), 6)?;
                write!(f, ")")
            }
        }
    }
}

/// A ratio scale: `counts` raw counts equal `equals` (a positive decimal) in the register's
/// unit; raw `r` means `r × equals / counts`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Ratio {
    /// The raw count the manual prints (3600), positive.
    pub counts: i64,
    /// The value it equals (60.0 Hz), positive.
    pub equals: Decimal,
}

/// Why a value is not written with a ratio scale: not a whole count, between the two counts
/// `below` and `above` (`below + 1 == above`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Between {
    /// The count below the value.
    pub below: i64,
    /// The count above it (`below + 1`).
    pub above: i64,
}

impl Ratio {
    /// `counts` raw = `equals`.
    pub const fn new(counts: i64, equals: Decimal) -> Ratio {
        Ratio { counts, equals }
    }

    /// Numerator per count and denominator: raw `r` means `r × per / den`.
    const fn parts(self) -> (i128, i128) {
        (
            self.equals.mantissa as i128,
            self.counts as i128 * 10i128.pow(self.equals.exponent),
        )
    }

    /// Whether conversions of raw values in `min ..= max` are exact as documented (both parts
    /// positive, every numerator and the denominator below 2^53 so [`Ratio::decode`] is one
    /// correctly rounded division). The map's validation refuses a ratio for which this fails.
    pub const fn exact_for(self, min: i64, max: i64) -> bool {
        if self.counts <= 0 || self.equals.mantissa <= 0 || self.equals.exponent > 18 {
            return false;
        }
        let (per, den) = self.parts();
        let far = if (min as i128).abs() > (max as i128).abs() {
            (min as i128).abs()
        } else {
            (max as i128).abs()
        };
        den <= EXACT_LIMIT && per * far <= EXACT_LIMIT
    }

    /// The value of one count, exactly (1/60 for 3600 = 60.0).
    pub const fn step(self) -> Fraction {
        self.exact(1)
    }

    /// The exact value of raw integer `raw`.
    pub const fn exact(self, raw: i64) -> Fraction {
        let (per, den) = self.parts();
        match Fraction::new(raw as i128 * per, den) {
            Some(f) => f,
            None => Fraction::int(0),
        }
    }

    /// The `f64` nearest to the value of `raw` (see [`Ratio::exact_for`]).
    pub fn decode(self, raw: i64) -> f64 {
        let (per, den) = self.parts();
        (raw as i128 * per) as f64 / den as f64
    }

    /// The count whose [`Ratio::decode`] is `value`, or the two counts around it. `value` must
    /// be finite and between the decoded limits of the register (checked by the caller).
    pub fn encode(self, value: f64) -> Result<i64, Between> {
        let (per, den) = self.parts();
        let estimate = value * den as f64 / per as f64;
        let mut below = if estimate.is_finite() && estimate.abs() < 9.0e15 {
            estimate as i64
        } else {
            0
        };
        // Decoding is monotone (a correctly rounded increasing function), so walking from the
        // estimate finds the counts around `value`; the estimate is off by at most one or two.
        while self.decode(below) > value {
            below -= 1;
        }
        while self.decode(below + 1) <= value {
            below += 1;
        }
        if self.decode(below) == value {
            Ok(below)
        } else {
            Err(Between {
                below,
                above: below + 1,
            })
        }
    }

    /// The count whose exact value is `value`, or the two counts around it.
    pub fn encode_exact(self, value: Fraction) -> Result<i64, Between> {
        let (per, den) = self.parts();
        // raw = value × den / per = value.num × den / (value.den × per)
        let (n, d) = (value.num * den, value.den * per);
        let floor = n.div_euclid(d);
        let below = floor.clamp(i64::MIN as i128, i64::MAX as i128 - 1) as i64;
        if n.rem_euclid(d) == 0 {
            Ok(below)
        } else {
            Err(Between {
                below,
                above: below + 1,
            })
        }
    }
}

impl fmt::Display for Ratio {
    /// `3600 = 60`: counts, then the value they equal.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let equals = Fraction::new(
            self.equals.mantissa as i128,
            10i128.pow(self.equals.exponent),
        )
        .unwrap_or(Fraction::int(0));
        write!(f, "{} = {}", self.counts, equals)
    }
}

/// Encodes an engineering value with a ratio scale: the range is checked on the value given,
/// then a value that is not the `f64` of a whole count is refused ([`ValueError::NotACount`],
/// naming the two counts around it) or, with [`Rounding::Nearest`], sent as the nearer count
/// (halves away from zero). A value accepted exactly decodes back to itself.
pub fn encode_ratio_with(
    register: &'static str,
    unit: &'static str,
    value: f64,
    ratio: Ratio,
    range: RawRange,
    rounding: Rounding,
) -> Result<i64, ValueError> {
    if !value.is_finite() {
        return Err(ValueError::NotFinite { register, value });
    }
    let (min, max) = (ratio.decode(range.min), ratio.decode(range.max));
    if value < min || value > max {
        return Err(outside(register, unit, value, range, min, max));
    }
    match ratio.encode(value) {
        Ok(raw) => Ok(raw),
        Err(b) => settle(register, unit, value, ratio, b, rounding, || {
            // Nearer by the exact value given (a tie goes away from zero); by the floats when
            // the exact comparison would overflow (values far below one count).
            let (lo, hi) = (ratio.exact(b.below), ratio.exact(b.above));
            let exact = Fraction::from_f64(value).and_then(|v| {
                let d_lo = v
                    .num
                    .checked_mul(lo.den)?
                    .checked_sub(lo.num.checked_mul(v.den)?)?
                    .checked_mul(hi.den)?;
                let d_hi = hi
                    .num
                    .checked_mul(v.den)?
                    .checked_sub(v.num.checked_mul(hi.den)?)?
                    .checked_mul(lo.den)?;
                Some(d_hi < d_lo || d_hi == d_lo && v.num > 0)
            });
            exact.unwrap_or_else(|| value - ratio.decode(b.below) > ratio.decode(b.above) - value)
        }),
    }
}

/// Encodes an exact value (typed as `59.9` or `3599/60`) with a ratio scale, as
/// [`encode_ratio_with`] with [`Rounding::Exact`] does an `f64`: the count it is, or
/// [`ValueError::NotACount`].
pub fn encode_ratio_exact(
    register: &'static str,
    unit: &'static str,
    value: Fraction,
    ratio: Ratio,
    range: RawRange,
) -> Result<i64, ValueError> {
    let (lo, hi) = (ratio.exact(range.min), ratio.exact(range.max));
    let less = |a: Fraction, b: Fraction| a.num * b.den < b.num * a.den;
    if less(value, lo) || less(hi, value) {
        let (min, max) = (ratio.decode(range.min), ratio.decode(range.max));
        return Err(outside(register, unit, value.to_f64(), range, min, max));
    }
    match ratio.encode_exact(value) {
        Ok(raw) => Ok(raw),
        Err(b) => settle(
            register,
            unit,
            value.to_f64(),
            ratio,
            b,
            Rounding::Exact,
            || false,
        ),
    }
}

fn settle(
    register: &'static str,
    unit: &'static str,
    value: f64,
    ratio: Ratio,
    b: Between,
    rounding: Rounding,
    above_is_nearer: impl FnOnce() -> bool,
) -> Result<i64, ValueError> {
    match rounding {
        Rounding::Nearest => Ok(if above_is_nearer() { b.above } else { b.below }),
        _ => Err(ValueError::NotACount {
            register,
            value,
            below: b.below,
            ratio,
            unit,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::format;

    const HZ: Ratio = Ratio::new(3600, Decimal::new(600, 1));

    #[test]
    fn display_is_exact_decimal_or_fraction() {
        assert_eq!(format!("{}", HZ.exact(3600)), "60");
        assert_eq!(format!("{}", HZ.exact(3594)), "59.9");
        assert_eq!(format!("{}", HZ.exact(3599)), "3599/60 (≈59.983333)");
        assert_eq!(format!("{}", HZ.exact(-1)), "-1/60 (≈-0.016667)");
        assert_eq!(format!("{HZ}"), "3600 = 60");
    }

    #[test]
    fn parse_is_exact() {
        assert_eq!(Fraction::parse("59.9"), Fraction::new(599, 10));
        assert_eq!(Fraction::parse("3599/60"), Fraction::new(3599, 60));
        assert_eq!(Fraction::parse("-0.5"), Fraction::new(-1, 2));
        assert_eq!(Fraction::parse("1e3"), None);
        assert_eq!(Fraction::parse("."), None);
        assert_eq!(Fraction::parse("1/0"), None);
    }

    #[test]
    fn from_f64_is_exact() {
        assert_eq!(Fraction::from_f64(0.5), Fraction::new(1, 2));
        assert_eq!(Fraction::from_f64(-3.0), Fraction::new(-3, 1));
        let tenth = Fraction::from_f64(0.1).unwrap();
        assert_eq!(tenth.den, 1 << 55);
        assert_eq!(tenth.to_f64(), 0.1);
    }

    #[test]
    fn encode_exact_names_the_counts_around() {
        assert_eq!(HZ.encode_exact(Fraction::parse("59.9").unwrap()), Ok(3594));
        assert_eq!(
            HZ.encode_exact(Fraction::parse("59.99").unwrap()),
            Err(Between {
                below: 3599,
                above: 3600
            })
        );
        assert_eq!(
            HZ.encode_exact(Fraction::parse("-0.001").unwrap()),
            Err(Between {
                below: -1,
                above: 0
            })
        );
    }
}
