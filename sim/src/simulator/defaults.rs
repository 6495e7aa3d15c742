//! The drive's power-on values: the map's defaults for the variant options in force
//! (`ir::Register::default_for`), and for a register without one the value nearest 0 that its
//! own map allows, so that nothing powers on at a value the map refuses.

use drivemap_live::{LiveSettings, codec};
use drivemap_map::RegisterRef;
use drivemap_map::facts::UnknownItem;
use drivemap_runtime::core::plan::Conversion;
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::core::text;
use drivemap_runtime::core::width::Width;
use std::sync::Arc;

use super::Simulator;

impl Simulator {
    pub(super) fn default_of(&self, r: RegisterRef<'_>, settings: &LiveSettings) -> Option<f64> {
        r.default_for(|option| settings.has_variant(&self.map, option))
    }

    /// Map defaults: selectors and references first (other registers' scales depend on them).
    /// A register without a default (or whose default cannot be encoded) keeps 0 where its map
    /// allows 0, else starts at the allowed value nearest 0 ([`Simulator::nearest_allowed`]).
    pub(super) fn apply_defaults(&mut self) {
        let first: Vec<usize> = self
            .selectors
            .iter()
            .chain(&self.references)
            .copied()
            .collect();
        let rest: Vec<usize> = (0..self.raw.len()).filter(|i| !first.contains(i)).collect();
        let map = Arc::clone(&self.map);
        for pass in [first, rest] {
            let settings = self.settings();
            for i in pass {
                let r = map.register_at(i).expect("an index of the map");
                if let Some(v) = self.default_of(r, &settings) {
                    match codec::encode(&self.map, r, v, &settings) {
                        Ok(raw) => {
                            self.raw[i] = raw;
                            continue;
                        }
                        Err(e) => self
                            .warnings
                            .push(format!("{}: default {v} not set: {e}", r.id())),
                    }
                }
                if self.allows(r, self.raw[i], &settings) {
                    continue;
                }
                match self.nearest_allowed(r, &settings) {
                    Some(raw) => self.raw[i] = raw,
                    None => self.warnings.push(format!(
                        "{}: powers on at {}, which its map refuses; no value it allows was found",
                        r.id(),
                        self.raw[i]
                    )),
                }
            }
        }
    }

    /// Whether `raw`, read from `r`, is a value its map allows under `settings` — what
    /// `drivemap probe` checks: no reserved bit set; a listed read code; a value that decodes
    /// and encodes back within its range and listed codes. An unlisted code of a list the
    /// manual leaves incomplete (`unknown: values`), and a value whose check needs a setting or
    /// quantity not known, are not refused.
    pub(super) fn allows(&self, r: RegisterRef<'_>, raw: u32, settings: &LiveSettings) -> bool {
        let plan = r.plan();
        if let Conversion::Bits { mask, .. } = plan.conversion {
            return raw & !u32::from(mask) == 0;
        }
        if !plan.read_values.is_empty() {
            return u16::try_from(raw)
                .ok()
                .and_then(|code| plan.read_label(code))
                .is_some();
        }
        let Ok(value) = codec::decode(&self.map, r, raw, settings) else {
            return true;
        };
        let Some(number) = value.as_f64() else {
            return true;
        };
        match codec::encode(&self.map, r, number, settings) {
            Ok(_) => true,
            Err(ValueError::UnknownCode { .. }) => values_unknown(r),
            Err(ValueError::MissingSetting { .. } | ValueError::LimitNotKnown { .. }) => true,
            Err(_) => false,
        }
    }

    /// The raw word of the value nearest 0 that `r`'s map allows: its listed read code or code
    /// nearest 0, or the bound of its range (for the variant options in force) nearest 0.
    fn nearest_allowed(&self, r: RegisterRef<'_>, settings: &LiveSettings) -> Option<u32> {
        let plan = r.plan();
        if !plan.read_values.is_empty() {
            return plan
                .read_values
                .iter()
                .map(|l| l.code)
                .min_by_key(|c| (i32::from(*c as i16).unsigned_abs(), *c))
                .map(u32::from);
        }
        let mut candidates: Vec<f64> = plan.labels().iter().map(|l| f64::from(l.code)).collect();
        let (min, max) = r.limits();
        candidates.extend(min);
        candidates.extend(max);
        // The limits of a selected scale's cases (a range a mode parameter selects): the
        // case in force is among them.
        if let Some(drivemap_map::facts::Scale::Selected(sel)) = r.written().scale {
            for c in &sel.cases {
                candidates.extend(c.min);
                candidates.extend(c.max);
            }
        }
        for option in r.variant_options() {
            if settings.has_variant(&self.map, option) {
                let (min, max) = r.limits_for(option);
                candidates.extend(min);
                candidates.extend(max);
            }
        }
        candidates.sort_by(|a, b| a.abs().total_cmp(&b.abs()).then(a.total_cmp(b)));
        candidates.into_iter().find_map(|v| {
            let raw = codec::encode(&self.map, r, v, settings).ok()?;
            self.allows(r, raw, settings).then_some(raw)
        })
    }
}

/// The map says the manual's list of codes is incomplete (`unknown: values`).
fn values_unknown(r: RegisterRef<'_>) -> bool {
    r.unknown().iter().any(|u| u.what == UnknownItem::Values)
}

/// What the simulator serves in a string register whose map gives no `string.example`: this
/// text, cut to the register's length. A placeholder of the simulator's, never the manual's.
pub(super) const PLACEHOLDER: &str = "DRIVEMAP-SIM";

/// The words a string register holds in the simulator: the manual's example as the map gives it
/// (`string.example`, checked printable and fitting by `drivemap check`), else
/// [`PLACEHOLDER`], padded with NUL, in the map's byte order; none for other registers.
pub(super) fn text_words(r: RegisterRef<'_>) -> Vec<u16> {
    let plan = r.plan();
    let (Width::Text(n), Conversion::Text { order }) = (plan.info.width, plan.conversion) else {
        return Vec::new();
    };
    let mut words = vec![0u16; usize::from(n)];
    let example = r.written().string.and_then(|t| t.example.as_deref());
    let text = example.unwrap_or(&PLACEHOLDER[..PLACEHOLDER.len().min(2 * usize::from(n))]);
    if text::encode(text.as_bytes(), order, &mut words).is_err() {
        // An example `check` refuses: the placeholder, which fits.
        let fit = &PLACEHOLDER[..PLACEHOLDER.len().min(2 * usize::from(n))];
        let _ = text::encode(fit.as_bytes(), order, &mut words);
    }
    words
}
