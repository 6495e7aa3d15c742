//! Parameter-set restores under faults (issue 40): a set saved from one simulated drive is
//! restored to another of the same map, over RTU framing and Modbus TCP, with a fault injected
//! at every request of the restore in turn (lost request, lost reply, late reply, an
//! exception, a connection broken before or after the drive executed the request, every
//! attempt of that request). After each interrupted restore:
//! - the report is exact: every setting reported verified holds the set's value on the drive,
//!   every setting reported not written was never written;
//! - no write meant anything but the set's value under the settings in force when the drive
//!   executed it, nor was outside the limits in force then (a selector written before what it
//!   scales);
//! - the run command never went out; the store command at most once per restore;
//!
//! and a second restore without faults completes, writes only what still differed, and leaves
//! the drive equal to the set. The checks are shown to fail when the writes are reversed or the
//! read-back skipped.

use drivemap_test_support::paths;

use std::cell::RefCell;
use std::io;
use std::rc::Rc;
use std::time::{Duration, Instant};

use drivemap_live::LiveSettings;
use drivemap_live::codec::{self, Value};
use drivemap_live::paramset::{self, ParameterSet, RestoreReport, Validated};
use drivemap_live::session::Session;
use drivemap_map::Map;
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::core::plan::Conversion;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::roles::{Role, Target};
use drivemap_runtime::pdu::Request;
use drivemap_runtime::transport::Transport;
use drivemap_sim::framing::{self, Decoded};
use drivemap_sim::{SimOptions, Simulator};
use drivemap_test_support::rng::SplitMix;
use drivemap_test_support::sim_link::{LinkFault, SimLink};

/// A [`SimLink`] the test keeps a handle on while the session owns the transport.
#[derive(Clone)]
struct Shared(Rc<RefCell<SimLink>>);

impl Transport for Shared {
    fn kind(&self) -> TransportKind {
        self.0.borrow().kind()
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.0.borrow_mut().send(frame)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.0.borrow_mut().recv(buf, deadline)
    }
    fn discard_input(&mut self) -> io::Result<()> {
        self.0.borrow_mut().discard_input()
    }
    fn reconnect(&mut self) -> io::Result<()> {
        self.0.borrow_mut().reconnect()
    }
    fn inter_char_timeout(&self) -> Option<Duration> {
        self.0.borrow().inter_char_timeout()
    }
}

/// A lost reply costs little: the link answers at once or never.
fn options() -> ClientOptions {
    ClientOptions {
        timeout: Duration::from_micros(20),
        retries: 1,
        request_gap: Duration::ZERO,
        ..ClientOptions::default()
    }
}

/// A new session (as each `drivemap restore` opens one) given `externals` ([`externals`]).
fn session<'d>(drive: &'d Map, link: &Shared, slave: u8, externals: &LiveSettings) -> Session<'d> {
    Session::over(
        drive,
        Box::new(link.clone()),
        options(),
        slave,
        SerialConfig::default(),
        externals.clone(),
    )
}

/// Every external quantity of the map at 100, as the simulator has them ([`simulator`]).
fn externals(drive: &Map) -> LiveSettings {
    let mut settings = LiveSettings::default();
    for q in drive.externals() {
        settings.references.insert(q.external.clone(), 100.0);
    }
    settings
}

fn maps() -> Vec<Map> {
    let dir = paths::maps();
    let mut out: Vec<Map> = drivemap_map::find_maps(dir.as_ref())
        .expect("maps/")
        .iter()
        .map(|p| drivemap_map::Loader::new().load(p).expect("shipped map"))
        .collect();
    out.sort_by(|a, b| a.id().cmp(b.id()));
    out
}

fn kinds(drive: &Map) -> Vec<TransportKind> {
    let mut out = vec![TransportKind::RtuOverTcp];
    let tcp = drive
        .protocol()
        .transports
        .iter()
        .any(|t| format!("{t:?}").eq_ignore_ascii_case("tcp"));
    if tcp {
        out.push(TransportKind::Tcp);
    }
    out
}

/// Every external quantity at 100 (the TDS-V8's inverter rated current bounds Cn-09).
fn simulator(drive: &Map) -> Simulator {
    let mut o = SimOptions::new();
    for q in drive.externals() {
        o = o.external(&q.external, 100.0);
    }
    let mut sim = Simulator::new(drive.clone(), o).expect("simulator");
    // A drive whose parameters are written in PRG mode only (TDS-V8) is put in it, as its
    // user does before a restore (the restore refuses them in DRV mode).
    if let Some(place) = drive.plan().roles.of(Role::ToProgramMode).next()
        && let Target::Field(f) = place.target
        && let Some(r) = drive.register_of_row(usize::from(f.row))
    {
        sim.set_raw(r.id(), u32::from(f.code(true)) << f.lsb)
            .unwrap();
    }
    sim
}

/// A raw value of `r` other than `current` that the map accepts under `settings`.
fn other_raw(
    drive: &Map,
    r: drivemap_map::RegisterRef<'_>,
    current: u32,
    settings: &LiveSettings,
    rng: &mut SplitMix,
) -> Option<u32> {
    let plan = r.plan();
    let mut raws: Vec<i64> = match plan.conversion {
        Conversion::Enum { values, .. } => values.iter().map(|v| i64::from(v.code)).collect(),
        Conversion::Bits { .. } => return None,
        _ => {
            let e = plan.envelope;
            let span = (e.max - e.min).max(1) as u64;
            vec![
                e.min + rng.below(span) as i64,
                e.max,
                e.min,
                e.min + 1,
                (e.min + e.max) / 2,
            ]
        }
    };
    let start = rng.below(raws.len() as u64) as usize;
    raws.rotate_left(start);
    raws.into_iter().find_map(|raw| {
        let raw = u32::try_from(raw & 0xFFFF_FFFF).ok()?;
        if raw == current {
            return None;
        }
        let text = match codec::decode(drive, r, raw, settings).ok()? {
            Value::Quantity {
                value,
                decimals,
                exact: None,
                ..
            } => format!("{value:.decimals$}"),
            Value::Word(w) => w.to_string(),
            Value::Code { code, .. } => code.to_string(),
            _ => return None,
        };
        (codec::parse_value(drive, r, &text, settings).ok()? == raw).then_some(raw)
    })
}

/// Words in a setting's name that belong to the link (changing them on a simulator changes
/// its answers).
const LINK_WORDS: &[&str] = &[
    "slave",
    "address",
    "baud",
    "parity",
    "bps",
    "transmission",
    "communication",
    "modbus",
    "memobus",
    "rts",
    "time_out",
    "timeout",
    "password",
    "initial",
    "stop_bit",
    "protocol",
    "station",
    "response",
];

/// The source drive: `n` settings changed, the selectors among them first (so what they scale
/// is chosen under the selected scale), each to a value the map accepts.
fn source(drive: &Map, base: &Simulator, n: usize, rng: &mut SplitMix) -> Simulator {
    let mut sim = base.clone();
    let regs: Vec<_> = paramset::settings_of(drive)
        .into_iter()
        .filter(|r| {
            let name = r.name().to_ascii_lowercase();
            !LINK_WORDS
                .iter()
                .any(|w| r.id().contains(w) || name.contains(&w.replace('_', " ")))
        })
        .collect();
    if regs.is_empty() {
        return sim;
    }
    let depended: Vec<String> = regs
        .iter()
        .flat_map(|r| paramset::depends_on(drive, *r))
        .map(|d| d.id().to_owned())
        .collect();
    let mut chosen: Vec<usize> = (0..n)
        .map(|_| rng.below(regs.len() as u64) as usize)
        .collect();
    // Half the time, a setting others depend on and one that depends on it.
    if rng.chance(50)
        && let Some(i) = regs
            .iter()
            .position(|r| depended.iter().any(|d| d == r.id()))
    {
        chosen.push(i);
        if let Some(j) = regs.iter().position(|r| {
            paramset::depends_on(drive, *r)
                .iter()
                .any(|d| d.id() == regs[i].id())
        }) {
            chosen.push(j);
        }
    }
    chosen.sort_by_key(|&i| !depended.iter().any(|d| d == regs[i].id()));
    chosen.dedup();
    for i in chosen {
        let r = regs[i];
        let current = sim.raw(r.id()).unwrap();
        if let Some(raw) = other_raw(drive, r, current, &sim.settings(), rng) {
            sim.set_raw(r.id(), raw).unwrap();
        }
    }
    sim
}

/// The frames of the log that wrote a register, with the settings before each: (register id,
/// raw value, settings), for executed writes only.
fn writes(
    drive: &Map,
    kind: TransportKind,
    link: &SimLink,
) -> Vec<(String, u32, Option<LiveSettings>)> {
    let offsets = drive.plan().profile.address_offsets;
    let mut out = Vec::new();
    for s in link.log.iter().filter(|s| s.executed) {
        let Decoded::Request { request, .. } = framing::decode(kind, &s.frame) else {
            continue;
        };
        let (pdu, words): (u16, Vec<u16>) = match request {
            Request::WriteSingle { address, value } => (address, vec![value]),
            Request::WriteMultiple { address, values } => (
                address,
                (0..values.len()).filter_map(|i| values.get(i)).collect(),
            ),
            _ => continue,
        };
        let Some(address) = offsets.communication_address(pdu, kind) else {
            continue;
        };
        // The store command (ENTER, save) is counted by the simulator.
        let command = drive
            .plan()
            .profile
            .commands
            .iter()
            .any(|c| c.writes.iter().any(|(a, _)| *a == address));
        if command {
            continue;
        }
        let settings = s.settings.clone().unwrap_or_default();
        let view = settings.view(drive);
        let r = drive
            .registers()
            .find(|r| r.plan().locate(&view, kind).is_ok_and(|a| a == address));
        if let Some(r) = r {
            let width = r.plan().info.width;
            let raw = width.join(&words[..usize::from(width.count()).min(words.len())]);
            out.push((r.id().to_owned(), raw, s.settings.clone()));
        }
    }
    out
}

/// What one restore run broke of the properties, one line each.
fn violations(
    drive: &Map,
    kind: TransportKind,
    set: &ParameterSet,
    source: &Simulator,
    link: &SimLink,
    report: Option<&RestoreReport>,
) -> Vec<String> {
    let mut out = Vec::new();
    let target = &link.sim;
    let wanted = source.settings();
    let in_set = |id: &str| set.get(id).is_some();
    for (id, raw, settings) in writes(drive, kind, link) {
        if !in_set(&id) {
            out.push(format!("{id}: written, not a setting of the set"));
            continue;
        }
        let r = drive.registers().find(|r| r.id() == id).unwrap();
        let settings = settings.unwrap_or_default();
        let then = codec::decode(drive, r, raw, &settings).map(|v| v.as_f64());
        let meant = codec::decode(drive, r, raw, &wanted).map(|v| v.as_f64());
        if then != meant {
            out.push(format!(
                "{id}: {raw} meant {then:?} when written, the set's value is {meant:?}"
            ));
        } else if let Ok(Some(v)) = then
            && matches!(
                r.plan().conversion,
                Conversion::Decimal { .. }
                    | Conversion::Relative { .. }
                    | Conversion::Selected { .. }
            )
            && let Err(e) = codec::encode(drive, r, v, &settings)
        {
            out.push(format!(
                "{id}: {v} outside the limits in force when written: {e}"
            ));
        }
    }
    if link.log.iter().any(|s| s.run_command == Some(true)) {
        out.push("the drive was commanded to run".to_owned());
    }
    if let Some(report) = report {
        for id in &report.verified {
            if target.raw(id).ok() != source.raw(id).ok() {
                out.push(format!(
                    "{id}: reported verified, the drive does not hold it"
                ));
            }
        }
        for s in &report.not_written {
            if target.executed(&s.id).unwrap_or(0) > 0 {
                out.push(format!(
                    "{}: reported not written, the drive executed a write",
                    s.id
                ));
            }
        }
    }
    out
}

/// Whether the drive holds every value of the set.
fn equal(set: &ParameterSet, source: &Simulator, target: &Simulator) -> Vec<String> {
    set.settings
        .iter()
        .filter(|s| target.raw(&s.id).ok() != source.raw(&s.id).ok())
        .map(|s| s.id.clone())
        .collect()
}

const FAULTS: [LinkFault; 6] = [
    LinkFault::LoseRequest,
    LinkFault::LoseReply,
    LinkFault::LateReply,
    LinkFault::Exception(0x04),
    LinkFault::Disconnect { executed: false },
    LinkFault::Disconnect { executed: true },
];

/// How a restore is mutated, to show the checks catch it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Mutation {
    None,
    /// The writes in reverse order.
    Reversed,
    /// What was written counted as verified without reading it back.
    Unverified,
}

/// A set validated against its map as a new session with `externals` validates it (what
/// `drivemap restore` does first; it sends nothing, so a sweep validates each set once).
fn validated<'d>(drive: &'d Map, set: &ParameterSet, externals: &LiveSettings) -> Validated<'d> {
    paramset::validate(drive, set, externals, false).expect("the set validates")
}

/// One restore of the `validated` set over `link` in a new session, the report (`None`:
/// refused, nothing written).
fn restore(
    drive: &Map,
    link: &Shared,
    slave: u8,
    validated: &Validated<'_>,
    externals: &LiveSettings,
    mutation: Mutation,
) -> Option<RestoreReport> {
    let mut s = session(drive, link, slave, externals);
    let mut plan = match paramset::plan(&mut s, validated) {
        Ok(plan) => plan,
        Err(e) => {
            if std::env::var_os("PARAMSET_DEBUG").is_some() {
                eprintln!("{}: refused: {e}", drive.id());
            }
            return None;
        }
    };
    if mutation == Mutation::Reversed {
        plan.writes.reverse();
    }
    let mut report = paramset::execute(&mut s, &plan, &mut |_| {});
    if mutation == Mutation::Unverified {
        for n in std::mem::take(&mut report.not_verified) {
            report.verified.push(n.id);
        }
    }
    Some(report)
}

/// Saves `source` over a link of `kind`.
fn save(drive: &Map, kind: TransportKind, source: &Simulator) -> ParameterSet {
    let link = Shared(Rc::new(RefCell::new(SimLink::new(kind, source.clone()))));
    let mut s = session(drive, &link, source.slave(), &externals(drive));
    let report = paramset::save(&mut s, "2026-01-01T00:00:00Z").expect("save");
    assert!(
        report.set.unread.is_empty(),
        "{}: {:?}",
        drive.id(),
        report.set.unread
    );
    report.set
}

/// Runs the sweep of one set: an interrupted restore at every request with every fault, then a
/// clean one. Returns the restores run and the violations found.
fn sweep(
    drive: &Map,
    kind: TransportKind,
    target: &Simulator,
    source: &Simulator,
    set: &ParameterSet,
    mutation: Mutation,
) -> (usize, Vec<String>) {
    let slave = target.slave();
    let externals = externals(drive);
    let validated = validated(drive, set, &externals);
    // The requests of a whole restore.
    let clean = Shared(Rc::new(RefCell::new(SimLink::new(kind, target.clone()))));
    restore(drive, &clean, slave, &validated, &externals, Mutation::None);
    let requests = clean.0.borrow().log.len();
    let mut runs = 0;
    let mut found = Vec::new();
    let attempts = usize::from(options().retries) + 1;
    for at in 0..requests {
        for fault in FAULTS {
            runs += 1;
            let mut link = SimLink::new(kind, target.clone());
            link.record_settings = true;
            link.script(std::iter::repeat_n(None, at));
            link.script(std::iter::repeat_n(Some(fault), attempts));
            let link = Shared(Rc::new(RefCell::new(link)));
            let first = restore(drive, &link, slave, &validated, &externals, mutation);
            let what = format!("{} {kind:?} fault {fault:?} at request {at}", drive.id());
            {
                let l = link.0.borrow();
                for v in violations(drive, kind, set, source, &l, first.as_ref()) {
                    found.push(format!("{what}: {v}"));
                }
                if l.sim.persist_count() > 1 {
                    found.push(format!("{what}: stored {} times", l.sim.persist_count()));
                }
            }
            // Run again without faults: it completes and the drive holds the set.
            let stored = link.0.borrow().sim.persist_count();
            {
                let mut l = link.0.borrow_mut();
                l.log.clear();
                l.clear_script();
            }
            let second = restore(drive, &link, slave, &validated, &externals, mutation);
            let l = link.0.borrow();
            match &second {
                Some(r) if r.complete() => {}
                other => found.push(format!(
                    "{what}: the second restore did not complete: {other:?}"
                )),
            }
            for v in violations(drive, kind, set, source, &l, second.as_ref()) {
                found.push(format!("{what}, second restore: {v}"));
            }
            if l.sim.persist_count() > stored + 1 {
                found.push(format!("{what}: the second restore stored more than once"));
            }
            let differ = equal(set, source, &l.sim);
            if !differ.is_empty() {
                found.push(format!(
                    "{what}: after the second restore {differ:?} differ"
                ));
            }
        }
    }
    (runs, found)
}

/// Sets restored per map and link: fewer on RTU framing, where every lost reply costs the
/// client its wait for silence (the drive's response time at 9600 baud, V7 12.5 ms).
fn sets(kind: TransportKind) -> usize {
    if kind.is_rtu_framed() { 10 } else { 40 }
}

#[test]
fn interrupted_restores_report_exactly_and_converge_for_every_map() {
    let started = Instant::now();
    let mut runs = 0;
    let mut rng = SplitMix(40);
    for drive in maps() {
        let base = simulator(&drive);
        for kind in kinds(&drive) {
            let (before, at) = (runs, Instant::now());
            for _ in 0..sets(kind) {
                let source = source(&drive, &base, 3, &mut rng);
                let set = part(save(&drive, kind, &source), &base, &source, 8, &mut rng);
                let (n, found) = sweep(&drive, kind, &base, &source, &set, Mutation::None);
                runs += n;
                assert!(
                    found.is_empty(),
                    "{}",
                    found[..found.len().min(20)].join("\n")
                );
            }
            eprintln!(
                "{} {kind:?}: {} interrupted restores in {:.1} s",
                drive.id(),
                runs - before,
                at.elapsed().as_secs_f64()
            );
        }
    }
    eprintln!(
        "{runs} interrupted restores (each followed by one without faults) in {:.1} s",
        started.elapsed().as_secs_f64()
    );
    assert!(runs >= 10_000, "{runs} interrupted restores");
}

/// The checks above are not vacuous: a restore that writes in the reverse order (C1-01 before
/// the C1-10 that selects its unit), or that counts what it wrote as verified without reading
/// it back, breaks them.
#[test]
fn the_sweep_fails_when_the_order_is_reversed_or_the_read_back_skipped() {
    let gpd = maps()
        .into_iter()
        .find(|d| d.id() == "yaskawa-gpd515")
        .unwrap();
    let base = simulator(&gpd);
    let mut source = base.clone();
    source.set_raw("C1-10", 0).unwrap();
    source.set_raw("C1-01", 500).unwrap();
    source.set_raw("C1-02", 700).unwrap();
    let kind = TransportKind::RtuOverTcp;
    let set = save(&gpd, kind, &source);
    let (_, clean) = sweep(&gpd, kind, &base, &source, &set, Mutation::None);
    assert!(clean.is_empty(), "{}", clean.join("\n"));
    let (_, reversed) = sweep(&gpd, kind, &base, &source, &set, Mutation::Reversed);
    assert!(
        reversed.iter().any(|v| v.contains("meant")),
        "reversed order not caught: {reversed:?}"
    );
    let (_, unverified) = sweep(&gpd, kind, &base, &source, &set, Mutation::Unverified);
    assert!(
        unverified
            .iter()
            .any(|v| v.contains("reported verified, the drive does not hold it")),
        "skipped read-back not caught: {unverified:?}"
    );
}

/// `set` cut to the settings `source` changed from `base` and about `others` more (a set may
/// hold any of the map's settings), in its order: keeps each restore to a few requests.
fn part(
    set: ParameterSet,
    base: &Simulator,
    source: &Simulator,
    others: u64,
    rng: &mut SplitMix,
) -> ParameterSet {
    let n = set.settings.len().max(1) as u64;
    let settings = set
        .settings
        .into_iter()
        .filter(|s| base.raw(&s.id).ok() != source.raw(&s.id).ok() || rng.below(n) < others)
        .collect();
    ParameterSet { settings, ..set }
}

/// What a restore writes survives a power cycle because it runs the map's store command once
/// (ENTER, save): a restore without it is caught, for every map with settings.
#[test]
fn a_restore_survives_a_power_cycle_and_one_without_its_store_command_does_not() {
    let mut rng = SplitMix(1);
    for drive in maps() {
        if paramset::settings_of(&drive).is_empty() {
            continue;
        }
        let base = simulator(&drive);
        let kind = TransportKind::RtuOverTcp;
        let source = source(&drive, &base, 3, &mut rng);
        let set = save(&drive, kind, &source);
        assert!(
            !equal(&set, &source, &base).is_empty(),
            "{}: the set differs",
            drive.id()
        );
        for store in [true, false] {
            let link = Shared(Rc::new(RefCell::new(SimLink::new(kind, base.clone()))));
            let mut s = session(&drive, &link, base.slave(), &externals(&drive));
            let given = s.settings.clone();
            let validated = paramset::validate(&drive, &set, &given, false).unwrap();
            let mut plan = paramset::plan(&mut s, &validated).unwrap();
            assert!(plan.store.is_some(), "{}: a store command", drive.id());
            if !store {
                plan.store = None;
            }
            let report = paramset::execute(&mut s, &plan, &mut |_| {});
            assert!(report.complete(), "{}: {report:?}", drive.id());
            let mut l = link.0.borrow_mut();
            assert!(
                equal(&set, &source, &l.sim).is_empty(),
                "{}: restored",
                drive.id()
            );
            assert_eq!(l.sim.persist_count(), u32::from(store), "{}", drive.id());
            l.sim.power_cycle();
            let lost = equal(&set, &source, &l.sim);
            assert_eq!(
                lost.is_empty(),
                store,
                "{} (store command {}): after a power cycle {lost:?} differ",
                drive.id(),
                if store { "run" } else { "skipped" }
            );
        }
    }
}

/// `save_with` reports its progress group by group, up to every setting, and reads in as few
/// requests as one plan over all of them (the planner bridges no group's area to another's).
#[test]
fn save_reports_progress_group_by_group_at_no_cost_in_requests() {
    for drive in maps() {
        let sim = simulator(&drive);
        let n = paramset::settings_of(&drive).len();
        let kind = TransportKind::RtuOverTcp;
        let link = Shared(Rc::new(RefCell::new(SimLink::new(kind, sim.clone()))));
        let mut s = session(&drive, &link, sim.slave(), &externals(&drive));
        let mut seen = Vec::new();
        let report =
            paramset::save_with(&mut s, "", &mut |done, total| seen.push((done, total))).unwrap();
        assert_eq!(report.set.settings.len(), n, "{}", drive.id());
        if n > 0 {
            assert_eq!(seen.last(), Some(&(n, n)), "{}", drive.id());
            assert!(
                seen.windows(2).all(|w| w[0].0 < w[1].0),
                "{}: {seen:?}",
                drive.id()
            );
        }
        // One plan over every setting.
        let link = Shared(Rc::new(RefCell::new(SimLink::new(kind, sim.clone()))));
        let mut s = session(&drive, &link, sim.slave(), &externals(&drive));
        let regs = paramset::settings_of(&drive);
        let mut plan = s.plan(&regs).unwrap();
        let (_, requests) = s.poll_counted(&mut plan);
        assert!(
            report.requests <= requests,
            "{}: {} requests group by group, {requests} in one plan",
            drive.id(),
            report.requests
        );
    }
}
