//! Comparing: two sets, a set and a drive (saved first), or either against the map's printed
//! defaults.

use drivemap_map::Map;
use drivemap_runtime::core::plan::Conversion;
use drivemap_runtime::core::ratio::Fraction;

use super::file::{FORMAT, ParameterSet, SavedSetting, UnreadSetting};
use super::{by_id, fingerprint, settings_of};

/// One side of a comparison.
#[derive(Debug, Clone)]
pub struct Side {
    /// What it is, for the report: a file name, `slave 1 over ...`, `defaults`.
    pub label: String,
    /// Its values.
    pub set: ParameterSet,
    /// The map's printed defaults: a setting without one is named as such, not a difference.
    pub defaults: bool,
}

impl Side {
    /// A set file or a drive's settings (saved).
    pub fn set(label: impl Into<String>, set: ParameterSet) -> Side {
        Side {
            label: label.into(),
            set,
            defaults: false,
        }
    }

    /// The map's printed factory values under `variant` (axis id → option id; axes not given
    /// take their first option), for every setting; settings without a printed default are in
    /// the set's `unread`.
    pub fn defaults(drive: &Map, variant: &std::collections::BTreeMap<String, String>) -> Side {
        let mut chosen = std::collections::BTreeMap::new();
        for a in drive.variants() {
            let o = variant
                .get(&a.id)
                .cloned()
                .unwrap_or_else(|| a.options[0].id.clone());
            chosen.insert(a.id.clone(), o);
        }
        let mut settings = Vec::new();
        let mut unread = Vec::new();
        for r in settings_of(drive) {
            let param = r.param().map(str::to_owned);
            match r.default_for(|o| chosen.values().any(|c| c == o)) {
                Some(v) => {
                    let plan = r.plan();
                    let code = match plan.conversion {
                        Conversion::Enum { .. } if v >= 0.0 && v <= f64::from(u16::MAX) => {
                            plan.label(v as u16).map(|l| l.id.to_owned())
                        }
                        _ => None,
                    };
                    settings.push(SavedSetting {
                        id: r.id().to_owned(),
                        param,
                        value: format_number(v),
                        code,
                    });
                }
                None => unread.push(UnreadSetting {
                    id: r.id().to_owned(),
                    param,
                    reason: "the manual prints no default".to_owned(),
                }),
            }
        }
        Side {
            label: "defaults".to_owned(),
            set: ParameterSet {
                format: FORMAT.to_owned(),
                drive: drive.id().to_owned(),
                variant: chosen,
                fingerprint: fingerprint(drive),
                slave: 0,
                saved: String::new(),
                settings,
                unread,
            },
            defaults: true,
        }
    }
}

/// A number as a set writes it: without a trailing `.0` noise beyond what it has.
fn format_number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

/// One setting held differently.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Difference {
    /// The register id.
    pub id: String,
    /// The manual's parameter number.
    pub param: Option<String>,
    /// The register as the manual names it (`n019 Accel Time 1`).
    pub name: String,
    /// The left side's value with its unit or meaning; `None` where that side has none.
    pub left: Option<String>,
    /// The right side's value.
    pub right: Option<String>,
    /// Why a side has no value (not in the set, not read), when one has none.
    pub why: Option<String>,
    /// The manual's line for the register.
    pub source: Option<String>,
}

/// What a comparison found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Compared {
    /// The two sides' labels.
    pub left: String,
    /// The right side's label.
    pub right: String,
    /// Settings held differently, in the map's order.
    pub differences: Vec<Difference>,
    /// Settings compared with the defaults that have no printed default (named, not a
    /// difference).
    pub no_default: Vec<String>,
    /// Settings both sides hold alike.
    pub same: usize,
    /// Warnings: a set saved under another fingerprint of the map.
    pub warnings: Vec<String>,
}

/// The number a value text stands for: a decimal or an exact fraction.
fn number(text: &str) -> Option<f64> {
    text.trim()
        .parse::<f64>()
        .ok()
        .or_else(|| Fraction::parse(text).map(|f| f.num as f64 / f.den as f64))
}

/// Whether two value texts are the same value.
fn same(a: &str, b: &str) -> bool {
    match (number(a), number(b)) {
        (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
        _ => a.trim() == b.trim(),
    }
}

/// A value with its unit, or a code with its meaning, as the manual says it.
fn shown(drive: &Map, id: &str, s: &SavedSetting) -> String {
    let Some(r) = by_id(drive, id) else {
        return s.value.clone();
    };
    let plan = r.plan();
    match plan.conversion {
        Conversion::Enum { .. } => {
            let label = s.value.parse::<u16>().ok().and_then(|c| plan.label(c));
            match label {
                Some(l) => format!("{}: {}", s.value, l.name),
                None => format!("{} (not listed)", s.value),
            }
        }
        _ => {
            // A number at the resolution of the register's scale where that does not depend
            // on a setting (`50.0 Hz` from a file's `50` as from a drive's `50.0`).
            let settings = crate::LiveSettings::default();
            let decimals = match plan.scale(&settings.view(drive)) {
                Some(Ok(scale)) => Some(scale.decimals()),
                _ => None,
            };
            let text = match (s.value.trim().parse::<f64>(), decimals) {
                (Ok(v), Some(d)) if v.is_finite() => format!("{v:.d$}"),
                _ => s.value.clone(),
            };
            if plan.unit.is_empty() {
                text
            } else {
                format!("{text} {}", plan.unit)
            }
        }
    }
}

/// Compares two sides setting by setting under `drive` (the map of the left side). Refused,
/// naming what differs, when the sides are of different maps or variants, unless
/// `other_allowed`.
pub fn compare(
    drive: &Map,
    left: &Side,
    right: &Side,
    other_allowed: bool,
) -> Result<Compared, String> {
    let mut mismatch = Vec::new();
    for side in [left, right] {
        if side.set.drive != drive.id() {
            mismatch.push(format!(
                "{} is of map {}, not {}",
                side.label,
                super::quoted(&side.set.drive, 60),
                drive.id()
            ));
        }
    }
    let variants = |s: &Side| -> Vec<String> {
        s.set
            .variant
            .iter()
            .map(|(a, o)| format!("{a}={o}"))
            .collect()
    };
    if left.set.variant != right.set.variant
        && !left.set.variant.is_empty()
        && !right.set.variant.is_empty()
    {
        mismatch.push(format!(
            "{} is of variant {}, {} of {}",
            left.label,
            variants(left).join(", "),
            right.label,
            variants(right).join(", ")
        ));
    }
    if !mismatch.is_empty() && !other_allowed {
        return Err(format!(
            "{}; compare them anyway with --other",
            mismatch.join("; ")
        ));
    }
    let mut warnings = mismatch;
    let print = fingerprint(drive);
    for side in [left, right] {
        if !side.defaults && side.set.fingerprint != print {
            warnings.push(format!(
                "{} was saved with another version of the {} map (fingerprint {}, this map {print}); compared by id",
                side.label,
                drive.id(),
                super::quoted(&side.set.fingerprint, 40)
            ));
        }
    }
    let mut differences = Vec::new();
    let mut no_default = Vec::new();
    let mut same_count = 0;
    // Every setting of the map, then ids of either side the map does not know.
    let mut ids: Vec<String> = settings_of(drive)
        .iter()
        .map(|r| r.id().to_owned())
        .collect();
    for side in [left, right] {
        for s in &side.set.settings {
            if !ids.contains(&s.id) {
                ids.push(s.id.clone());
            }
        }
    }
    for id in ids {
        let l = left.set.get(&id);
        let r = right.set.get(&id);
        let register = by_id(drive, &id);
        let name = register.map_or_else(|| id.clone(), |r| r.label());
        let why_missing = |side: &Side| -> String {
            side.set
                .unread
                .iter()
                .find(|u| u.id == id)
                .map(|u| format!("{}: {}", side.label, u.reason))
                .unwrap_or_else(|| format!("{}: not in the set", side.label))
        };
        match (l, r) {
            (Some(a), Some(b)) if same(&a.value, &b.value) => same_count += 1,
            (None, None) => {}
            (Some(_), None) if right.defaults => no_default.push(name),
            (None, Some(_)) if left.defaults => no_default.push(name),
            (a, b) => differences.push(Difference {
                id: id.clone(),
                param: register.and_then(|r| r.param().map(str::to_owned)),
                name,
                left: a.map(|s| shown(drive, &id, s)),
                right: b.map(|s| shown(drive, &id, s)),
                why: match (a, b) {
                    (None, _) => Some(why_missing(left)),
                    (_, None) => Some(why_missing(right)),
                    _ => None,
                },
                source: register.and_then(|r| r.source().map(str::to_owned)),
            }),
        }
    }
    Ok(Compared {
        left: left.label.clone(),
        right: right.label.clone(),
        differences,
        no_default,
        same: same_count,
        warnings,
    })
}
