//! The coil drive (`tests/fixtures/tindra-tc4`) through its generated module: a coil or a
//! discrete input is a `bool` register of its own table, read with 01h/02h and written with
//! 05h (FF00h on, 0000h off), and the drive trait runs, reverses, stops and resets the drive
//! through its coils, reading its state from discrete inputs, against the simulated drive.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::{Register, Table};
use drivemap_runtime::pdu::Request;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::vfd::{Direction, VariableFrequencyDrive, Vfd};
use drivemap_runtime::{client::Client, client::ClientOptions};
use drivemap_sim::framing::{self, Decoded};
use drivemap_sim::{SimOptions, Simulator, clock::ManualClock};
use drivemap_test_support::sim_link::SimLink;

// The generated module of the coil fixture (`build.rs`), compiled with this runtime.
#[allow(dead_code)]
mod tindra_tc4 {
    include!(concat!(env!("OUT_DIR"), "/tindra_tc4.rs"));
}

use tindra_tc4::{Drive, InverterReady, MultiSpeed1, OperationCommand, OperationStatus, Settings};

fn map() -> drivemap_map::Map {
    let path = paths::fixture("tindra-tc4/tindra-tc4.yaml");
    drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn client(kind: TransportKind) -> (Client<SimLink>, ManualClock) {
    let clock = ManualClock::new();
    let sim = Simulator::new(
        map(),
        SimOptions::new()
            .network_source(kind)
            .clock(Arc::new(clock.clone())),
    )
    .unwrap();
    let options = ClientOptions {
        timeout: Duration::from_millis(50),
        retries: 0,
        ..ClientOptions::default()
    };
    (
        Client::with_options(SimLink::new(kind, sim), &tindra_tc4::PROFILE, options),
        clock,
    )
}

/// The coil writes (address, state) the client sent since the log was last cleared, and what
/// else it wrote: (function, PDU address) of every write.
fn writes(c: &mut Client<SimLink>) -> Vec<(u8, u16, u16)> {
    let kind = c.transport().kind();
    let out = c
        .transport()
        .log
        .iter()
        .filter_map(|s| match framing::decode(kind, &s.frame) {
            Decoded::Request { request, .. } => match request {
                Request::WriteCoil { address, value } => Some((0x05, address, u16::from(value))),
                Request::WriteCoils { address, values } => {
                    Some((0x0F, address, u16::from(values.get(0)?)))
                }
                Request::WriteSingle { address, value } => Some((0x06, address, value)),
                Request::WriteMultiple { address, values } => Some((0x10, address, values.get(0)?)),
                _ => None,
            },
            _ => None,
        })
        .collect();
    c.transport().log.clear();
    out
}

#[test]
fn the_generated_coils_are_bools_of_their_own_tables() {
    assert_eq!(<OperationCommand as Register>::TABLE, Table::Coil);
    assert_eq!(<OperationStatus as Register>::TABLE, Table::DiscreteInput);
    // The same address in two tables: two registers.
    assert_eq!(
        (OperationCommand::ADDRESS, OperationStatus::ADDRESS),
        (0x0001, 0x0001)
    );
    assert_eq!(tindra_tc4::PROFILE.max_read_bits, 32);
    assert_eq!(tindra_tc4::PROFILE.max_write_bits, 16);
    for kind in [TransportKind::Rtu, TransportKind::Tcp] {
        let (mut c, _) = client(kind);
        let settings = Settings::default();
        let on: bool = c.read::<MultiSpeed1>(1, &settings).unwrap();
        assert!(!on);
        c.write::<MultiSpeed1>(1, &true, &settings).unwrap();
        // 05h with FF00h to coil 0006h, sent as PDU 0005h.
        assert_eq!(writes(&mut c), [(0x05, 0x0005, 1)], "{kind:?}");
        assert!(c.read::<MultiSpeed1>(1, &settings).unwrap());
        assert!(c.read::<InverterReady>(1, &settings).unwrap());
        assert!(!c.read::<OperationStatus>(1, &settings).unwrap());
        assert_eq!(c.transport().sim.raw("multi_speed_1").unwrap(), 1);
    }
}

#[test]
fn the_drive_trait_runs_and_stops_the_drive_through_its_run_coil() {
    for kind in [TransportKind::Rtu, TransportKind::Tcp] {
        let (mut c, clock) = client(kind);
        let mut d = Vfd::new::<Drive>(&mut c, 1, Settings::default());
        d.set_reference(30.0).unwrap();
        d.set_direction(Direction::Reverse).unwrap();
        writes(d.client());
        d.run().unwrap();
        // The run coil (0001h, PDU 0) on, with 05h.
        let sent = writes(d.client());
        assert!(sent.contains(&(0x05, 0x0000, 1)), "{kind:?}: {sent:?}");
        clock.advance(Duration::from_secs(2));
        let status = d.status().unwrap();
        assert_eq!(status.running, Some(true));
        assert_eq!(status.reversing, Some(true));
        assert!(d.client().transport().sim.state().unwrap().reverse_command);
        // Stop: the run coil off, and nothing else that runs.
        d.stop().unwrap();
        let sent = writes(d.client());
        assert!(sent.contains(&(0x05, 0x0000, 0)), "{kind:?}: {sent:?}");
        assert!(!sent.contains(&(0x05, 0x0000, 1)), "{kind:?}: {sent:?}");
        assert!(!d.client().transport().sim.state().unwrap().run_command);
        // A trip is reset on the trip-reset coil's rising edge (coil 0004h, PDU 3).
        d.client().transport().sim.trip(7);
        assert_eq!(d.status().unwrap().fault, Some(true));
        d.reset_fault().unwrap();
        let sent = writes(d.client());
        let reset: Vec<u16> = sent.iter().filter(|w| w.1 == 0x0003).map(|w| w.2).collect();
        // The coil was never set (the trait knows what it told the drive): set, then release.
        assert_eq!(reset, [1, 0], "{kind:?}: set, release");
        assert_eq!(d.status().unwrap().fault, Some(false));
    }
}

/// At the factory setting (A002 = 02, the operator panel) the drive ignores network commands:
/// the trait refuses `run()` with what to set, sends nothing to the run coil, and `stop()` is
/// never refused — it clears the run coil.
#[test]
fn run_is_refused_at_the_factory_setting_and_stop_never_is() {
    let clock = ManualClock::new();
    let sim = Simulator::new(map(), SimOptions::new().clock(Arc::new(clock))).unwrap();
    let mut c = Client::new(SimLink::new(TransportKind::Rtu, sim), &tindra_tc4::PROFILE);
    let mut d = Vfd::new::<Drive>(&mut c, 1, Settings::default());
    let e = d.run().unwrap_err();
    assert!(e.to_string().contains("A002"), "{e}");
    let sent = writes(d.client());
    assert!(sent.iter().all(|w| w.1 != 0x0000), "{sent:?}");
    d.stop().unwrap();
    // The run coil cleared; the command coils as the drive was told (forward), none set.
    let sent = writes(d.client());
    assert!(sent.contains(&(0x05, 0x0000, 0)), "{sent:?}");
    assert!(sent.iter().all(|w| w.2 == 0), "{sent:?}");
}
