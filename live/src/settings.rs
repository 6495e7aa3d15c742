//! What conversions depend on, for a map loaded at run time: the generated `Settings`, keyed by
//! name instead of typed fields.

use std::collections::BTreeMap;

use drivemap_codegen::ir::{Drive, ValueKind};
use drivemap_codegen::model::Scale;

use crate::codec;

/// Variant choices, selector codes, reference values and external quantities.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LiveSettings {
    /// Variant axis id → option id. Missing axes use their first option.
    pub variants: BTreeMap<String, String>,
    /// Selector register id → raw code read from the drive.
    pub selectors: BTreeMap<String, u16>,
    /// Reference register id or external quantity name → engineering value.
    pub references: BTreeMap<String, f64>,
}

impl LiveSettings {
    /// The option chosen on `axis`, or the axis's base option.
    pub fn variant<'a>(&'a self, drive: &'a Drive, axis: &str) -> Option<&'a str> {
        self.variants.get(axis).map(String::as_str).or_else(|| {
            drive
                .variants
                .iter()
                .find(|a| a.id == axis)
                .map(|a| a.options[0].id.as_str())
        })
    }

    /// Whether `option` is the chosen option of its axis.
    pub fn has_variant(&self, drive: &Drive, option: &str) -> bool {
        drive
            .variant_option(option)
            .is_some_and(|(axis, _)| self.variant(drive, &axis.id) == Some(option))
    }

    /// Addresses of the parameters conversions depend on, for a client to read.
    pub fn dependencies(drive: &Drive) -> Vec<u16> {
        let mut out: Vec<u16> = drive.selectors().iter().map(|r| r.def.address).collect();
        for r in drive.references() {
            if !out.contains(&r.def.address) {
                out.push(r.def.address);
            }
        }
        out
    }

    /// Records a raw word read from one of the dependencies; returns whether it was used.
    pub fn absorb(&mut self, drive: &Drive, address: u16, raw: u16) -> bool {
        let mut used = false;
        for sel in drive.selectors() {
            if sel.def.address == address {
                self.selectors.insert(sel.def.id.clone(), raw);
                used = true;
            }
        }
        for r in drive.references() {
            if r.def.address == address {
                let value = match r.kind() {
                    ValueKind::Word => {
                        Some(drivemap_runtime::scale::word_to_int(raw, r.def.signed) as f64)
                    }
                    ValueKind::Quantity(Scale::Factor(_)) | ValueKind::UnitQuantity => {
                        codec::decode(drive, r, raw, self)
                            .ok()
                            .and_then(|v| v.as_f64())
                    }
                    _ => None,
                };
                if let Some(v) = value {
                    self.references.insert(r.def.id.clone(), v);
                    used = true;
                }
            }
        }
        used
    }
}
