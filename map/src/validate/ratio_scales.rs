//! Ratio scales (`scale: {counts: 3600, equals: 60.0}`): positive parts fine enough to convert
//! exactly for the register's width, and `min`, `max` and `default` (base and every variant
//! override) each a whole number of counts inside the word, `min <= max`, the default inside.
//! A ratio is not allowed as a case of a selected scale.

use drivemap_core::ratio::Ratio;

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register};
use crate::model::{DefaultValue, Scale};
use crate::ratio::{exact, ratio_of};
use crate::source::Path;

fn err(drive: &Drive, out: &mut Vec<Diagnostic>, r: &Register, path: Path, message: String) {
    out.push(drive.error(&path, Some(r.id()), message));
}

/// The count of `value`, or an error naming the two counts around it.
fn count(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    r: &Register,
    ratio: Ratio,
    what: &str,
    value: f64,
    path: Path,
) -> Option<i64> {
    let unit = r.def.unit.as_deref().unwrap_or("");
    let Some(given) = exact(value) else {
        err(
            drive,
            out,
            r,
            path,
            format!("{what} {value} is not a decimal"),
        );
        return None;
    };
    match ratio.encode_exact(given) {
        Ok(raw) => {
            let word = r.full_limits();
            if raw < word.min || raw > word.max {
                err(
                    drive,
                    out,
                    r,
                    path,
                    format!(
                        "{what} {value} {unit} is raw {raw}, outside the register's word ({}..={})",
                        word.min, word.max
                    ),
                );
                return None;
            }
            Some(raw)
        }
        Err(b) => {
            err(
                drive,
                out,
                r,
                path,
                format!(
                    "{what} {value} {unit} is not a whole number of counts of {ratio} {unit}: the nearest legal values are {} and {} {unit}",
                    ratio.exact(b.below),
                    ratio.exact(b.above)
                ),
            );
            None
        }
    }
}

// The register, its ratio and the three values checked against it (min, max, default),
// where to report them (map, diagnostics, path) and the label: one check, no shared state.
#[allow(clippy::too_many_arguments)]
fn limits(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    r: &Register,
    ratio: Ratio,
    min: Option<f64>,
    max: Option<f64>,
    default: Option<&DefaultValue>,
    path: &Path,
    label: &str,
) {
    let lo = min.and_then(|v| {
        count(
            drive,
            out,
            r,
            ratio,
            &format!("{label}min"),
            v,
            path.key("min"),
        )
    });
    let hi = max.and_then(|v| {
        count(
            drive,
            out,
            r,
            ratio,
            &format!("{label}max"),
            v,
            path.key("max"),
        )
    });
    if let (Some(lo), Some(hi)) = (lo, hi)
        && lo > hi
    {
        err(
            drive,
            out,
            r,
            path.key("min"),
            format!(
                "{label}min {} is above max {}",
                min.unwrap_or_default(),
                max.unwrap_or_default()
            ),
        );
    }
    if let Some(DefaultValue::Value(d)) = default
        && let Some(raw) = count(
            drive,
            out,
            r,
            ratio,
            &format!("{label}default"),
            *d,
            path.key("default"),
        )
        && (lo.is_some_and(|lo| raw < lo) || hi.is_some_and(|hi| raw > hi))
    {
        err(
            drive,
            out,
            r,
            path.key("default"),
            format!("{label}default {d} is outside min..=max"),
        );
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        match &r.def.scale {
            Some(Scale::Ratio(s)) => {
                let word = r.full_limits();
                let Some(ratio) = ratio_of(s) else {
                    err(
                        drive,
                        out,
                        r,
                        r.key_path("scale"),
                        format!(
                            "ratio scale {} = {}: counts must be a whole number above 0 and equals a positive decimal",
                            s.counts, s.equals
                        ),
                    );
                    continue;
                };
                if !ratio.exact_for(word.min, word.max) {
                    err(
                        drive,
                        out,
                        r,
                        r.key_path("scale"),
                        format!(
                            "ratio scale {ratio} cannot be converted exactly for this register's word: counts × 10^decimals of equals, and equals' digits × the largest raw value, must stay below 2^53"
                        ),
                    );
                    continue;
                }
                limits(
                    drive,
                    out,
                    r,
                    ratio,
                    r.def.min,
                    r.def.max,
                    r.def.default.as_ref(),
                    &r.path,
                    "",
                );
                for (k, o) in &r.def.by_variant {
                    let (min, max) = r.limits_for(k);
                    limits(
                        drive,
                        out,
                        r,
                        ratio,
                        min,
                        max,
                        o.default.as_ref(),
                        &r.key_path("by_variant").key(k),
                        &format!("{k} "),
                    );
                }
            }
            Some(Scale::Selected(sel)) => {
                for (ci, case) in sel.cases.iter().enumerate() {
                    if matches!(case.scale, Scale::Ratio(_)) {
                        err(
                            drive,
                            out,
                            r,
                            r.key_path("scale").key("cases").index(ci).key("scale"),
                            "a ratio scale cannot be a case of a selected scale (not supported yet); give the case a decimal scale or split the register".into(),
                        );
                    }
                }
            }
            _ => {}
        }
    }
}
