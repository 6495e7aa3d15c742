//! The drive trait on every compiled drive: one generic routine, written against
//! `VariableFrequencyDrive` only, runs each drive of `for_each_drive!` against its simulator (over
//! RTU framing and over Modbus TCP, where the map gives the drive other registers), ramps it to the
//! reference, reverses it where the map can, stops it, and gets a clear refusal for a role the map
//! lacks. Time is a manual clock: the ramps are exact, not timed.

use std::sync::Arc;
use std::time::Duration;

use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::roles::Role;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::vfd::{Direction, VariableFrequencyDrive, Vfd};
use drivemap_runtime::{Client, DrivePlan, DriveSettings, Error, Refusal, ValueError};
use drivemap_sim::{ManualClock, SimOptions, Simulator, TcpFraming, TcpServer};

/// The map of a compiled drive, from the directory the drives crate was generated from
/// (`DRIVEMAP_MAPS` when it was set for the build, else `maps/`).
fn map(id: &str) -> drivemap_codegen::Drive {
    let dir = option_env!("DRIVEMAP_MAPS").map_or_else(
        || format!("{}/../maps", env!("CARGO_MANIFEST_DIR")),
        str::to_owned,
    );
    let path = format!("{dir}/{id}.yaml");
    drivemap_codegen::read_map(path.as_ref(), &Default::default()).unwrap()
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
    let sim = Simulator::new(map(id), SimOptions::new().clock(Arc::new(clock.clone()))).unwrap();
    assert!(sim.has_model(), "{id}: its map gives roles");
    let slave = sim.slave();
    let externals: Vec<(String, f64)> = sim.externals().clone().into_iter().collect();
    let shared = drivemap_sim::shared(sim);
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
            r.transports.contains(kind) && r.broadcast != drivemap_runtime::Broadcast::Only
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
        let sim =
            Simulator::new(map(id), SimOptions::new().clock(Arc::new(clock.clone()))).unwrap();
        let slave = sim.slave();
        let externals: Vec<(String, f64)> = sim.externals().clone().into_iter().collect();
        let shared = drivemap_sim::shared(sim);
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
    use drivemap_runtime::ClientOptions;
    use drivemap_sim::{Fault, FaultyLink, SimulatedSlave};

    let options = ClientOptions {
        retries: 0,
        timeout: Duration::from_millis(50),
        ..ClientOptions::default()
    };
    let link = FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &tds::PROFILE));
    let mut c = Client::with_options(link, &tds::PROFILE, options);
    let mut d = Vfd::new::<tds::Drive>(&mut c, 1, tds::Settings::default());
    let address = <tds::OperationCommand as drivemap_runtime::Register>::address(
        &tds::Settings::default(),
        TransportKind::Rtu,
    )
    .unwrap();
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
