//! The map's defaults at power-on. The only use of the serde model (`DefaultValue`): a variant's
//! default (`by_variant`) is in neither `drivemap_codegen::ir` nor the plan (`ir::Register::
//! default_value` gives the base variant's only).

use drivemap_codegen::ir::Register;
use drivemap_codegen::model::DefaultValue;
use drivemap_live::{LiveSettings, codec};

use super::Simulator;

impl Simulator {
    pub(super) fn default_of(&self, r: &Register, settings: &LiveSettings) -> Option<f64> {
        let by_variant = r
            .def
            .by_variant
            .iter()
            .find(|(k, _)| settings.has_variant(&self.drive, k))
            .and_then(|(_, o)| o.default.as_ref());
        match by_variant.or(r.def.default.as_ref()) {
            Some(DefaultValue::Value(v)) => Some(*v),
            _ => None,
        }
    }

    /// Map defaults: selectors and references first (other registers' scales depend on them).
    pub(super) fn apply_defaults(&mut self) {
        let first: Vec<usize> = self
            .selectors
            .iter()
            .chain(&self.references)
            .copied()
            .collect();
        let rest: Vec<usize> = (0..self.raw.len()).filter(|i| !first.contains(i)).collect();
        for pass in [first, rest] {
            let settings = self.settings();
            for i in pass {
                let r = &self.drive.registers[i];
                let Some(v) = self.default_of(r, &settings) else {
                    continue;
                };
                match codec::encode(&self.drive, r, v, &settings) {
                    Ok(raw) => self.raw[i] = raw,
                    Err(e) => self
                        .warnings
                        .push(format!("{}: default {v} not set: {e}", r.id())),
                }
            }
        }
    }
}
