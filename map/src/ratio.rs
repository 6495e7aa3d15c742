//! Exact ratio scales in a map (`scale: {counts: 3600, equals: 60.0}`): the core's
//! [`Ratio`] of a map's scale, and the raw limits of its `min`/`max` (each must be a whole
//! number of counts; `validate::ratio_scales` reports those that are not).

use drivemap_core::ratio::{Fraction, Ratio};
use drivemap_core::scale::Decimal;

use drivemap_core::scale::RawRange;

use crate::ir::Register;
use crate::model::RatioScale;

/// The core's ratio for a map's scale; `None` when `counts` is 0 or `equals` is not a
/// positive decimal with at most 18 decimals.
pub(crate) fn ratio_of(s: &RatioScale) -> Option<Ratio> {
    let equals = Decimal::from_f64(s.equals)?;
    if s.counts == 0 || equals.mantissa <= 0 || equals.exponent > 18 {
        return None;
    }
    Some(Ratio::new(i64::from(s.counts), equals))
}

/// The exact value a map's number was written as (`59.9` is 599/10, not the binary float).
pub(crate) fn exact(value: f64) -> Option<Fraction> {
    let d = Decimal::from_f64(value)?;
    Fraction::new(i128::from(d.mantissa), 10i128.checked_pow(d.exponent)?)
}

/// The count an engineering value of the map is, if it is a whole number of counts.
pub(crate) fn count_of(ratio: Ratio, value: f64) -> Option<i64> {
    ratio.encode_exact(exact(value)?).ok()
}

impl Register {
    /// Raw limits for engineering limits with a ratio scale; missing limits are the word's own.
    /// `None` when a limit is not a whole number of counts.
    pub(crate) fn ratio_limits(
        &self,
        ratio: Ratio,
        min: Option<f64>,
        max: Option<f64>,
    ) -> Option<RawRange> {
        let word = self.full_limits();
        Some(RawRange {
            min: match min {
                Some(m) => count_of(ratio, m)?,
                None => word.min,
            },
            max: match max {
                Some(m) => count_of(ratio, m)?,
                None => word.max,
            },
        })
    }
}
