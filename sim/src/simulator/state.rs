//! The drive model and the map's roles behind it: which registers run the drive, ramp its
//! output and show its status. Everything that reads the roles is here.

use std::collections::BTreeMap;
use std::sync::Arc;

use drivemap_live::{LiveSettings, codec};
use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::WriteRestriction;

use crate::DriveState;
use crate::model::Model;
use crate::roles::{self, Follow, Plausible, Resolved, Source};

use super::options::known_list;
use super::{SimError, SimOptions, Simulator};

/// Whether the simulator runs a drive model.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum RolesChoice {
    /// The drive model the map's `roles:` describe; a map without roles gets none.
    #[default]
    FromMap,
    /// No drive model: registers only.
    NoModel,
}

/// What `tick` needs, resolved once and refreshed only when a register it depends on changes,
/// so a request allocates nothing and converts nothing while the drive model is steady.
#[derive(Debug, Clone, Default)]
pub(super) struct TickCache {
    /// Registers whose raw word the settings and the model's inputs come from.
    pub(super) inputs: Vec<usize>,
    /// Their words when `settings` and `params` were computed.
    pub(super) seen: Vec<u32>,
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
    /// The map's roles, resolved, and the external quantities: the options', else plausible
    /// values ([`Plausible`]).
    pub(super) fn resolve_roles(
        map: &Map,
        options: &SimOptions,
    ) -> Result<(Option<Arc<Resolved>>, Externals), SimError> {
        use drivemap_runtime::core::roles::Role;
        use drivemap_runtime::core::roles::Target;
        let known_externals: Vec<String> =
            map.externals().iter().map(|q| q.external.clone()).collect();
        let max_external = map
            .plan()
            .roles
            .of(Role::MaxFrequency)
            .find_map(|p| match p.target {
                Target::External { name, .. } => Some(name),
                _ => None,
            });
        let mut externals: Externals = known_externals
            .iter()
            .map(|name| {
                let v = if Some(name.as_str()) == max_external {
                    Plausible::MAX_FREQUENCY
                } else {
                    Plausible::EXTERNAL
                };
                (name.clone(), v)
            })
            .collect();
        for (name, v) in &options.externals {
            if !known_externals.contains(name) {
                return Err(SimError::External {
                    drive: map.id().to_owned(),
                    name: name.clone(),
                    known: known_list(known_externals.clone()),
                });
            }
            externals.insert(name.clone(), *v);
        }
        let resolved = match options.roles {
            RolesChoice::FromMap => {
                roles::resolve(map, &|name: &str| externals.get(name).copied()).map(Arc::new)
            }
            RolesChoice::NoModel => None,
        };
        Ok((resolved, externals))
    }

    /// Plausible power-on values of role registers the map prints no default for (after the
    /// map's defaults, before the options').
    pub(super) fn apply_role_values(&mut self) -> Result<(), SimError> {
        if let Some(r) = self.roles.clone() {
            for &(i, v) in &r.initial {
                self.set_index(i, v)?;
            }
        }
        Ok(())
    }

    /// The model at power-on: program mode where the map has mode roles, the first frequency
    /// reference.
    pub(super) fn start_model(&mut self) {
        if let Some(r) = self.roles.clone() {
            self.model.mode = r.modes.then_some(roles::Mode::Prg);
            self.model.reference_register = r.frequency_reference.first().copied();
            // A drive with a command profile powers on in the state its manual names.
            self.model.machine = r.profile.map(|p| p.profile.power_on);
        }
    }
}

impl Simulator {
    /// The values of the map's external quantities the simulator converts with (given, or
    /// plausible: [`Plausible`]).
    pub fn externals(&self) -> &BTreeMap<String, f64> {
        &self.externals
    }

    /// Whether the simulator runs a drive model (the map gives roles).
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
    pub(super) fn may_write_now(&self, r: RegisterRef<'_>) -> bool {
        match r.plan().restriction {
            WriteRestriction::None => true,
            WriteRestriction::Stopped => !self.running(),
            WriteRestriction::PrgMode => match self.model.mode {
                Some(m) => m == roles::Mode::Prg,
                None => !self.running(),
            },
        }
    }

    pub(super) fn decode_f64(&self, i: usize, settings: &LiveSettings) -> Option<f64> {
        codec::decode(&self.map, self.reg(i), self.raw[i], settings)
            .ok()
            .and_then(|v| v.as_f64())
    }

    pub(super) fn source_value(&self, s: &Source, settings: &LiveSettings) -> Option<f64> {
        match s {
            Source::Register(i) => self.decode_f64(*i, settings),
            Source::Value(v) => Some(*v),
        }
    }

    /// Trips the drive with fault `code`, as a drive does on overcurrent: the output stops at
    /// once (coasting), the run command is dropped, the `fault` status roles hold, `ready` does
    /// not, and the `fault_code` registers show `code` until a `fault_reset` command clears it
    /// (on its off → on transition where the map says `edge`). Run commands are ignored while
    /// tripped. Without a drive model, nothing happens.
    pub fn trip(&mut self, code: u16) {
        self.tick();
        let Some(roles) = self.roles.clone() else {
            return;
        };
        if self.model.fault.is_none() {
            self.fault_words = roles
                .follow
                .iter()
                .filter(|(_, f)| f.is_fault_code())
                .map(|&(i, f)| (i, self.raw[i], f.mask()))
                .collect();
        }
        self.model.fault = Some(code);
        self.model.run = false;
        if let Some(p) = roles.profile {
            self.model.machine = p.fault_state().or(self.model.machine);
        }
        self.model.output = 0.0;
        self.invalidate();
        self.tick();
    }

    /// Stops the drive at its own panel (a local stop, not a network command): the run
    /// command is dropped and the output ramps down; a drive with a command profile goes to
    /// the state its stop path's first transition leads to (CiA 402 *ready to switch on*). The
    /// network control word keeps what it held. Without a drive model, nothing happens.
    pub fn local_stop(&mut self) {
        self.tick();
        let Some(roles) = self.roles.clone() else {
            return;
        };
        self.model.run = false;
        if let Some(p) = roles.profile
            && self.model.fault.is_none()
        {
            let stop = p
                .profile
                .path(drivemap_runtime::core::command_profile::PathKind::Stop)
                .and_then(|path| path.via.first())
                .and_then(|&t| p.profile.transition(t));
            if let Some(t) = stop {
                self.model.machine = Some(t.to);
            }
        }
        self.invalidate();
        self.tick();
    }

    /// Opens (`true`) or closes an interlock at the drive (a safe torque off input, a DC bus not
    /// yet charged): while it is open a drive with a command profile refuses the transitions
    /// towards running (those of its run path that no stop, coast or quick stop path takes), so
    /// a master's run() waits out the transition's time limit and reports the state the drive
    /// stayed in; stops are still taken. Without a command profile, nothing changes.
    pub fn set_interlock(&mut self, open: bool) {
        self.model.interlock = open;
    }

    /// The state of the drive's command profile, by id, for a drive with one.
    pub fn profile_state(&self) -> Option<&'static str> {
        let p = self.roles.as_ref()?.profile?;
        Some(p.profile.state_id(self.model.machine?))
    }

    /// The source parameters at power-on: the map's defaults (the manual's factory setting)
    /// are in place; a status field that reports the source shows its `off` code (the drive
    /// at its factory setting takes commands from elsewhere); with `network`, the sources
    /// select the network on that link instead.
    pub(super) fn sources_at_power_on(&mut self, network: Option<TransportKind>) {
        let Some(roles) = self.roles.clone() else {
            return;
        };
        for p in roles.command_source.iter().chain(&roles.reference_source) {
            if p.field.width < 16
                && let Some(off) = p.field.off
            {
                self.raw[p.register] = u32::from(p.field.put(self.raw[p.register] as u16, off));
            }
        }
        if let Some(kind) = network {
            self.select_network_source(kind);
        }
        self.invalidate();
    }

    /// Selects the network as the source of run commands and of the reference on `kind`, as
    /// a person at the drive would (the simulator's operator panel: no protocol checks). Returns
    /// what was set, one line each (`n003 = 2 ("Built-in Modbus RTU ...")`).
    pub fn select_network_source(&mut self, kind: TransportKind) -> Vec<String> {
        let Some(roles) = self.roles.clone() else {
            return Vec::new();
        };
        self.tick();
        let mut done = Vec::new();
        for p in roles.command_source.iter().chain(&roles.reference_source) {
            if !p.transports.contains(kind) {
                continue;
            }
            let Some(&code) = p.field.on.first() else {
                continue;
            };
            let map = Arc::clone(&self.map);
            let r = map.register_at(p.register).expect("an index of the map");
            let plan = r.plan();
            self.raw[p.register] = u32::from(p.field.put(self.raw[p.register] as u16, code));
            let line = if p.field.width == 16 {
                let param = r.shown();
                match plan.label(code) {
                    Some(l) => format!("{param} = {code} (\"{}\")", l.name),
                    None => format!("{param} = {code}"),
                }
            } else {
                let fields = match plan.conversion {
                    drivemap_runtime::core::plan::Conversion::Bits { fields, .. } => fields,
                    _ => &[],
                };
                let field = fields
                    .iter()
                    .find(|f| (f.lsb, f.width) == (p.field.lsb, p.field.width))
                    .map_or("?", |f| f.id);
                format!("{}.{field} = {code}", r.id())
            };
            if !done.contains(&line) {
                done.push(line);
            }
        }
        self.invalidate();
        self.tick();
        done
    }

    /// Reacts to a write of register `i` (its word was `before`) that came over `via` (`None`:
    /// set by hand): mode switches, run/direction commands, fault reset, reference. Run and
    /// direction commands over a link whose command source is not selected are ignored, as the
    /// drive ignores them (fault resets and mode switches are taken whatever the source).
    pub(super) fn after_write(&mut self, i: usize, before: u32, via: Option<TransportKind>) {
        let Some(roles) = self.roles.clone() else {
            return;
        };
        use drivemap_runtime::core::roles::Role;
        let from_network = |places: &[roles::SourcePlace], raw: &[u32]| {
            via.is_none_or(|k| roles::network_selected(places, raw, k))
        };
        let takes_run = from_network(&roles.command_source, &self.raw);
        let raw = self.raw[i];
        let (mut run, mut fwd, mut rev, mut reverse) = (None, None, None, None);
        for c in roles.commands.iter().filter(|c| c.bit.register == i) {
            let on = c.bit.holds(raw);
            match c.role {
                Role::Run => run = Some(on),
                Role::RunForward => fwd = Some(on),
                Role::RunReverse => rev = Some(on),
                Role::Reverse => reverse = Some(on),
                Role::ToDriveMode | Role::ToProgramMode if on => {
                    // Mode switches act once and clear themselves.
                    self.model.mode = Some(if c.role == Role::ToDriveMode {
                        roles::Mode::Drv
                    } else {
                        roles::Mode::Prg
                    });
                    self.raw[i] = c.bit.put(self.raw[i], c.bit.field.code(false));
                }
                Role::FaultReset => {
                    // Where the manual does not print edge or level, the simulated drive acts
                    // on the edge: the stricter of the two, so a master that only sets fails here.
                    let acts = if c.bit.field.edge.needs_release_first() {
                        on && !c.bit.holds(before)
                    } else {
                        on
                    };
                    if acts && self.model.fault.take().is_some() {
                        for (r, word, mask) in std::mem::take(&mut self.fault_words) {
                            self.raw[r] = (self.raw[r] & !mask) | (word & mask);
                        }
                    }
                }
                _ => {}
            }
        }
        if self.model.fault.is_some() || !takes_run {
            // A tripped drive takes no run command until reset; a drive whose run command
            // source is not this link takes none from it (nor a direction).
            run = None;
            fwd = None;
            rev = None;
        }
        if !takes_run {
            reverse = None;
        }
        if run.is_some() || fwd.is_some() || rev.is_some() {
            self.model.run = run == Some(true) || fwd == Some(true) || rev == Some(true);
        }
        if let Some(r) = reverse {
            self.model.reverse = r;
        } else if fwd.is_some() || rev.is_some() {
            self.model.reverse = rev == Some(true) && fwd != Some(true);
        }
        if let Some(p) = roles.profile
            && p.control == i
            && let Some(state) = self.model.machine
            && let Some(t) = p.next(state, before as u16, raw as u16)
        {
            // The state machine as the manual prints it: only the transition the word asks
            // for from the state the drive is in; a run only from the network the drive takes
            // commands from, an acknowledge from any.
            let fault = p.fault_state() == Some(state);
            let refused = self.model.interlock && p.towards_run(t);
            if (takes_run || fault) && !refused {
                if fault && self.model.fault.take().is_some() {
                    for (r, word, mask) in std::mem::take(&mut self.fault_words) {
                        self.raw[r] = (self.raw[r] & !mask) | (word & mask);
                    }
                }
                self.model.machine = Some(t.to);
                self.model.run = p.profile.is_running(t.to) && self.model.fault.is_none();
            }
        }
        if roles.frequency_reference.contains(&i) {
            self.model.reference_register = Some(i);
            self.reference_via = via;
            self.cache.params = None;
        }
    }

    /// Whether the reference in force comes from a source the drive takes: set by hand, or
    /// written on a link whose reference source is selected.
    fn reference_taken(&self, roles: &Resolved) -> bool {
        self.reference_via
            .is_none_or(|k| roles::network_selected(&roles.reference_source, &self.raw, k))
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
            v.extend(
                r.command_source
                    .iter()
                    .chain(&r.reference_source)
                    .map(|p| p.register),
            );
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
                // A network reference the drive does not take: its own source (terminals the
                // simulator does not have) gives 0 Hz.
                let reference = self
                    .model
                    .reference_register
                    .filter(|_| self.reference_taken(&roles))
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

    /// Publishes a value the drive model computed (an output frequency while ramping): the drive
    /// shows the nearest step of the register, as a real monitor does.
    pub(super) fn store(&mut self, i: usize, value: f64, settings: &LiveSettings) {
        let r = self.reg(i);
        let nearest = drivemap_runtime::core::scale::Rounding::Nearest;
        if let Ok(raw) = codec::encode_with(&self.map, r, value, settings, nearest) {
            self.raw[i] = raw;
        }
    }

    pub(super) fn publish(&mut self, roles: &Resolved, settings: &LiveSettings, max_f: f64) {
        let out = self.model.output.abs();
        for s in &roles.status {
            if let Some(code) = s.code(|c| self.model.holds(c)) {
                self.raw[s.register] = s.put(self.raw[s.register], code);
            }
        }
        if let Some(p) = roles.profile
            && let Some(s) = self
                .model
                .machine
                .and_then(|s| p.profile.states.get(usize::from(s)))
        {
            // The state's bits in the status word, over what the status roles show.
            self.raw[p.status] = u32::from((self.raw[p.status] as u16 & !s.mask) | s.value);
        }
        let running = self.model.running();
        let fraction = if max_f > 0.0 { out / max_f } else { 0.0 };
        for &(i, follow) in &roles.follow {
            let v = match follow {
                Follow::Output => out,
                Follow::Reference => self.model.reference,
                Follow::Voltage => Plausible::RATED_VOLTAGE * fraction,
                Follow::Current if running => {
                    let (at_zero, at_max) = Plausible::CURRENT;
                    at_zero + (at_max - at_zero) * fraction
                }
                Follow::Current => 0.0,
                Follow::DcBus => Plausible::DC_BUS,
                Follow::FaultCode | Follow::LastFault => {
                    if let Some(code) = self.model.fault {
                        self.raw[i] = u32::from(code);
                    }
                    continue;
                }
                Follow::FaultCodeField(f) => {
                    if let Some(code) = self.model.fault {
                        // The code's low bits in the field; the rest of the word is kept.
                        let mask = f.mask();
                        self.raw[i] =
                            u32::from((self.raw[i] as u16 & !mask) | ((code << f.lsb) & mask));
                    }
                    continue;
                }
            };
            self.store(i, v, settings);
        }
    }
}
