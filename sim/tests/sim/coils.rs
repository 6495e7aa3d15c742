//! The simulated coil drive (`tests/fixtures/tindra-tc4`): coils served with 01h, 05h and 0Fh,
//! discrete inputs with 02h, each table its own address space, with the drive's exception codes
//! (01h function not supported, 02h no coil there, 03h a bad quantity or a 05h value other than
//! FF00h/0000h, 21h a read-only coil written), its broadcast rules (05h to the run and direction
//! coils only), and the drive model run and stopped through its run coil.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::pdu::{BitValues, Request};
use drivemap_runtime::{crc, rtu, tcp};
use drivemap_sim::{SimOptions, Simulator, clock::ManualClock};

fn text() -> String {
    let path = paths::fixture("tindra-tc4/tindra-tc4.yaml");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn start_text(text: &str) -> (Simulator, ManualClock) {
    let map = drivemap_map::Loader::new()
        .load_str("tindra-tc4.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"));
    let clock = ManualClock::new();
    let sim = Simulator::new(
        map,
        SimOptions::new()
            .network_source(TransportKind::Rtu)
            .clock(Arc::new(clock.clone())),
    )
    .unwrap();
    (sim, clock)
}

fn start() -> (Simulator, ManualClock) {
    start_text(&text())
}

/// The reply to `r` sent to `slave` over RTU: its PDU (`None` when the drive stays silent).
fn ask(sim: &mut Simulator, slave: u8, r: Request<'_>) -> Option<Vec<u8>> {
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(slave, &r, &mut buf).unwrap();
    let mut out = [0u8; tcp::MAX_FRAME];
    let h = sim.handle(TransportKind::Rtu, &buf[..n], &mut out);
    h.reply.map(|n| out[1..n - 2].to_vec())
}

/// A raw RTU frame of `pdu` to slave 1 (with its CRC): for requests the encoder would refuse.
fn ask_raw(sim: &mut Simulator, pdu: &[u8]) -> Option<Vec<u8>> {
    let mut frame = vec![1u8];
    frame.extend_from_slice(pdu);
    let c = crc::crc16(&frame);
    frame.extend_from_slice(&c.to_le_bytes());
    let mut out = [0u8; tcp::MAX_FRAME];
    let h = sim.handle(TransportKind::Rtu, &frame, &mut out);
    h.reply.map(|n| out[1..n - 2].to_vec())
}

fn read_coils(address: u16, quantity: u16) -> Request<'static> {
    Request::ReadCoils { address, quantity }
}

#[test]
fn coils_and_discrete_inputs_are_served_in_their_own_spaces() {
    let (mut sim, _) = start();
    // Coils 0001h-0009h are PDU 0-8; coil 0005h is reserved and reads 0 inside a read.
    sim.set("multi_speed_2", 1.0).unwrap();
    assert_eq!(
        ask(&mut sim, 1, read_coils(0, 9)).unwrap(),
        [0x01, 0x02, 0b0100_0000, 0x00]
    );
    // A read that starts where no coil is: 02h.
    assert_eq!(ask(&mut sim, 1, read_coils(4, 1)).unwrap(), [0x81, 0x02]);
    assert_eq!(ask(&mut sim, 1, read_coils(0x20, 1)).unwrap(), [0x81, 0x02]);
    // More than the 32 the manual allows per message: 03h.
    assert_eq!(ask(&mut sim, 1, read_coils(0, 33)).unwrap(), [0x81, 0x03]);
    // The discrete inputs: the drive is stopped and ready (IRDY, 0003h).
    let inputs = ask(
        &mut sim,
        1,
        Request::ReadDiscreteInputs {
            address: 0,
            quantity: 7,
        },
    )
    .unwrap();
    assert_eq!(inputs[..2], [0x02, 0x01]);
    assert_eq!(inputs[2] & 0b0000_0101, 0b0000_0100, "not running, ready");
    // Holding register 0001h is not coil 0001h: the register space has none there.
    assert_eq!(
        ask(
            &mut sim,
            1,
            Request::ReadHolding {
                address: 0,
                quantity: 1
            }
        )
        .unwrap(),
        [0x83, 0x02]
    );
    // The drive implements no 04h.
    assert_eq!(
        ask(
            &mut sim,
            1,
            Request::ReadInput {
                address: 0,
                quantity: 1
            }
        )
        .unwrap(),
        [0x84, 0x01]
    );
}

#[test]
fn coil_writes_follow_the_manuals_rules() {
    let (mut sim, _) = start();
    // 05h FF00h turns a coil on and is echoed.
    let on = Request::WriteCoil {
        address: 5,
        value: true,
    };
    assert_eq!(
        ask(&mut sim, 1, on).unwrap(),
        [0x05, 0x00, 0x05, 0xFF, 0x00]
    );
    assert_eq!(sim.raw("multi_speed_1").unwrap(), 1);
    // A value other than FF00h or 0000h: 03h ("any other value is answered with exception
    // code 03h"), and nothing changes.
    assert_eq!(
        ask_raw(&mut sim, &[0x05, 0x00, 0x05, 0x00, 0x01]).unwrap(),
        [0x85, 0x03]
    );
    assert_eq!(sim.raw("multi_speed_1").unwrap(), 1);
    // The reserved coil 0005h (PDU 4): 02h.
    let reserved = Request::WriteCoil {
        address: 4,
        value: true,
    };
    assert_eq!(ask(&mut sim, 1, reserved).unwrap(), [0x85, 0x02]);
    // 0Fh over CF1 and CF2.
    let two = Request::WriteCoils {
        address: 5,
        values: BitValues::Native(&[false, true]),
    };
    assert_eq!(
        ask(&mut sim, 1, two).unwrap(),
        [0x0F, 0x00, 0x05, 0x00, 0x02]
    );
    assert_eq!(
        (
            sim.raw("multi_speed_1").unwrap(),
            sim.raw("multi_speed_2").unwrap()
        ),
        (0, 1)
    );
    // A 0Fh over the reserved coil writes none of its coils.
    let across = Request::WriteCoils {
        address: 3,
        values: BitValues::Native(&[true, true, true]),
    };
    assert_eq!(ask(&mut sim, 1, across).unwrap(), [0x8F, 0x02]);
    assert_eq!(sim.raw("trip_reset").unwrap(), 0);
    assert_eq!(sim.raw("multi_speed_1").unwrap(), 0);
    // More than 16 coils per 0Fh: 03h.
    let many = Request::WriteCoils {
        address: 0,
        values: BitValues::Native(&[false; 17]),
    };
    assert_eq!(ask(&mut sim, 1, many).unwrap(), [0x8F, 0x03]);
    // A read-only coil written: the manual's 21h.
    let read_only = text().replace(
        "{id: jogging, param: JG, name: Jogging, address: 0x0008,",
        "{id: jogging, param: JG, name: Jogging, address: 0x0008, access: r,",
    );
    let (mut sim, _) = start_text(&read_only);
    let jog = Request::WriteCoil {
        address: 7,
        value: true,
    };
    assert_eq!(ask(&mut sim, 1, jog).unwrap(), [0x85, 0x21]);
    assert_eq!(sim.raw("jogging").unwrap(), 0);
}

#[test]
fn the_run_coil_runs_the_drive_model_and_a_broadcast_stops_it() {
    let (mut sim, clock) = start();
    sim.set("output_frequency_setting", 30.0).unwrap();
    let run = Request::WriteCoil {
        address: 0,
        value: true,
    };
    assert!(ask(&mut sim, 1, run).is_some());
    clock.advance(Duration::from_secs(5));
    sim.tick();
    let state = sim.state().unwrap();
    assert!(state.run_command, "the run coil runs the drive");
    assert!(state.output_hz > 0.0);
    // The operation status input shows it.
    let status = ask(
        &mut sim,
        1,
        Request::ReadDiscreteInputs {
            address: 0,
            quantity: 1,
        },
    )
    .unwrap();
    assert_eq!(status, [0x02, 0x01, 0x01]);
    // A broadcast 05h to the external trip coil is not executed (only 0001h and 0002h).
    let trip = Request::WriteCoil {
        address: 2,
        value: true,
    };
    assert!(ask(&mut sim, 0, trip).is_none());
    assert_eq!(sim.raw("external_trip").unwrap(), 0);
    // Nor is a broadcast 0Fh, whatever coil it writes.
    let stop_many = Request::WriteCoils {
        address: 0,
        values: BitValues::Native(&[false]),
    };
    assert!(ask(&mut sim, 0, stop_many).is_none());
    assert!(sim.state().unwrap().run_command);
    // A broadcast 05h to the run coil stops every drive, unanswered.
    let stop = Request::WriteCoil {
        address: 0,
        value: false,
    };
    assert!(ask(&mut sim, 0, stop).is_none());
    assert!(!sim.state().unwrap().run_command);
    assert_eq!(sim.stats().broadcasts_executed, 1);
    assert_eq!(sim.stats().broadcasts_refused, 2);
}
