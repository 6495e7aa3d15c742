//! The bounds and step of a number input for a register (Home Assistant's `number` entity,
//! an input box of any front end): decided here once, from the map, so no consumer derives
//! them from a scale of its own.

use super::data::ScaleData;
use crate::ir::{Drive, Register};
use crate::model::Reference;

/// The widest bounds the manual gives a number register and the finest step of its value;
/// a front end checks the bounds in force when a value comes (the write gate does).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputBounds {
    /// Its minimum, else the lowest of its selected scale's cases, else the raw word's.
    pub min: f64,
    /// Its maximum, else the highest of its selected scale's cases, else its maximum through
    /// another parameter at that parameter's maximum, else the raw word's.
    pub max: f64,
    /// Its scale's finest step ([`ScaleData::step`]: the factor where fixed, one count of a
    /// ratio scale, the finest of a selected scale's cases, [`InputBounds::RELATIVE_STEP`] for
    /// a scale relative to another quantity), else 1.
    pub step: f64,
}

impl InputBounds {
    /// The step of a value relative to another quantity, whose size in engineering units
    /// depends on that quantity at run time: a hundredth.
    pub const RELATIVE_STEP: f64 = 0.01;

    pub(crate) fn of(drive: &Drive, r: &Register) -> InputBounds {
        let scale = r
            .def
            .scale
            .as_ref()
            .map(|s| super::data::scale_of(drive, s));
        let step = scale
            .as_ref()
            .map(ScaleData::step)
            .filter(|f| f.is_finite() && *f > 0.0)
            .unwrap_or(1.0);
        let cases = scale.as_ref().map_or(&[][..], ScaleData::cases);
        let min = r.def.min.or_else(|| {
            cases
                .iter()
                .filter_map(|c| c.min)
                .fold(None, |a: Option<f64>, b| Some(a.map_or(b, |a| a.min(b))))
        });
        let max = r
            .def
            .max
            .or_else(|| {
                cases
                    .iter()
                    .filter_map(|c| c.max)
                    .fold(None, |a: Option<f64>, b| Some(a.map_or(b, |a| a.max(b))))
            })
            .or_else(|| {
                let l = r.def.max_relative.as_ref()?;
                let Reference::Register(id) = &l.relative_to else {
                    return None;
                };
                let of = drive.find(id)?;
                Some(of.def.max? * l.percent / 100.0)
            });
        let words = if r.def.pair.is_some() { 32 } else { 16 };
        let full = (2f64.powi(words) - 1.0) * step;
        let (lo, hi) = if r.def.signed {
            (-full / 2.0, full / 2.0)
        } else {
            (0.0, full)
        };
        InputBounds {
            min: min.unwrap_or(lo),
            max: max.unwrap_or(hi),
            step,
        }
    }
}
