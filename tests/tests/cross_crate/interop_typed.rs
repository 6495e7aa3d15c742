//! Our client against our simulator through the generated typed API of every map
//! (`drivemap_drives::{ptlk_tds_v8, yaskawa_v7, yaskawa_j7, yaskawa_gpd515, automationdirect_acn}`),
//! over loopback TCP carrying RTU frames (as a serial gateway does) and, for the drives that have
//! it, Modbus TCP. The settings the scales and addresses depend on are read from the simulated
//! drive; values go through the generated encode/decode; the drive model ramps on a manual clock.
//! Each simulated drive starts with the network selected as its command and reference source for
//! the link the test uses (at the factory setting it would ignore the run commands written here).

use crate::interop_support;

use std::net::SocketAddr;
use std::time::Duration;

use drivemap_drives::{
    automationdirect_acn as acn, ptlk_tds_v8 as tds, yaskawa_gpd515 as gpd, yaskawa_j7 as j7,
    yaskawa_v7 as v7,
};
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::DriveSettings;
use drivemap_runtime::error::{Error, Refusal};
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{client::Client, client::ClientOptions};
use drivemap_sim::{SimOptions, server::TcpFraming, server::TcpServer};
use interop_support::Sim;

fn serve(sim: &Sim, framing: TcpFraming) -> TcpServer {
    TcpServer::spawn(sim.sim.clone(), "127.0.0.1:0", framing, Some(sim.logger()))
        .expect("serving on loopback")
}

fn options() -> ClientOptions {
    ClientOptions {
        timeout: Duration::from_millis(500),
        retries: 0,
        ..ClientOptions::default()
    }
}

fn rtu_client(addr: SocketAddr, profile: &'static Profile) -> Client<RtuOverTcpTransport> {
    let link = RtuOverTcpTransport::connect(addr, Duration::from_secs(2)).expect("connect");
    Client::with_options(link, profile, options())
}

fn tcp_client(addr: SocketAddr, profile: &'static Profile) -> Client<TcpTransport> {
    let link = TcpTransport::connect(addr, Duration::from_secs(2)).expect("connect");
    Client::with_options(link, profile, options())
}

/// Reads every parameter the drive's conversions depend on, as an application does, and checks
/// that each one was taken.
fn load<T: Transport, S: DriveSettings + Clone + PartialEq + std::fmt::Debug>(
    c: &mut Client<T>,
    slave: u8,
    s: &mut S,
) {
    c.load_settings(slave, s)
        .unwrap_or_else(|e| panic!("reading the settings: {e}"));
    for &address in S::DEPENDENCIES {
        let mut w = [0u16; 1];
        c.read_holding(slave, address, &mut w).unwrap();
        let mut again = s.clone();
        assert!(again.absorb(address, w[0]), "{address:04X}h absorbed");
        assert_eq!(&again, s, "{address:04X}h already loaded");
    }
}

fn code(e: Error) -> u8 {
    e.exception()
        .unwrap_or_else(|| panic!("expected an exception, got: {e}"))
        .code
}

#[test]
fn tds_v8_through_its_generated_module() {
    let sim = Sim::new(
        "ptlk-tds-v8",
        SimOptions::new().network_source(TransportKind::Rtu),
    );
    let server = serve(&sim, TcpFraming::RtuOverTcp);
    let mut c = rtu_client(server.local_addr(), &tds::PROFILE);
    let mut s = tds::Settings::new();
    load(&mut c, 1, &mut s);
    assert_eq!(
        s.max_output_frequency,
        Some(60.0),
        "Cn-02 read from the drive"
    );
    c.write::<tds::AccelTime1>(1, &5.0, &s).unwrap();
    c.write::<tds::DecelTime1>(1, &2.5, &s).unwrap();
    c.write::<tds::FrequencyCommand>(1, &40.0, &s).unwrap();
    let bits = tds::OperationCommandBits::new().with_run(true);
    c.write::<tds::OperationCommand>(1, &bits, &s).unwrap();
    sim.clock.advance(Duration::from_secs(2)); // 60 Hz / 5 s: 24 Hz
    let st = c.read::<tds::InverterStatus>(1, &s).unwrap();
    assert!(st.running() && !st.zero_speed() && !st.reverse());
    let (reference, output) = c
        .read_many::<(tds::FrequencyCommandMonitor, tds::OutputFrequency)>(1, &s)
        .unwrap();
    assert_eq!((reference, output), (40.0, 24.0));
    assert!(c.read::<tds::OutputCurrent>(1, &s).unwrap() > 1.0);
    // Cn parameters are PRG-mode only: DRV mode (bit 8, self-clearing) makes the drive refuse
    // with its 03h "Data Value Error".
    let drv = tds::OperationCommandBits::new()
        .with_run(true)
        .with_switch_to_drv_mode(true);
    c.write::<tds::OperationCommand>(1, &drv, &s).unwrap();
    assert!(c.read::<tds::InverterStatus>(1, &s).unwrap().drv_mode());
    assert_eq!(
        code(
            c.write::<tds::MaxOutputFrequency>(1, &50.0, &s)
                .unwrap_err()
        ),
        0x03
    );
    // Broadcast stop (0000h is allowed): no reply, and the drive ramps down.
    c.write::<tds::OperationCommand>(0, &tds::OperationCommandBits::new(), &s)
        .unwrap();
    sim.wait_broadcasts(1);
    sim.clock.advance(Duration::from_secs(1)); // 24 Hz / 24 Hz/s
    let st = c.read::<tds::InverterStatus>(1, &s).unwrap();
    assert!(!st.running() && st.zero_speed());
    // Save (PRG mode again, bit 9): one persist command.
    let prg = tds::OperationCommandBits::new().with_switch_to_prg_mode(true);
    c.write::<tds::OperationCommand>(1, &prg, &s).unwrap();
    c.persist(1, "save_parameters").unwrap();
    sim.with(|x| assert_eq!(x.persist_count(), 1));
}

fn v7_run_and_stop<T: Transport>(c: &mut Client<T>, sim: &Sim, s: &v7::Settings, tcp: bool) {
    if tcp {
        c.write::<v7::TcpFrequencyReference>(1, &45.0, s).unwrap();
    } else {
        c.write::<v7::FrequencyReference>(1, &45.0, s).unwrap();
        // The option card's status word exists only on Modbus TCP: the typed API refuses it
        // here before sending, and the drive would answer a raw read of its address with 02h.
        assert!(matches!(
            c.read::<v7::TcpStatusWord>(1, s).unwrap_err(),
            Error::Refused(drivemap_runtime::error::Refusal::NotOnTransport { .. })
        ));
        let mut raw = [0u16; 1];
        let address = <v7::TcpStatusWord as drivemap_runtime::core::register::Register>::ADDRESS;
        assert_eq!(
            code(c.read_holding(1, address, &mut raw).unwrap_err()),
            0x02
        );
    }
    if tcp {
        let bits = v7::TcpDigitalInputCommandBits::new().with_terminal_s1(true);
        c.write::<v7::TcpDigitalInputCommand>(1, &bits, s).unwrap();
    } else {
        let bits = v7::DigitalInputCommandBits::new().with_run_command(true);
        c.write::<v7::DigitalInputCommand>(1, &bits, s).unwrap();
    }
    sim.clock.advance(Duration::from_millis(1500)); // 60 Hz / 2 s: 30 Hz/s -> 45 Hz
    let st = c.read::<v7::StatusSignal1>(1, s).unwrap();
    assert!(st.during_run() && st.inverter_ready() && !st.reverse_direction());
    let (reference, output) = c
        .read_many::<(v7::FrequencyReferenceMonitor, v7::OutputFrequency)>(1, s)
        .unwrap();
    assert_eq!((reference, output), (45.0, 45.0));
    assert!(c.read::<v7::StatusSignal2>(1, s).unwrap().speed_agree());
    if tcp {
        assert!(c.read::<v7::TcpStatusWord>(1, s).unwrap().speed_agree());
    }
    // Stopped-only while running: the V7's 22h.
    assert_eq!(
        code(c.write::<v7::AccelTime1>(1, &3.0, s).unwrap_err()),
        0x22
    );
    assert_eq!(code(c.persist(1, "enter").unwrap_err()), 0x22);
    if tcp {
        c.write::<v7::TcpDigitalInputCommand>(1, &v7::TcpDigitalInputCommandBits::new(), s)
            .unwrap();
    } else {
        c.write::<v7::DigitalInputCommand>(1, &v7::DigitalInputCommandBits::new(), s)
            .unwrap();
    }
    sim.clock.advance(Duration::from_secs(3));
    assert!(!c.read::<v7::StatusSignal1>(1, s).unwrap().during_run());
    c.persist(1, "accept").unwrap();
    c.persist(1, "enter").unwrap();
    sim.with(|x| assert_eq!(x.persist_count(), 1));
}

#[test]
fn yaskawa_v7_through_its_generated_module_over_rtu_framing() {
    // n152 = 1 (0.01 Hz) and n018 = 1 (0.01 s): the client must read them to convert.
    let sim = Sim::new(
        "yaskawa-v7",
        SimOptions::new()
            .set("n152", 1.0)
            .set("n018", 1.0)
            .network_source(TransportKind::Rtu),
    );
    let server = serve(&sim, TcpFraming::RtuOverTcp);
    let mut c = rtu_client(server.local_addr(), &v7::PROFILE);
    let mut s = v7::Settings::new();
    load(&mut c, 1, &mut s);
    c.write::<v7::AccelTime1>(1, &2.0, &s).unwrap();
    c.write::<v7::DecelTime1>(1, &2.0, &s).unwrap();
    sim.with(|x| {
        assert_eq!(x.raw("n019").unwrap(), 200, "2 s at 0.01 s");
    });
    v7_run_and_stop(&mut c, &sim, &s, false);
    sim.with(|x| assert_eq!(x.raw("frequency_reference").unwrap(), 4500, "0.01 Hz"));
    // Broadcast reference: fixed 30000 = n011, whatever n152 says.
    c.write::<v7::BroadcastFrequencyReference>(0, &30.0, &s)
        .unwrap();
    sim.wait_broadcasts(1);
    assert_eq!(
        c.read::<v7::FrequencyReferenceMonitor>(1, &s).unwrap(),
        30.0
    );
}

#[test]
fn yaskawa_v7_through_its_generated_module_over_modbus_tcp() {
    let sim = Sim::new(
        "yaskawa-v7",
        SimOptions::new()
            .set("n019", 2.0)
            .set("n020", 2.0)
            .network_source(TransportKind::Tcp),
    );
    let server = serve(&sim, TcpFraming::ModbusTcp);
    let mut c = tcp_client(server.local_addr(), &v7::PROFILE);
    let mut s = v7::Settings::new();
    load(&mut c, 1, &mut s);
    v7_run_and_stop(&mut c, &sim, &s, true);
}

#[test]
fn yaskawa_j7_through_its_generated_module() {
    let sim = Sim::new(
        "yaskawa-j7",
        SimOptions::new().network_source(TransportKind::Rtu),
    );
    let server = serve(&sim, TcpFraming::RtuOverTcp);
    let mut c = rtu_client(server.local_addr(), &j7::PROFILE);
    let mut s = j7::Settings {
        max_output_frequency: Some(60.0),
        ..j7::Settings::new()
    };
    load(&mut c, 1, &mut s);
    // No 06h on the J7: the client writes single registers with 10h.
    c.write::<j7::FrequencyReference>(1, &30.0, &s).unwrap();
    let bits = j7::DigitalInputCommandBits::new()
        .with_run_command(true)
        .with_reverse(true);
    c.write::<j7::DigitalInputCommand>(1, &bits, &s).unwrap();
    assert!(sim.records().iter().all(|r| r.function != Some(0x06)));
    sim.clock.advance(Duration::from_secs(2)); // fixed 10 s to 60 Hz: 12 Hz
    let st = c.read::<j7::StatusSignal1>(1, &s).unwrap();
    assert!(st.during_run() && st.reverse_direction());
    assert_eq!(c.read::<j7::OutputFrequency>(1, &s).unwrap(), 12.0);
    assert_eq!(code(c.persist(1, "enter").unwrap_err()), 0x22);
    // Broadcast with 10h: stop.
    c.write::<j7::BroadcastDigitalInputCommand>(
        0,
        &j7::BroadcastDigitalInputCommandBits::new(),
        &s,
    )
    .unwrap();
    sim.wait_broadcasts(1);
    sim.clock.advance(Duration::from_secs(3));
    assert!(!c.read::<j7::StatusSignal1>(1, &s).unwrap().during_run());
    c.persist(1, "enter").unwrap();
    sim.with(|x| assert_eq!(x.persist_count(), 1));
}

#[test]
fn yaskawa_gpd515_through_its_generated_module() {
    // The drive rating the application supplies is the simulated drive's.
    let sim = Sim::new(
        "yaskawa-gpd515",
        SimOptions::new()
            .external("drive_rated_current", 9.6)
            .network_source(TransportKind::Rtu),
    );
    let server = serve(&sim, TcpFraming::RtuOverTcp);
    let mut c = rtu_client(server.local_addr(), &gpd::PROFILE);
    let mut s = gpd::Settings {
        drive_rated_current: Some(9.6),
        ..gpd::Settings::new()
    };
    // Before o2-09 is read the client would use the o2-09 = 1 layout; reading it moves the
    // command registers to 00h/01h, where the simulated drive (o2-09 = 0) has them.
    load(&mut c, 31, &mut s);
    assert_eq!(s.initial_mode_select, Some(0));
    c.write::<gpd::AccelTime1>(31, &4.0, &s).unwrap();
    c.persist(31, "accept").unwrap();
    c.write::<gpd::FrequencyReference>(31, &35.75, &s).unwrap();
    let bits = gpd::OperationCommandBits::new().with_forward_run(true);
    c.write::<gpd::OperationCommand>(31, &bits, &s).unwrap();
    sim.clock.advance(Duration::from_secs(2)); // 60 Hz / 4 s: 30 Hz
    let st = c.read::<gpd::StatusSignal>(31, &s).unwrap();
    assert!(st.run_command() && st.drive_ready() && !st.speed_agreed());
    let (reference, output, current) = c
        .read_many::<(
            gpd::MonitorFrequencyReference,
            gpd::OutputFrequency,
            gpd::OutputCurrent,
        )>(31, &s)
        .unwrap();
    assert_eq!((reference, output), (35.75, 30.0));
    // The simulator's plausible current at 30 of 60 Hz: 1.0 + 1.5 * 0.5 A.
    assert!((current - 1.75).abs() < 0.01, "{current}");
    assert_eq!(
        code(c.write::<gpd::AccelTime1>(31, &4.0, &s).unwrap_err()),
        0x22
    );
    c.write::<gpd::OperationCommand>(31, &gpd::OperationCommandBits::new(), &s)
        .unwrap();
    sim.clock.advance(Duration::from_secs(10));
    assert!(c.read::<gpd::StatusSignal>(31, &s).unwrap().at_zero_speed());
    c.persist(31, "enter").unwrap();
    sim.with(|x| assert_eq!(x.persist_count(), 1));
}

fn acn_conversation<T: Transport>(c: &mut Client<T>, sim: &Sim) {
    let s = acn::Settings::new();
    c.write::<acn::AccTime>(1, &5.0, &s).unwrap();
    c.write::<acn::AccelerationTime>(1, &3.0, &s).unwrap();
    c.write::<acn::FrequencyCommand>(1, &30.0, &s).unwrap();
    let bits = acn::OperationCommandBits::new()
        .with_run(true)
        .with_forward(true);
    c.write::<acn::OperationCommand>(1, &bits, &s).unwrap();
    sim.clock.advance(Duration::from_secs(1)); // 60 Hz / 3 s: 20 Hz
    let st = c.read::<acn::DriveOperationState>(1, &s).unwrap();
    assert_eq!(
        st.run_direction_state(),
        acn::DriveOperationStateRunDirectionState::OperatingForward
    );
    assert_eq!(
        st.operation_state(),
        acn::DriveOperationStateOperationState::Accelerating
    );
    let (current, output) = c
        .read_many::<(acn::OutputCurrent, acn::OutputFrequency)>(1, &s)
        .unwrap();
    assert_eq!(output, 20.0);
    assert!(current > 1.2, "{current}");
    assert_eq!(c.read::<acn::AccTime>(1, &s).unwrap(), 5.0);
    // The save command is stopped-only; the ACN names no write-mode code: 03h.
    assert_eq!(code(c.persist(1, "save_parameters").unwrap_err()), 0x03);
    // No broadcast on the ACN: the client refuses before sending.
    let e = c
        .write::<acn::OperationCommand>(0, &acn::OperationCommandBits::new(), &s)
        .unwrap_err();
    assert!(
        matches!(e, Error::Refused(Refusal::BroadcastFunction { .. })),
        "{e}"
    );
    c.write::<acn::OperationCommand>(1, &acn::OperationCommandBits::new(), &s)
        .unwrap();
    // deceleration_time prints no default: the simulator's 10 s to 60 Hz, 20 Hz in 3.3 s.
    sim.clock.advance(Duration::from_secs(4));
    let st = c.read::<acn::DriveOperationState>(1, &s).unwrap();
    assert_eq!(
        st.run_direction_state(),
        acn::DriveOperationStateRunDirectionState::Stopped
    );
    c.persist(1, "save_parameters").unwrap();
    sim.with(|x| assert_eq!(x.persist_count(), 1));
}

#[test]
fn automationdirect_acn_through_its_generated_module_over_rtu_framing() {
    // RTU: PDU address = communication address - 1.
    let sim = Sim::new(
        "automationdirect-acn",
        SimOptions::new().network_source(TransportKind::Rtu),
    );
    let server = serve(&sim, TcpFraming::RtuOverTcp);
    let mut c = rtu_client(server.local_addr(), &acn::PROFILE);
    acn_conversation(&mut c, &sim);
    assert!(sim.records().iter().any(|r| r.address == Some(0x1102)));
}

#[test]
fn automationdirect_acn_through_its_generated_module_over_modbus_tcp() {
    // Modbus TCP: PDU address = communication address.
    let sim = Sim::new("automationdirect-acn", SimOptions::new());
    let server = serve(&sim, TcpFraming::ModbusTcp);
    let mut c = tcp_client(server.local_addr(), &acn::PROFILE);
    acn_conversation(&mut c, &sim);
    assert!(sim.records().iter().any(|r| r.address == Some(0x1103)));
}
