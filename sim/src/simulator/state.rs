//! The drive model and the roles table behind it: which registers run the drive, ramp its
//! output and show its status. Everything that reads the roles table is here, so that the table
//! can be replaced without touching the other modules.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use drivemap_codegen::ir::{Drive, Register};
use drivemap_live::{LiveSettings, codec};
use drivemap_runtime::WriteRestriction;

use crate::model::{DriveState, Model};
use crate::roles::{self, Resolved, Roles, Rule, Source};

use super::options::known_list;
use super::{SimError, SimOptions, Simulator};

/// Which roles table the simulator uses.
#[derive(Debug, Clone, Default)]
pub enum RolesChoice {
    /// The built-in table (`sim/roles.yaml`); a drive it does not list gets no drive model.
    #[default]
    Builtin,
    /// A table given by the caller.
    Custom(Box<Roles>),
    /// No drive model: registers only.
    NoModel,
}

/// What `tick` needs, resolved once and refreshed only when a register it depends on changes,
/// so a request allocates nothing and converts nothing while the drive model is steady.
#[derive(Debug, Default)]
pub(super) struct TickCache {
    /// Registers whose raw word the settings and the model's inputs come from.
    pub(super) inputs: Vec<usize>,
    /// Their words when `settings` and `params` were computed.
    pub(super) seen: Vec<u16>,
    /// The frequency reference register when `params` were computed.
    pub(super) reference_register: Option<usize>,
    pub(super) settings: LiveSettings,
    /// The settings are not yet built or out of date.
    pub(super) stale: bool,
    /// max frequency, accel, decel, reference (Hz); `None`: to compute.
    pub(super) params: Option<[f64; 4]>,
    /// The model as last published into the registers; `None`: publish at the next tick.
    pub(super) published: Option<Model>,
}

/// External quantities by name (drive rating...).
type Externals = BTreeMap<String, f64>;

impl Simulator {
    /// The roles table `options` choose, checked against the map with the external quantities
    /// (the table's, then the options'), and those quantities.
    pub(super) fn resolve_roles(
        drive: &Drive,
        index: &HashMap<String, usize>,
        options: &SimOptions,
    ) -> Result<(Option<Arc<Resolved>>, Externals), SimError> {
        let table = match &options.roles {
            RolesChoice::Builtin => roles::builtin(&drive.meta.id).map_err(SimError::RolesTable)?,
            RolesChoice::Custom(r) => Some((**r).clone()),
            RolesChoice::NoModel => None,
        };
        let known_externals = roles::external_names(drive);
        let mut externals = table
            .as_ref()
            .map(|r| r.externals.clone())
            .unwrap_or_default();
        for (name, v) in &options.externals {
            if !known_externals.contains(name) {
                return Err(SimError::External {
                    drive: drive.meta.id.clone(),
                    name: name.clone(),
                    known: known_list(known_externals.clone()),
                });
            }
            externals.insert(name.clone(), *v);
        }
        let resolved = match &table {
            Some(t) => Some(Arc::new(roles::resolve(drive, index, t, &externals)?)),
            None => None,
        };
        Ok((resolved, externals))
    }

    /// The roles table's power-on values (after the map's defaults, before the options').
    pub(super) fn apply_role_values(&mut self) -> Result<(), SimError> {
        if let Some(r) = self.roles.clone() {
            for &(i, v) in &r.initial {
                self.set_index(i, v)?;
            }
        }
        Ok(())
    }

    /// The model at power-on: the roles table's initial mode and first frequency reference.
    pub(super) fn start_model(&mut self) {
        if let Some(r) = self.roles.clone() {
            self.model.mode = r.mode.as_ref().map(|m| m.initial);
            self.model.reference_register = r.frequency_reference.first().copied();
        }
    }
}

impl Simulator {
    /// Whether a roles table gives this drive a model (run, ramp, status).
    pub fn has_model(&self) -> bool {
        self.roles.is_some()
    }

    /// The drive model's state, if it has one.
    pub fn state(&self) -> Option<DriveState> {
        self.roles.as_ref().map(|_| self.model.state())
    }

    pub(super) fn running(&self) -> bool {
        self.roles.is_some() && self.model.running()
    }

    /// Whether the drive's state allows writing `r` now.
    pub(super) fn may_write_now(&self, r: &Register) -> bool {
        match self.drive.register_plan(r).restriction {
            WriteRestriction::None => true,
            WriteRestriction::Stopped => !self.running(),
            WriteRestriction::PrgMode => match self.model.mode {
                Some(m) => m == roles::Mode::Prg,
                None => !self.running(),
            },
        }
    }

    pub(super) fn decode_f64(&self, i: usize, settings: &LiveSettings) -> Option<f64> {
        codec::decode(&self.drive, &self.drive.registers[i], self.raw[i], settings)
            .ok()
            .and_then(|v| v.as_f64())
    }

    pub(super) fn source_value(&self, s: &Source, settings: &LiveSettings) -> Option<f64> {
        match s {
            Source::Register(i) => self.decode_f64(*i, settings),
            Source::Value(v) => Some(*v),
        }
    }

    /// Reacts to a write of register `i`: mode switches, run/direction commands, reference.
    pub(super) fn after_write(&mut self, i: usize) {
        let Some(roles) = self.roles.clone() else {
            return;
        };
        if let Some(m) = &roles.mode {
            for (bit, mode) in [(m.to_drv, roles::Mode::Drv), (m.to_prg, roles::Mode::Prg)] {
                if bit.register == i && bit.get(self.raw[i]) != 0 {
                    self.model.mode = Some(mode);
                    self.raw[i] = bit.put(self.raw[i], 0);
                }
            }
        }
        let raw = self.raw[i];
        for c in roles.commands.iter().filter(|c| c.register == i) {
            let on = |b: Option<roles::Bit>| b.map(|b| b.get(raw) != 0);
            let (fwd, rev) = (on(c.run_forward), on(c.run_reverse));
            self.model.run = on(c.run).unwrap_or(false) || fwd == Some(true) || rev == Some(true);
            self.model.reverse = on(c.reverse)
                .or(on(c.forward).map(|f| !f))
                .unwrap_or(rev == Some(true) && fwd != Some(true));
        }
        if roles.frequency_reference.contains(&i) {
            self.model.reference_register = Some(i);
        }
    }

    /// Registers the settings and the model's inputs are read from.
    pub(super) fn tick_inputs(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self
            .selectors
            .iter()
            .chain(&self.references)
            .copied()
            .collect();
        if let Some(r) = &self.roles {
            for s in [
                Some(&r.max_frequency),
                Some(&r.accel_time),
                r.decel_time.as_ref(),
            ]
            .into_iter()
            .flatten()
            {
                if let Source::Register(i) = s {
                    v.push(*i);
                }
            }
            v.extend(&r.frequency_reference);
        }
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Everything cached is recomputed at the next tick (after a write by hand).
    pub(super) fn invalidate(&mut self) {
        self.cache.stale = true;
        self.cache.params = None;
        self.cache.published = None;
    }

    /// Brings the cached settings up to date with the registers; allocates only when a
    /// register they depend on changed.
    pub(super) fn refresh_settings(&mut self) {
        let c = &mut self.cache;
        let mut changed = c.stale || c.reference_register != self.model.reference_register;
        for (k, &i) in c.inputs.iter().enumerate() {
            if c.seen[k] != self.raw[i] {
                c.seen[k] = self.raw[i];
                changed = true;
            }
        }
        if changed {
            c.reference_register = self.model.reference_register;
            c.stale = false;
            c.params = None;
            c.published = None;
            self.cache.settings = self.settings();
        }
    }

    /// Advances the drive model to the clock's time and updates the registers it drives.
    pub fn tick(&mut self) {
        let now = self.clock.now();
        let dt = now.saturating_sub(self.last_tick).as_secs_f64();
        self.last_tick = self.last_tick.max(now);
        let Some(roles) = self.roles.clone() else {
            return;
        };
        self.refresh_settings();
        let settings = std::mem::take(&mut self.cache.settings);
        let [max_f, accel, decel, reference] = match self.cache.params {
            Some(p) => p,
            None => {
                let max_f = self
                    .source_value(&roles.max_frequency, &settings)
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .unwrap_or(60.0);
                let accel = self
                    .source_value(&roles.accel_time, &settings)
                    .unwrap_or(0.0);
                let decel = roles
                    .decel_time
                    .as_ref()
                    .and_then(|s| self.source_value(s, &settings))
                    .unwrap_or(accel);
                let reference = self
                    .model
                    .reference_register
                    .and_then(|i| self.decode_f64(i, &settings))
                    .unwrap_or(0.0);
                let p = [max_f, accel, decel, reference];
                self.cache.params = Some(p);
                p
            }
        };
        self.model.aim(reference, max_f);
        self.model.advance(dt, max_f, accel, decel);
        // The registers the model drives are a function of the model, the settings and the
        // maximum frequency: published again only when one of them changed.
        if self.cache.published.as_ref() != Some(&self.model) {
            self.publish(&roles, &settings, max_f);
            self.cache.published = Some(self.model.clone());
        }
        self.cache.settings = settings;
    }

    pub(super) fn store(&mut self, i: usize, value: f64, settings: &LiveSettings) {
        if let Ok(raw) = codec::encode(&self.drive, &self.drive.registers[i], value, settings) {
            self.raw[i] = raw;
        }
    }

    pub(super) fn publish(&mut self, roles: &Resolved, settings: &LiveSettings, max_f: f64) {
        let out = self.model.output.abs();
        for &i in &roles.output_frequency {
            self.store(i, out, settings);
        }
        for &i in &roles.reference_monitor {
            self.store(i, self.model.reference, settings);
        }
        for s in &roles.status {
            let v = match &s.rule {
                Rule::When(c) => u16::from(self.model.holds(*c)),
                Rule::Codes(codes) => codes
                    .iter()
                    .find(|(c, _)| self.model.holds(*c))
                    .map(|&(_, code)| code)
                    .unwrap_or(0),
            };
            let r = s.bit.register;
            self.raw[r] = s.bit.put(self.raw[r], v);
        }
        let running = self.model.running();
        for f in &roles.follow {
            let v = if running {
                f.at_zero + (f.at_max - f.at_zero) * out / max_f
            } else {
                f.stopped
            };
            self.store(f.register, v, settings);
        }
    }
}
