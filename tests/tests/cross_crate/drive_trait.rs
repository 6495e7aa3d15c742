//! The drive trait on every compiled drive: one generic routine, written against
//! `VariableFrequencyDrive` only, runs each drive of `for_each_drive!` against its simulator (over
//! RTU framing and over Modbus TCP, where the map gives the drive other registers), ramps it to the
//! reference, reverses it where the map can, stops it, and gets a clear refusal for a role the map
//! lacks. Time is a manual clock: the ramps are exact, not timed.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::{DrivePlan, DriveSettings};
use drivemap_runtime::core::roles::Role;
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::vfd::{Direction, VariableFrequencyDrive, Vfd};
use drivemap_runtime::{client::Client, error::Error, error::Refusal};
use drivemap_sim::{
    SimOptions, Simulator, clock::ManualClock, server::TcpFraming, server::TcpServer,
};

/// The map of a compiled drive, from `maps/`, which the drives crate is generated from.
fn map(id: &str) -> drivemap_map::Map {
    let path = paths::shipped_map(id);
    drivemap_map::Loader::new().load(path.as_ref()).unwrap()
}

/// The generic part: what an application does with any drive. `wait` lets simulated time pass.
fn exercise(
    d: &mut impl VariableFrequencyDrive,
    wait: &dyn Fn(f64),
    reverse: bool,
) -> Result<(), Error> {
    let id = d.drive_id();
    if d.supports(Role::AccelTime) && d.supports(Role::DecelTime) {
        d.set_ramp(2.0, 2.0)?;
    }
    d.set_reference(30.0)?;
    if reverse {
        d.set_direction(Direction::Reverse)?;
    }
    d.run()?;
    // 2 s to the maximum frequency (60 Hz or more): 0.2 s is part of the way to 30 Hz.
    wait(0.2);
    let status = d.status()?;
    assert_eq!(
        status.running,
        Some(true),
        "{id}: running after run: {status}"
    );
    let rising = d.output_frequency()?;
    assert!(
        rising > 0.0 && rising < 30.0,
        "{id}: ramping, at {rising} Hz"
    );
    wait(60.0);
    let hz = d.output_frequency()?;
    assert!((hz - 30.0).abs() <= 0.1, "{id}: at the reference, {hz} Hz");
    let status = d.status()?;
    if status.reversing.is_some() {
        assert_eq!(status.reversing, Some(reverse), "{id}: {status}");
    }
    if let Some(agree) = status.speed_agree {
        assert!(agree, "{id}: speed agree at the reference: {status}");
    }
    if d.supports(Role::ReferenceMonitor) {
        let r = d.reference()?;
        assert!((r - 30.0).abs() <= 0.1, "{id}: reference monitor {r}");
    }
    d.stop()?;
    wait(60.0);
    assert_eq!(d.output_frequency()?, 0.0, "{id}: stopped");
    let status = d.status()?;
    assert_eq!(status.running, Some(false), "{id}: {status}");
    if let Some(zero) = status.zero_speed {
        assert!(zero, "{id}: zero speed when stopped: {status}");
    }
    Ok(())
}

/// Runs `exercise` on drive `D` through a simulator of its map on a link of `kind`.
fn through<D>(id: &str, kind: TransportKind)
where
    D: DrivePlan,
    D::Settings: DriveSettings + Default,
{
    let clock = ManualClock::new();
    // Installed for network control: the source parameters select the network (at the factory
    // setting the drive ignores network run commands: see `run_is_refused_at_the_factory_setting`).
    let sim = Simulator::new(
        map(id),
        SimOptions::new()
            .clock(Arc::new(clock.clone()))
            .network_source(kind),
    )
    .unwrap();
    assert!(sim.has_model(), "{id}: its map gives roles");
    let slave = sim.slave();
    let externals: Vec<(String, f64)> = sim.externals().clone().into_iter().collect();
    let shared = drivemap_sim::server::shared(sim);
    let framing = match kind {
        TransportKind::Tcp => TcpFraming::ModbusTcp,
        _ => TcpFraming::RtuOverTcp,
    };
    let server = TcpServer::spawn(shared, "127.0.0.1:0", framing, None).unwrap();
    let addr = server.local_addr();
    let ext: Vec<(&str, f64)> = externals.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    let wait = |s: f64| clock.advance(Duration::from_secs_f64(s));
    fn go<D, T>(link: T, slave: u8, ext: &[(&str, f64)], wait: &dyn Fn(f64)) -> Result<(), Error>
    where
        D: DrivePlan,
        D::Settings: DriveSettings + Default,
        T: Transport,
    {
        let mut c = Client::new(link, D::PROFILE);
        let mut d = Vfd::connect::<D>(&mut c, slave, D::Settings::default(), ext)?;
        exercise(&mut d, wait, false)?;
        if d.supports(Role::Reverse) || d.supports(Role::RunReverse) {
            exercise(&mut d, wait, true)?;
            d.set_direction(Direction::Forward)?;
        } else {
            // No way to reverse on this link: refused, and nothing sent.
            match d.set_direction(Direction::Reverse) {
                Err(Error::Refused(Refusal::NoRole {
                    role: "reverse", ..
                })) => {}
                other => panic!("{}: reverse without a way: {other:?}", D::PROFILE.drive_id),
            }
        }
        // A reference above the drive's maximum frequency (1000 Hz: the maps print at most
        // 400 Hz) is refused where the map gives the role, and the drive keeps its reference.
        if D::ROLES.of(Role::MaxFrequency).next().is_some() {
            match d.set_reference(1000.0) {
                Err(Error::Value(ValueError::AboveLimit { value, max, .. })) => {
                    assert_eq!(value, 1000.0);
                    assert!(max < 1000.0, "{}: max {max}", D::PROFILE.drive_id);
                }
                other => panic!("{}: 1000 Hz: {other:?}", D::PROFILE.drive_id),
            }
            if d.supports(Role::ReferenceMonitor) {
                let r = d.reference()?;
                assert!((r - 30.0).abs() <= 0.1, "{}: kept {r}", D::PROFILE.drive_id);
            }
        }
        // A role the map lacks is refused before anything is sent.
        for (role, call) in [
            (
                Role::DcBusVoltage,
                VariableFrequencyDrive::dc_bus_voltage as fn(&mut _) -> _,
            ),
            (Role::OutputVoltage, VariableFrequencyDrive::output_voltage),
            (Role::OutputCurrent, VariableFrequencyDrive::output_current),
        ] {
            if !d.supports(role) {
                match call(&mut d) {
                    Err(Error::Refused(Refusal::NoRole { role: r, .. })) => {
                        assert_eq!(r, role.id())
                    }
                    other => panic!("{}: {role:?} absent, got {other:?}", D::PROFILE.drive_id),
                }
            }
        }
        Ok(())
    }
    let result = match kind {
        TransportKind::Tcp => go::<D, _>(
            TcpTransport::connect(addr, Duration::from_secs(2)).unwrap(),
            slave,
            &ext,
            &wait,
        ),
        _ => go::<D, _>(
            RtuOverTcpTransport::connect(addr, Duration::from_secs(2)).unwrap(),
            slave,
            &ext,
            &wait,
        ),
    };
    server.stop();
    result.unwrap_or_else(|e| panic!("{id} over {kind:?}: {e}"));
}

/// Whether the map gives a frequency reference on `kind` (the J7 has no Modbus TCP registers).
fn on<D: DrivePlan>(kind: TransportKind) -> bool {
    D::ROLES.of(Role::FrequencyReference).any(|p| {
        p.target.row().is_some_and(|row| {
            let r = &D::REGISTERS[usize::from(row)];
            r.transports.contains(kind)
                && r.broadcast != drivemap_runtime::core::rule::Broadcast::Only
        })
    })
}

#[test]
fn one_routine_runs_every_drive_over_serial_framing() {
    let mut ran = Vec::new();
    macro_rules! each {
        ($m:ident, $id:literal) => {{
            through::<drivemap_drives::$m::Drive>($id, TransportKind::Rtu);
            ran.push($id);
        }};
    }
    drivemap_drives::for_each_drive!(each);
    assert_eq!(ran.len(), drivemap_drives::DRIVES.len());
}

/// Over Modbus TCP framing the V7 takes its TCP option card's registers (run through terminal
/// S1, a status word of its own): the trait picks the places usable on the link.
#[test]
fn one_routine_runs_every_drive_over_modbus_tcp() {
    let mut ran = Vec::new();
    macro_rules! each {
        ($m:ident, $id:literal) => {{
            if on::<drivemap_drives::$m::Drive>(TransportKind::Tcp) {
                through::<drivemap_drives::$m::Drive>($id, TransportKind::Tcp);
                ran.push($id);
            }
        }};
    }
    drivemap_drives::for_each_drive!(each);
    assert!(ran.contains(&"yaskawa-v7"), "{ran:?}");
}

/// A trip shows through the trait on every drive whose map gives a fault status, and
/// `reset_fault` clears it where the map gives a reset usable on the link (an edge-triggered one
/// included: the trait releases it first if it was left set); elsewhere it is refused.
#[test]
fn a_trip_is_seen_and_reset_through_the_trait() {
    fn check<D>(id: &str) -> Option<bool>
    where
        D: DrivePlan,
        D::Settings: DriveSettings + Default,
    {
        if !D::ROLES.has(Role::Fault) {
            return None;
        }
        let clock = ManualClock::new();
        let sim = Simulator::new(
            map(id),
            SimOptions::new()
                .clock(Arc::new(clock.clone()))
                .network_source(TransportKind::RtuOverTcp),
        )
        .unwrap();
        let slave = sim.slave();
        let externals: Vec<(String, f64)> = sim.externals().clone().into_iter().collect();
        let shared = drivemap_sim::server::shared(sim);
        let server =
            TcpServer::spawn(shared.clone(), "127.0.0.1:0", TcpFraming::RtuOverTcp, None).unwrap();
        let link =
            RtuOverTcpTransport::connect(server.local_addr(), Duration::from_secs(2)).unwrap();
        let mut c = Client::new(link, D::PROFILE);
        let ext: Vec<(&str, f64)> = externals.iter().map(|(k, v)| (k.as_str(), *v)).collect();
        let mut d = Vfd::connect::<D>(&mut c, slave, D::Settings::default(), &ext).unwrap();
        assert_eq!(d.status().unwrap().fault, Some(false), "{id}");
        drivemap_sim::server::lock(&shared).trip(1);
        let status = d.status().unwrap();
        assert_eq!(status.fault, Some(true), "{id}: {status}");
        if status.ready.is_some() {
            assert_eq!(status.ready, Some(false), "{id}: not ready while tripped");
        }
        if d.supports(Role::FaultCode) {
            assert_eq!(d.fault_code().unwrap().code, 1, "{id}");
        }
        let reset = d.supports(Role::FaultReset);
        if reset {
            d.reset_fault().unwrap();
            // A second trip and reset: an edge-triggered reset must have been released.
            drivemap_sim::server::lock(&shared).trip(1);
            d.reset_fault().unwrap();
            assert_eq!(d.status().unwrap().fault, Some(false), "{id}: reset");
        } else {
            match d.reset_fault() {
                Err(Error::Refused(Refusal::NoRole {
                    role: "fault_reset",
                    ..
                })) => {}
                other => panic!("{id}: no reset on this link, got {other:?}"),
            }
        }
        drop(d);
        server.stop();
        Some(reset)
    }
    let mut reset = Vec::new();
    macro_rules! each {
        ($m:ident, $id:literal) => {
            if let Some(r) = check::<drivemap_drives::$m::Drive>($id) {
                reset.push(($id, r));
            }
        };
    }
    drivemap_drives::for_each_drive!(each);
    assert!(
        reset.iter().any(|(_, r)| *r),
        "some shipped drive resets: {reset:?}"
    );
}

/// A run whose reply is lost is not sent again by a later, unrelated command: the `Vfd`'s copy
/// of the command word changes only when a write succeeds, so setting the direction afterwards
/// writes the word with run released (a master that does not know whether the drive started
/// errs towards stop). And a client made for another drive is refused.
#[test]
fn a_command_that_failed_is_not_resent_by_the_next() {
    use drivemap_drives::ptlk_tds_v8 as tds;
    use drivemap_runtime::client::ClientOptions;
    use drivemap_sim::{Fault, FaultyLink, SimulatedSlave};

    let options = ClientOptions {
        retries: 0,
        timeout: Duration::from_millis(50),
        ..ClientOptions::default()
    };
    let mut slave = SimulatedSlave::new(1, &tds::PROFILE);
    // Sn-04 = 2: run commands from the RS-485 port.
    slave.set_holding(
        <tds::RunSource as drivemap_runtime::core::register::Register>::address(
            &tds::Settings::default(),
            TransportKind::Rtu,
        )
        .unwrap(),
        2,
    );
    let link = FaultyLink::new(TransportKind::Rtu, slave);
    let mut c = Client::with_options(link, &tds::PROFILE, options);
    let mut d = Vfd::new::<tds::Drive>(&mut c, 1, tds::Settings::default());
    let address = <tds::OperationCommand as drivemap_runtime::core::register::Register>::address(
        &tds::Settings::default(),
        TransportKind::Rtu,
    )
    .unwrap();
    // The first run reads the command source (once); stopped again, the drive is where it was.
    d.run().unwrap();
    d.stop().unwrap();
    d.client().transport().inject(Fault::Drop);
    assert!(matches!(d.run(), Err(Error::Timeout { .. })));
    // The drive did get it: the reply alone was lost.
    assert_eq!(
        d.client().transport().slave.holding(address) & 0x0001,
        0x0001
    );
    d.set_direction(Direction::Reverse).unwrap();
    let word = d.client().transport().slave.holding(address);
    assert_eq!(word & 0x0001, 0, "run not re-sent: {word:04X}h");
    assert_eq!(word & 0x0002, 0x0002, "reverse set: {word:04X}h");
    d.run().unwrap();
    assert_eq!(
        d.client().transport().slave.holding(address) & 0x0003,
        0x0003
    );
    drop(d);

    let mut other = Client::new(
        FaultyLink::new(
            TransportKind::Rtu,
            SimulatedSlave::new(1, &drivemap_drives::yaskawa_v7::PROFILE),
        ),
        &drivemap_drives::yaskawa_v7::PROFILE,
    );
    match Vfd::connect::<tds::Drive>(&mut other, 1, tds::Settings::default(), &[]) {
        Err(Error::Refused(Refusal::OtherDrive { .. })) => {}
        Err(e) => panic!("expected OtherDrive, got {e}"),
        Ok(_) => panic!("expected OtherDrive, got a Vfd"),
    }
}

/// The place of a source role on `kind`, if the map names one there.
fn source_place<D: DrivePlan>(
    role: Role,
    kind: TransportKind,
) -> Option<drivemap_runtime::core::roles::FieldRole> {
    D::ROLES
        .of(role)
        .find(|p| p.transports.contains(kind))
        .and_then(|p| match p.target {
            drivemap_runtime::core::roles::Target::Field(f) => Some(f),
            _ => None,
        })
}

/// Every compiled drive at its factory setting (the simulator powers on with the manual's
/// defaults for the source parameters): `run()` and `set_reference()` are refused with what to
/// set, nothing reaches the command register, `stop()` is not refused; a run command written
/// to the drive anyway is ignored by the simulator, as the drive would. After the source is
/// set — over the link where the parameter has an address (V7 n003, GPD 515 b1-02, TDS-V8
/// Sn-04, ACN dr.06, acme...), at the simulated drive where it has none (J7 n02) — the same
/// calls run the drive.
#[test]
fn run_is_refused_at_the_factory_setting_and_works_after_setting_the_source() {
    fn check<D>(id: &str, kind: TransportKind) -> bool
    where
        D: DrivePlan,
        D::Settings: DriveSettings + Default,
    {
        let Some(command) = source_place::<D>(Role::CommandSource, kind) else {
            return false;
        };
        let clock = ManualClock::new();
        let sim =
            Simulator::new(map(id), SimOptions::new().clock(Arc::new(clock.clone()))).unwrap();
        let slave = sim.slave();
        let externals: Vec<(String, f64)> = sim.externals().clone().into_iter().collect();
        let shared = drivemap_sim::server::shared(sim);
        let framing = match kind {
            TransportKind::Tcp => TcpFraming::ModbusTcp,
            _ => TcpFraming::RtuOverTcp,
        };
        let server = TcpServer::spawn(shared.clone(), "127.0.0.1:0", framing, None).unwrap();
        let link: Box<dyn Transport> = match kind {
            TransportKind::Tcp => Box::new(
                TcpTransport::connect(server.local_addr(), Duration::from_secs(2)).unwrap(),
            ),
            _ => Box::new(
                RtuOverTcpTransport::connect(server.local_addr(), Duration::from_secs(2)).unwrap(),
            ),
        };
        let mut c = Client::new(link, D::PROFILE);
        let ext: Vec<(&str, f64)> = externals.iter().map(|(k, v)| (k.as_str(), *v)).collect();
        let mut d = Vfd::connect::<D>(&mut c, slave, D::Settings::default(), &ext).unwrap();
        let wait = |s: f64| clock.advance(Duration::from_secs_f64(s));
        let running = || {
            drivemap_sim::server::lock(&shared)
                .state()
                .is_some_and(|s| s.running)
        };
        match d.run() {
            Err(Error::Refused(Refusal::NotNetworkSource { what, now, fix, .. })) => {
                assert_eq!(what, "run commands", "{id}");
                let message = d.run().unwrap_err().to_string();
                assert!(message.contains("; "), "{id}: {message}");
                if command.width == 16 {
                    let r = &D::REGISTERS[usize::from(command.row)];
                    let param = r.info.param.unwrap_or(r.info.id);
                    assert!(now.contains(&format!("({param} = ")), "{id}: {now}");
                    assert!(
                        fix.starts_with(&format!("set {param} = {}", command.on[0])),
                        "{id}: {fix}"
                    );
                } else {
                    assert!(now.starts_with("elsewhere than the network"), "{id}: {now}");
                }
            }
            other => panic!("{id} over {kind:?}: run at the factory setting gave {other:?}"),
        }
        if source_place::<D>(Role::ReferenceSource, kind).is_some() {
            match d.set_reference(20.0) {
                Err(Error::Refused(Refusal::NotNetworkSource { what, .. })) => {
                    assert_eq!(what, "the frequency reference", "{id}")
                }
                other => panic!("{id}: set_reference at the factory setting gave {other:?}"),
            }
        }
        // Stop is never refused for its source.
        d.stop()
            .unwrap_or_else(|e| panic!("{id}: stop refused: {e}"));
        wait(1.0);
        assert!(!running(), "{id}: not running");
        drop(d);

        // A run command written anyway (the trait refused it; a master without the trait does
        // not): the drive ignores it.
        let run = D::ROLES
            .of(Role::Run)
            .chain(D::ROLES.of(Role::RunForward))
            .find_map(|p| match p.target {
                drivemap_runtime::core::roles::Target::Field(f)
                    if D::REGISTERS[usize::from(f.row)].transports.contains(kind)
                        && D::REGISTERS[usize::from(f.row)].broadcast
                            != drivemap_runtime::core::rule::Broadcast::Only =>
                {
                    Some(f)
                }
                _ => None,
            })
            .expect("a run command on the link");
        let run_row = &D::REGISTERS[usize::from(run.row)];
        let settings = D::Settings::default();
        let run_address = run_row.address_for(&settings, kind);
        let word = run.put(0, run.code(true));
        c.write_rule(slave, &run_row.write_rule(), run_address, u32::from(word))
            .unwrap();
        wait(1.0);
        assert!(
            !running(),
            "{id} over {kind:?}: a network run at the factory setting is ignored"
        );
        let released = run.put(0, run.code(false));
        c.write_rule(
            slave,
            &run_row.write_rule(),
            run_address,
            u32::from(released),
        )
        .unwrap();

        // Set the source, then the same calls run the drive.
        if command.width == 16 {
            for role in [Role::CommandSource, Role::ReferenceSource] {
                if let Some(f) = source_place::<D>(role, kind) {
                    let r = &D::REGISTERS[usize::from(f.row)];
                    c.write_rule(
                        slave,
                        &r.write_rule(),
                        r.address_for(&settings, kind),
                        u32::from(f.on[0]),
                    )
                    .unwrap_or_else(|e| panic!("{id}: setting the source: {e}"));
                }
            }
        } else {
            drivemap_sim::server::lock(&shared).select_network_source(kind);
        }
        let mut d = Vfd::connect::<D>(&mut c, slave, D::Settings::default(), &ext).unwrap();
        d.set_reference(20.0)
            .unwrap_or_else(|e| panic!("{id}: set_reference after setting the source: {e}"));
        d.run()
            .unwrap_or_else(|e| panic!("{id}: run after setting the source: {e}"));
        wait(60.0);
        assert!(
            running(),
            "{id} over {kind:?}: running once the network is the source"
        );
        let hz = d.output_frequency().unwrap();
        assert!(
            (hz - 20.0).abs() <= 0.1,
            "{id}: the network reference is used: {hz} Hz"
        );
        d.stop().unwrap();
        // The source is read once per Vfd: set to another source over the link, the next run
        // is still sent (the drive ignores it) until the Vfd is told to read it again.
        if command.width == 16 {
            wait(60.0); // stopped: some drives take parameter writes only then
            let r = &D::REGISTERS[usize::from(command.row)];
            let other = (0..=3u16).find(|c| !command.on.contains(c)).unwrap();
            let address = r.address_for(&settings, kind);
            d.client()
                .write_rule(slave, &r.write_rule(), address, u32::from(other))
                .unwrap();
            d.run().unwrap();
            d.stop().unwrap();
            d.forget_sources();
            assert!(
                matches!(
                    d.run(),
                    Err(Error::Refused(Refusal::NotNetworkSource { .. }))
                ),
                "{id}: read again after forget_sources"
            );
        }
        drop(d);
        server.stop();
        true
    }
    let mut checked = Vec::new();
    macro_rules! each {
        ($m:ident, $id:literal) => {
            for kind in [TransportKind::Rtu, TransportKind::Tcp] {
                if on::<drivemap_drives::$m::Drive>(kind)
                    && check::<drivemap_drives::$m::Drive>($id, kind)
                {
                    checked.push(($id, kind));
                }
            }
        };
    }
    drivemap_drives::for_each_drive!(each);
    for id in [
        "yaskawa-v7",
        "yaskawa-j7",
        "yaskawa-gpd515",
        "ptlk-tds-v8",
        "automationdirect-acn",
    ] {
        assert!(
            checked.contains(&(id, TransportKind::Rtu)),
            "{id} is checked over RTU: {checked:?}"
        );
    }
    assert!(
        checked.contains(&("yaskawa-v7", TransportKind::Tcp)),
        "{checked:?}"
    );
}
