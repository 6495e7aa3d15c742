//! What conversions depend on, for a map loaded at run time: the generated `Settings`, keyed by
//! name instead of typed fields, and seen through the plan's slots ([`View`]).

use std::collections::BTreeMap;

use drivemap_map::Map;
use drivemap_map::{MapPlan, Quantity};
use drivemap_runtime::core::plan::SettingsView;

/// Variant choices, selector codes, reference values and external quantities.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LiveSettings {
    /// Variant axis id → option id. Missing axes use their first option.
    pub variants: BTreeMap<String, String>,
    /// Selector register id → raw word read from the drive (or set). A slot that selects by a
    /// field of the register (`selected_by: status.decimals`) takes the field's value from it,
    /// as the generated `Settings::absorb` does.
    pub selectors: BTreeMap<String, u16>,
    /// Reference register id or external quantity name → engineering value.
    pub references: BTreeMap<String, f64>,
}

/// [`LiveSettings`] answering the plan's slots, as generated `Settings` do.
#[derive(Debug, Clone, Copy)]
pub struct View<'a> {
    plan: &'a MapPlan,
    settings: &'a LiveSettings,
}

impl SettingsView for View<'_> {
    fn code(&self, slot: u8) -> Option<u16> {
        let c = self.plan.settings.codes.get(usize::from(slot))?;
        self.settings
            .selectors
            .get(self.plan.registers[c.register].info.id)
            .map(|&word| c.code(word))
    }

    fn quantity(&self, slot: u8) -> Option<f64> {
        let key = match self.plan.settings.quantities.get(usize::from(slot))? {
            Quantity::Register(i) => self.plan.registers[*i].info.id,
            Quantity::External { id, .. } => id.as_str(),
        };
        self.settings.references.get(key).copied()
    }

    fn variant(&self, axis: u8) -> u8 {
        let Some((id, options)) = self.plan.settings.axes.get(usize::from(axis)) else {
            return 0;
        };
        self.settings
            .variants
            .get(id)
            .and_then(|chosen| options.iter().position(|o| o == chosen))
            .map_or(0, |i| i as u8)
    }
}

impl LiveSettings {
    /// These settings seen through `drive`'s plan.
    pub fn view<'a>(&'a self, drive: &'a Map) -> View<'a> {
        View {
            plan: drive.plan(),
            settings: self,
        }
    }

    /// The option chosen on `axis`, or the axis's base option.
    pub fn variant<'a>(&'a self, drive: &'a Map, axis: &str) -> Option<&'a str> {
        self.variants.get(axis).map(String::as_str).or_else(|| {
            drive
                .variants()
                .iter()
                .find(|a| a.id == axis)
                .map(|a| a.options[0].id.as_str())
        })
    }

    /// Whether `option` is the chosen option of its axis.
    pub fn has_variant(&self, drive: &Map, option: &str) -> bool {
        drive
            .variant_option(option)
            .is_some_and(|(axis, _)| self.variant(drive, &axis.id) == Some(option))
    }

    /// Addresses of the parameters conversions depend on, for a client to read.
    pub fn dependencies(drive: &Map) -> Vec<u16> {
        drive.plan().dependencies()
    }

    /// Records a raw word read from one of the dependencies; returns whether it was used.
    pub fn absorb(&mut self, drive: &Map, address: u16, raw: u16) -> bool {
        let plan = drive.plan();
        let mut used = false;
        for c in &plan.settings.codes {
            let r = &plan.registers[c.register];
            if r.info.address == address {
                self.selectors.insert(r.info.id.to_owned(), raw);
                used = true;
            }
        }
        for q in &plan.settings.quantities {
            if let Quantity::Register(i) = q {
                let r = &plan.registers[*i];
                if r.info.address == address
                    && let Ok(v) = r.decode_number(u32::from(raw), &self.view(drive))
                {
                    self.references.insert(r.info.id.to_owned(), v);
                    used = true;
                }
            }
        }
        used
    }
}
