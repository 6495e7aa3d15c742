//! Exact decimal arithmetic for limits and scales.
//!
//! YAML gives `0.1` and `6000.0` as binary floats. Their shortest decimal form (what Rust's
//! `Display` prints) is exactly what was written, so we reparse that text as an integer mantissa
//! and a power of ten and do all limit arithmetic on integers: `6000.0 / 0.1` is exactly 60000,
//! and a limit that is not a whole number of increments is reported instead of rounded.

use std::fmt;

/// `mantissa` × 10^-`exponent`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Dec {
    pub mantissa: i128,
    pub exponent: u32,
}

impl Dec {
    /// The decimal a float was written as (its shortest round-trip form).
    pub fn from_f64(x: f64) -> Option<Dec> {
        if !x.is_finite() {
            return None;
        }
        let text = format!("{x}");
        let (neg, digits) = match text.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, text.as_str()),
        };
        let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
        let frac = frac.trim_end_matches('0');
        let all = format!("{int}{frac}");
        if all.len() > 30 {
            return None;
        }
        let mut mantissa: i128 = all.parse().ok()?;
        if neg {
            mantissa = -mantissa;
        }
        Some(
            Dec {
                mantissa,
                exponent: frac.len() as u32,
            }
            .normalized(),
        )
    }

    fn normalized(mut self) -> Dec {
        while self.exponent > 0 && self.mantissa % 10 == 0 {
            self.mantissa /= 10;
            self.exponent -= 1;
        }
        self
    }

    fn rescaled(self, exponent: u32) -> i128 {
        self.mantissa * 10i128.pow(exponent - self.exponent)
    }

    /// `self / by` if it is a whole number.
    pub fn div_exact(self, by: Dec) -> Option<i128> {
        let e = self.exponent.max(by.exponent);
        let (a, b) = (self.rescaled(e), by.rescaled(e));
        if b == 0 || a % b != 0 {
            return None;
        }
        Some(a / b)
    }

    /// `self / by` rounded toward negative infinity.
    pub fn div_floor(self, by: Dec) -> Option<i128> {
        let e = self.exponent.max(by.exponent);
        let (a, b) = (self.rescaled(e), by.rescaled(e));
        if b == 0 {
            return None;
        }
        Some(a.div_euclid(b))
    }

    pub fn is_positive(self) -> bool {
        self.mantissa > 0
    }

    pub fn to_f64(self) -> f64 {
        self.mantissa as f64 / 10f64.powi(self.exponent as i32)
    }
}

impl fmt::Display for Dec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.to_f64())
    }
}

/// The raw integer of an engineering value at a decimal scale, if it is a whole number of
/// increments.
pub fn raw_of(value: f64, scale: Dec) -> Option<i128> {
    Dec::from_f64(value)?.div_exact(scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_exact() {
        let tenth = Dec::from_f64(0.1).unwrap();
        assert_eq!(
            tenth,
            Dec {
                mantissa: 1,
                exponent: 1
            }
        );
        assert_eq!(raw_of(6000.0, tenth), Some(60000));
        assert_eq!(raw_of(0.3, tenth), Some(3));
        assert_eq!(raw_of(0.05, tenth), None);
        assert_eq!(raw_of(-100.0, tenth), Some(-1000));
        assert_eq!(raw_of(65.535, Dec::from_f64(0.001).unwrap()), Some(65535));
        assert_eq!(raw_of(400.0, Dec::from_f64(0.01).unwrap()), Some(40000));
        assert_eq!(
            Dec::from_f64(5.0).unwrap(),
            Dec {
                mantissa: 5,
                exponent: 0
            }
        );
    }
}
