//! The simulated drive: register memory laid out by the map, the manual's rules, the drive model.
//!
//! By concern, one module each: `options` ([`SimOptions`], [`SimError`]), `defaults` (the map's
//! power-on values), `layout` (where each register lies per transport), `rules` (what a read or
//! a write may do, persist commands), `state` (the drive model from the map's roles: the only
//! module that reads them; the others name their type only, in the `roles` field), `dispatch`
//! (one frame in, one reply out, [`RequestRecord`], [`Stats`]), `functions` (a function a register
//! does not accept, answered with the map's exception).

mod defaults;
mod dispatch;
mod functions;
mod layout;
mod options;
mod rules;
mod state;

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Duration;

use drivemap_live::codec::{self, Value};
use drivemap_live::{LiveSettings, leak_profile};
use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::core::profile::{Profile, TransportKind};

use crate::ExceptionPlan;
use crate::clock::Clock;
use crate::model::Model;
use crate::roles::Resolved;

pub use dispatch::{Handled, Outcome, RequestRecord, Stats};
use layout::Layout;
use options::known_list;
pub use options::{SimError, SimOptions};
use rules::CommandTrack;
pub use state::RolesChoice;
use state::TickCache;

/// A drive simulated from its map.
///
/// A clone is the same drive in the same state, going on on its own from there (starting one is
/// far dearer: a test that needs many fresh drives clones one); it keeps the clock until
/// [`Simulator::set_clock`] gives it another.
#[derive(Debug, Clone)]
pub struct Simulator {
    map: Arc<Map>,
    profile: &'static Profile,
    slave: u8,
    /// Each register's index by id (the map's, shared by clones).
    index: Arc<HashMap<String, usize>>,
    /// Each register's raw value: its word, or a 32-bit pair's value.
    raw: Vec<u32>,
    /// Each string register's words (`string:`; empty for other registers): the manual's
    /// example, or the simulator's placeholder ([`defaults::PLACEHOLDER`]). Read-only.
    texts: Vec<Vec<u16>>,
    /// The last value a master wrote to each register (none since power-on), to tell a changed
    /// value from a repeated one (`repeat_needs_change`), and for registers whose reads mean
    /// something else (`read_values`) or return another parameter (`read_param`), whose `raw`
    /// value is the read state.
    last_written: Vec<Option<u32>>,
    /// Writes the drive executed, per register: every accepted write, except that a register
    /// with `repeat_needs_change` executes only a value that differs from the previous write.
    executed: Vec<u32>,
    /// [RTU-framed, Modbus TCP].
    layouts: [Layout; 2],
    plan: ExceptionPlan,
    roles: Option<Arc<Resolved>>,
    model: Model,
    clock: Arc<dyn Clock>,
    last_tick: Duration,
    variants: BTreeMap<String, String>,
    externals: BTreeMap<String, f64>,
    selectors: Vec<usize>,
    references: Vec<usize>,
    commands: Vec<CommandTrack>,
    warnings: Vec<String>,
    /// The fault code registers' words before the drive tripped, restored by a reset.
    /// With the bits of each that show the code (a field's, or the whole word).
    fault_words: Vec<(usize, u32, u32)>,
    /// The link the frequency reference in force was last written on (`None`: set by hand or
    /// power-on): a reference from a link whose reference source is not selected is not used.
    reference_via: Option<TransportKind>,
    stats: Stats,
    cache: TickCache,
    /// Index/value register pairs: what each value register shows for the index selected.
    indexed: crate::indexed::IndexedBank,
    /// What the drive keeps over a power cycle ([`Simulator::power_cycle`]): each register's
    /// raw value at power-on, replaced by the values in force whenever a persist command of the
    /// map (ENTER, save) completes. Written values not stored are lost.
    stored: Vec<u32>,
    /// The checked writes of one request, before any is executed: kept from request to request
    /// (room for the longest coil write) so that a write allocates nothing.
    write_targets: Vec<(u16, Option<usize>, u32)>,
}

impl Simulator {
    /// Starts a simulated drive: registers at the map's defaults (then plausible values for role
    /// registers without one, then the options' power-on values), the model stopped.
    pub fn new(map: Map, options: SimOptions) -> Result<Simulator, SimError> {
        let map = Arc::new(map);
        let profile = leak_profile(&map);
        let index: Arc<HashMap<String, usize>> = Arc::new(
            map.registers()
                .map(|r| (r.id().to_owned(), r.index()))
                .collect(),
        );
        for (axis, option) in &options.variants {
            let ok = map
                .variants()
                .iter()
                .any(|a| a.id == *axis && a.options.iter().any(|o| o.id == *option));
            if !ok {
                return Err(SimError::Variant {
                    drive: map.id().to_owned(),
                    axis: axis.clone(),
                    option: option.clone(),
                    known: known_list(
                        map.variants().iter().flat_map(|a| {
                            a.options.iter().map(move |o| format!("{}={}", a.id, o.id))
                        }),
                    ),
                });
            }
        }
        let (resolved, externals) = Simulator::resolve_roles(&map, &options)?;
        let sa = &map.protocol().slave_address;
        // A range the manual does not print is the Modbus 1..=247.
        let (min, max) = sa.range();
        let slave = options.slave.or(sa.default).unwrap_or(1);
        if !(min..=max).contains(&slave) {
            return Err(SimError::Slave {
                drive: map.id().to_owned(),
                slave,
                min,
                max,
            });
        }
        let ids = |list: Vec<RegisterRef<'_>>| -> Vec<usize> {
            list.iter().map(RegisterRef::index).collect()
        };
        let selectors = ids(map.selectors());
        let references = ids(map.references());
        let commands = profile
            .commands
            .iter()
            .map(|c| CommandTrack {
                id: c.id,
                kind: c.kind,
                writes: c.writes,
                progress: 0,
                count: 0,
            })
            .collect();
        let count = map.registers().len();
        let mut sim = Simulator {
            raw: vec![0; count],
            texts: map.registers().map(defaults::text_words).collect(),
            last_written: vec![None; count],
            executed: vec![0; count],
            plan: ExceptionPlan::from_exceptions(profile.exceptions),
            map,
            profile,
            slave,
            index,
            layouts: [Layout::default(), Layout::default()],
            roles: resolved,
            model: Model::default(),
            last_tick: options.clock.now(),
            clock: options.clock.clone(),
            variants: options.variants.clone(),
            externals,
            selectors,
            references,
            commands,
            warnings: Vec::new(),
            fault_words: Vec::new(),
            reference_via: None,
            stats: Stats::default(),
            cache: TickCache::default(),
            indexed: crate::indexed::IndexedBank::default(),
            stored: Vec::new(),
            write_targets: Vec::with_capacity(usize::from(drivemap_runtime::pdu::MAX_WRITE_BITS)),
        };
        sim.indexed = crate::indexed::IndexedBank::new(sim.map.plan().indexed);
        sim.cache.inputs = sim.tick_inputs();
        sim.cache.seen = vec![0; sim.cache.inputs.len()];
        sim.cache.stale = true;
        sim.apply_defaults();
        sim.apply_role_values()?;
        sim.sources_at_power_on(options.network_source);
        for (name, v) in &options.initial {
            let i = sim.index_of(name)?;
            sim.set_index(i, *v)?;
        }
        sim.layouts = [sim.layout(false), sim.layout(true)];
        sim.start_model();
        sim.tick();
        sim.stored = sim.raw.clone();
        Ok(sim)
    }

    /// Switches the drive off and on: every register takes the value it had at power-on or at
    /// the last persist command (ENTER, save) that completed since, so what was written and
    /// not stored is lost; the drive model starts stopped, the last-written memory is empty.
    pub fn power_cycle(&mut self) {
        self.raw = self.stored.clone();
        self.last_written = vec![None; self.raw.len()];
        self.fault_words.clear();
        self.reference_via = None;
        self.model = Model::default();
        self.invalidate();
        self.layouts = [self.layout(false), self.layout(true)];
        self.last_tick = self.clock.now();
        self.start_model();
        self.tick();
    }

    /// The raw value of a register the drive would power on with ([`Simulator::power_cycle`]),
    /// by id, parameter number or name.
    pub fn stored(&self, name: &str) -> Result<u32, SimError> {
        Ok(self.stored[self.index_of(name)?])
    }

    /// The entries of the index/value register pairs (`indexed:` in the map), as served.
    pub fn indexed(&self) -> &crate::indexed::IndexedBank {
        &self.indexed
    }

    /// The entries of the index/value register pairs, to set as the keypad would.
    pub fn indexed_mut(&mut self) -> &mut crate::indexed::IndexedBank {
        &mut self.indexed
    }

    /// Takes its time from `clock` from now on: the drive model stands still between the last
    /// tick on the old clock and `clock`'s present time.
    pub fn set_clock(&mut self, clock: Arc<dyn Clock>) {
        self.tick();
        self.last_tick = clock.now();
        self.clock = clock;
    }

    /// The map.
    pub fn drive(&self) -> &Map {
        &self.map
    }

    /// Register `i` of the map (map order): `i` comes from the map itself.
    pub(super) fn reg(&self, i: usize) -> RegisterRef<'_> {
        self.map
            .register_at(i)
            .expect("a register index taken from the same map")
    }

    /// The runtime profile built from the map (the same a client of this drive uses).
    pub fn profile(&self) -> &'static Profile {
        self.profile
    }

    /// The slave address the drive answers to.
    pub fn slave(&self) -> u8 {
        self.slave
    }

    /// The exception code for each rule.
    pub fn exceptions(&self) -> ExceptionPlan {
        self.plan
    }

    /// Map defaults that could not be encoded at start (the register then starts at 0).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Counters since start.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    pub(super) fn index_of(&self, name: &str) -> Result<usize, SimError> {
        // An id is found first by `lookup::find` too; the other names go through it.
        if let Some(&i) = self.index.get(name) {
            return Ok(i);
        }
        let r = drivemap_live::lookup::find(&self.map, name)?;
        Ok(self.index[r.id()])
    }

    /// A register's raw word (a 32-bit pair's value), by id, parameter number or name.
    pub fn raw(&self, name: &str) -> Result<u32, SimError> {
        Ok(self.raw[self.index_of(name)?])
    }

    /// How many writes of this register the drive executed (see `repeat_needs_change` in the
    /// schema): every write the drive accepted, except that a register whose drive executes
    /// only a changed value ("244 > 0 > 244") counts a write equal to the previous one as not
    /// executed, and its drive model does not react to it.
    pub fn executed(&self, name: &str) -> Result<u32, SimError> {
        Ok(self.executed[self.index_of(name)?])
    }

    /// The last raw value a master wrote to this register since power-on. For a register whose
    /// reads mean something else (`read_values`) this is the only trace of a write: the
    /// simulator does not know the drive's password, so a write does not change what reads
    /// give (set that with [`Simulator::set_raw`]). Likewise for a register read from another
    /// parameter than the one written (`read_param`, BICO: a write sets P2200, a read returns
    /// the status bit r0055.8, which the simulated drive does not derive from it).
    pub fn last_written(&self, name: &str) -> Result<Option<u32>, SimError> {
        Ok(self.last_written[self.index_of(name)?])
    }

    /// A register's value decoded by the map under the drive's own settings.
    pub fn value(&self, name: &str) -> Result<Value, SimError> {
        let i = self.index_of(name)?;
        let r = self.reg(i);
        codec::decode(&self.map, r, self.raw[i], &self.settings()).map_err(|error| {
            SimError::Value {
                register: r.id().into(),
                value: f64::from(self.raw[i]),
                error,
            }
        })
    }

    /// Sets a register as if a master had written it (engineering units), without the
    /// protocol's checks of access and state. The drive model reacts as to a write.
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), SimError> {
        let i = self.index_of(name)?;
        self.tick();
        let before = self.raw[i];
        self.set_index(i, value)?;
        self.after_write(i, before, None);
        self.invalidate();
        self.tick();
        Ok(())
    }

    /// Sets a register's raw word (a 32-bit pair's value), without any check.
    pub fn set_raw(&mut self, name: &str, raw: u32) -> Result<(), SimError> {
        let i = self.index_of(name)?;
        self.tick();
        let before = self.raw[i];
        self.raw[i] = raw;
        self.after_write(i, before, None);
        self.invalidate();
        self.tick();
        Ok(())
    }

    /// The settings conversions depend on, from the drive's own registers: selector codes,
    /// reference values, variants and external quantities.
    pub fn settings(&self) -> LiveSettings {
        let mut s = LiveSettings {
            variants: self.variants.clone(),
            ..LiveSettings::default()
        };
        for (k, v) in &self.externals {
            s.references.insert(k.clone(), *v);
        }
        // Selectors first: a reference's conversion may depend on one. `absorb` converts each
        // word by the plan, as the generated `Settings::absorb` does.
        for &i in self.selectors.iter().chain(&self.references) {
            let r = self.reg(i);
            s.absorb(&self.map, r.address(), self.raw[i] as u16);
        }
        s
    }

    pub(super) fn set_index(&mut self, i: usize, value: f64) -> Result<(), SimError> {
        let r = self.reg(i);
        let raw = codec::encode(&self.map, r, value, &self.settings()).map_err(|error| {
            SimError::Value {
                register: r.id().into(),
                value,
                error,
            }
        })?;
        self.raw[i] = raw;
        Ok(())
    }
}
