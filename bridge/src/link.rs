//! One link (a serial line, a gateway, a drive's own TCP port) and the drives on it, polled by
//! the runtime's read planner in one blocking task: every drive each period, the commands of
//! its drives (from the [`Board`]) before every request of a cycle and while waiting for the
//! next, values into the metrics and onto the MQTT queue.
//!
//! A drive that does not answer a request is not asked again in that cycle (the rest of its
//! reads fail with that timeout), and after cycles without an answer it is polled with a
//! back-off (every 2nd, 4th, ... cycle, at most every 32nd), so a silent drive costs the line
//! one timeout per poll of it, not one per request, and holds no command back for longer.
//!
//! Nothing here waits for Prometheus or the broker: the metrics are atomics read by scrapes,
//! and MQTT updates are offered to a bounded queue with `try_send` (an update that does not fit
//! is dropped and counted, and the value is offered again at the next cycle, since it is only
//! marked published once queued).

use std::collections::BTreeSet;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use drivemap_live::codec::{self, Value};
use drivemap_live::session::rows_on_link;
use drivemap_live::{LiveSettings, lookup};
use drivemap_map::Map;
use drivemap_map::Quantity;
use drivemap_map::RegisterRef;
use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::core::roles::{Role, RoleKind};
use drivemap_runtime::core::width::Width;
use drivemap_runtime::planner::Poller;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{client::Client, client::ClientOptions, error::Error};

use crate::command::{Board, Intent, Next};
use crate::commander::Commander;
use crate::log::{Limiter, quote};
use crate::metrics::{Labels, Metrics};
use crate::points::{self, Meaning, Point};
use crate::{CommandFailure, PollFailure};

/// The client of a link: one for every drive on it, switched to each in turn
/// ([`Client::switch_drive`]), so the line's timing (the gap after the last reply, a late
/// reply still expected) holds across drives.
pub type LinkClient = Client<Box<dyn Transport>>;

/// A new connection of a link's transport.
pub type Connect = Box<dyn FnMut() -> Result<Box<dyn Transport>, crate::ConnectError> + Send>;

/// A drive on a link, as configured.
pub struct DriveSpec {
    /// Its map (loaded once, kept for the life of the process).
    pub drive: &'static Map,
    /// Slave address.
    pub slave: u8,
    /// A name unique in the bridge, used in topics and labels (`yaskawa-v7-1`).
    pub name: String,
    /// The client's timing for this drive on this link.
    pub options: ClientOptions,
    /// Variants and values given instead of read.
    pub settings: LiveSettings,
    /// Register ids whose value was given (not read from the drive).
    pub fixed: BTreeSet<String>,
    /// Registers to poll by name; empty: every role register and every read-only register.
    pub registers: Vec<String>,
    /// Whether writes may go through the drive's map when it is a draft (`--draft`); a
    /// reviewed map's writes are not affected.
    pub draft: drivemap_live::draft::DraftWrites,
    /// Poll periods longer than the link's for some registers: `(what, period)`, `what` a
    /// register (id, parameter number or name), a role id, a group of the map, or `status`
    /// (registers holding status roles), `monitors` (read-only) or `parameters` (writable). The
    /// most specific wins (register, then role, then group); the rest every cycle.
    pub periods: Vec<(String, Duration)>,
}

/// A link, as configured.
pub struct LinkSpec {
    /// How it is shown (`rtu-tcp 127.0.0.1:5020`), the `link` label.
    pub name: String,
    /// Its transport kind (addresses and framing).
    pub kind: TransportKind,
    /// The serial line, for the bus-time model.
    pub line: SerialConfig,
    /// Opens the transport.
    pub connect: Connect,
    /// The drives on it.
    pub drives: Vec<DriveSpec>,
    /// Whether its drives are polled every period (off for a link that only carries commands
    /// and proxied requests: `drivemap proxy`).
    pub poll: bool,
    /// Modbus TCP masters served on this link through the proxy (`--serve-modbus`,
    /// `drivemap proxy`).
    pub proxy: Option<crate::proxy::ProxyOptions>,
}

/// A command for a drive, from MQTT.
#[derive(Debug, Clone)]
pub struct Command {
    /// The drive's index in the bridge.
    pub drive: usize,
    /// What to do.
    pub action: Action,
    /// The topic it came on.
    pub topic: String,
    /// Its payload, as text.
    pub payload: String,
}

/// What a command does.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Write a register (by id, parameter or printed name) in engineering units.
    Set {
        /// The register as the command topic names it.
        register: String,
    },
    /// The drive trait's run.
    Run,
    /// The drive trait's stop.
    Stop,
    /// The drive trait's frequency reference (Hz).
    Reference,
    /// The drive trait's fault reset.
    FaultReset,
}

impl Action {
    /// The command's name in topics and metrics: `set`, `run`, `stop`, `reference`,
    /// `fault_reset`.
    pub fn name(&self) -> &'static str {
        match self {
            Action::Set { .. } => "set",
            Action::Run => "run",
            Action::Stop => "stop",
            Action::Reference => "reference",
            Action::FaultReset => "fault_reset",
        }
    }
}

/// What the link tells the MQTT side.
#[derive(Debug, Clone)]
pub enum Update {
    /// New values of points (index among the drive's points, payload).
    State {
        /// The drive's index in the bridge.
        drive: usize,
        /// Per changed point: its index among the drive's points, and the payload.
        values: Vec<(usize, String)>,
    },
    /// The drive answered (true) or stopped answering (false).
    Availability {
        /// The drive's index in the bridge.
        drive: usize,
        /// Whether it answers.
        online: bool,
    },
    /// A command's outcome: `Ok(what was done)` or `Err(why nothing was)`, with its word
    /// (`done`, `refused`, `expired`, `superseded`, `failed`, `pending` for a stop sent again).
    Outcome {
        /// The command.
        command: Command,
        /// What was done, or why nothing was.
        result: Result<String, Arc<CommandFailure>>,
        /// The outcome's word.
        outcome: &'static str,
    },
}

/// Offers an update to the MQTT side without waiting.
pub type Updates = Option<tokio::sync::mpsc::Sender<Update>>;

/// The reads of a drive that share a period.
struct Class {
    /// `None`: every cycle.
    period: Option<Duration>,
    poller: Poller,
    /// When it is due next.
    next: Instant,
    /// Polled in the cycle in progress.
    polled: bool,
}

/// The planned reads of a drive, by period.
struct Plan {
    classes: Vec<Class>,
    /// Per polled register: its class, its index among that class's wanted and its width, or
    /// why it is not read.
    slots: Vec<Result<(usize, usize, Width), PollFailure>>,
}

/// A raw value as a poll left it: the word(s), or the error kind and text.
type Raw = Result<u32, (&'static str, String)>;

/// A drive being polled.
pub struct Polled {
    /// Index in the bridge.
    pub index: usize,
    spec: DriveSpec,
    kind: TransportKind,
    settings: LiveSettings,
    regs: Vec<RegisterRef<'static>>,
    /// Indices in `regs` of what conversions and addresses depend on: selectors, then references.
    deps: Vec<usize>,
    /// The points published.
    pub points: Vec<Point<'static>>,
    base: Labels,
    plan: Option<Plan>,
    /// Last value given to MQTT per point.
    published: Vec<Option<String>>,
    /// The info-style label set in force per point.
    info: Vec<Option<Labels>>,
    online: Option<bool>,
    /// Cycles in a row in which the drive answered nothing.
    silent: u32,
    /// Cycles still to skip before it is polled again (the back-off of a silent drive).
    skip: u32,
    /// It answered its last poll.
    answered: bool,
    /// Per polled register: its period (`None`: every cycle).
    periods: Vec<Option<Duration>>,
    /// Per polled register: what its last poll read.
    last: Vec<Option<Raw>>,
}

/// The registers polled for `spec` on `kind`, and the indices of the dependencies among them.
pub fn choose(
    spec: &DriveSpec,
    kind: TransportKind,
) -> Result<(Vec<RegisterRef<'static>>, Vec<usize>), crate::Error> {
    let drive = spec.drive;
    let on = |r: RegisterRef<'_>| r.plan().transports.contains(kind);
    let readable = |r: RegisterRef<'_>| r.readable() && !r.broadcast_only() && on(r);
    let mut regs: Vec<RegisterRef<'static>> = Vec::new();
    let add = |r: RegisterRef<'static>, regs: &mut Vec<RegisterRef<'static>>| {
        if !regs.iter().any(|x| x.id() == r.id()) {
            regs.push(r);
        }
    };
    if spec.registers.is_empty() {
        for r in points::role_registers(drive, kind) {
            if readable(r) {
                add(r, &mut regs);
            }
        }
        for r in drive.registers() {
            if readable(r) && !r.writable() {
                add(r, &mut regs);
            }
        }
    } else {
        let mut errors = Vec::new();
        for n in &spec.registers {
            match lookup::find(drive, n) {
                Ok(r) if readable(r) => add(r, &mut regs),
                Ok(r) => errors.push(crate::RegisterProblem::Unreadable {
                    link: spec.name.clone(),
                    register: r.label(),
                }),
                Err(source) => errors.push(crate::RegisterProblem::NotFound {
                    link: spec.name.clone(),
                    source,
                }),
            }
        }
        if !errors.is_empty() {
            return Err(crate::Error::Registers(errors));
        }
    }
    // What conversions and addresses depend on, read with every cycle: selectors first, then
    // references, so that a change is seen at the next cycle.
    let plan = drive.plan();
    let mut deps = Vec::new();
    let selectors = plan.settings.codes.iter().map(|c| c.register);
    let references = plan.settings.quantities.iter().filter_map(|q| match q {
        Quantity::Register(i) => Some(*i),
        Quantity::External { .. } => None,
    });
    for row in selectors.chain(references) {
        let Some(r) = drive.register_of_row(row) else {
            continue;
        };
        if spec.fixed.contains(r.id()) || !readable(r) {
            continue;
        }
        add(r, &mut regs);
        if let Some(i) = regs.iter().position(|x| x.id() == r.id())
            && !deps.contains(&i)
        {
            deps.push(i);
        }
    }
    if regs.is_empty() {
        return Err(crate::Error::NothingReadable {
            link: spec.name.clone(),
        });
    }
    Ok((regs, deps))
}

/// The points the bridge publishes of `spec` on `kind`: those of the registers [`choose`]
/// polls.
pub fn points_of(
    spec: &DriveSpec,
    kind: TransportKind,
) -> Result<Vec<Point<'static>>, crate::Error> {
    let (regs, _) = choose(spec, kind)?;
    Ok(points::polled(spec.drive, &regs, kind))
}

/// The period of each of `regs` from `spec.periods` (see [`DriveSpec::periods`]); the
/// dependencies (`deps`, what conversions depend on) every cycle. A `what` that names no polled
/// register is an error.
fn periods_of(
    spec: &DriveSpec,
    kind: TransportKind,
    regs: &[RegisterRef<'static>],
    deps: &[usize],
) -> Result<Vec<Option<Duration>>, crate::Error> {
    let drive = spec.drive;
    let plan = drive.plan();
    let roles_of = |r: RegisterRef<'_>| -> Vec<Role> {
        let row = u16::try_from(plan.order[r.index()]).ok();
        plan.roles
            .places
            .iter()
            .filter(|p| p.transports.contains(kind) && p.target.row() == row)
            .map(|p| p.role)
            .collect()
    };
    // Rank 0 register, 1 role, 2 group; the lowest rank that matches, the shortest period.
    let rank = |what: &str, r: RegisterRef<'_>| -> Option<u8> {
        if lookup::find(drive, what).is_ok_and(|x| x.id() == r.id()) {
            return Some(0);
        }
        let roles = roles_of(r);
        if Role::from_id(what).is_some_and(|role| roles.contains(&role)) {
            return Some(1);
        }
        let group = match what {
            "status" => roles.iter().any(|r| r.kind() == RoleKind::Status),
            "monitors" => !r.writable(),
            "parameters" => r.writable(),
            g => r.group().id == g,
        };
        group.then_some(2)
    };
    let mut errors = Vec::new();
    for (what, _) in &spec.periods {
        if !regs.iter().any(|r| rank(what, *r).is_some()) {
            errors.push(crate::RegisterProblem::NoPeriodTarget {
                link: spec.name.clone(),
                what: crate::log::quote(what),
            });
        }
    }
    if !errors.is_empty() {
        return Err(crate::Error::Registers(errors));
    }
    Ok(regs
        .iter()
        .enumerate()
        .map(|(k, r)| {
            if deps.contains(&k) {
                return None;
            }
            let matches: Vec<(u8, Duration)> = spec
                .periods
                .iter()
                .filter_map(|(what, period)| Some((rank(what, *r)?, *period)))
                .collect();
            let best = matches.iter().map(|(rank, _)| *rank).min()?;
            matches
                .iter()
                .filter(|(rank, _)| *rank == best)
                .map(|(_, p)| *p)
                .min()
        })
        .collect())
}

fn now_unix() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// The kind of an error, for `drivemap_bridge_errors_total{kind}`.
pub fn error_kind(e: &Error) -> &'static str {
    match e {
        Error::Timeout { .. } => "timeout",
        Error::Exception { .. } => "exception",
        Error::Io { .. } => "io",
        Error::Refused(_) => "refused",
        Error::Value(_) => "value",
        _ => "line",
    }
}

impl Polled {
    /// The drive as published before it is connected: its points and labels.
    pub fn new(
        index: usize,
        spec: DriveSpec,
        link: &str,
        kind: TransportKind,
    ) -> Result<Polled, crate::Error> {
        let (regs, deps) = choose(&spec, kind)?;
        let periods = periods_of(&spec, kind, &regs, &deps)?;
        let points = points::polled(spec.drive, &regs, kind);
        let base: Labels = vec![
            ("drive".into(), spec.drive.id().to_owned()),
            ("slave".into(), spec.slave.to_string()),
            ("name".into(), spec.name.clone()),
            ("link".into(), link.to_owned()),
        ];
        let n = points.len();
        Ok(Polled {
            index,
            settings: spec.settings.clone(),
            spec,
            kind,
            regs,
            deps,
            points,
            base,
            plan: None,
            published: vec![None; n],
            info: vec![None; n],
            online: None,
            silent: 0,
            skip: 0,
            answered: false,
            last: vec![None; periods.len()],
            periods,
        })
    }

    /// What carries out this drive's commands: the same map, slave, timing and settings.
    pub(crate) fn commander(&self) -> Commander {
        Commander {
            index: self.index,
            name: self.spec.name.clone(),
            drive: self.spec.drive,
            slave: self.spec.slave,
            options: self.spec.options,
            kind: self.kind,
            fixed: self.spec.fixed.clone(),
            deps: self
                .deps
                .iter()
                .map(|&d| self.regs[d].id().to_owned())
                .collect(),
            settings: self.settings.clone(),
            memory: None,
            forget: true,
            replan: false,
            draft: drivemap_live::draft::check_write(self.spec.drive, self.spec.draft),
        }
    }

    /// The drive's name.
    pub fn name(&self) -> &str {
        &self.spec.name
    }

    /// The drive's map.
    pub fn drive(&self) -> &'static Map {
        self.spec.drive
    }

    fn address(&self, r: RegisterRef<'_>) -> Result<u16, PollFailure> {
        let drive = self.spec.drive;
        r.plan()
            .locate(&self.settings.view(drive), self.kind)
            .map_err(|e| PollFailure::AddressUnknown {
                register: r.label(),
                setting: e.setting,
            })
    }

    fn make_plan(&self, line: SerialConfig) -> Result<Plan, PollFailure> {
        let drive = self.spec.drive;
        let kind = self.kind;
        // Plans, not bare infos: the planner respects each register's `function_codes`.
        let infos = rows_on_link(drive, kind, |r| self.address(r).ok());
        let mut periods: Vec<Option<Duration>> = self.periods.clone();
        periods.sort();
        periods.dedup();
        let mut wanted: Vec<Vec<(Table, u16)>> = vec![Vec::new(); periods.len()];
        let mut slots = Vec::new();
        for (r, period) in self.regs.iter().zip(&self.periods) {
            match self.address(*r) {
                Err(why) => slots.push(Err(why)),
                Ok(address) => {
                    let c = periods.iter().position(|p| p == period).unwrap_or(0);
                    let info = r.plan().info;
                    wanted[c].push((info.table, address));
                    slots.push(Ok((c, wanted[c].len() - 1, info.width)));
                }
            }
        }
        let profile = self.spec.drive.plan().profile;
        let now = Instant::now();
        let mut classes = Vec::new();
        for (period, wanted) in periods.into_iter().zip(wanted) {
            let poller =
                Poller::new(profile, &infos, wanted)?.with_model(BusModel::new(profile, line));
            classes.push(Class {
                period,
                poller,
                next: now,
                polled: false,
            });
        }
        Ok(Plan { classes, slots })
    }

    /// The modelled bus time of one cycle of the drive's plan (every class), in seconds.
    pub fn model_seconds(&self) -> f64 {
        self.plan.as_ref().map_or(0.0, |p| {
            p.classes.iter().map(|c| c.poller.plan_ns()).sum::<u64>() as f64 / 1e9
        })
    }

    /// The share of the line the drive's reads take at their periods (`period`: the link's),
    /// by the bus-time model: above 1 the line cannot meet them.
    pub fn load(&self, period: Duration) -> f64 {
        self.plan.as_ref().map_or(0.0, |p| {
            p.classes
                .iter()
                .map(|c| {
                    let every = c.period.unwrap_or(period).max(period).as_secs_f64();
                    c.poller.plan_ns() as f64 / 1e9 / every
                })
                .sum()
        })
    }

    /// One poll of the drive: reads, settings absorbed (re-planned and read again when they
    /// changed), values published; `between` is called before every request (the link's
    /// commands). A drive that answered nothing in its last cycles is skipped with a back-off.
    /// Returns the requests sent and their modelled bus time (ns).
    pub fn cycle(
        &mut self,
        client: &mut LinkClient,
        line: SerialConfig,
        metrics: &Metrics,
        updates: &Updates,
        between: &mut dyn FnMut(&mut LinkClient),
    ) -> (u32, u64) {
        if self.skip > 0 {
            self.skip -= 1;
            return (0, 0);
        }
        let profile = self.spec.drive.plan().profile;
        let options = self.spec.options;
        client.switch_drive(profile, options);
        let mut requests = 0;
        let mut bus_ns = 0;
        let link_label = self.base[3].1.clone();
        // Selectors, then the references their scales pick, then the values: at most three
        // rounds when settings change.
        let mut rounds = 0;
        let mut polled_ok;
        let raws = loop {
            rounds += 1;
            if self.plan.is_none() {
                match self.make_plan(line) {
                    Ok(p) => self.plan = Some(p),
                    Err(e) => {
                        eprintln!("bridge: {}: cannot plan the reads: {e}", self.spec.name);
                        return (0, 0);
                    }
                }
            }
            let Some(plan) = self.plan.as_mut() else {
                return (requests, bus_ns);
            };
            let now = Instant::now();
            for class in &mut plan.classes {
                class.polled = class.period.is_none() || class.next <= now;
                if !class.polled {
                    continue;
                }
                if let Some(p) = class.period {
                    class.next = now + p;
                }
                let stats = class.poller.poll_between(
                    client,
                    self.spec.slave,
                    &mut |c: &mut LinkClient| {
                        between(c);
                        c.switch_drive(profile, options);
                    },
                );
                requests += stats.requests;
                bus_ns += stats.bus_ns;
            }
            polled_ok = false;
            for (k, slot) in plan.slots.iter().enumerate() {
                let raw = match slot {
                    Err(why) => Err(("address", why.to_string())),
                    Ok((c, i, width)) => {
                        let class = &plan.classes[*c];
                        if !class.polled {
                            continue; // not due: its last value stands
                        }
                        match class.poller.raw(*i, *width) {
                            Some(Ok(w)) => {
                                polled_ok = true;
                                Ok(w)
                            }
                            Some(Err(e)) => Err((error_kind(e), e.to_string())),
                            None => Err(("line", "not read".into())),
                        }
                    }
                };
                self.last[k] = Some(raw);
            }
            let raws: Vec<Raw> = self
                .last
                .iter()
                .map(|l| l.clone().unwrap_or(Err(("line", "not read yet".into()))))
                .collect();
            let mut settings = self.settings.clone();
            for &d in &self.deps {
                if let Ok(raw) = raws[d] {
                    let r = self.regs[d];
                    settings.absorb(self.spec.drive, r.address(), raw as u16);
                }
            }
            if settings == self.settings || rounds >= 3 {
                if settings != self.settings {
                    self.settings = settings;
                    self.plan = None;
                }
                break raws;
            }
            self.settings = settings;
            self.plan = None;
        };
        // Only what was read in this cycle says whether the drive answers.
        let answered = polled_ok;
        self.answered = answered;
        if answered {
            self.silent = 0;
        } else {
            self.silent = self.silent.saturating_add(1);
            // Polled again after 0, 1, 3, 7, ... 31 cycles.
            self.skip = (1u32 << self.silent.min(6).saturating_sub(1)) - 1;
        }
        let mut changes = Vec::new();
        for (pi, p) in self.points.iter().enumerate() {
            let r = self.regs[p.slot];
            let family = metrics.family(p);
            let mut labels = self.base.clone();
            labels.push(("register".into(), p.id().to_owned()));
            labels.push(("param".into(), p.param().to_owned()));
            if let Some(f) = p.field() {
                labels.push(("field".into(), f.to_owned()));
            }
            let value = match &raws[p.slot] {
                Ok(raw) => codec::decode(self.spec.drive, r, *raw, &self.settings)
                    .map_err(|e| ("value", e.to_string())),
                Err((kind, why)) => Err((*kind, why.clone())),
            };
            let value = match value {
                Ok(v) => v,
                Err((kind, _why)) => {
                    // Only the first point of a register counts its error.
                    if !matches!(p.meaning, Meaning::Field { index, .. } if index != 0) {
                        let mut l = self.base[..3].to_vec();
                        l.push(("link".into(), link_label.clone()));
                        l.push(("kind".into(), kind.into()));
                        metrics.errors.get_or_create(&l).inc();
                    }
                    // A value not read is not shown as if it were current.
                    match self.info[pi].take() {
                        Some(old) => {
                            family.remove(&old);
                        }
                        None => {
                            family.remove(&labels);
                        }
                    }
                    continue;
                }
            };
            let (number, info, text) = match (&p.meaning, &value) {
                (Meaning::Number(_) | Meaning::Word, v) => {
                    let factor = p.metric_unit().map_or(1.0, |u| u.factor);
                    let n = v.as_f64().unwrap_or(f64::NAN);
                    let text = match v {
                        Value::Quantity {
                            value, decimals, ..
                        } => format!("{value:.decimals$}"),
                        other => other.as_f64().map(|x| x.to_string()).unwrap_or_default(),
                    };
                    (n * factor, None, text)
                }
                (Meaning::Code(_), Value::Code { code, id, name }) => (
                    1.0,
                    Some(vec![
                        ("code".to_owned(), code.to_string()),
                        ("value".to_owned(), id.clone().unwrap_or_default()),
                        ("meaning".to_owned(), name.clone().unwrap_or_default()),
                    ]),
                    option_text(*code, id.as_deref(), name.as_deref()),
                ),
                (Meaning::Field { index, field }, Value::Bits { fields, .. }) => {
                    let width = field.width;
                    let Some(f) = fields.get(*index) else {
                        continue;
                    };
                    if width == 1 {
                        (f64::from(f.value), None, f.value.to_string())
                    } else {
                        (
                            1.0,
                            Some(vec![
                                ("code".to_owned(), f.value.to_string()),
                                ("meaning".to_owned(), f.label.clone().unwrap_or_default()),
                            ]),
                            f.label.clone().unwrap_or_else(|| f.value.to_string()),
                        )
                    }
                }
                (Meaning::Bit, v) => {
                    let on = v.as_f64().is_some_and(|x| x != 0.0);
                    (f64::from(u8::from(on)), None, u8::from(on).to_string())
                }
                (_, v) => (v.as_f64().unwrap_or(f64::NAN), None, v.to_string()),
            };
            match info {
                Some(extra) => {
                    labels.extend(extra);
                    if let Some(old) = self.info[pi].take()
                        && old != labels
                    {
                        family.remove(&old);
                    }
                    family.get_or_create(&labels).set(1.0);
                    self.info[pi] = Some(labels);
                }
                None => {
                    family.get_or_create(&labels).set(number);
                }
            }
            if self.published[pi].as_deref() != Some(text.as_str()) {
                changes.push((pi, text));
            }
        }
        let id = self.base[..3].to_vec();
        metrics
            .up
            .get_or_create(&id)
            .set(if answered { 1.0 } else { 0.0 });
        if answered {
            metrics.last_success.get_or_create(&id).set(now_unix());
        }
        if let Some(tx) = updates {
            if self.online != Some(answered)
                && tx
                    .try_send(Update::Availability {
                        drive: self.index,
                        online: answered,
                    })
                    .is_ok()
            {
                self.online = Some(answered);
            }
            if !changes.is_empty() {
                let sent: Vec<(usize, String)> = changes.clone();
                match tx.try_send(Update::State {
                    drive: self.index,
                    values: sent,
                }) {
                    Ok(()) => {
                        for (pi, text) in changes {
                            self.published[pi] = Some(text);
                        }
                    }
                    Err(_) => {
                        metrics.mqtt_dropped.get_or_create(&Vec::new()).inc();
                    }
                }
            }
        }
        (requests, bus_ns)
    }

    /// Whether the drive answered its last poll.
    pub fn answering(&self) -> bool {
        self.answered
    }

    /// The settings the last poll read (what conversions and limits depend on).
    pub fn settings(&self) -> &LiveSettings {
        &self.settings
    }

    /// Plans the reads again at the next cycle (a command wrote what they depend on).
    pub fn replan(&mut self) {
        self.plan = None;
    }

    /// Forgets what MQTT was given, so that every value is published again (after the broker
    /// connection was re-established).
    pub fn republish(&mut self) {
        self.published.iter_mut().for_each(|p| *p = None);
        self.online = None;
    }
}

/// How a code is offered to Home Assistant and published: its meaning, else its id, else the
/// number (each accepted back as a value by the register's parser).
pub fn option_text(code: u16, id: Option<&str>, name: Option<&str>) -> String {
    id.or(name)
        .map(str::to_owned)
        .unwrap_or_else(|| code.to_string())
}

/// Runs a link until `stop` is set: connects (with the client's back-off, 100 ms doubling to
/// 5 s), then polls every drive each `period`, carrying out the drives' commands from `board`
/// before every request and while waiting (a stop before anything else). While the link cannot
/// be opened, stops wait for it and other commands expire. Returns when the cycle in flight is
/// done after `stop`.
// The thread's inputs, each moved into it for its whole life (the link, its channels,
// shared flags and counters); `lib.rs` builds them once and hands them over.
#[allow(clippy::too_many_arguments)]
pub fn run(
    mut link: LinkSpec,
    first_index: usize,
    period: Duration,
    metrics: Arc<Metrics>,
    updates: Updates,
    board: Arc<Board>,
    stop: Arc<AtomicBool>,
    republish: Arc<AtomicBool>,
    proxy: Option<crate::proxy::LineSide>,
) {
    let label = vec![("link".to_owned(), link.name.clone())];
    metrics
        .period_seconds
        .get_or_create(&label)
        .set(period.as_secs_f64());
    let count = link.drives.len();
    let mut drives: Vec<Polled> = Vec::new();
    for (i, spec) in std::mem::take(&mut link.drives).into_iter().enumerate() {
        match Polled::new(first_index + i, spec, &link.name, link.kind) {
            Ok(p) => drives.push(p),
            Err(e) => eprintln!("bridge: {e}"),
        }
    }
    for d in &drives {
        // Down until it answers (an alert on `drivemap_up == 0` fires from the start).
        metrics.up.get_or_create(&d.base[..3].to_vec()).set(0.0);
    }
    let mut serving = Serving {
        board,
        first: first_index,
        count,
        commanders: drives.iter().map(Polled::commander).collect(),
        metrics: Arc::clone(&metrics),
        updates: updates.clone(),
        log: Limiter::default(),
        proxy,
    };
    let mut wait = Duration::from_millis(100);
    let transport = loop {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        match (link.connect)() {
            Ok(t) => break t,
            Err(e) => {
                eprintln!(
                    "bridge: {}: {e}; trying again in {} ms",
                    link.name,
                    wait.as_millis()
                );
                let mut l = label.clone();
                l.push(("kind".into(), "connect".into()));
                metrics.errors.get_or_create(&l).inc();
                // Commands other than a stop expire while the link cannot be opened.
                let until = Instant::now() + wait;
                while !stop.load(Ordering::Relaxed) && Instant::now() < until {
                    serving.expire_only();
                    serving.board.wait(
                        until
                            .saturating_duration_since(Instant::now())
                            .min(Duration::from_millis(50)),
                    );
                }
                wait = (wait * 2).min(Duration::from_secs(5));
            }
        }
    };
    let Some(first) = drives.first() else {
        return;
    };
    let mut client: LinkClient =
        Client::with_options(transport, first.drive().plan().profile, first.spec.options);
    let mut next = Instant::now();
    let mut warned_model = false;
    loop {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        if republish.swap(false, Ordering::Relaxed) {
            drives.iter_mut().for_each(Polled::republish);
        }
        serving.serve(&mut client);
        let began = Instant::now();
        let mut requests = 0;
        let mut bus_ns = 0;
        // By index: the commanders are lent to the cycle's `between` (a command for any drive
        // of the link goes out between two requests), so they cannot be borrowed alongside.
        #[allow(clippy::needless_range_loop)]
        for k in 0..drives.len() {
            if !link.poll {
                break;
            }
            let d = &mut drives[k];
            let (n, ns) = d.cycle(&mut client, link.line, &metrics, &updates, &mut |c| {
                serving.serve(c)
            });
            requests += n;
            bus_ns += ns;
            serving.board.set_answering(d.index, d.answering());
            let c = &mut serving.commanders[k];
            c.update_settings(d.settings());
            if c.take_replan() {
                d.replan();
            }
        }
        metrics
            .cycle_seconds
            .get_or_create(&label)
            .set(began.elapsed().as_secs_f64());
        let load: f64 = drives.iter().map(|d| d.load(period)).sum();
        metrics.line_load.get_or_create(&label).set(load);
        if load > 1.0 && !warned_model {
            warned_model = true;
            eprintln!(
                "bridge: {}: the reads at their periods need {:.0} % of the line by the bus-time model (one cycle of every read {:.3} s, period {} ms): the line cannot meet them; cycles run back to back (drivemap_bridge_line_load_ratio > 1)",
                link.name,
                load * 100.0,
                drives.iter().map(Polled::model_seconds).sum::<f64>(),
                period.as_millis()
            );
        }
        metrics
            .model_seconds
            .get_or_create(&label)
            .set(bus_ns as f64 / 1e9);
        metrics
            .requests
            .get_or_create(&label)
            .inc_by(u64::from(requests));
        metrics.cycles.get_or_create(&label).inc();
        next += period;
        let now = Instant::now();
        if next < now {
            // A cycle longer than the period: the next starts at once, none are made up.
            next = now;
        }
        // Commands are carried out as they come while waiting for the next cycle.
        loop {
            serving.serve(&mut client);
            if stop.load(Ordering::Relaxed) {
                break;
            }
            let left = next.saturating_duration_since(Instant::now());
            if left.is_zero() {
                break;
            }
            serving.board.wait(left.min(Duration::from_millis(100)));
        }
    }
    if let Some(tx) = &updates {
        for d in &drives {
            let _ = tx.try_send(Update::Availability {
                drive: d.index,
                online: false,
            });
        }
    }
}

/// The commands side of a link: the board it takes them from, a commander per drive, and where
/// outcomes go.
struct Serving {
    board: Arc<Board>,
    first: usize,
    count: usize,
    commanders: Vec<Commander>,
    metrics: Arc<Metrics>,
    updates: Updates,
    log: Limiter,
    proxy: Option<crate::proxy::LineSide>,
}

impl Serving {
    /// Carries out every command of the link's drives that is due (stops first), reports the
    /// expired ones, gives back a stop that could not be delivered.
    fn serve(&mut self, client: &mut LinkClient) {
        loop {
            let Some(next) = self.board.next(self.first, self.count, Instant::now()) else {
                // No command due: a proxied master's request, then look again.
                match self.proxy.as_mut().and_then(|p| p.next().map(|r| (p, r))) {
                    Some((p, r)) => {
                        p.serve(r, client, &mut self.commanders);
                        continue;
                    }
                    None => break,
                }
            };
            match next {
                Next::Expired(i) => {
                    let waited = i.received.elapsed();
                    let why = CommandFailure::Expired {
                        waited,
                        deadline: self.board.deadline(),
                    };
                    self.report(i, Err(why), "expired");
                }
                Next::Due(i) => {
                    let Some(c) = self
                        .commanders
                        .iter_mut()
                        .find(|c| c.index == i.command.drive)
                    else {
                        self.report(i, Err(CommandFailure::NoSuchDrive), "refused");
                        continue;
                    };
                    let result = c.execute(client, &i.command);
                    match result {
                        Err(e) if i.command.action == Action::Stop && e.retryable() => {
                            let attempts = i.attempts + 1;
                            let (topic, payload) =
                                (quote(&i.command.topic), quote(&i.command.payload));
                            let name = c.name.clone();
                            if self.board.retry_stop(i.clone(), Instant::now()) {
                                if attempts == 1 || attempts.is_power_of_two() {
                                    eprintln!(
                                        "bridge: stop on {topic} ({payload}) not delivered to {name} (attempt {attempts}): {e}; sent again every {} ms until delivered or a run replaces it",
                                        crate::command::STOP_RETRY.as_millis()
                                    );
                                }
                                if attempts == 1 {
                                    self.outcome(&i, Err(e), "pending");
                                }
                            } else {
                                self.report(i, Err(e), "superseded");
                            }
                        }
                        Ok(what) => {
                            let labels = vec![
                                ("name".to_owned(), c.name.clone()),
                                ("command".to_owned(), i.command.action.name().to_owned()),
                            ];
                            self.metrics
                                .command_latency
                                .get_or_create(&labels)
                                .observe(i.received.elapsed().as_secs_f64());
                            self.report(i, Ok(what), "done");
                        }
                        Err(e) => {
                            let outcome = if e.retryable() { "failed" } else { "refused" };
                            self.report(i, Err(e), outcome);
                        }
                    }
                }
            }
        }
    }

    /// Reports the commands that expired, without touching the line (it is not open).
    fn expire_only(&mut self) {
        for i in self.board.expired(self.first, self.count, Instant::now()) {
            let why = CommandFailure::Expired {
                waited: i.received.elapsed(),
                deadline: self.board.deadline(),
            };
            self.report(i, Err(why), "expired");
        }
    }

    /// Logs (at a bounded rate), counts and publishes what became of a command.
    fn report(&mut self, i: Intent, result: Result<String, CommandFailure>, outcome: &'static str) {
        let (topic, payload) = (quote(&i.command.topic), quote(&i.command.payload));
        match &result {
            Ok(what) => eprintln!("bridge: command on {topic} ({payload}): {what}"),
            Err(why) => {
                let (ok, held) = self.log.allow(Instant::now());
                if let Some(n) = held {
                    eprintln!("bridge: {n} more command refusal(s) not logged");
                }
                if ok {
                    eprintln!(
                        "bridge: command on {topic} ({payload}) {outcome}, nothing written: {why}"
                    );
                }
            }
        }
        self.outcome(&i, result, outcome);
    }

    fn outcome(
        &mut self,
        i: &Intent,
        result: Result<String, CommandFailure>,
        outcome: &'static str,
    ) {
        if let Some(c) = self.commanders.iter().find(|c| c.index == i.command.drive) {
            self.metrics
                .commands
                .get_or_create(&vec![
                    ("name".to_owned(), c.name.clone()),
                    ("outcome".to_owned(), outcome.to_owned()),
                ])
                .inc();
        }
        if let Some(tx) = &self.updates {
            let result = result.map_err(Arc::new);
            let _ = tx.try_send(Update::Outcome {
                command: i.command.clone(),
                result,
                outcome,
            });
        }
    }
}
