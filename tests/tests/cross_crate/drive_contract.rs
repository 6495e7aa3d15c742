//! The drive trait's safety contract (`runtime/src/vfd.rs`, "Safety contract"), each guarantee
//! by a test against a drive simulated from its map, with faults injected at the transport
//! ([`SimLink`]): replies lost, late, refused, connections reset.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_live::LiveSettings;
use drivemap_map::Map;
use drivemap_runtime::async_client::AsyncClient;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::core::roles::Role;
use drivemap_runtime::pdu::Request;
use drivemap_runtime::vfd::{
    AsyncVariableFrequencyDrive, AsyncVfd, Direction, VariableFrequencyDrive, Vfd,
};
use drivemap_runtime::{client::Client, client::ClientOptions, error::Error};
use drivemap_sim::framing::{self, Decoded};
use drivemap_sim::{SimOptions, Simulator, clock::ManualClock};
use drivemap_test_support::sim_link::{LinkFault, SimLink};

mod command_profiles;
mod paramset_faults;

fn map(path: &str) -> Map {
    let path = paths::workspace().join(path);
    drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Options that make a lost reply cheap: the link answers at once or never.
fn options(retries: u8) -> ClientOptions {
    ClientOptions {
        timeout: Duration::from_micros(20),
        retries,
        request_gap: Duration::ZERO,
        ..ClientOptions::default()
    }
}

/// A client over `kind` to a simulator of `drive`, the settings the simulator holds and its
/// slave address.
fn connect(drive: &Map, kind: TransportKind, retries: u8) -> (Client<SimLink>, LiveSettings, u8) {
    let clock = ManualClock::new();
    // Installed for network control on the link (at the factory setting the drive ignores
    // network runs, and the trait refuses them: drive_trait::run_is_refused_at_the_factory_setting...).
    let sim = Simulator::new(
        drive.clone(),
        SimOptions::new()
            .clock(Arc::new(clock))
            .network_source(kind),
    )
    .unwrap();
    let settings = sim.settings();
    let slave = sim.slave();
    let link = SimLink::new(kind, sim);
    (
        Client::with_options(link, drive.plan().profile, options(retries)),
        settings,
        slave,
    )
}

fn run_command(c: &mut Client<SimLink>) -> bool {
    c.transport()
        .sim
        .state()
        .expect("a drive model")
        .run_command
}

/// The issue's sequences: run succeeds, the three replies of stop are lost (the drive did
/// stop), then an unrelated command. On the old code the V7 ran again: over RTU framing
/// `reset_fault` wrote 0001h = 0009h then 0001h, and `set_direction(Reverse)` wrote 0003h;
/// over Modbus TCP `reset_fault` wrote S1 (run forward) back with the reset.
#[test]
fn a_stop_whose_replies_were_lost_stays_a_stop() {
    let v7 = map("maps/yaskawa-v7.yaml");
    type Call = fn(&mut dyn VariableFrequencyDrive) -> Result<(), Error>;
    let calls: [(&str, Call); 2] = [
        ("reset_fault", |d| d.reset_fault()),
        ("set_direction(Reverse)", |d| {
            d.set_direction(Direction::Reverse)
        }),
    ];
    for kind in [TransportKind::RtuOverTcp, TransportKind::Tcp] {
        for (what, call) in calls {
            let (mut c, settings, slave) = connect(&v7, kind, 2);
            let view = settings.view(&v7);
            let p = v7.plan();
            let mut d = Vfd::from_plan(&mut c, slave, view, p.registers, p.roles);
            if !d.supports(Role::Reverse) && what.starts_with("set_direction") {
                // Over Modbus TCP the direction is the choice of run terminal: nothing to write.
                continue;
            }
            d.set_reference(30.0).unwrap();
            d.run().unwrap();
            assert!(run_command(d.client()), "{kind:?}: running after run()");
            for _ in 0..3 {
                d.client().transport().inject(LinkFault::LoseReply);
            }
            assert!(
                matches!(d.stop(), Err(Error::Timeout { .. })),
                "{kind:?}: stop's replies lost"
            );
            assert!(!run_command(d.client()), "{kind:?}: the drive got stop");
            let _ = call(&mut d);
            assert!(
                !run_command(d.client()),
                "{kind:?}: {what} after a stop whose replies were lost restarted the drive: {}",
                wire(d.client())
            );
        }
    }
}

/// The frames written, for messages.
fn wire(c: &mut Client<SimLink>) -> String {
    c.transport()
        .log
        .iter()
        .map(|s| {
            s.frame
                .iter()
                .map(|b| format!("{b:02X}"))
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The function, PDU address and (first) word written of every frame on the wire (RTU
/// framing).
fn requests(c: &mut Client<SimLink>) -> Vec<(u8, u16, Option<u16>)> {
    c.transport()
        .log
        .iter()
        .map(|s| {
            let f = &s.frame;
            let value = match f[1] {
                0x06 => Some(u16::from_be_bytes([f[4], f[5]])),
                0x10 => Some(u16::from_be_bytes([f[7], f[8]])),
                _ => None,
            };
            (f[1], u16::from_be_bytes([f[2], f[3]]), value)
        })
        .collect()
}

/// After a write of a command register fails, the next command reads the register back where
/// the map lets it be read (the V7's 0001h over RTU) and keeps the drive's other bits; where the
/// read fails too, or the register cannot be read (the GPD 515's operation command is
/// write-only), it composes from the released state: stop unless `run()` succeeded last, no
/// reset, the direction set.
#[test]
fn an_unknown_command_register_is_read_again_or_released() {
    let v7 = map("maps/yaskawa-v7.yaml");
    let p = v7.plan();
    // Read back: the drive got reverse (the reply was lost) and shows an external fault bit.
    let (mut c, settings, slave) = connect(&v7, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&v7), p.registers, p.roles);
    d.run().unwrap();
    d.client().transport().inject(LinkFault::LoseReply);
    assert!(d.set_direction(Direction::Reverse).is_err());
    let sim = &mut d.client().transport().sim;
    assert_eq!(sim.raw("digital_input_command").unwrap(), 0x0003);
    sim.set_raw("digital_input_command", 0x0007).unwrap();
    d.client().transport().log.clear();
    d.reset_fault().unwrap();
    // 03h 0001h x1, then reset set and released (the V7's reset is not edge-triggered), running
    // forward as the last run() said (the reverse was not confirmed), the external fault bit
    // kept.
    assert_eq!(
        requests(d.client()),
        [
            (0x03, 0x0001, None),
            (0x06, 0x0001, Some(0x000D)),
            (0x06, 0x0001, Some(0x0005)),
        ],
        "{}",
        wire(d.client())
    );
    drop(d);

    // The read back fails too: the released state, with run as the last run() left it.
    let (mut c, settings, slave) = connect(&v7, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&v7), p.registers, p.roles);
    d.run().unwrap();
    d.client().transport().inject(LinkFault::LoseReply);
    assert!(d.set_direction(Direction::Reverse).is_err());
    d.client()
        .transport()
        .sim
        .set_raw("digital_input_command", 0x0007)
        .unwrap();
    d.client().transport().log.clear();
    d.client().transport().inject(LinkFault::LoseReply);
    d.client().transport().inject(LinkFault::LoseReply);
    assert!(
        d.reset_fault().is_err(),
        "the reset's write after the failed read is lost"
    );
    assert_eq!(
        requests(d.client()),
        [(0x03, 0x0001, None), (0x06, 0x0001, Some(0x0009))],
        "{}",
        wire(d.client())
    );
    drop(d);

    // Write-only: the GPD 515's operation command. A run whose reply is lost, then stop: no
    // read, the released word.
    let gpd = map("maps/yaskawa-gpd515.yaml");
    let p = gpd.plan();
    let (mut c, settings, slave) = connect(&gpd, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&gpd), p.registers, p.roles);
    // The first run reads the command source b1-02 (once); stopped again, the drive is released.
    d.run().unwrap();
    d.stop().unwrap();
    d.client().transport().inject(LinkFault::LoseReply);
    let e = d.run().unwrap_err();
    assert!(
        run_command(d.client()),
        "the drive got the run: {e}; {}",
        wire(d.client())
    );
    d.client().transport().log.clear();
    d.stop().unwrap();
    assert!(!run_command(d.client()));
    let written: Vec<_> = requests(d.client());
    assert!(
        written.iter().all(|(f, _, _)| *f != 0x03) && written.len() == 1,
        "{}",
        wire(d.client())
    );
    assert_eq!(written[0].2, Some(0x0000));
}

// ------------------------------------------------------------------------------------------
// The fault-injection property test.

/// One step of a sequence: a trait call, or something that happens to the drive.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Step {
    Run,
    Stop,
    Direction(Direction),
    Reference(f64),
    Ramp(f64, f64),
    ResetFault,
    Status,
    OutputFrequency,
    /// Coast to a stop (`coast()`: a command profile's path, refused elsewhere).
    Coast,
    /// Quick stop (`quick_stop()`: a command profile's path, refused elsewhere).
    QuickStop,
    /// The drive trips (not a call: the simulated drive faults).
    Trip,
    /// The drive is stopped at its own panel (not a call).
    LocalStop,
    /// An interlock at the drive opens (`true`: a command profile's drive refuses the
    /// transitions towards running) or closes (not a call).
    Interlock(bool),
    /// Simulated time passes (s).
    Wait(f64),
}

impl Step {
    /// A call that stops the drive: `stop()`, and on a drive with a command profile (`profile`)
    /// `coast()` and `quick_stop()` (refused elsewhere, where they send nothing).
    fn stops(&self, profile: bool) -> bool {
        *self == Step::Stop || (profile && matches!(self, Step::Coast | Step::QuickStop))
    }
}

/// A sequence and what happens on the link: the fault of each request in turn (`None`:
/// delivered and answered), and the client's retries.
#[derive(Debug, Clone)]
struct Case {
    steps: Vec<Step>,
    faults: Vec<Option<LinkFault>>,
    retries: u8,
}

fn step() -> impl proptest::strategy::Strategy<Value = Step> {
    use proptest::prelude::*;
    let direction = prop_oneof![Just(Direction::Forward), Just(Direction::Reverse)];
    prop_oneof![
        4 => Just(Step::Run),
        4 => Just(Step::Stop),
        2 => direction.prop_map(Step::Direction),
        // Mostly on a 0.1 Hz grid, some on 0.01 Hz (between the steps of a 0.1 Hz register).
        2 => (-10.0f64..150.0, prop_oneof![3 => Just(10.0), 1 => Just(100.0)])
            .prop_map(|(hz, per)| Step::Reference((hz * per).round() / per)),
        1 => (0.0f64..120.0, 0.0f64..120.0, any::<bool>()).prop_map(|(a, d, same)| {
            let (a, d) = ((a * 10.0).round() / 10.0, (d * 10.0).round() / 10.0);
            Step::Ramp(a, if same { a } else { d })
        }),
        2 => Just(Step::ResetFault),
        1 => Just(Step::Status),
        1 => Just(Step::OutputFrequency),
        1 => Just(Step::Coast),
        1 => Just(Step::QuickStop),
        1 => Just(Step::Trip),
        1 => Just(Step::LocalStop),
        1 => any::<bool>().prop_map(Step::Interlock),
        1 => (0.0f64..30.0).prop_map(Step::Wait),
    ]
}

fn fault() -> impl proptest::strategy::Strategy<Value = Option<LinkFault>> {
    use proptest::prelude::*;
    prop_oneof![
        12 => Just(None),
        2 => Just(Some(LinkFault::LoseReply)),
        1 => Just(Some(LinkFault::LoseRequest)),
        2 => Just(Some(LinkFault::LateReply)),
        1 => prop_oneof![Just(4u8), Just(6u8)].prop_map(|c| Some(LinkFault::Exception(c))),
        1 => any::<bool>().prop_map(|executed| Some(LinkFault::Disconnect { executed })),
    ]
}

fn case() -> impl proptest::strategy::Strategy<Value = Case> {
    use proptest::prelude::*;
    (
        proptest::collection::vec(step(), 1..14),
        proptest::collection::vec(fault(), 0..40),
        0u8..3,
    )
        .prop_map(|(steps, faults, retries)| Case {
            steps,
            faults,
            retries,
        })
}

/// What a sequence left to check: each step with its outcome, the drive's run command before
/// and after it, and the frames on the wire.
struct Trace {
    steps: Vec<(Step, Result<(), String>)>,
    /// Run command of the drive model before and after each step.
    run_command: Vec<(bool, bool)>,
    log: Vec<drivemap_test_support::sim_link::Sent>,
}

/// Plays `case` on a copy of `drive`'s simulator `template` (at power-on) over `kind`.
fn play(drive: &Map, template: &Simulator, kind: TransportKind, case: &Case) -> Trace {
    let clock = ManualClock::new();
    let mut sim = template.clone();
    sim.set_clock(Arc::new(clock.clone()));
    let settings = sim.settings();
    let slave = sim.slave();
    let mut link = SimLink::new(kind, sim);
    link.record_settings = true;
    link.script(case.faults.iter().copied());
    let p = drive.plan();
    let mut c = Client::with_options(link, p.profile, options(case.retries));
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(drive), p.registers, p.roles);
    let mut trace = Trace {
        steps: Vec::new(),
        run_command: Vec::new(),
        log: Vec::new(),
    };
    for (i, &s) in case.steps.iter().enumerate() {
        d.client().transport().tag = i as u32;
        let before = run_command(d.client());
        let result = match s {
            Step::Run => d.run(),
            Step::Stop => d.stop(),
            Step::Direction(dir) => d.set_direction(dir),
            Step::Reference(hz) => d.set_reference(hz),
            Step::Ramp(a, dec) => d.set_ramp(a, dec),
            Step::ResetFault => d.reset_fault(),
            Step::Status => d.status().map(|_| ()),
            Step::OutputFrequency => d.output_frequency().map(|_| ()),
            Step::Coast => d.coast(),
            Step::QuickStop => d.quick_stop(),
            Step::Trip => {
                d.client().transport().sim.trip(1);
                Ok(())
            }
            Step::LocalStop => {
                d.client().transport().sim.local_stop();
                Ok(())
            }
            Step::Interlock(open) => {
                d.client().transport().sim.set_interlock(open);
                Ok(())
            }
            Step::Wait(s) => {
                clock.advance(Duration::from_secs_f64(s));
                d.client().transport().sim.tick();
                Ok(())
            }
        };
        let after = run_command(d.client());
        trace.steps.push((s, result.map_err(|e| e.to_string())));
        trace.run_command.push((before, after));
    }
    drop(d);
    trace.log = std::mem::take(&mut c.transport().log);
    trace
}

/// Plays `case` as [`play`] does, through the async drive ([`AsyncVfd`] over an
/// [`AsyncClient`] that owns its link) on `runtime`.
fn play_async(
    drive: &Map,
    template: &Simulator,
    kind: TransportKind,
    case: &Case,
    runtime: &tokio::runtime::Runtime,
) -> Trace {
    let clock = ManualClock::new();
    let mut sim = template.clone();
    sim.set_clock(Arc::new(clock.clone()));
    let settings = sim.settings();
    let slave = sim.slave();
    let mut link = SimLink::new(kind, sim);
    link.record_settings = true;
    link.script(case.faults.iter().copied());
    let p = drive.plan();
    let c = AsyncClient::with_options(link, p.profile, options(case.retries));
    // The drive owns its client.
    let mut d = AsyncVfd::from_plan(c, slave, settings.view(drive), p.registers, p.roles);
    let mut trace = Trace {
        steps: Vec::new(),
        run_command: Vec::new(),
        log: Vec::new(),
    };
    runtime.block_on(async {
        for (i, &s) in case.steps.iter().enumerate() {
            d.client().transport().tag = i as u32;
            let before = link_runs(d.client().transport());
            let result = match s {
                Step::Run => d.run().await,
                Step::Stop => d.stop().await,
                Step::Direction(dir) => d.set_direction(dir).await,
                Step::Reference(hz) => d.set_reference(hz).await,
                Step::Ramp(a, dec) => d.set_ramp(a, dec).await,
                Step::ResetFault => d.reset_fault().await,
                Step::Status => d.status().await.map(|_| ()),
                Step::OutputFrequency => d.output_frequency().await.map(|_| ()),
                Step::Coast => d.coast().await,
                Step::QuickStop => d.quick_stop().await,
                Step::Trip => {
                    d.client().transport().sim.trip(1);
                    Ok(())
                }
                Step::LocalStop => {
                    d.client().transport().sim.local_stop();
                    Ok(())
                }
                Step::Interlock(open) => {
                    d.client().transport().sim.set_interlock(open);
                    Ok(())
                }
                Step::Wait(s) => {
                    clock.advance(Duration::from_secs_f64(s));
                    d.client().transport().sim.tick();
                    Ok(())
                }
            };
            let after = link_runs(d.client().transport());
            trace.steps.push((s, result.map_err(|e| e.to_string())));
            trace.run_command.push((before, after));
        }
    });
    trace.log = std::mem::take(&mut d.into_client().transport().log);
    trace
}

fn link_runs(link: &SimLink) -> bool {
    link.sim.state().expect("a drive model").run_command
}

/// Whether `raw` is a value the map allows register `r` to take with `settings`: the plan's
/// own conversion accepts it (its ranges, codes and reserved bits in force) and gives it back
/// unchanged.
fn within_limits(
    r: &drivemap_runtime::core::plan::RegisterPlan,
    raw: u32,
    settings: &impl drivemap_runtime::core::plan::SettingsView,
) -> Result<(), String> {
    use drivemap_runtime::core::plan::Conversion;
    let again = match r.conversion {
        Conversion::Word { .. } | Conversion::Enum { .. } | Conversion::Bits { .. } => {
            r.encode_word(r.int(raw), settings)
        }
        _ => r
            .decode_number(raw, settings)
            .and_then(|v| r.encode_number(v, settings)),
    };
    match again {
        Ok(back) if back == raw => Ok(()),
        Ok(back) => Err(format!(
            "{}: {raw:#X} does not encode back ({back:#X})",
            r.info.id
        )),
        Err(e) => Err(format!("{}: {raw:#X}: {e}", r.info.id)),
    }
}

/// The rows of a map a write over one link may land on, by table and PDU address: those whose
/// address never moves, looked up; those that move with a setting, variant or transport, to
/// locate under the settings in force at each frame. Built once per map and link.
struct Rows {
    fixed: std::collections::HashMap<(Table, u16), Vec<usize>>,
    moving: Vec<usize>,
}

impl Rows {
    fn new(drive: &Map, kind: TransportKind) -> Rows {
        let p = drive.plan();
        let mut fixed: std::collections::HashMap<(Table, u16), Vec<usize>> = Default::default();
        let mut moving = Vec::new();
        for (i, r) in p.registers.iter().enumerate() {
            if !r.transports.contains(kind)
                || r.broadcast == drivemap_runtime::core::rule::Broadcast::Only
            {
                continue;
            }
            if !r.moves.is_empty() {
                moving.push(i);
            } else if let Some(pdu) = p.profile.address_offsets.pdu_address(r.info.address, kind) {
                fixed.entry((r.info.table, pdu)).or_default().push(i);
            }
        }
        Rows { fixed, moving }
    }

    /// The rows of `table` at `pdu` on the link under `view`, in the plan's order.
    fn at(
        &self,
        drive: &Map,
        kind: TransportKind,
        table: Table,
        pdu: u16,
        view: &impl drivemap_runtime::core::plan::SettingsView,
    ) -> Vec<usize> {
        let p = drive.plan();
        let mut rows: Vec<usize> = self.fixed.get(&(table, pdu)).cloned().unwrap_or_default();
        rows.extend(self.moving.iter().copied().filter(|&i| {
            let r = &p.registers[i];
            r.info.table == table
                && p.profile
                    .address_offsets
                    .pdu_address(r.address_for(view, kind), kind)
                    == Some(pdu)
        }));
        rows.sort_unstable();
        rows
    }
}

/// The invariants of the safety contract on one trace; `Err` says which failed and where.
fn check(drive: &Map, kind: TransportKind, rows: &Rows, trace: &Trace) -> Result<(), String> {
    use drivemap_runtime::core::roles::Target;
    let p = drive.plan();
    let profile = p.roles.profile.is_some();
    let run_roles: Vec<_> = [Role::Run, Role::RunForward, Role::RunReverse]
        .into_iter()
        .flat_map(|role| p.roles.of(role))
        .filter_map(|place| match place.target {
            Target::Field(f) => Some(f),
            _ => None,
        })
        .collect();
    // Whether step `t` may write a run code: it is run(), or the last of run() and stop()
    // before it is a run() that succeeded.
    let may_run = |t: usize| -> bool {
        if trace.steps[t].0 == Step::Run {
            return true;
        }
        trace.steps[..t]
            .iter()
            .rev()
            .find(|(s, _)| matches!(s, Step::Run) || s.stops(profile))
            .is_some_and(|(s, r)| *s == Step::Run && r.is_ok())
    };
    for sent in &trace.log {
        let t = sent.tag as usize;
        let step = &trace.steps[t].0;
        // For messages only: made when one is.
        let frame = Hex(&sent.frame);
        let Decoded::Request { origin, request } = framing::decode(kind, &sent.frame) else {
            return Err(format!("step {t} ({step:?}): undecodable frame {frame}"));
        };
        let (table, address, words): (Table, u16, Vec<u16>) = match request {
            Request::WriteSingle { address, value } => (Table::Holding, address, vec![value]),
            Request::WriteMultiple { address, values } => (
                Table::Holding,
                address,
                (0..values.len()).filter_map(|i| values.get(i)).collect(),
            ),
            // A coil: its raw value is 1 (on) or 0 (off).
            Request::WriteCoil { address, value } => (Table::Coil, address, vec![value.into()]),
            Request::WriteCoils { address, values } => {
                (Table::Coil, address, values.iter().map(u16::from).collect())
            }
            _ => continue,
        };
        if origin.slave() == 0 {
            return Err(format!("step {t} ({step:?}): a broadcast {frame}"));
        }
        let settings = sent.settings.as_ref().expect("recorded");
        let view = settings.view(drive);
        let mut at = 0usize;
        while at < words.len() {
            let pdu = address.wrapping_add(at as u16);
            let rows = rows.at(drive, kind, table, pdu, &view);
            let [row] = rows[..] else {
                return Err(format!(
                    "step {t} ({step:?}): {frame} writes {pdu:04X}h, where {} registers of the map are",
                    rows.len()
                ));
            };
            let r = &p.registers[row];
            let n = usize::from(r.info.width.count());
            let Some(mine) = words.get(at..at + n) else {
                return Err(format!("step {t} ({step:?}): {frame} splits {}", r.info.id));
            };
            let raw = r.info.width.join(mine);
            within_limits(r, raw, &view).map_err(|e| {
                format!("step {t} ({step:?}): {frame}: outside the map's limits: {e}")
            })?;
            // A run code of a run field, or a control word that asks the drive's command
            // profile for a run transition.
            let runs = run_roles
                .iter()
                .any(|f| usize::from(f.row) == row && f.holds(raw as u16))
                || p.roles.profile.is_some_and(|profile| {
                    usize::from(profile.control) == row && profile.word_runs(raw as u16)
                });
            if runs && !may_run(t) {
                return Err(format!(
                    "step {t} ({step:?}) wrote a run code ({frame}: {} = {raw:#06X}) although the last of run() and stop() before it was not a successful run()",
                    r.info.id
                ));
            }
            at += n;
        }
    }
    // After stop(), once the drive's run command is off it stays off until the next run().
    let mut frames = trace.log.iter().peekable();
    let mut stopped = false;
    for (t, (step, _)) in trace.steps.iter().enumerate() {
        let (before, after) = trace.run_command[t];
        match step {
            Step::Run => stopped = false,
            s if s.stops(profile) => stopped = !before,
            _ if stopped && before => {
                return Err(format!("the drive ran again before step {t} ({step:?})"));
            }
            _ => {}
        }
        let stop_window = step.stops(profile)
            || (*step != Step::Run
                && trace.steps[..t]
                    .iter()
                    .rev()
                    .find(|(s, _)| matches!(s, Step::Run) || s.stops(profile))
                    .is_some_and(|(s, _)| s.stops(profile)));
        while let Some(sent) = frames.next_if(|s| s.tag as usize == t) {
            let Some(on) = sent.run_command else { continue };
            if stop_window && stopped && on {
                return Err(format!(
                    "step {t} ({step:?}): {} made the drive run again after stop()",
                    hex(&sent.frame)
                ));
            }
            stopped |= stop_window && !on;
        }
        if stop_window && stopped && after {
            return Err(format!("the drive ran again during step {t} ({step:?})"));
        }
        stopped |= stop_window && !after;
    }
    Ok(())
}

fn hex(bytes: &[u8]) -> String {
    Hex(bytes).to_string()
}

/// Bytes in hex, written when displayed.
struct Hex<'a>(&'a [u8]);

impl std::fmt::Display for Hex<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02X}"))
    }
}

/// Every map of `maps/` (the directory, not a list, as for the other per-map tests) and the
/// acme-vf1 fixture.
fn every_map() -> Vec<(String, Map)> {
    let dir = paths::maps();
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    files.sort();
    files.push(paths::fixture("acme-vf1/acme-vf1.yaml"));
    let mut maps: Vec<(String, Map)> = files
        .into_iter()
        .map(|p| {
            let d = drivemap_map::Loader::new()
                .load(&p)
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (d.id().to_owned(), d)
        })
        .collect();
    // The drives run through a command profile (a control-word state machine), with every
    // transition's time limit cut to 3 ms: a transition the drive refuses (an interlock) is
    // waited out in real time.
    for f in command_profiles::FIXTURES {
        let text = std::fs::read_to_string(paths::workspace().join(f)).unwrap();
        let fast = text
            .lines()
            .map(|l| match l.find("limit_ms: ") {
                Some(i) => {
                    let rest = &l[i + "limit_ms: ".len()..];
                    let digits = rest.chars().take_while(char::is_ascii_digit).count();
                    format!("{}limit_ms: 3{}", &l[..i], &rest[digits..])
                }
                None => l.to_owned(),
            })
            .collect::<Vec<_>>()
            .join("\n");
        let d = drivemap_map::Loader::new()
            .load_str(f, &fast)
            .unwrap_or_else(|e| panic!("{f}: {e}"));
        maps.push((d.id().to_owned(), d));
    }
    // A drive run through coils (run, direction, trip reset) and read through discrete inputs.
    let coils = paths::fixture("tindra-tc4/tindra-tc4.yaml");
    let d = drivemap_map::Loader::new()
        .load(&coils)
        .unwrap_or_else(|e| panic!("{}: {e}", coils.display()));
    maps.push((d.id().to_owned(), d));
    maps
}

/// The links a map is driven over: RTU framing (RTU over TCP, which can reconnect) always,
/// Modbus TCP where the map lists it.
fn links(drive: &Map) -> Vec<TransportKind> {
    let mut kinds = vec![TransportKind::RtuOverTcp];
    if drive
        .protocol()
        .transports
        .contains(&drivemap_map::facts::TransportName::Tcp)
    {
        kinds.push(TransportKind::Tcp);
    }
    kinds
}

/// Sequences in all (`DRIVEMAP_CONTRACT_CASES`; 100,000 by default, split evenly over every
/// map and link).
fn total_cases() -> u32 {
    match std::env::var("DRIVEMAP_CONTRACT_CASES") {
        Ok(v) => v
            .parse()
            .unwrap_or_else(|_| panic!("DRIVEMAP_CONTRACT_CASES={v}: give a number of sequences")),
        Err(_) => 100_000,
    }
}

/// Of the runners of each map and link, these play their sequences through the async drive
/// ([`AsyncVfd`]); the others through the blocking one.
const ASYNC_SHARDS: u32 = 2;

/// Runners per map and link, side by side: on RTU framing the client waits for the line to
/// be silent for the drive's response time after every unanswered request (real time, spent
/// asleep), so sequences are played by many threads at once.
const SHARDS: u32 = 8;

/// Random sequences of trait calls, with reply loss, late replies, exceptions and reconnects
/// injected at the transport, and the drive changing on its own (a trip, a stop at its panel,
/// an interlock that refuses a command profile's way to running), against the simulator of
/// every map, the acme-vf1 fixture and its two variants with shared roles, the command-profile
/// fixtures (time limits cut to 3 ms), over RTU framing and Modbus TCP, through the blocking drive
/// ([`Vfd`]) and, on [`ASYNC_SHARDS`] of the [`SHARDS`] runners of each, the async one
/// ([`AsyncVfd`], owning its client). Invariants, on what reached the wire and on the drive: a run code
/// is written only by `run()` (or while a successful `run()` was the last of `run()` and
/// `stop()`); after `stop()`, successful or not, the drive never runs again until the next
/// `run()`; every word written is within the map's limits in force.
#[test]
fn the_contract_holds_under_faults() {
    use proptest::test_runner::{Config, TestCaseError, TestError, TestRunner};
    let mut maps = every_map();
    // And the constructs no shipped map has: roles that share a register.
    maps.push(("acme-vf1 (one ramp register)".into(), acme_one_ramp().0));
    maps.push(("acme-vf1 (run codes)".into(), acme_run_codes()));
    let targets: Vec<(&str, &Map, TransportKind)> = maps
        .iter()
        .filter(|(_, d)| !d.plan().roles.is_empty())
        .flat_map(|(id, d)| links(d).into_iter().map(move |k| (id.as_str(), d, k)))
        .collect();
    assert!(
        maps.iter().any(|(id, _)| id == "acme-vf1") && targets.len() >= maps.len(),
        "every map with roles, and the fixture"
    );
    let per_shard = total_cases().div_ceil(targets.len() as u32 * SHARDS);
    let started = std::time::Instant::now();
    let failures: Vec<String> = std::thread::scope(|scope| {
        let runs: Vec<_> = targets
            .iter()
            .flat_map(|t| (0..SHARDS).map(move |shard| (t, shard)))
            .map(|(&(id, drive, kind), shard)| {
                scope.spawn(move || {
                    let template =
                        Simulator::new(drive.clone(), SimOptions::new().network_source(kind))
                            .unwrap();
                    let mut runner = TestRunner::new(Config {
                        cases: per_shard,
                        failure_persistence: None,
                        ..Config::default()
                    });
                    let runtime = tokio::runtime::Builder::new_current_thread()
                        .enable_time()
                        .build()
                        .unwrap();
                    let asynchronous = shard < ASYNC_SHARDS;
                    let rows = Rows::new(drive, kind);
                    let result = runner.run(&case(), |case| {
                        let trace = if asynchronous {
                            play_async(drive, &template, kind, &case, &runtime)
                        } else {
                            play(drive, &template, kind, &case)
                        };
                        check(drive, kind, &rows, &trace).map_err(TestCaseError::fail)
                    });
                    let which = if asynchronous {
                        "the async drive"
                    } else {
                        "the drive"
                    };
                    match result {
                        Ok(()) => None,
                        Err(TestError::Fail(why, case)) => Some(format!(
                            "{which}, {id} over {kind:?}: {why}\n  shrunk case: {case:?}"
                        )),
                        Err(e) => Some(format!("{which}, {id} over {kind:?}: {e}")),
                    }
                })
            })
            .collect();
        runs.into_iter()
            .filter_map(|r| r.join().expect("a runner panicked"))
            .collect()
    });
    eprintln!(
        "{} sequences ({per_shard} x {SHARDS} on each of {} maps x links, {} of them through the async drive) in {:.1} s",
        u64::from(per_shard * SHARDS) * targets.len() as u64,
        targets.len(),
        u64::from(per_shard * ASYNC_SHARDS) * targets.len() as u64,
        started.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The acme-vf1 fixture's map text, changed in memory: `from` replaced by `to`.
fn acme_changed(from: &str, to: &str) -> (Map, String) {
    let text = std::fs::read_to_string(paths::fixture("acme-vf1/acme-vf1.yaml")).unwrap();
    assert!(text.contains(from), "the fixture has {from}");
    let changed = text.replace(from, to);
    let drive = drivemap_map::Loader::new()
        .load_str("acme-vf1.yaml", &changed)
        .unwrap_or_else(|e| panic!("{e}"));
    (drive, changed)
}

/// acme-vf1 with one ramp register for both directions: its deceleration role moved onto the
/// acceleration register, `shared_with` said once. Also the map's text.
fn acme_one_ramp() -> (Map, String) {
    acme_changed(
        r#"    - {register: deceleration_time, source: "acme-vf1.txt:21"}"#,
        r#"    - {register: acceleration_time, shared_with: accel_time, source: "acme-vf1.txt:20"}"#,
    )
}

/// acme-vf1 run by two codes of one field: 2 runs forward, 3 runs reverse, 1 stops
/// (`run_forward` and `run_reverse` on the same bits, `shared_with` said once).
fn acme_run_codes() -> Map {
    acme_changed(
        r#"  run:
    - {register: control_word, field: run_stop, on: run, off: stop, source: "acme-vf1.txt:16"}
  reverse:
    - {register: control_word, field: direction, on: reverse, off: forward, source: "acme-vf1.txt:17"}
"#,
        r#"  run_forward:
    - {register: control_word, field: run_stop, on: 2, off: 1, source: "acme-vf1.txt:16"}
  run_reverse:
    - {register: control_word, field: run_stop, on: 3, off: 1, shared_with: run_forward, source: "acme-vf1.txt:16"}
"#,
    )
    .0
}

/// A drive with one ramp register for both directions (the acme-vf1 fixture with its
/// deceleration role moved onto the acceleration register, `shared_with` said once): the plan
/// gives both places the sharing, `set_ramp(2, 1)` is refused before anything is sent (it wrote
/// the register twice and reported success), and `set_ramp(2, 2)` writes it once.
#[test]
fn one_ramp_register_takes_one_value() {
    let (drive, shared) = acme_one_ramp();
    let p = drive.plan();
    let place = |role| p.roles.of(role).next().unwrap();
    assert_eq!(place(Role::AccelTime).shared_with, Some(Role::DecelTime));
    assert_eq!(place(Role::DecelTime).shared_with, Some(Role::AccelTime));
    // The reference document says so beside the register.
    let doc = drivemap_review::reference::render(&drive, "acme-vf1.yaml");
    assert!(
        doc.contains("| `decel_time` | `acceleration_time` (one register with `accel_time`) |"),
        "{doc}"
    );
    // Without `shared_with` the map is refused.
    let unsaid = shared.replace("shared_with: accel_time, ", "");
    let e = drivemap_map::Loader::new()
        .load_str("acme-vf1.yaml", &unsaid)
        .unwrap_err()
        .to_string();
    assert!(e.contains("shared_with: accel_time"), "{e}");

    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    match d.set_ramp(2.0, 1.0) {
        Err(Error::Refused(e @ drivemap_runtime::error::Refusal::SharedRegister { .. })) => {
            let message = e.to_string();
            assert!(
                message.contains("accel_time and decel_time are one register (acceleration_time)")
                    && message.contains("2 s and 1 s"),
                "{message}"
            );
        }
        other => panic!("set_ramp(2, 1) on one ramp register: {other:?}"),
    }
    assert!(d.client().transport().log.is_empty(), "nothing sent");
    d.set_ramp(2.0, 2.0).unwrap();
    assert_eq!(d.client().transport().log.len(), 1, "{}", wire(d.client()));
    assert_eq!(
        d.client()
            .transport()
            .sim
            .value("acceleration_time")
            .unwrap()
            .as_f64(),
        Some(2.0)
    );
}

/// The property test's limit check has teeth: a word for 500 Hz to the V7's frequency reference
/// registers (a 16-bit word allows it; the manual bounds it by n011, 60 Hz at the simulator's
/// power-on) is outside the limits in force, 30 Hz is within, and a run word with a reserved
/// bit set is outside.
#[test]
fn the_limit_check_refuses_what_the_map_does_not_allow() {
    let v7 = map("maps/yaskawa-v7.yaml");
    let sim = Simulator::new(v7.clone(), SimOptions::new()).unwrap();
    let settings = sim.settings();
    let view = settings.view(&v7);
    let p = v7.plan();
    let row = |id: &str| p.registers.iter().find(|r| r.info.id == id).unwrap();
    for id in ["frequency_reference", "tcp_frequency_reference"] {
        let r = row(id);
        // The raw word for `hz` without any check: the register's own step in force.
        let step = r.decode_number(1, &view).unwrap();
        let at = |hz: f64| (hz / step).round() as u32;
        let raw_30 = at(30.0);
        assert_eq!(within_limits(r, raw_30, &view), Ok(()), "{id}: 30 Hz");
        let raw_500 = at(500.0);
        assert!(raw_500 <= 0xFFFF, "{id}: 500 Hz fits the word");
        let e = within_limits(r, raw_500, &view).unwrap_err();
        assert!(e.contains(id), "{id}: 500 Hz refused: {e}");
    }
    let command = row("digital_input_command");
    assert_eq!(within_limits(command, 0x0001, &view), Ok(()));
    assert!(
        within_limits(command, 0x8001, &view).is_err(),
        "a reserved bit"
    );
}

/// Two command roles on the same bits, said with `shared_with`: run forward and run reverse as
/// two codes of one run field (the acme-vf1 fixture changed in memory: code 2 runs forward, 3
/// runs reverse, 1 stops). A word is composed with releases first, so the role set wins: run()
/// forward writes 2 (it wrote 1, stop, when the release of run reverse came after), and run()
/// in reverse writes 3.
#[test]
fn command_roles_sharing_bits_get_the_one_set() {
    let drive = acme_run_codes();
    let p = drive.plan();
    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    let run_code = |d: &mut Vfd<_, &mut Client<SimLink>>| {
        d.client().transport().sim.raw("control_word").unwrap() & 0x0003
    };
    d.run().unwrap();
    assert_eq!(run_code(&mut d), 2, "{}", wire(d.client()));
    assert!(run_command(d.client()));
    d.stop().unwrap();
    assert_eq!(run_code(&mut d), 1);
    d.set_direction(Direction::Reverse).unwrap();
    d.run().unwrap();
    assert_eq!(run_code(&mut d), 3, "{}", wire(d.client()));
    let state = d.client().transport().sim.state().unwrap();
    assert!(state.run_command && state.reverse_command, "{state:?}");
}
