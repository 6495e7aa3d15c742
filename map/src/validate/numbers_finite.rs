//! Every number that means a duration, a timing figure, a scale, a limit or a default is finite,
//! and timing figures are small enough to become a `Duration` (`frame_gap_chars: .inf` or
//! `1e30` used to pass validation and panic wherever the runtime turned them into time).

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register};
use crate::model::{DefaultValue, Interval, Scale};
use crate::source::Path;
use serde_yaml::Value;

/// The largest timing figure in milliseconds: one minute. Drives answer in milliseconds;
/// anything near this is a typo, and it keeps every derived `Duration` far from overflow.
pub(super) const MAX_TIMING_MS: f64 = 60_000.0;

/// The largest timing figure in character times (a minute at 115200 baud is ~630,000
/// characters; drives quote 1.5 to 10).
pub(super) const MAX_TIMING_CHARS: f64 = 1_000.0;

fn finite(drive: &Drive, out: &mut Vec<Diagnostic>, reg: Option<&str>, v: f64, path: Path) {
    if !v.is_finite() {
        out.push(drive.error(
            &path,
            reg,
            format!("`{v}` is not a finite number (`.inf` and `.nan` are not values)"),
        ));
    }
}

fn bounded(drive: &Drive, out: &mut Vec<Diagnostic>, v: f64, max: f64, unit: &str, path: Path) {
    if !v.is_finite() || !(0.0..=max).contains(&v) {
        out.push(drive.error(
            &path,
            None,
            format!("timing figure `{v}` {unit} must be a finite number in 0..={max} {unit}"),
        ));
    }
}

fn interval(drive: &Drive, out: &mut Vec<Diagnostic>, i: &Interval, path: Path) {
    if let Some(ms) = i.ms {
        bounded(drive, out, ms, MAX_TIMING_MS, "ms", path.key("ms"));
    }
    if let Some(chars) = i.chars {
        bounded(
            drive,
            out,
            chars,
            MAX_TIMING_CHARS,
            "chars",
            path.key("chars"),
        );
    }
    if let Some(bits) = i.bits {
        // 11 bits per character.
        bounded(
            drive,
            out,
            f64::from(bits),
            MAX_TIMING_CHARS * 11.0,
            "bits",
            path.key("bits"),
        );
    }
}

/// Every number a scale is written with, whatever its kind (a factor, `full_scale`, `equals`,
/// a selected case's scale and limits), read off the scale's serialized form: a kind of scale
/// adds no code here.
fn scale(drive: &Drive, out: &mut Vec<Diagnostic>, reg: &str, s: &Scale, path: Path) {
    // Serializing a map's scale cannot fail (no map keys but strings, no custom serializer).
    if let Ok(value) = serde_yaml::to_value(s) {
        numbers(drive, out, reg, &value, path);
    }
}

fn numbers(drive: &Drive, out: &mut Vec<Diagnostic>, reg: &str, v: &Value, path: Path) {
    match v {
        Value::Number(n) => {
            if let Some(f) = n.as_f64() {
                finite(drive, out, Some(reg), f, path);
            }
        }
        // Nesting is bounded by the map's nesting depth (source::MAX_DEPTH).
        Value::Sequence(items) => {
            for (i, item) in items.iter().enumerate() {
                numbers(drive, out, reg, item, path.index(i));
            }
        }
        Value::Mapping(entries) => {
            for (key, item) in entries {
                if let Some(key) = key.as_str() {
                    numbers(drive, out, reg, item, path.key(key));
                }
            }
        }
        Value::Tagged(tagged) => numbers(drive, out, reg, &tagged.value, path),
        Value::Null | Value::Bool(_) | Value::String(_) => {}
    }
}

fn limits(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    reg: &str,
    min: Option<f64>,
    max: Option<f64>,
    default: Option<&DefaultValue>,
    path: &Path,
) {
    if let Some(v) = min {
        finite(drive, out, Some(reg), v, path.key("min"));
    }
    if let Some(v) = max {
        finite(drive, out, Some(reg), v, path.key("max"));
    }
    if let Some(DefaultValue::Value(v)) = default {
        finite(drive, out, Some(reg), *v, path.key("default"));
    }
}

fn register(drive: &Drive, out: &mut Vec<Diagnostic>, r: &Register) {
    let d = &r.def;
    let id = r.id();
    if let Some(s) = &d.scale {
        scale(drive, out, id, s, r.path.key("scale"));
    }
    limits(drive, out, id, d.min, d.max, d.default.as_ref(), &r.path);
    for (option, o) in &d.by_variant {
        let vp = r.path.key("by_variant").key(option);
        limits(drive, out, id, o.min, o.max, o.default.as_ref(), &vp);
    }
    for (i, step) in d.display_steps.iter().enumerate() {
        let sp = r.path.key("display_steps").index(i);
        finite(drive, out, Some(id), step.from, sp.key("from"));
        finite(drive, out, Some(id), step.step, sp.key("step"));
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    if let Some(t) = &drive.protocol.timing {
        let tp = Path::root().key("protocol").key("timing");
        bounded(
            drive,
            out,
            t.frame_gap_chars(),
            MAX_TIMING_CHARS,
            "chars",
            tp.key("frame_gap_chars"),
        );
        for (name, i) in t.figures() {
            if let Some(i) = i {
                interval(drive, out, i, tp.key(name));
            }
        }
    }
    for r in &drive.registers {
        register(drive, out, r);
    }
}
