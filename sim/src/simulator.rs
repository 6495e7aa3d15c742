//! The simulated drive: register memory laid out by the map, the manual's rules, the drive model.

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;
use std::time::Duration;

use drivemap_codegen::ir::{Drive, Register};
use drivemap_codegen::model::DefaultValue;
use drivemap_live::{LiveSettings, Value, codec, leak_profile};
use drivemap_runtime::ValueError;
use drivemap_runtime::pdu::{self, Request, RequestDecodeError, Response, Words, function};
use drivemap_runtime::profile::CommandKind;
use drivemap_runtime::profile::{Profile, TransportKind};
use drivemap_runtime::{Table, WriteRestriction};
use drivemap_runtime::{rtu, tcp};

use crate::clock::{Clock, SystemClock};
use crate::exceptions::ExceptionPlan;
use crate::framing::{self, Decoded, Origin};
use crate::model::{DriveState, Model};
use crate::roles::{self, Resolved, Roles, RolesError, Rule, Source};

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

/// How to start a simulator.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// Slave address; default: the map's default slave address, else 1.
    pub slave: Option<u8>,
    /// Variant axis id → option id; axes not named take their first option.
    pub variants: BTreeMap<String, String>,
    /// External quantities (drive rating...), over the roles table's values.
    pub externals: BTreeMap<String, f64>,
    /// Power-on values, applied last: register id, parameter number or name → engineering
    /// value (a code for enumerations, the raw word for bit fields and plain words).
    pub initial: Vec<(String, f64)>,
    /// The roles table.
    pub roles: RolesChoice,
    /// Time for the drive model.
    pub clock: Arc<dyn Clock>,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            slave: None,
            variants: BTreeMap::new(),
            externals: BTreeMap::new(),
            initial: Vec::new(),
            roles: RolesChoice::Builtin,
            clock: Arc::new(SystemClock::new()),
        }
    }
}

impl SimOptions {
    /// Defaults: the map's slave address, base variants, built-in roles, the system clock.
    pub fn new() -> SimOptions {
        SimOptions::default()
    }

    /// Sets the slave address.
    pub fn slave(mut self, slave: u8) -> SimOptions {
        self.slave = Some(slave);
        self
    }

    /// Sets the clock.
    pub fn clock(mut self, clock: Arc<dyn Clock>) -> SimOptions {
        self.clock = clock;
        self
    }

    /// Chooses a variant option on an axis.
    pub fn variant(mut self, axis: &str, option: &str) -> SimOptions {
        self.variants.insert(axis.into(), option.into());
        self
    }

    /// Sets an external quantity.
    pub fn external(mut self, name: &str, value: f64) -> SimOptions {
        self.externals.insert(name.into(), value);
        self
    }

    /// Sets a register's power-on value (engineering units).
    pub fn set(mut self, register: &str, value: f64) -> SimOptions {
        self.initial.push((register.into(), value));
        self
    }

    /// Chooses the roles table.
    pub fn roles(mut self, roles: RolesChoice) -> SimOptions {
        self.roles = roles;
        self
    }
}

/// Why a simulator cannot start, or a register cannot be set.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The roles table names what the map does not have.
    #[error(transparent)]
    Roles(#[from] RolesError),
    /// The roles table does not parse.
    #[error("{0}")]
    RolesTable(String),
    /// No register by that name.
    #[error(transparent)]
    NotFound(#[from] drivemap_live::NotFound),
    /// A value the register cannot hold.
    #[error("cannot set {register} to {value}: {error}")]
    Value {
        register: String,
        value: f64,
        error: ValueError,
    },
    /// A slave address outside the drive's range.
    #[error("slave address {slave} is outside {drive}'s range {min} ..= {max}")]
    Slave {
        drive: String,
        slave: u8,
        min: u8,
        max: u8,
    },
    /// A variant the map does not define.
    #[error("{drive} has no variant `{option}` on axis `{axis}`; known: {known}")]
    Variant {
        drive: String,
        axis: String,
        option: String,
        known: String,
    },
    /// An external quantity the map does not use.
    #[error("{drive} has no external quantity `{name}`; known: {known}")]
    External {
        drive: String,
        name: String,
        known: String,
    },
}

/// What became of one request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Executed and answered normally.
    Ok,
    /// Answered with an exception.
    Exception {
        /// The drive's code.
        code: u8,
        /// Its name in the drive's manual, or the Modbus name.
        name: &'static str,
    },
    /// Addressed to slave 0: never answered; executed only where the drive allows broadcast.
    Broadcast {
        /// Whether the writes were executed.
        executed: bool,
    },
    /// Addressed to another slave: ignored.
    NotAddressed,
    /// CRC error or a frame that cannot be a request: ignored, as the manuals prescribe.
    Damaged,
}

/// One request as the log shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RequestRecord {
    /// The transport it came on.
    pub transport: TransportKind,
    /// Slave address or unit id (0: broadcast).
    pub slave: u8,
    /// Function code, if the frame got that far.
    pub function: Option<u8>,
    /// First register address in the PDU.
    pub address: Option<u16>,
    /// Registers read or written (0 for loop-back).
    pub quantity: usize,
    /// What happened.
    pub outcome: Outcome,
}

impl fmt::Display for RequestRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "slave {:>3}", self.slave)?;
        match self.function {
            Some(func) => write!(f, "  {func:02X}h")?,
            None => write!(f, "  --h")?,
        }
        match self.address {
            Some(a) => write!(f, "  {a:04X}h x{:<3}", self.quantity)?,
            None => write!(f, "  {:11}", "")?,
        }
        match self.outcome {
            Outcome::Ok => write!(f, "  ok"),
            Outcome::Exception { code, name } => write!(f, "  exception {code:02X}h ({name})"),
            Outcome::Broadcast { executed: true } => write!(f, "  broadcast executed, no reply"),
            Outcome::Broadcast { executed: false } => write!(f, "  broadcast refused, no reply"),
            Outcome::NotAddressed => write!(f, "  another slave's address, no reply"),
            Outcome::Damaged => write!(f, "  CRC or framing error, no reply"),
        }
    }
}

/// The result of [`Simulator::handle`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Handled {
    /// Length of the reply frame written to `out`, or `None` when the drive stays silent.
    pub reply: Option<usize>,
    /// What happened, for the log.
    pub record: RequestRecord,
}

/// Counters since start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Frames handled.
    pub requests: u32,
    /// Normal replies sent.
    pub replies: u32,
    /// Exception replies sent.
    pub exceptions: u32,
    /// Broadcasts executed.
    pub broadcasts_executed: u32,
    /// Broadcasts not executed (function or register not allowed, bad value).
    pub broadcasts_refused: u32,
    /// Frames for other slaves.
    pub not_addressed: u32,
    /// Damaged frames (CRC, length).
    pub damaged: u32,
}

/// Hashes a communication address by one multiplication (Fibonacci hashing), so that the
/// request path's lookups cost a few nanoseconds instead of SipHash's tens. The keys are the
/// map's addresses; a peer only chooses which key to look up, so hash flooding does not apply.
#[derive(Debug, Clone, Copy, Default)]
struct AddressHasher(u64);

impl Hasher for AddressHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u16(&mut self, n: u16) {
        // The multiplication spreads the address into the high bits, which the table's
        // control bytes use.
        self.0 = u64::from(n).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// Communication address → register index.
type AddressMap = HashMap<u16, usize, BuildHasherDefault<AddressHasher>>;

#[derive(Debug, Clone, Default)]
struct Layout {
    holding: AddressMap,
    input: AddressMap,
    broadcast: AddressMap,
}

#[derive(Debug, Clone)]
struct CommandTrack {
    id: &'static str,
    kind: CommandKind,
    writes: &'static [(u16, u16)],
    progress: usize,
    count: u32,
}

/// A drive simulated from its map.
#[derive(Debug)]
pub struct Simulator {
    drive: Arc<Drive>,
    profile: &'static Profile,
    slave: u8,
    index: HashMap<String, usize>,
    raw: Vec<u16>,
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
    stats: Stats,
    cache: TickCache,
}

/// What `tick` needs, resolved once and refreshed only when a register it depends on changes,
/// so a request allocates nothing and converts nothing while the drive model is steady.
#[derive(Debug, Default)]
struct TickCache {
    /// Registers whose raw word the settings and the model's inputs come from.
    inputs: Vec<usize>,
    /// Their words when `settings` and `params` were computed.
    seen: Vec<u16>,
    /// The frequency reference register when `params` were computed.
    reference_register: Option<usize>,
    settings: LiveSettings,
    /// The settings are not yet built or out of date.
    stale: bool,
    /// max frequency, accel, decel, reference (Hz); `None`: to compute.
    params: Option<[f64; 4]>,
    /// The model as last published into the registers; `None`: publish at the next tick.
    published: Option<Model>,
}

fn known_list(items: impl IntoIterator<Item = String>) -> String {
    let v: Vec<String> = items.into_iter().collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

impl Simulator {
    /// Starts a simulated drive: registers at the map's defaults (then the roles table's and the
    /// options' power-on values), the model stopped.
    pub fn new(drive: Drive, options: SimOptions) -> Result<Simulator, SimError> {
        let drive = Arc::new(drive);
        let profile = leak_profile(&drive);
        let index: HashMap<String, usize> = drive
            .registers
            .iter()
            .enumerate()
            .map(|(i, r)| (r.def.id.clone(), i))
            .collect();
        for (axis, option) in &options.variants {
            let ok = drive
                .variants
                .iter()
                .any(|a| a.id == *axis && a.options.iter().any(|o| o.id == *option));
            if !ok {
                return Err(SimError::Variant {
                    drive: drive.meta.id.clone(),
                    axis: axis.clone(),
                    option: option.clone(),
                    known: known_list(
                        drive.variants.iter().flat_map(|a| {
                            a.options.iter().map(move |o| format!("{}={}", a.id, o.id))
                        }),
                    ),
                });
            }
        }
        let table = match &options.roles {
            RolesChoice::Builtin => roles::builtin(&drive.meta.id).map_err(SimError::RolesTable)?,
            RolesChoice::Custom(r) => Some((**r).clone()),
            RolesChoice::NoModel => None,
        };
        let known_externals = roles::external_names(&drive);
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
            Some(t) => Some(Arc::new(roles::resolve(&drive, &index, t, &externals)?)),
            None => None,
        };
        let sa = &drive.protocol.slave_address;
        let slave = options.slave.or(sa.default).unwrap_or(1);
        if !(sa.min..=sa.max).contains(&slave) {
            return Err(SimError::Slave {
                drive: drive.meta.id.clone(),
                slave,
                min: sa.min,
                max: sa.max,
            });
        }
        let ids = |list: Vec<&Register>| -> Vec<usize> {
            list.iter()
                .filter_map(|r| index.get(r.id()).copied())
                .collect()
        };
        let selectors = ids(drive.selectors());
        let references = ids(drive.references());
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
        let mut sim = Simulator {
            raw: vec![0; drive.registers.len()],
            plan: ExceptionPlan::from_exceptions(profile.exceptions),
            drive,
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
            stats: Stats::default(),
            cache: TickCache::default(),
        };
        sim.cache.inputs = sim.tick_inputs();
        sim.cache.seen = vec![0; sim.cache.inputs.len()];
        sim.cache.stale = true;
        sim.apply_defaults();
        if let Some(r) = sim.roles.clone() {
            for &(i, v) in &r.initial {
                sim.set_index(i, v)?;
            }
        }
        for (name, v) in &options.initial {
            let i = sim.index_of(name)?;
            sim.set_index(i, *v)?;
        }
        sim.layouts = [sim.layout(false), sim.layout(true)];
        if let Some(r) = sim.roles.clone() {
            sim.model.mode = r.mode.as_ref().map(|m| m.initial);
            sim.model.reference_register = r.frequency_reference.first().copied();
        }
        sim.tick();
        Ok(sim)
    }

    /// The map.
    pub fn drive(&self) -> &Drive {
        &self.drive
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

    /// Whether a roles table gives this drive a model (run, ramp, status).
    pub fn has_model(&self) -> bool {
        self.roles.is_some()
    }

    /// The drive model's state, if it has one.
    pub fn state(&self) -> Option<DriveState> {
        self.roles.as_ref().map(|_| self.model.state())
    }

    /// Map defaults that could not be encoded at start (the register then starts at 0).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Counters since start.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Persist commands (`protocol.commands` of kind persist: ENTER, save) executed.
    pub fn persist_count(&self) -> u32 {
        self.commands
            .iter()
            .filter(|c| c.kind == CommandKind::Persist)
            .map(|c| c.count)
            .sum()
    }

    /// How often the command with this map id was executed, if the map has it.
    pub fn command_count(&self, id: &str) -> Option<u32> {
        self.commands.iter().find(|c| c.id == id).map(|c| c.count)
    }

    fn index_of(&self, name: &str) -> Result<usize, SimError> {
        let r = drivemap_live::find(&self.drive, name)?;
        Ok(self.index[r.id()])
    }

    /// A register's raw word, by id, parameter number or name.
    pub fn raw(&self, name: &str) -> Result<u16, SimError> {
        Ok(self.raw[self.index_of(name)?])
    }

    /// A register's value decoded by the map under the drive's own settings.
    pub fn value(&self, name: &str) -> Result<Value, SimError> {
        let i = self.index_of(name)?;
        let r = &self.drive.registers[i];
        codec::decode(&self.drive, r, self.raw[i], &self.settings()).map_err(|error| {
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
        self.set_index(i, value)?;
        self.after_write(i);
        self.invalidate();
        self.tick();
        Ok(())
    }

    /// Sets a register's raw word, without any check.
    pub fn set_raw(&mut self, name: &str, raw: u16) -> Result<(), SimError> {
        let i = self.index_of(name)?;
        self.tick();
        self.raw[i] = raw;
        self.after_write(i);
        self.invalidate();
        self.tick();
        Ok(())
    }

    /// The communication address of a register on a transport, as laid out at power-on (address
    /// alternatives resolved by the drive's own settings), if the register exists there.
    pub fn address_of(&self, name: &str, kind: TransportKind) -> Option<u16> {
        let i = self.index_of(name).ok()?;
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        [&layout.holding, &layout.input, &layout.broadcast]
            .iter()
            .find_map(|m| m.iter().find(|(_, v)| **v == i).map(|(a, _)| *a))
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
            let r = &self.drive.registers[i];
            s.absorb(&self.drive, r.def.address, self.raw[i]);
        }
        s
    }

    fn default_of(&self, r: &Register, settings: &LiveSettings) -> Option<f64> {
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
    fn apply_defaults(&mut self) {
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

    fn set_index(&mut self, i: usize, value: f64) -> Result<(), SimError> {
        let r = &self.drive.registers[i];
        let raw = codec::encode(&self.drive, r, value, &self.settings()).map_err(|error| {
            SimError::Value {
                register: r.id().into(),
                value,
                error,
            }
        })?;
        self.raw[i] = raw;
        Ok(())
    }

    /// Where each register lies on this link, as the plan places it: registers that do not exist
    /// on the transport are left out, and a register that moves (by setting, variant or
    /// transport) is at the address `RegisterPlan::address_for` gives, the same one the clients
    /// and the generated code use.
    fn layout(&self, tcp: bool) -> Layout {
        let settings = self.settings();
        let view = settings.view(&self.drive);
        let here = if tcp {
            TransportKind::Tcp
        } else {
            TransportKind::Rtu
        };
        let mut layout = Layout::default();
        for (i, r) in self.drive.registers.iter().enumerate() {
            let plan = self.drive.register_plan(r);
            if !plan.transports.contains(here) {
                continue;
            }
            let address = plan.address_for(&view, here);
            let space = if r.broadcast {
                &mut layout.broadcast
            } else {
                match plan.info.table {
                    Table::Holding => &mut layout.holding,
                    Table::Input => &mut layout.input,
                }
            };
            space.entry(address).or_insert(i);
        }
        layout
    }

    fn in_gap(&self, address: u16) -> bool {
        self.drive
            .gaps
            .iter()
            .filter_map(|g| g.addresses)
            .any(|[lo, hi]| (lo..=hi).contains(&address))
    }

    fn running(&self) -> bool {
        self.roles.is_some() && self.model.running()
    }

    /// Whether the drive's state allows writing `r` now.
    fn may_write_now(&self, r: &Register) -> bool {
        match self.drive.register_plan(r).restriction {
            WriteRestriction::None => true,
            WriteRestriction::Stopped => !self.running(),
            WriteRestriction::PrgMode => match self.model.mode {
                Some(m) => m == roles::Mode::Prg,
                None => !self.running(),
            },
        }
    }

    /// Whether the generated `encode` of this register would produce `raw`: decode it, encode
    /// the value back. Conversions that need a setting the drive cannot supply are accepted.
    fn accepts(&self, r: &Register, raw: u16, settings: &LiveSettings) -> bool {
        let value = match codec::decode(&self.drive, r, raw, settings) {
            Ok(Value::Bits { .. }) => f64::from(raw),
            Ok(v) => match v.as_f64() {
                Some(v) => v,
                None => return true,
            },
            Err(_) => return true,
        };
        match codec::encode(&self.drive, r, value, settings) {
            Ok(_) => true,
            Err(
                ValueError::OutOfRange { .. }
                | ValueError::WordOverflow { .. }
                | ValueError::UnknownCode { .. }
                | ValueError::NotFinite { .. },
            ) => false,
            Err(_) => true,
        }
    }

    fn decode_f64(&self, i: usize, settings: &LiveSettings) -> Option<f64> {
        codec::decode(&self.drive, &self.drive.registers[i], self.raw[i], settings)
            .ok()
            .and_then(|v| v.as_f64())
    }

    fn source_value(&self, s: &Source, settings: &LiveSettings) -> Option<f64> {
        match s {
            Source::Register(i) => self.decode_f64(*i, settings),
            Source::Value(v) => Some(*v),
        }
    }

    /// Reacts to a write of register `i`: mode switches, run/direction commands, reference.
    fn after_write(&mut self, i: usize) {
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

    fn track_commands(&mut self, address: u16, value: u16) {
        for c in &mut self.commands {
            if !c.writes.iter().any(|&(a, _)| a == address) {
                continue;
            }
            if c.writes.get(c.progress) == Some(&(address, value)) {
                c.progress += 1;
            } else if c.writes.first() == Some(&(address, value)) {
                c.progress = 1;
            } else {
                c.progress = 0;
            }
            if c.progress == c.writes.len() {
                c.count += 1;
                c.progress = 0;
            }
        }
    }

    /// Registers the settings and the model's inputs are read from.
    fn tick_inputs(&self) -> Vec<usize> {
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
    fn invalidate(&mut self) {
        self.cache.stale = true;
        self.cache.params = None;
        self.cache.published = None;
    }

    /// Brings the cached settings up to date with the registers; allocates only when a
    /// register they depend on changed.
    fn refresh_settings(&mut self) {
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

    fn store(&mut self, i: usize, value: f64, settings: &LiveSettings) {
        if let Ok(raw) = codec::encode(&self.drive, &self.drive.registers[i], value, settings) {
            self.raw[i] = raw;
        }
    }

    fn publish(&mut self, roles: &Resolved, settings: &LiveSettings, max_f: f64) {
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

    /// Answers one complete frame of `kind`. Returns the reply length written to `out` (at least
    /// [`tcp::MAX_FRAME`] bytes), or `None` when the drive stays silent. The frame is decoded
    /// and the reply framed by [`crate::framing`], the runtime's `decode_request` and
    /// `encode_response`.
    pub fn handle(&mut self, kind: TransportKind, frame: &[u8], out: &mut [u8]) -> Handled {
        self.stats.requests += 1;
        let mut record = RequestRecord {
            transport: kind,
            slave: 0,
            function: None,
            address: None,
            quantity: 0,
            outcome: Outcome::Damaged,
        };
        if kind.is_rtu_framed() {
            record.slave = frame.first().copied().unwrap_or(0);
            record.function = frame.get(1).copied();
        } else {
            record.function = frame.get(tcp::HEADER_LEN).copied();
        }
        let reply = match framing::decode(kind, frame) {
            Decoded::Damaged => None,
            Decoded::Refused { origin, error } => {
                record.slave = origin.slave();
                self.reject(origin, error, &mut record, out)
            }
            Decoded::Request { origin, request } => {
                record.slave = origin.slave();
                describe(&request, &mut record);
                self.dispatch(kind, origin, &request, &mut record, out)
            }
        };
        match record.outcome {
            Outcome::Ok => self.stats.replies += 1,
            Outcome::Exception { .. } => self.stats.exceptions += 1,
            Outcome::Broadcast { executed: true } => self.stats.broadcasts_executed += 1,
            Outcome::Broadcast { executed: false } => self.stats.broadcasts_refused += 1,
            Outcome::NotAddressed => self.stats.not_addressed += 1,
            Outcome::Damaged => self.stats.damaged += 1,
        }
        Handled { reply, record }
    }

    fn exception(&self, code: u8) -> Outcome {
        let name = match self.profile.exception(code) {
            Some(e) => e.name,
            None => drivemap_runtime::exception::standard(code)
                .map(|(n, _)| n)
                .unwrap_or("exception"),
        };
        Outcome::Exception { code, name }
    }

    /// A request the PDU decoder refused: an exception when addressed to this drive.
    fn reject(
        &mut self,
        origin: Origin,
        error: RequestDecodeError,
        record: &mut RequestRecord,
        out: &mut [u8],
    ) -> Option<usize> {
        let slave = origin.slave();
        if slave == rtu::BROADCAST {
            record.outcome = Outcome::Broadcast { executed: false };
            return None;
        }
        if slave != self.slave {
            record.outcome = Outcome::NotAddressed;
            return None;
        }
        let Some((f, code)) = framing::refusal(
            error,
            self.plan.illegal_function,
            self.plan.illegal_quantity,
        ) else {
            record.outcome = Outcome::Damaged;
            return None;
        };
        record.function = Some(f);
        record.outcome = self.exception(code);
        origin.reply(f, &Response::Exception { function: f, code }, out)
    }

    fn dispatch(
        &mut self,
        kind: TransportKind,
        origin: Origin,
        request: &Request<'_>,
        record: &mut RequestRecord,
        out: &mut [u8],
    ) -> Option<usize> {
        let slave = origin.slave();
        if slave == rtu::BROADCAST {
            let executed = self.broadcast(kind, request);
            record.outcome = Outcome::Broadcast { executed };
            return None;
        }
        if slave != self.slave {
            record.outcome = Outcome::NotAddressed;
            return None;
        }
        let f = request.function();
        let mut words = [0u16; pdu::MAX_READ as usize];
        let response = match self.execute(kind, request, &mut words) {
            Ok(r) => {
                record.outcome = Outcome::Ok;
                r
            }
            Err(code) => {
                record.outcome = self.exception(code);
                Response::Exception { function: f, code }
            }
        };
        origin.reply(f, &response, out)
    }

    fn broadcast(&mut self, kind: TransportKind, request: &Request<'_>) -> bool {
        let Some(b) = self.profile.broadcast else {
            return false;
        };
        let f = request.function();
        if !b.functions.contains(&f) {
            return false;
        }
        self.tick();
        let mut values = [0u16; pdu::MAX_WRITE as usize];
        let (address, n) = match *request {
            Request::WriteSingle { address, value } => {
                values[0] = value;
                (address, 1)
            }
            Request::WriteMultiple { address, values: v } => (address, v.copy_to(&mut values)),
            _ => return false,
        };
        if f == function::WRITE_MULTIPLE && n > usize::from(self.profile.max_write) {
            return false;
        }
        self.write(kind, address, &values[..n], true).is_ok()
    }

    fn execute<'w>(
        &mut self,
        kind: TransportKind,
        request: &Request<'_>,
        words: &'w mut [u16; pdu::MAX_READ as usize],
    ) -> Result<Response<'w>, u8> {
        self.tick();
        let f = request.function();
        if !self.profile.supports(f) {
            return Err(self.plan.illegal_function);
        }
        match *request {
            Request::ReadHolding { address, quantity }
            | Request::ReadInput { address, quantity } => {
                let q = usize::from(quantity);
                if q == 0 || q > usize::from(self.profile.max_read) || q > words.len() {
                    return Err(self.plan.illegal_quantity);
                }
                let table = if f == function::READ_HOLDING {
                    Table::Holding
                } else {
                    Table::Input
                };
                for (k, w) in words.iter_mut().take(q).enumerate() {
                    *w = self.read_one(kind, table, u32::from(address) + k as u32, k == 0)?;
                }
                Ok(Response::Registers(Words::Native(&words[..q])))
            }
            Request::WriteSingle { address, value } => {
                self.write(kind, address, &[value], false)?;
                Ok(Response::WriteSingle { address, value })
            }
            Request::WriteMultiple { address, values } => {
                let q = values.len();
                if q == 0 || q > usize::from(self.profile.max_write) {
                    return Err(self.plan.illegal_quantity);
                }
                let mut buf = [0u16; pdu::MAX_WRITE as usize];
                let n = values.copy_to(&mut buf);
                self.write(kind, address, &buf[..n], false)?;
                Ok(Response::WriteMultiple {
                    address,
                    quantity: n as u16,
                })
            }
            Request::LoopBack { data } => Ok(Response::LoopBack { data }),
        }
    }

    fn communication_address(&self, kind: TransportKind, pdu: u32) -> Result<u16, u8> {
        u16::try_from(pdu)
            .ok()
            .and_then(|p| self.profile.address_offsets.communication_address(p, kind))
            .ok_or(self.plan.illegal_address)
    }

    /// One word of a read. The first address must hold a readable register (or lie in a gap the
    /// map records); further addresses without a register are reserved and read 0 ("Reserved
    /// registers and data are meaningless", `000_032dced3a1e91a75.txt:908`). A write-only
    /// register answers 02h wherever it is.
    fn read_one(
        &self,
        kind: TransportKind,
        table: Table,
        pdu: u32,
        first: bool,
    ) -> Result<u16, u8> {
        let address = self.communication_address(kind, pdu)?;
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        let map = match table {
            Table::Holding => &layout.holding,
            Table::Input => &layout.input,
        };
        match map.get(&address) {
            Some(&i) if self.drive.registers[i].readable() => Ok(self.raw[i]),
            Some(_) => Err(self.plan.illegal_address),
            None if !first || (table == Table::Holding && self.in_gap(address)) => Ok(0),
            None => Err(self.plan.illegal_address),
        }
    }

    /// Checks every register of a write, then writes them all; a refused register writes none.
    fn write(
        &mut self,
        kind: TransportKind,
        address: u16,
        values: &[u16],
        broadcast: bool,
    ) -> Result<(), u8> {
        self.refresh_settings();
        let settings = &self.cache.settings;
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        let broadcast_space = broadcast && !layout.broadcast.is_empty();
        let allowed = self
            .profile
            .broadcast
            .map(|b| b.addresses)
            .unwrap_or_default();
        let mut targets = [(0u16, None, 0u16); pdu::MAX_WRITE as usize];
        if values.len() > targets.len() {
            return Err(self.plan.illegal_quantity);
        }
        for (k, &v) in values.iter().enumerate() {
            let comm = self.communication_address(kind, u32::from(address) + k as u32)?;
            let found = if broadcast_space {
                layout.broadcast.get(&comm)
            } else {
                layout.holding.get(&comm)
            };
            match found {
                Some(&i) => {
                    if broadcast
                        && !broadcast_space
                        && !allowed.is_empty()
                        && !allowed.contains(&comm)
                    {
                        return Err(self.plan.illegal_address);
                    }
                    let r = &self.drive.registers[i];
                    if !r.writable() {
                        return Err(self.plan.read_only);
                    }
                    if !self.may_write_now(r) {
                        return Err(self.plan.refused_now);
                    }
                    if !self.accepts(r, v, settings) {
                        return Err(self.plan.out_of_range);
                    }
                    targets[k] = (comm, Some(i), v);
                }
                None if !broadcast && v == 0 && self.in_gap(comm) => targets[k] = (comm, None, v),
                None => return Err(self.plan.illegal_address),
            }
        }
        for &(comm, i, v) in &targets[..values.len()] {
            if let Some(i) = i {
                self.raw[i] = v;
                self.after_write(i);
            }
            self.track_commands(comm, v);
        }
        self.tick();
        Ok(())
    }
}

fn describe(request: &Request<'_>, record: &mut RequestRecord) {
    record.function = Some(request.function());
    record.address = request.address();
    record.quantity = request.quantity();
}
