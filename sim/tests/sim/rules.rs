//! The simulator against every shipped map, frame by frame: the manuals' example frames, each
//! rule with the drive's own exception code, silence where the manuals prescribe it, broadcast,
//! persist commands, and the drive model through the maps' scales.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::crc;
use drivemap_runtime::pdu::{Request, Words};
use drivemap_runtime::{rtu, tcp};
use drivemap_sim::{Outcome, RolesChoice, SimOptions, Simulator, clock::ManualClock};

/// Every map in `maps/` by id (the directory is read: a new map is covered with no edit here).
fn drives() -> Vec<String> {
    let dir = paths::maps();
    let mut ids: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    ids.sort();
    assert!(!ids.is_empty(), "no maps in {}", dir.display());
    ids
}

fn drive(id: &str) -> drivemap_map::Map {
    let path = paths::shipped_map(id);
    drivemap_map::Loader::new()
        .load(path.as_ref())
        .unwrap_or_else(|e| panic!("{id}: {e}"))
}

/// A simulator of `id`, installed for network control over RTU framing unless `options` say
/// another link: its source parameters select the network (at the factory setting the drive
/// ignores network run commands and references; `the_factory_setting_ignores_network_runs`).
fn start(id: &str, mut options: SimOptions) -> (Simulator, ManualClock) {
    if options.network_source.is_none() {
        options = options.network_source(TransportKind::Rtu);
    }
    let clock = ManualClock::new();
    let sim = Simulator::new(drive(id), options.clock(Arc::new(clock.clone())))
        .unwrap_or_else(|e| panic!("{id}: {e}"));
    (sim, clock)
}

/// Sends a raw RTU frame; returns the reply bytes, if any.
fn send(sim: &mut Simulator, frame: &[u8]) -> Option<Vec<u8>> {
    let mut out = [0u8; tcp::MAX_FRAME];
    let h = sim.handle(TransportKind::Rtu, frame, &mut out);
    h.reply.map(|n| out[..n].to_vec())
}

fn request(sim: &mut Simulator, slave: u8, r: Request<'_>) -> Option<Vec<u8>> {
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(slave, &r, &mut buf).unwrap();
    send(sim, &buf[..n])
}

fn read(sim: &mut Simulator, address: u16, quantity: u16) -> Result<Vec<u16>, u8> {
    let slave = sim.slave();
    let reply = request(sim, slave, Request::ReadHolding { address, quantity }).expect("reply");
    if reply[1] & 0x80 != 0 {
        return Err(reply[2]);
    }
    Ok(reply[3..reply.len() - 2]
        .chunks(2)
        .map(|c| u16::from_be_bytes([c[0], c[1]]))
        .collect())
}

fn write(sim: &mut Simulator, address: u16, values: &[u16]) -> Result<(), u8> {
    let slave = sim.slave();
    let r = if values.len() == 1 && sim.profile().supports(0x06) {
        Request::WriteSingle {
            address,
            value: values[0],
        }
    } else {
        Request::WriteMultiple {
            address,
            values: Words::Native(values),
        }
    };
    let reply = request(sim, slave, r).expect("reply");
    if reply[1] & 0x80 != 0 {
        Err(reply[2])
    } else {
        Ok(())
    }
}

fn hz(sim: &Simulator, id: &str) -> f64 {
    sim.value(id).unwrap().as_f64().unwrap()
}

#[test]
fn every_map_starts_with_its_roles_and_defaults() {
    for id in &drives() {
        let (sim, _) = start(id, SimOptions::new());
        assert!(sim.has_model(), "{id}");
        assert!(sim.warnings().is_empty(), "{id}: {:?}", sim.warnings());
        assert!(!sim.state().unwrap().running, "{id}");
    }
    let (sim, _) = start("yaskawa-v7", SimOptions::new());
    assert_eq!(hz(&sim, "n019"), 10.0, "default 10.0 s encoded at n018 = 0");
    assert_eq!(sim.raw("n019").unwrap(), 100);
    assert_eq!(sim.raw("n011").unwrap(), 600);
    let (sim, _) = start("yaskawa-gpd515", SimOptions::new());
    assert_eq!(sim.slave(), 31, "H5-01 default");
    assert_eq!(
        sim.raw("C1-01").unwrap(),
        100,
        "10.0 s at C1-10 = 1 (0.1 s)"
    );
}

#[test]
fn tds_v8_manual_frames() {
    // The example's drive has its LCD operator connected (bit 11, not a role the model drives):
    // the bench sets it.
    let (mut sim, clock) = start(
        "ptlk-tds-v8",
        SimOptions::new().set("inverter_status", 2048.0),
    );
    // 03h example: 0802h, stopped in PRG mode (002_661580cce154f322.txt:183-208): zero speed
    // and the LCD operator set, Ready clear (no run command is taken in PRG mode).
    let reply = send(&mut sim, &[0x01, 0x03, 0x00, 0x20, 0x00, 0x01, 0x85, 0xC0]);
    assert_eq!(reply.unwrap(), [0x01, 0x03, 0x02, 0x08, 0x02, 0x3E, 0x45]);
    // 06h example, echoed.
    let w = [0x01, 0x06, 0x00, 0x01, 0x00, 0x20, 0xD9, 0xD2];
    assert_eq!(send(&mut sim, &w).unwrap(), w);
    // Loop test.
    let l = [0x01, 0x08, 0x00, 0x00, 0x12, 0x34, 0xED, 0x7C];
    assert_eq!(send(&mut sim, &l).unwrap(), l);
    // Step 1: forward run at 80 % (5DC0h), reserved 0002h-0006h written 0, R1 output on.
    let step1 = [
        0x01, 0x10, 0x00, 0x00, 0x00, 0x08, 0x10, 0x00, 0x01, 0x5D, 0xC0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0x00, 0x01, 0x44, 0x91,
    ];
    assert_eq!(
        send(&mut sim, &step1).unwrap(),
        [0x01, 0x10, 0x00, 0x00, 0x00, 0x08, 0xC1, 0xCF]
    );
    assert_eq!(hz(&sim, "frequency_command_monitor"), 48.0);
    clock.advance(Duration::from_secs(4)); // Bn-01 10 s to Cn-02 60 Hz: 6 Hz/s
    let status = read(&mut sim, 0x0020, 6).unwrap();
    assert_eq!(status[0] & 0x0003, 0x0001, "running, not at zero speed");
    assert_eq!(status[5], 12000, "24 Hz = 40 % of Cn-02 = 12000");
    // Step 2: forward at 50 % (3A98h); step 3: reverse at 50 %, down through 0 (Bn-02 10 s)
    // and up in reverse (002_661580cce154f322.txt:794).
    let mut step = [
        0x01, 0x10, 0x00, 0x00, 0x00, 0x08, 0x10, 0x00, 0x01, 0x3A, 0x98, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0x00, 0x01, 0xFD, 0x2E,
    ];
    assert!(send(&mut sim, &step).is_some());
    clock.advance(Duration::from_secs(1)); // 24 -> 30 Hz
    sim.tick();
    assert_eq!(sim.state().unwrap().output_hz, 30.0);
    step[8] = 0x03;
    step[23..].copy_from_slice(&[0x7F, 0x2F]);
    assert!(send(&mut sim, &step).is_some());
    clock.advance(Duration::from_secs(7)); // 5 s down to 0, 2 s up: 12 Hz reverse
    sim.tick();
    assert!((sim.state().unwrap().output_hz + 12.0).abs() < 1e-9);
    assert_eq!(read(&mut sim, 0x0020, 1).unwrap()[0] & 0x0005, 0x0005);
    // Step 4: stop.
    let step4 = [
        0x01, 0x10, 0x00, 0x00, 0x00, 0x01, 0x02, 0x00, 0x00, 0xA6, 0x50,
    ];
    assert_eq!(
        send(&mut sim, &step4).unwrap(),
        [0x01, 0x10, 0x00, 0x00, 0x00, 0x01, 0x01, 0xC9]
    );
    clock.advance(Duration::from_secs(60));
    assert_eq!(read(&mut sim, 0x0020, 1).unwrap()[0], 0x0802);
}

#[test]
fn tds_v8_uses_its_own_codes_and_prg_mode() {
    let (mut sim, _) = start("ptlk-tds-v8", SimOptions::new());
    // The printed exception replies 01 83 03 01 31, 01 86 03 02 61, 01 90 03 0C 01.
    let mut frame = [0u8; 8];
    let n = rtu::encode_request(
        1,
        &Request::ReadHolding {
            address: 0x0020,
            quantity: 17,
        },
        &mut frame,
    )
    .unwrap();
    assert_eq!(
        send(&mut sim, &frame[..n]).unwrap(),
        [0x01, 0x83, 0x03, 0x01, 0x31]
    );
    let too_long = request(
        &mut sim,
        1,
        Request::WriteSingle {
            address: 0x0200,
            value: 60001,
        },
    );
    assert_eq!(too_long.unwrap(), [0x01, 0x86, 0x03, 0x02, 0x61]);
    let too_long = request(
        &mut sim,
        1,
        Request::WriteMultiple {
            address: 0x0200,
            values: Words::Native(&[100, 60001]),
        },
    );
    assert_eq!(too_long.unwrap(), [0x01, 0x90, 0x03, 0x0C, 0x01]);
    assert_eq!(
        sim.raw("accel_time_1").unwrap(),
        100,
        "a refused 10h writes nothing"
    );
    // Read-only monitor: 02h; reserved 0002h read: 0; 0500H (write-only) read: 02h.
    assert_eq!(write(&mut sim, 0x0025, &[1]), Err(0x02));
    assert_eq!(read(&mut sim, 0x0002, 1), Ok(vec![0]));
    assert_eq!(read(&mut sim, 0x0500, 1), Err(0x02));
    assert_eq!(read(&mut sim, 0x0600, 1), Err(0x02));
    // Cn-02 in PRG mode: accepted. Switch to DRV mode (bit 8, clears itself): refused with 03h.
    assert_eq!(write(&mut sim, 0x0301, &[500]), Ok(()));
    assert_eq!(hz(&sim, "Cn-02"), 50.0);
    assert_eq!(write(&mut sim, 0x0000, &[0x0100]), Ok(()));
    assert_eq!(read(&mut sim, 0x0000, 1), Ok(vec![0]), "auto clear");
    assert_eq!(
        read(&mut sim, 0x0020, 1).unwrap()[0] & 0x0010,
        0x0010,
        "DRV mode"
    );
    assert_eq!(write(&mut sim, 0x0301, &[600]), Err(0x03));
    assert_eq!(write(&mut sim, 0x0200, &[50]), Ok(()), "Bn: both modes");
    // Saving is PRG-only too; back to PRG (bit 9) and save: counted.
    assert_eq!(write(&mut sim, 0x0500, &[0]), Err(0x03));
    assert_eq!(sim.persist_count(), 0);
    assert_eq!(write(&mut sim, 0x0000, &[0x0200]), Ok(()));
    assert_eq!(write(&mut sim, 0x0500, &[0]), Ok(()));
    assert_eq!(write(&mut sim, 0x0500, &[1]), Err(0x03), "only 0000h saves");
    assert_eq!(sim.persist_count(), 1);
    assert_eq!(sim.command_count("save_parameters"), Some(1));
    // Function 04h is not a TDS-V8 function.
    let r = request(
        &mut sim,
        1,
        Request::ReadInput {
            address: 0x20,
            quantity: 1,
        },
    );
    assert_eq!(r.unwrap()[1..3], [0x84, 0x01]);
}

#[test]
fn silence_for_crc_errors_other_slaves_and_broadcast() {
    let (mut sim, _) = start("ptlk-tds-v8", SimOptions::new());
    let good = [0x01, 0x03, 0x00, 0x20, 0x00, 0x01, 0x85, 0xC0];
    let mut bad = good;
    bad[7] ^= 0x01;
    assert_eq!(send(&mut sim, &bad), None);
    let mut other = [0x02, 0x03, 0x00, 0x20, 0x00, 0x01, 0, 0];
    let c = crc::crc_bytes(&other[..6]);
    other[6..].copy_from_slice(&c);
    assert_eq!(send(&mut sim, &other), None);
    // Broadcast frequency command: executed, not answered.
    assert_eq!(
        request(
            &mut sim,
            0,
            Request::WriteSingle {
                address: 0x0001,
                value: 15000
            }
        ),
        None
    );
    assert_eq!(hz(&sim, "frequency_command"), 30.0);
    // Broadcast to a register the manual does not allow: not executed either.
    assert_eq!(
        request(
            &mut sim,
            0,
            Request::WriteSingle {
                address: 0x0200,
                value: 5
            }
        ),
        None
    );
    assert_eq!(sim.raw("accel_time_1").unwrap(), 100);
    // Broadcast read: nothing happens.
    assert_eq!(
        request(
            &mut sim,
            0,
            Request::ReadHolding {
                address: 0x20,
                quantity: 1
            }
        ),
        None
    );
    let s = sim.stats();
    assert_eq!(
        (
            s.damaged,
            s.not_addressed,
            s.broadcasts_executed,
            s.broadcasts_refused
        ),
        (1, 1, 1, 2)
    );
}

#[test]
fn yaskawa_v7_rules_with_its_codes() {
    let (mut sim, clock) = start("yaskawa-v7", SimOptions::new());
    // ENTER 0900h is write-only: a read answers 02h (003_8bcf5d50afb8e230.txt:730).
    assert_eq!(read(&mut sim, 0x0900, 1), Err(0x02));
    // 8 registers at most per read on the V7 (000): 9 answer 03h.
    assert!(read(&mut sim, 0x0020, 8).is_ok());
    assert_eq!(read(&mut sim, 0x0020, 9), Err(0x03));
    // Out of range: n019 6000.1 s -> 21h. Read-only monitor -> 22h.
    assert_eq!(write(&mut sim, 0x0113, &[60001]), Err(0x21));
    assert_eq!(write(&mut sim, 0x0024, &[1]), Err(0x22));
    // Reserved bits of the command register are a data setting error too.
    assert_eq!(write(&mut sim, 0x0001, &[0x8000]), Err(0x21));
    // 04h is not a V7 function.
    let r = request(
        &mut sim,
        1,
        Request::ReadInput {
            address: 0x20,
            quantity: 1,
        },
    );
    assert_eq!(r.unwrap()[1..3], [0x84, 0x01]);
    // Run at 30 Hz (n152 = 0: 0.1 Hz): status during run, output ramps at n011/n019.
    assert_eq!(write(&mut sim, 0x0001, &[0x0001, 300]), Ok(()));
    clock.advance(Duration::from_secs(2)); // 60 Hz / 10 s: 12 Hz
    let w = read(&mut sim, 0x0020, 5).unwrap();
    assert_eq!(w[0] & 0x0007, 0x0005, "during run, ready, forward");
    assert_eq!((w[3], w[4]), (300, 120), "reference and output in 0.1 Hz");
    // Parameters are stopped-only: 22h while running; ENTER too, and it is not counted.
    assert_eq!(write(&mut sim, 0x0113, &[50]), Err(0x22));
    assert_eq!(write(&mut sim, 0x0900, &[0]), Err(0x22));
    assert_eq!(sim.persist_count(), 0);
    // Stop, ramp down, then ENTER and ACCEPT: only ENTER is a persist command.
    assert_eq!(write(&mut sim, 0x0001, &[0x0000]), Ok(()));
    clock.advance(Duration::from_secs(10));
    assert_eq!(read(&mut sim, 0x0020, 1).unwrap()[0] & 0x0001, 0);
    assert_eq!(write(&mut sim, 0x0113, &[50]), Ok(()));
    assert_eq!(write(&mut sim, 0x0900, &[0]), Ok(()));
    assert_eq!(write(&mut sim, 0x0910, &[0]), Ok(()));
    assert_eq!(sim.persist_count(), 1);
    assert_eq!(sim.command_count("accept"), Some(1));
}

#[test]
fn v7_broadcast_uses_its_own_registers() {
    let (mut sim, clock) = start("yaskawa-v7", SimOptions::new());
    // Broadcast 0002h is 30000 = 100 % of n011 whatever n152 says: 15000 = 30 Hz.
    assert_eq!(
        request(
            &mut sim,
            0,
            Request::WriteMultiple {
                address: 0x0001,
                values: Words::Native(&[0x0001, 15000]),
            }
        ),
        None
    );
    assert_eq!(sim.stats().broadcasts_executed, 1);
    clock.advance(Duration::from_secs(60));
    assert_eq!(read(&mut sim, 0x0023, 2), Ok(vec![300, 300]));
    // A broadcast starting elsewhere is not executed (003_8bcf5d50afb8e230.txt:737).
    request(
        &mut sim,
        0,
        Request::WriteSingle {
            address: 0x0113,
            value: 5,
        },
    );
    assert_eq!(sim.raw("n019").unwrap(), 100);
}

#[test]
fn v7_selected_scales_follow_its_own_registers() {
    let options = SimOptions::new()
        .set("n152", 1.0)
        .set("n018", 1.0)
        .set("n019", 5.0);
    let (mut sim, clock) = start("yaskawa-v7", options);
    assert_eq!(sim.raw("n019").unwrap(), 500, "5 s at 0.01 s");
    assert_eq!(
        write(&mut sim, 0x0001, &[0x0003, 4500]),
        Ok(()),
        "reverse, 45.00 Hz"
    );
    clock.advance(Duration::from_millis(2500)); // 60 Hz / 5 s = 12 Hz/s -> 30 Hz
    let w = read(&mut sim, 0x0020, 5).unwrap();
    assert_eq!(w[0] & 0x0003, 0x0003, "during run, reverse");
    assert_eq!((w[3], w[4]), (4500, 3000), "0.01 Hz units");
    // Relative units: n152 = 2 makes 30000 = n011.
    let (mut sim, _) = start("yaskawa-v7", SimOptions::new().set("n152", 2.0));
    assert_eq!(write(&mut sim, 0x0002, &[15000]), Ok(()));
    assert_eq!(hz(&sim, "frequency_reference_monitor"), 30.0);
}

#[test]
fn v7_over_tcp_has_the_option_card_registers() {
    let (mut sim, clock) = start(
        "yaskawa-v7",
        SimOptions::new().network_source(TransportKind::Tcp),
    );
    let mut out = [0u8; tcp::MAX_FRAME];
    let mut frame = [0u8; tcp::MAX_FRAME];
    // Terminal S1 (n050 = Run Forward) and 40.0 Hz through 0001h/0002h of the option card.
    let r = Request::WriteMultiple {
        address: 0x0001,
        values: Words::Native(&[0x0001, 400]),
    };
    let n = tcp::encode_request(7, 1, &r, &mut frame).unwrap();
    let h = sim.handle(TransportKind::Tcp, &frame[..n], &mut out);
    assert_eq!(h.record.outcome, Outcome::Ok);
    assert_eq!(&out[..2], &[0, 7], "transaction id echoed");
    clock.advance(Duration::from_secs(60));
    let r = Request::ReadHolding {
        address: 0x2000,
        quantity: 1,
    };
    let n = tcp::encode_request(8, 1, &r, &mut frame).unwrap();
    let h = sim.handle(TransportKind::Tcp, &frame[..n], &mut out);
    let m = h.reply.unwrap();
    let status = u16::from_be_bytes([out[m - 2], out[m - 1]]);
    assert_eq!(
        status & 0x0031,
        0x0031,
        "during run, speed agree, drive ready"
    );
    assert_eq!(hz(&sim, "output_frequency"), 40.0);
    // The status word 2000h does not exist on RTU.
    assert_eq!(read(&mut sim, 0x2000, 1), Err(0x02));
}

#[test]
fn j7_has_no_06h_and_broadcasts_only_with_10h() {
    let (mut sim, clock) = start("yaskawa-j7", SimOptions::new());
    let r = request(
        &mut sim,
        1,
        Request::WriteSingle {
            address: 0x0002,
            value: 100,
        },
    );
    assert_eq!(r.unwrap()[1..3], [0x86, 0x01]);
    assert!(read(&mut sim, 0x0020, 16).is_ok());
    assert_eq!(read(&mut sim, 0x0020, 17), Err(0x03));
    request(
        &mut sim,
        0,
        Request::WriteSingle {
            address: 0x0001,
            value: 1,
        },
    );
    assert!(!sim.state().unwrap().run_command, "06h broadcast refused");
    request(
        &mut sim,
        0,
        Request::WriteMultiple {
            address: 0x0001,
            values: Words::Native(&[0x0001, 30000]),
        },
    );
    clock.advance(Duration::from_secs(5)); // fixed 10 s ramp to the external 60 Hz
    sim.tick();
    assert_eq!(sim.state().unwrap().output_hz, 30.0);
    assert_eq!(sim.state().unwrap().reference_hz, 60.0);
    // Read-only n68-n74 (J7: 22h covers "read-only data written").
    assert_eq!(write(&mut sim, 0x0198, &[1]), Err(0x22));
}

#[test]
fn gpd515_addresses_follow_o2_09_and_enter_is_counted() {
    let (mut sim, clock) = start("yaskawa-gpd515", SimOptions::new());
    // o2-09 = 0 (default): operation signal at 00h, frequency reference at 01h.
    assert_eq!(
        sim.address_of("operation_command", TransportKind::Rtu),
        Some(0x0000)
    );
    assert_eq!(write(&mut sim, 0x0000, &[0x0001, 3575]), Ok(()));
    // The command registers are write-only: 02h.
    assert_eq!(read(&mut sim, 0x0000, 1), Err(0x02));
    clock.advance(Duration::from_secs(1)); // E1-04 60 Hz / C1-01 10 s: 6 Hz
    let w = read(&mut sim, 0x0010, 1).unwrap();
    assert_eq!(w[0] & 0x0021, 0x0021, "run, drive ready");
    assert_eq!(read(&mut sim, 0x0020, 2), Ok(vec![3575, 600]));
    // Output current is relative to the drive rating (8192 = 100 %), which the simulator takes
    // as 1 A when not given; the model's current at 6 of 60 Hz is 1.0 + 1.5 * 0.1 A.
    let current = hz(&sim, "output_current");
    assert!((current - 1.15).abs() < 0.001, "{current}");
    // Parameters are stopped-only (22h); ENTER when stopped counts.
    assert_eq!(write(&mut sim, 0x0200, &[50]), Err(0x22));
    assert_eq!(write(&mut sim, 0x0000, &[0x0000]), Ok(()));
    clock.advance(Duration::from_secs(30));
    assert_eq!(write(&mut sim, 0xFFFD, &[0]), Ok(()));
    assert_eq!(sim.persist_count(), 1);
    // With o2-09 = 1 the registers sit at 01h/02h.
    let (sim, _) = start("yaskawa-gpd515", SimOptions::new().set("o2-09", 1.0));
    assert_eq!(
        sim.address_of("operation_command", TransportKind::Rtu),
        Some(0x0001)
    );
}

#[test]
fn acn_offsets_save_sequence_and_codes() {
    let (mut sim, clock) = start(
        "automationdirect-acn",
        SimOptions::new().set("drive_model", 6.0),
    );
    // The manual's RTU example: 0x1102 carries Acc time 0x1103 = 5.0 s, Dec time 10.0 s.
    let req = [
        0x01, 0x10, 0x11, 0x02, 0x00, 0x02, 0x04, 0x00, 0x32, 0x00, 0x64, 0x12, 0x02,
    ];
    assert_eq!(
        send(&mut sim, &req).unwrap(),
        [0x01, 0x10, 0x11, 0x02, 0x00, 0x02, 0xE5, 0x34]
    );
    assert_eq!(hz(&sim, "dr.03"), 5.0);
    // A power-on value set by the bench: drive model 0006h ("ACN", the only code listed) at 0h0300.
    assert_eq!(read(&mut sim, 0x02FF, 1), Ok(vec![6]));
    // Forward run 0003h at 0h0382 (PDU 0381h on RTU), 30 Hz at 0h0380.
    assert_eq!(write(&mut sim, 0x037F, &[3000]), Ok(()));
    assert_eq!(write(&mut sim, 0x0381, &[0x0003]), Ok(()));
    // The accel_time role, acceleration_time (0h0383), prints no default: the simulator powers
    // it on at Plausible::RAMP_TIME, 10 s to 60 Hz, so 6 Hz after 1 s.
    clock.advance(Duration::from_secs(1));
    let state = read(&mut sim, 0x0304, 1).unwrap()[0];
    assert_eq!(state & 0x000F, 1, "operating forward");
    assert_eq!((state >> 4) & 0xF, 2, "accelerating");
    assert_eq!(
        read(&mut sim, 0x0310, 1),
        Ok(vec![600]),
        "6.00 Hz at 0h0311"
    );
    // Reverse (0001h): ramps through 0.
    assert_eq!(write(&mut sim, 0x0381, &[0x0001]), Ok(()));
    clock.advance(Duration::from_secs(10));
    let state = read(&mut sim, 0x0304, 1).unwrap()[0];
    assert_eq!(
        (state & 0x000F, (state >> 4) & 0xF),
        (2, 3),
        "reverse, constant"
    );
    // No input registers: 04h reads answer 02h; 0x03E0 save is stopped-only (03h: the ACN names
    // no write-mode code), then 0 and 1 save once.
    let r = request(
        &mut sim,
        1,
        Request::ReadInput {
            address: 0x0310,
            quantity: 1,
        },
    );
    assert_eq!(r.unwrap()[1..3], [0x84, 0x02]);
    assert_eq!(write(&mut sim, 0x03DF, &[0]), Err(0x03));
    assert_eq!(write(&mut sim, 0x0381, &[0x0000]), Ok(()));
    clock.advance(Duration::from_secs(10));
    assert_eq!(write(&mut sim, 0x03DF, &[1]), Ok(()));
    assert_eq!(sim.persist_count(), 0, "1 alone does not save");
    assert_eq!(write(&mut sim, 0x03DF, &[0]), Ok(()));
    assert_eq!(write(&mut sim, 0x03DF, &[1]), Ok(()));
    assert_eq!(sim.persist_count(), 1);
    // No broadcast on the ACN: ignored.
    request(
        &mut sim,
        0,
        Request::WriteSingle {
            address: 0x037F,
            value: 1000,
        },
    );
    assert_eq!(hz(&sim, "frequency_command"), 30.0);
}

/// The fictional drive of `tests/fixtures/acme-vf1/` (not a shipped map), with a manual clock.
fn acme() -> (Simulator, ManualClock) {
    let path = paths::fixture("acme-vf1/acme-vf1.yaml");
    let clock = ManualClock::new();
    let sim = Simulator::new(
        drivemap_map::Loader::new().load(path.as_ref()).unwrap(),
        SimOptions::new()
            .clock(Arc::new(clock.clone()))
            .network_source(TransportKind::Rtu),
    )
    .unwrap();
    (sim, clock)
}

/// The fictional drive of `tests/fixtures/acme-vf1/` has a 2-bit run/stop code (01b stop,
/// 10b run) and reports its state as codes of a 3-bit field: its map's roles alone make the
/// model run it, and the stop code stops it.
#[test]
fn a_two_bit_run_code_runs_and_its_stop_code_stops() {
    let (mut sim, clock) = acme();
    assert!(sim.has_model());
    let state = |sim: &mut Simulator| read(sim, 0x2100, 1).unwrap()[0] & 0x0007;
    assert_eq!(write(&mut sim, 0x2001, &[3000]), Ok(())); // 30.00 Hz
    assert_eq!(write(&mut sim, 0x2000, &[0b0110]), Ok(())); // run, forward
    clock.advance(Duration::from_secs(1));
    assert_eq!(state(&mut sim), 1, "accelerating");
    assert!(sim.state().unwrap().running);
    clock.advance(Duration::from_secs(10));
    assert_eq!(state(&mut sim), 2, "at speed");
    assert_eq!(hz(&sim, "output_frequency"), 30.0);
    // Direction code 10b = reverse while running: ramps through 0, rotation bit set.
    assert_eq!(write(&mut sim, 0x2000, &[0b1010]), Ok(()));
    clock.advance(Duration::from_secs(20));
    assert_eq!(read(&mut sim, 0x2100, 1).unwrap()[0] & 0x0008, 0x0008);
    // The stop code, 01b: the drive ramps to stop and stops.
    assert_eq!(write(&mut sim, 0x2000, &[0b1001]), Ok(()));
    clock.advance(Duration::from_millis(100));
    assert!(!sim.state().unwrap().run_command);
    assert_eq!(state(&mut sim), 4, "ramping to stop");
    clock.advance(Duration::from_secs(20));
    assert_eq!(state(&mut sim), 0, "stopped");
    assert_eq!(hz(&sim, "output_frequency"), 0.0);
    assert!(!sim.state().unwrap().running);
    // 00b and 11b are not the run code: the drive does not start on them.
    assert_eq!(write(&mut sim, 0x2000, &[0b0111]), Ok(()));
    clock.advance(Duration::from_secs(1));
    assert!(!sim.state().unwrap().running);
}

/// A trip and an edge-triggered reset: the fixture's fault_reset (bit 7) acts on its 0 -> 1
/// transition only, and a tripped drive takes no run command.
#[test]
fn a_trip_holds_until_the_reset_edge() {
    let (mut sim, clock) = acme();
    let status = |sim: &mut Simulator| read(sim, 0x2100, 1).unwrap()[0];
    assert_eq!(status(&mut sim) & 0x0030, 0x0010, "ready, no fault");
    assert_eq!(write(&mut sim, 0x2001, &[3000]), Ok(()));
    assert_eq!(write(&mut sim, 0x2000, &[0b0110]), Ok(())); // run forward
    clock.advance(Duration::from_secs(2));
    assert!(hz_after_read(&mut sim) > 0.0);
    sim.trip(2); // overvoltage
    assert_eq!(
        status(&mut sim) & 0x0037,
        0x0020,
        "fault, not ready, stopped"
    );
    assert_eq!(read(&mut sim, 0x2105, 1), Ok(vec![2]));
    assert_eq!(hz(&sim, "output_frequency"), 0.0);
    // Run is ignored while tripped.
    assert_eq!(write(&mut sim, 0x2000, &[0b0110]), Ok(()));
    clock.advance(Duration::from_secs(1));
    assert_eq!(hz_after_read(&mut sim), 0.0);
    // The reset bit held at 1 from before does not reset: it acts on the transition.
    assert_eq!(write(&mut sim, 0x2000, &[0b1000_0101]), Ok(()));
    assert_eq!(status(&mut sim) & 0x0020, 0, "reset on the 0 -> 1 edge");
    sim.trip(1);
    assert_eq!(write(&mut sim, 0x2000, &[0b1000_0101]), Ok(())); // still 1: no edge
    assert_eq!(status(&mut sim) & 0x0020, 0x0020, "no edge, still tripped");
    assert_eq!(read(&mut sim, 0x2105, 1), Ok(vec![1]));
    assert_eq!(write(&mut sim, 0x2000, &[0b0000_0101]), Ok(()));
    assert_eq!(write(&mut sim, 0x2000, &[0b1000_0101]), Ok(()));
    assert_eq!(status(&mut sim) & 0x0030, 0x0010, "reset: ready again");
    assert_eq!(read(&mut sim, 0x2105, 1), Ok(vec![0]), "no fault");
}

fn hz_after_read(sim: &mut Simulator) -> f64 {
    let _ = read(sim, 0x2101, 1);
    hz(sim, "output_frequency")
}

#[test]
fn without_a_model_registers_still_work_and_nothing_runs() {
    let (mut sim, _) = start("ptlk-tds-v8", SimOptions::new().roles(RolesChoice::NoModel));
    assert_eq!(write(&mut sim, 0x0000, &[1]), Ok(()));
    assert!(sim.state().is_none());
    assert_eq!(read(&mut sim, 0x0020, 1), Ok(vec![0]));
}

#[test]
fn bad_options_are_named() {
    let e = Simulator::new(drive("yaskawa-v7"), SimOptions::new().slave(40)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "slave address 40 is outside yaskawa-v7's range 1 ..= 32"
    );
    let e = Simulator::new(
        drive("yaskawa-v7"),
        SimOptions::new().variant("voltage_class", "v999"),
    )
    .unwrap_err();
    assert!(e.to_string().contains("voltage_class=v460"), "{e}");
    let e = Simulator::new(drive("yaskawa-v7"), SimOptions::new().set("n019", 7000.0)).unwrap_err();
    assert!(
        e.to_string().starts_with("cannot set accel_time_1 to 7000"),
        "{e}"
    );
    let e = Simulator::new(drive("yaskawa-v7"), SimOptions::new().set("n9999", 1.0)).unwrap_err();
    assert!(e.to_string().contains("no register `n9999`"), "{e}");
}

#[test]
fn garbage_never_panics() {
    let (mut sim, _) = start("automationdirect-acn", SimOptions::new());
    let mut out = [0u8; tcp::MAX_FRAME];
    let mut seed = 0x1234_5678u32;
    for len in 0..300usize {
        let frame: Vec<u8> = (0..len)
            .map(|_| {
                seed ^= seed << 13;
                seed ^= seed >> 17;
                seed ^= seed << 5;
                (seed >> 24) as u8
            })
            .collect();
        for kind in [TransportKind::Rtu, TransportKind::Tcp] {
            let _ = sim.handle(kind, &frame, &mut out);
        }
        // Valid CRC on random bytes: reaches the request decoder.
        if len >= 4 {
            let mut f = frame.clone();
            f[0] = 1;
            let c = crc::crc_bytes(&f[..len - 2]);
            f[len - 2..].copy_from_slice(&c);
            let _ = sim.handle(TransportKind::Rtu, &f, &mut out);
        }
    }
    // A reply never overruns a short output buffer.
    let mut tiny = [0u8; 4];
    let h = sim.handle(
        TransportKind::Rtu,
        &[0x01, 0x03, 0x03, 0x10, 0x00, 0x08, 0x44, 0x49],
        &mut tiny,
    );
    assert_eq!(h.reply, None);
}

/// ACN 0h03E8 Lock parameter mode: "When the same parameter value is entered continuously, the
/// parameter is executed just once" (004_c5cbf92472673495.txt:1111-1112). The simulator counts a
/// write equal to the previous one as not executed; reads keep the lock state (0 Unlock / 1 Lock,
/// :1076-1080), which a password write does not change here: the simulator has no password.
#[test]
fn acn_memory_control_executes_only_a_changed_value_and_reads_the_lock_state() {
    let (mut sim, _clock) = start("automationdirect-acn", SimOptions::new());
    // RTU: communication address 0x03E8 is PDU 0x03E7.
    let lock = 0x03E7;
    assert_eq!(sim.executed("lock_parameter_mode").unwrap(), 0);
    write(&mut sim, lock, &[244]).unwrap();
    write(&mut sim, lock, &[244]).unwrap();
    assert_eq!(
        sim.executed("lock_parameter_mode").unwrap(),
        1,
        "a repeat is ignored"
    );
    write(&mut sim, lock, &[0]).unwrap();
    write(&mut sim, lock, &[244]).unwrap();
    assert_eq!(
        sim.executed("lock_parameter_mode").unwrap(),
        3,
        "244 > 0 > 244"
    );
    assert_eq!(sim.last_written("lock_parameter_mode").unwrap(), Some(244));
    // A read is the lock state, not the password written.
    assert_eq!(read(&mut sim, lock, 1), Ok(vec![0]));
    match sim.value("lock_parameter_mode").unwrap() {
        drivemap_live::codec::Value::Code { code, name, .. } => {
            assert_eq!((code, name.as_deref()), (0, Some("Unlock")));
        }
        other => panic!("a read gives the read meaning: {other:?}"),
    }
    sim.set_raw("lock_parameter_mode", 1).unwrap();
    assert_eq!(read(&mut sim, lock, 1), Ok(vec![1]));
    // A register without the rule executes every write (0x03E9 Easy start on, PDU 0x03E8).
    write(&mut sim, 0x03E8, &[1]).unwrap();
    write(&mut sim, 0x03E8, &[1]).unwrap();
    assert_eq!(sim.executed("easy_start_on").unwrap(), 2);
    // 0x03E0 carries the rule too: 1 written twice is one execution, and the save command
    // counts only the 0 -> 1 sequence.
    write(&mut sim, 0x03DF, &[1]).unwrap();
    write(&mut sim, 0x03DF, &[1]).unwrap();
    assert_eq!(sim.executed("save_parameters").unwrap(), 1);
    assert_eq!(sim.command_count("save_parameters"), Some(0));
    write(&mut sim, 0x03DF, &[0]).unwrap();
    write(&mut sim, 0x03DF, &[1]).unwrap();
    assert_eq!(sim.executed("save_parameters").unwrap(), 3);
    assert_eq!(sim.command_count("save_parameters"), Some(1));
}

/// A clone is the same drive going on on its own: what one is told, the other is not; with
/// its own clock (`set_clock`) its model ramps by that clock only.
#[test]
fn a_clone_goes_on_on_its_own_clock() {
    let (mut a, clock_a) = start("ptlk-tds-v8", SimOptions::new());
    a.set("frequency_command", 30.0).unwrap();
    let mut b = a.clone();
    let clock_b = ManualClock::new();
    b.set_clock(Arc::new(clock_b.clone()));
    b.set_raw("operation_command", 0x0001).unwrap(); // run forward
    assert!(b.state().unwrap().run_command);
    assert!(
        !a.state().unwrap().run_command,
        "the original was not told to run"
    );
    // Bn-01 10 s to 60 Hz: 6 Hz/s. Time passes on the original's clock only: b stands still.
    clock_a.advance(Duration::from_secs(2));
    b.tick();
    assert_eq!(hz(&b, "output_frequency"), 0.0);
    clock_b.advance(Duration::from_secs(2));
    b.tick();
    a.tick();
    assert_eq!(hz(&b, "output_frequency"), 12.0);
    assert_eq!(hz(&a, "output_frequency"), 0.0);
}

/// Every shipped map's simulator starts at the manual's factory setting of its source
/// parameters, where a run command and a reference written over the network are accepted on
/// the wire and ignored, as the drive ignores them; once the parameter selects the network (set
/// over the link where it has an address), the same write runs the drive.
#[test]
fn the_factory_setting_ignores_network_runs() {
    use drivemap_runtime::core::roles::{Role, Target};
    for id in &drives() {
        let d = drive(id);
        let plan = d.plan();
        let clock = ManualClock::new();
        let mut sim =
            Simulator::new(d.clone(), SimOptions::new().clock(Arc::new(clock.clone()))).unwrap();
        let run = plan
            .roles
            .of(Role::Run)
            .chain(plan.roles.of(Role::RunForward))
            .find_map(|p| match p.target {
                Target::Field(f)
                    if plan.registers[usize::from(f.row)].transports.rtu
                        && plan.registers[usize::from(f.row)].broadcast
                            != drivemap_runtime::core::rule::Broadcast::Only =>
                {
                    Some(f)
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("{id}: a run command over RTU"));
        let row = &plan.registers[usize::from(run.row)];
        let address = row.address_for(&sim.settings().view(&d), TransportKind::Rtu);
        let offsets = plan.profile.address_offsets;
        let pdu = |a: u16| offsets.pdu_address(a, TransportKind::Rtu).unwrap();
        let word = run.put(0, run.code(true));
        assert_eq!(
            write(&mut sim, pdu(address), &[word]),
            Ok(()),
            "{id}: accepted on the wire"
        );
        clock.advance(Duration::from_secs(30));
        let state = sim.state().unwrap();
        assert!(
            !state.running,
            "{id}: a network run at the factory setting is ignored: {state:?}"
        );
        // The source parameter over the link, where it has an address; at the drive otherwise.
        let source = plan
            .roles
            .of(Role::CommandSource)
            .find(|p| p.transports.rtu)
            .unwrap_or_else(|| panic!("{id}: a command source over RTU"));
        let Target::Field(f) = source.target else {
            panic!("{id}: a source is a field")
        };
        if f.width == 16 {
            let r = &plan.registers[usize::from(f.row)];
            let a = r.address_for(&sim.settings().view(&d), TransportKind::Rtu);
            assert_eq!(
                write(&mut sim, pdu(a), &[f.on[0]]),
                Ok(()),
                "{id}: source set"
            );
        } else {
            assert!(!sim.select_network_source(TransportKind::Rtu).is_empty());
        }
        assert_eq!(write(&mut sim, pdu(address), &[word]), Ok(()));
        clock.advance(Duration::from_secs(30));
        assert!(
            sim.state().unwrap().running,
            "{id}: runs once the network is the source"
        );
    }
}

/// The string fixture (`tests/fixtures/lumen-lx2`): the simulator serves each string's example
/// in its byte order, NUL-padded, and answers a write to any of a string's registers with the
/// drive's exception, leaving the text as it was.
#[test]
fn strings_are_served_from_the_example_and_never_written() {
    let path = paths::fixture("lumen-lx2/lumen-lx2.yaml");
    let mut sim = Simulator::new(
        drivemap_map::Loader::new().load(path.as_ref()).unwrap(),
        SimOptions::new().network_source(TransportKind::Rtu),
    )
    .unwrap();
    let model = read(&mut sim, 0x2100, 12).unwrap();
    assert_eq!(
        model,
        [
            0x4C58, 0x322D, 0x3037, 0x3530, 0x2D45, 0, 0, 0, 0x5631, 0x2E30, 0x3400, 0
        ]
    );
    // Input registers, low byte first: "SN" is 4E53h.
    let slave = sim.slave();
    let reply = request(
        &mut sim,
        slave,
        Request::ReadInput {
            address: 0x3000,
            quantity: 6,
        },
    )
    .unwrap();
    assert_eq!(&reply[3..7], &[0x4E, 0x53, 0x34, 0x32], "{reply:02X?}");
    for address in [0x2100, 0x2103, 0x2107] {
        assert!(
            write(&mut sim, address, &[0x4141]).is_err(),
            "{address:04X}h"
        );
    }
    assert_eq!(read(&mut sim, 0x2100, 8).unwrap(), model[..8]);
}
