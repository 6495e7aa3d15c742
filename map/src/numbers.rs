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
    ///
    /// Without allocating for numbers below 2^53 (every scale and limit of a drive map): the
    /// fewest decimal places `e` at which an integer `m` gives back `x` as `m / 10^e` (both exact
    /// in `f64`, so the division is correctly rounded, as parsing the decimal text is) is the
    /// shortest form. The run-time interpreter converts scales on every request with it.
    pub fn from_f64(x: f64) -> Option<Dec> {
        if !x.is_finite() {
            return None;
        }
        const EXACT: f64 = 9_007_199_254_740_992.0; // 2^53
        if x.abs() < EXACT {
            let mut power = 1.0f64;
            for exponent in 0..=22u32 {
                let m = (x * power).round();
                if m.abs() < EXACT && m / power == x {
                    return Some(
                        Dec {
                            mantissa: m as i128,
                            exponent,
                        }
                        .normalized(),
                    );
                }
                power *= 10.0;
            }
        }
        Self::from_text(x)
    }

    /// [`Dec::from_f64`] through the float's shortest `Display` text.
    fn from_text(x: f64) -> Option<Dec> {
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
    fn from_f64_agrees_with_the_shortest_text() {
        let mut values = vec![0.0, -0.0, 1e-7, 0.3, 2.675, 655.35, 1e15 + 0.5, 123456.789];
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
            assert_eq!(Dec::from_f64(v), Dec::from_text(v), "{v}");
        }
    }

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
