//! Limits and defaults: min <= max, the default inside them, each a whole number of increments
//! that fits the word, for the base variant, every variant override and every selected case.

use crate::diagnostic::Diagnostic;
use crate::facts::data::{CaseData, Limits, scale_of};
use crate::ir::{Drive, Register, ValueKind};
use crate::model::DefaultValue;
use crate::source::Path;
use drivemap_core::scale::{Decimal, raw_of};

struct Checker<'a> {
    drive: &'a Drive,
    r: &'a Register,
    out: &'a mut Vec<Diagnostic>,
}

impl Checker<'_> {
    fn err(&mut self, path: Path, message: String) {
        let d = self.drive.error(&path, Some(self.r.id()), message);
        self.out.push(d);
    }

    /// Checks one value against the word at a factor; returns its raw integer.
    fn raw(&mut self, what: &str, value: f64, factor: Decimal, path: Path) -> Option<i128> {
        let word = self.r.full_limits();
        match raw_of(value, factor) {
            None => {
                self.err(
                    path,
                    format!("{what} {value} is not a whole number of increments of {factor}"),
                );
                None
            }
            Some(raw) if raw < i128::from(word.min) || raw > i128::from(word.max) => {
                self.err(
                    path,
                    format!(
                        "{what} {value} is raw {raw}, outside a {} ({}..={})",
                        match (self.r.def.pair.is_some(), self.r.def.signed) {
                            (false, true) => "signed word",
                            (false, false) => "16-bit word",
                            (true, true) => "signed 32-bit pair",
                            (true, false) => "32-bit pair",
                        },
                        word.min,
                        word.max
                    ),
                );
                None
            }
            Some(raw) => Some(raw),
        }
    }

    fn set(
        &mut self,
        min: Option<f64>,
        max: Option<f64>,
        default: Option<&DefaultValue>,
        factor: Decimal,
        path: &Path,
        label: &str,
    ) {
        let lo = min.and_then(|v| self.raw(&format!("{label}min"), v, factor, path.key("min")));
        let hi = max.and_then(|v| self.raw(&format!("{label}max"), v, factor, path.key("max")));
        if let (Some(lo), Some(hi)) = (lo, hi)
            && lo > hi
        {
            self.err(
                path.key("min"),
                format!(
                    "{label}min {} is above max {}",
                    min.unwrap_or_default(),
                    max.unwrap_or_default()
                ),
            );
        }
        if let Some(DefaultValue::Value(d)) = default
            && let Some(raw) = self.raw(&format!("{label}default"), *d, factor, path.key("default"))
        {
            let below = lo.is_some_and(|lo| raw < lo);
            let above = hi.is_some_and(|hi| raw > hi);
            if below || above {
                self.err(
                    path.key("default"),
                    format!(
                        "{label}default {d} is outside {}..={}",
                        min.map(|v| v.to_string()).unwrap_or("-".into()),
                        max.map(|v| v.to_string()).unwrap_or("-".into())
                    ),
                );
            }
        }
    }

    fn no_limits(&mut self, why: &str) {
        let d = &self.r.def;
        if d.min.is_some() || d.max.is_some() {
            let key = if d.min.is_some() { "min" } else { "max" };
            self.err(
                self.r.key_path(key),
                format!("`min`/`max` are not allowed here: {why}"),
            );
        }
        for (k, o) in &d.by_variant {
            if o.min.is_some() || o.max.is_some() {
                self.err(
                    self.r.key_path("by_variant").key(k),
                    format!("`min`/`max` are not allowed here: {why}"),
                );
            }
        }
    }

    /// `min`, `max` and `default` of the base variant and of every variant override, each a
    /// whole number of increments of `factor` inside the word.
    fn increments(&mut self, factor: Decimal) {
        let (r, d) = (self.r, &self.r.def);
        self.set(d.min, d.max, d.default.as_ref(), factor, &r.path, "");
        for (k, o) in &d.by_variant {
            let (min, max) = r.limits_for(k);
            let label = format!("{k} ");
            self.set(
                min,
                max,
                o.default.as_ref(),
                factor,
                &r.key_path("by_variant").key(k),
                &label,
            );
        }
    }

    /// A positive decimal factor, or an error at `path`.
    fn factor(&mut self, f: f64, path: Path) -> Option<Decimal> {
        match Decimal::from_f64(f) {
            Some(dec) if dec.is_positive() => Some(dec),
            _ => {
                self.err(path, format!("scale {f} must be a positive decimal"));
                None
            }
        }
    }

    fn full_scale(&mut self, full_scale: f64, path: Path) {
        if !full_scale.is_finite() || full_scale <= 0.0 {
            self.err(path, format!("full_scale {full_scale} must be positive"));
        }
    }

    /// The cases of a selected scale, each by its own scale's rule.
    fn cases(&mut self, cases: &[CaseData]) {
        for (ci, case) in cases.iter().enumerate() {
            let cp = self.r.cases_path().index(ci);
            match case.scale.limits() {
                Some(Limits::Increments(f)) => {
                    if let Some(dec) = self.factor(f, cp.key("scale")) {
                        let label = format!("case {:?} ", case.when);
                        self.set(case.min, case.max, None, dec, &cp, &label);
                    }
                }
                Some(Limits::Share { full_scale }) => {
                    if case.min.is_some() || case.max.is_some() {
                        self.err(
                            cp.key("min"),
                            "limits of a relative case are not supported; note them".into(),
                        );
                    }
                    self.full_scale(full_scale, cp.key("scale").key("full_scale"));
                }
                // Refused by `ratio_scales`.
                Some(Limits::OwnPass) | None => {}
                Some(Limits::Cases(_)) => self.err(
                    cp.key("scale"),
                    "a selected case cannot select again".into(),
                ),
            }
        }
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    // A coil's or discrete input's keys of a word and its default are `bits_valid`'s.
    for r in drive.registers.iter().filter(|r| !r.table.is_bits()) {
        let mut c = Checker { drive, r, out };
        let d = &r.def;
        match r.kind() {
            ValueKind::Word | ValueKind::UnitQuantity => c.increments(Decimal::ONE),
            ValueKind::Quantity(scale) => match scale_of(drive, scale).limits() {
                Some(Limits::Increments(f)) => match c.factor(f, r.key_path("scale")) {
                    Some(factor) => c.increments(factor),
                    None => continue,
                },
                Some(Limits::Share { full_scale }) => {
                    c.no_limits("the manual states relative values as a fraction of another quantity; record limits in a note");
                    c.full_scale(full_scale, r.key_path("scale").key("full_scale"));
                    if let Some(DefaultValue::Value(_)) = &d.default {
                        c.err(
                            r.key_path("default"),
                            "a relative value has no default in engineering units; note it instead"
                                .into(),
                        );
                    }
                }
                // Checked by `ratio_scales`.
                Some(Limits::OwnPass) | None => {}
                Some(Limits::Cases(cases)) => {
                    c.no_limits(
                        "the scale is selected by another parameter; give `min`/`max` in each case",
                    );
                    c.cases(cases);
                }
            },
            ValueKind::Enum(values) => {
                // A partial enumeration: the manual prints a range of codes but names only some.
                let one = Decimal::ONE;
                c.set(d.min, d.max, None, one, &r.path, "");
                for (k, o) in &d.by_variant {
                    if o.min.is_some() || o.max.is_some() {
                        c.err(
                            r.key_path("by_variant").key(k),
                            "an enumeration's code range cannot vary by variant".into(),
                        );
                    }
                }
                for (vi, v) in values.iter().enumerate() {
                    let below = d.min.is_some_and(|m| f64::from(v.value) < m);
                    let above = d.max.is_some_and(|m| f64::from(v.value) > m);
                    if below || above {
                        c.err(
                            r.key_path("values").index(vi).key("value"),
                            format!("listed code {} lies outside the printed range", v.value),
                        );
                    }
                }
                let mut defaults: Vec<(Path, f64)> = Vec::new();
                if let Some(DefaultValue::Value(v)) = &d.default {
                    defaults.push((r.key_path("default"), *v));
                }
                for (k, o) in &d.by_variant {
                    if let Some(DefaultValue::Value(v)) = &o.default {
                        defaults.push((r.key_path("by_variant").key(k).key("default"), *v));
                    }
                }
                for (path, v) in defaults {
                    let in_range = d.min.is_some_and(|m| v >= m)
                        && d.max.is_some_and(|m| v <= m)
                        && v.fract() == 0.0;
                    if !in_range && !values.iter().any(|e| f64::from(e.value) == v) {
                        c.err(path, format!("default {v} is not one of the listed codes"));
                    }
                }
            }
            // `min`, `max` and `default` on text are refused by `strings_valid`.
            ValueKind::Text(_) => {}
            ValueKind::Bits(_) => {
                c.no_limits("a bit-field register has no range");
                if let Some(DefaultValue::Value(v)) = &d.default
                    && !(v.fract() == 0.0 && (0.0..=65535.0).contains(v))
                {
                    c.err(
                        r.key_path("default"),
                        format!("default {v} is not a 16-bit word"),
                    );
                }
            }
        }
        let mut prev: Option<f64> = None;
        for (i, s) in d.display_steps.iter().enumerate() {
            if s.step.is_nan() || s.step <= 0.0 || prev.is_some_and(|p| s.from <= p) {
                c.err(
                    r.key_path("display_steps").index(i),
                    "display steps need a positive `step` and increasing `from`".into(),
                );
            }
            prev = Some(s.from);
        }
    }
}
