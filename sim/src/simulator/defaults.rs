//! The map's defaults at power-on, for the variant options in force
//! (`ir::Register::default_for`).

use drivemap_codegen::ir::Register;
use drivemap_live::{LiveSettings, codec};

use super::Simulator;

impl Simulator {
    pub(super) fn default_of(&self, r: &Register, settings: &LiveSettings) -> Option<f64> {
        r.default_for(|option| settings.has_variant(&self.drive, option))
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
