//! GPD 515 / G5: the example frames of Chapter 6 of `001_ef66da56d29a05af.txt` ("GPD 515/G5
//! Modbus RTU") decode through the generated module `drivemap_drives::yaskawa_gpd515` to the
//! values the manual states.
//!
//! The OCR text lost the slave-address byte of every frame; the text gives it ("the slave is
//! addressed at 2" for the 03h example, line 517; "at 1" for 08h and 10h, lines 665 and 781), and
//! with those addresses every printed CRC verifies. CRC-16: init FFFFh, poly A001h, low byte first.

use drivemap_drives::runtime::core::profile::{CommandKind, TransportKind};
use drivemap_drives::runtime::core::register::{Register, Writable};
use drivemap_drives::runtime::core::scale::ValueError;
use drivemap_drives::runtime::pdu::{Request, Response, Words};
use drivemap_drives::runtime::{crc, rtu};
use drivemap_drives::yaskawa_gpd515 as gpd;
use drivemap_runtime::core::register::Enumeration;

/// Settings of a drive whose flash is 1024 or later with o2-09 = 1 (Chapter 6 layout: operation
/// command at 01h, frequency reference at 02h) and, for the current scale, a drive rating.
fn settings(rated_current: f64) -> gpd::Settings {
    gpd::Settings {
        initial_mode_select: Some(1),
        drive_rated_current: Some(rated_current),
        maximum_output_frequency: Some(60.0),
        ..gpd::Settings::default()
    }
}

fn words(response: Response<'_>) -> Vec<u16> {
    match response {
        Response::Registers(w) => w.iter().collect(),
        other => panic!("expected registers, got {other:?}"),
    }
}

// ---- 03h Read Multiple Registers (lines 489-637) -------------------------------------------

/// Command: slave 2, 03h, start 0020h, quantity 4, CRC 45h F0h (lines 493-526).
const READ_COMMAND: [u8; 8] = [0x02, 0x03, 0x00, 0x20, 0x00, 0x04, 0x45, 0xF0];
/// Normal response: 8 bytes: 1770h, 1770h, 0109h, 0000h, CRC 38h ACh (lines 539-594).
const READ_RESPONSE: [u8; 13] = [
    0x02, 0x03, 0x08, 0x17, 0x70, 0x17, 0x70, 0x01, 0x09, 0x00, 0x00, 0x38, 0xAC,
];
/// Fault response: 83h, error 02h, CRC 30h F1h (lines 611-630).
const READ_FAULT: [u8; 5] = [0x02, 0x83, 0x02, 0x30, 0xF1];

#[test]
fn read_command_is_the_manual_frame() {
    let s = settings(100.0);
    // "the starting register is 20h, indicating that the first register is the Frequency
    // Reference" (line 519-520).
    let start = gpd::MonitorFrequencyReference::address(&s, TransportKind::Rtu).unwrap();
    assert_eq!(start, 0x0020);
    assert_eq!(gpd::OutputFrequency::ADDRESS, 0x0021);
    assert_eq!(gpd::OutputCurrent::ADDRESS, 0x0022);
    assert_eq!(gpd::ControlMethod::ADDRESS, 0x0023);
    let request = Request::ReadHolding {
        address: start,
        quantity: 4,
    };
    let mut out = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(2, &request, &mut out).unwrap();
    assert_eq!(&out[..n], &READ_COMMAND);
    assert_eq!(rtu::decode_request(&READ_COMMAND).unwrap(), (2, request));
}

#[test]
fn read_response_decodes_to_the_stated_values() {
    let rated = 32.0;
    let s = settings(rated);
    let request = Request::ReadHolding {
        address: 0x0020,
        quantity: 4,
    };
    let w = words(rtu::decode_response(2, &request, &READ_RESPONSE).unwrap());
    assert_eq!(w, [0x1770, 0x1770, 0x0109, 0x0000]);

    // 20h Frequency Reference: 1770h = 6000 dec. (60.00 Hz), lines 552-555.
    assert_eq!(
        gpd::MonitorFrequencyReference::decode(w[0].into(), &s),
        Ok(60.0)
    );
    // 21h Output Frequency: 1770h = 6000 dec. (60.00 Hz), lines 556-559.
    assert_eq!(gpd::OutputFrequency::decode(w[1].into(), &s), Ok(60.0));
    // 22h Output Current: 109h = 265 dec. (drive rating / 8192), lines 560-577.
    let amps = gpd::OutputCurrent::decode(w[2].into(), &s).unwrap();
    assert!((amps - 265.0 * rated / 8192.0).abs() < 1e-12, "{amps}");
    // 23h Control Method: 00h = 0 (V/f Control), lines 585-594.
    assert_eq!(
        gpd::ControlMethod::decode(w[3].into(), &s),
        Ok(gpd::ControlMethodValue::VFControl)
    );
    assert_eq!(
        gpd::ControlMethodValue::VFControl.name(),
        Some("V/f Control")
    );
}

#[test]
fn output_current_needs_the_drive_rating() {
    let s = gpd::Settings::default();
    assert!(matches!(
        gpd::OutputCurrent::decode(0x0109, &s),
        Err(ValueError::MissingSetting { .. })
    ));
    // 8192 counts are the full drive rating.
    assert_eq!(gpd::OutputCurrent::decode(8192, &settings(45.0)), Ok(45.0));
}

#[test]
fn read_fault_is_register_number_error() {
    let request = Request::ReadHolding {
        address: 0x0020,
        quantity: 4,
    };
    let response = rtu::decode_response(2, &request, &READ_FAULT).unwrap();
    assert_eq!(
        response,
        Response::Exception {
            function: 0x03,
            code: 0x02
        }
    );
    // "The value of 2h ... indicates that the command message requested data be read from an
    // invalid register" (line 627-629); Chapter 8: 02h Register No. Error (line 1461).
    assert_eq!(
        gpd::PROFILE.exception(0x02).unwrap().name,
        "Register No. Error"
    );
}

#[test]
fn read_quantity_above_16_is_refused_by_the_profile() {
    // "The quantity may range from 1 to 16 registers. If the quantity is greater than 16, an
    // error code of 3 is returned" (lines 522-524, 794-796; Chapter 8 line 1462).
    assert_eq!(gpd::PROFILE.max_read, 16);
    assert_eq!(gpd::PROFILE.max_write, 16);
    assert_eq!(
        gpd::PROFILE.exception(0x03).unwrap().name,
        "No. of Registers"
    );
}

// ---- 08h Loop-back test (lines 639-727) ----------------------------------------------------

/// Command = normal response: slave 1, 08h, test code 0000h, data A537h, CRC DAh 8Dh.
const LOOP_BACK: [u8; 8] = [0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D];
/// Fault response: 88h, error 01h, CRC 87h C0h (lines 703-713).
const LOOP_BACK_FAULT: [u8; 5] = [0x01, 0x88, 0x01, 0x87, 0xC0];

#[test]
fn loop_back_command_and_echo() {
    let request = Request::LoopBack { data: 0xA537 };
    let mut out = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(1, &request, &mut out).unwrap();
    assert_eq!(&out[..n], &LOOP_BACK);
    // "A normal response message for the loop-back test should be identical to the command
    // message" (line 702).
    assert_eq!(
        rtu::decode_response(1, &request, &LOOP_BACK).unwrap(),
        Response::LoopBack { data: 0xA537 }
    );
    assert!(gpd::PROFILE.supports(0x08));
}

#[test]
fn loop_back_fault() {
    let request = Request::LoopBack { data: 0xA537 };
    assert_eq!(
        rtu::decode_response(1, &request, &LOOP_BACK_FAULT).unwrap(),
        Response::Exception {
            function: 0x08,
            code: 0x01
        }
    );
    assert_eq!(gpd::PROFILE.exception(0x01).unwrap().name, "Function Error");
}

// ---- 10h Write Multiple Registers (lines 729-874) ------------------------------------------

/// Command: slave 1, 10h, start 0001h, quantity 2, 4 bytes, 0001h, 1770h, CRC 6Dh B7h.
const WRITE_COMMAND: [u8; 13] = [
    0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x17, 0x70, 0x6D, 0xB7,
];
/// Normal response: start 0001h, quantity 2, CRC 10h 08h (lines 813-833).
const WRITE_RESPONSE: [u8; 8] = [0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x10, 0x08];
/// Fault response: 90h, error 02h, CRC CDh C1h (lines 848-867).
const WRITE_FAULT: [u8; 5] = [0x01, 0x90, 0x02, 0xCD, 0xC1];

#[test]
fn write_command_is_built_from_typed_values() {
    let s = settings(100.0);
    // "The first register, 01h (Operation Command) has a value of 01h or 1 dec. (forward run
    // command)" (lines 768-771).
    let start = gpd::OperationCommand::address(&s, TransportKind::Rtu).unwrap();
    assert_eq!(start, 0x0001);
    let run = gpd::OperationCommandBits::new().with_forward_run(true);
    let run_word = gpd::OperationCommand::encode(&run, &s).unwrap();
    assert_eq!(run_word, 0x0001);
    // "The next register, 02h (Frequency Reference) has a value of 1770h or 6000 dec.
    // (60.00 Hz)" (lines 772-775).
    assert_eq!(
        gpd::FrequencyReference::address(&s, TransportKind::Rtu).unwrap(),
        0x0002
    );
    let hz_word = gpd::FrequencyReference::encode(&60.0, &s).unwrap();
    assert_eq!(hz_word, 0x1770);

    let values = [run_word as u16, hz_word as u16];
    let request = Request::WriteMultiple {
        address: start,
        values: Words::Native(&values),
    };
    let mut out = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(1, &request, &mut out).unwrap();
    assert_eq!(&out[..n], &WRITE_COMMAND);

    // And the other way: the manual's frame decodes to those typed values.
    let (slave, decoded) = rtu::decode_request(&WRITE_COMMAND).unwrap();
    assert_eq!(slave, 1);
    let Request::WriteMultiple { address, values } = decoded else {
        panic!("expected 10h, got {decoded:?}");
    };
    assert_eq!(address, 0x0001);
    let v: Vec<u16> = values.iter().collect();
    let bits = gpd::OperationCommand::decode(v[0].into(), &s).unwrap();
    assert!(bits.forward_run());
    assert_eq!(gpd::FrequencyReference::decode(v[1].into(), &s), Ok(60.0));
}

#[test]
fn write_response_echoes_start_and_quantity() {
    let values = [0x0001, 0x1770];
    let request = Request::WriteMultiple {
        address: 0x0001,
        values: Words::Native(&values),
    };
    assert_eq!(
        rtu::decode_response(1, &request, &WRITE_RESPONSE).unwrap(),
        Response::WriteMultiple {
            address: 0x0001,
            quantity: 2
        }
    );
}

#[test]
fn write_fault_is_register_number_error() {
    let values = [0x0001, 0x1770];
    let request = Request::WriteMultiple {
        address: 0x0001,
        values: Words::Native(&values),
    };
    assert_eq!(
        rtu::decode_response(1, &request, &WRITE_FAULT).unwrap(),
        Response::Exception {
            function: 0x10,
            code: 0x02
        }
    );
}

// ---- CRC-16 (lines 890-953) ----------------------------------------------------------------

#[test]
fn crc_example_and_every_printed_crc() {
    // "Slave Address = 2, Function Code = 7, CRC-16 Lower = 41h, CRC-16 Upper = 12h".
    assert_eq!(crc::crc_bytes(&[0x02, 0x07]), [0x41, 0x12]);
    let frames: [&[u8]; 8] = [
        &READ_COMMAND,
        &READ_RESPONSE,
        &READ_FAULT,
        &LOOP_BACK,
        &LOOP_BACK_FAULT,
        &WRITE_COMMAND,
        &WRITE_RESPONSE,
        &WRITE_FAULT,
    ];
    for frame in frames {
        assert!(crc::check(frame).is_ok(), "{frame:02X?}");
    }
}

// ---- Chapter 7 statements the examples rely on ---------------------------------------------

#[test]
fn frequency_reference_35_75_hz_is_3575() {
    // "Desired frequency of 35.75 Hz requires a value of 3575 in register data code 002h"
    // (line 988).
    let s = settings(100.0);
    assert_eq!(gpd::FrequencyReference::encode(&35.75, &s), Ok(3575));
}

#[test]
fn operation_signal_and_frequency_reference_move_with_o2_09_and_flash() {
    // o2-09 = 1: 001h / 002h (lines 395-397); flash before 1024: 00h / 01h (lines 397-399).
    let s = settings(100.0);
    assert_eq!(
        gpd::OperationCommand::address(&s, TransportKind::Rtu).unwrap(),
        0x0001
    );
    assert_eq!(
        gpd::FrequencyReference::address(&s, TransportKind::Rtu).unwrap(),
        0x0002
    );

    let old = gpd::Settings {
        firmware: gpd::Firmware::FlashLt1024,
        ..settings(100.0)
    };
    assert_eq!(
        gpd::OperationCommand::address(&old, TransportKind::Rtu).unwrap(),
        0x0000
    );
    assert_eq!(
        gpd::FrequencyReference::address(&old, TransportKind::Rtu).unwrap(),
        0x0001
    );
    assert_eq!(
        gpd::BroadcastOperationSignals::address(&old, TransportKind::Rtu).unwrap(),
        0x0000
    );
    assert_eq!(
        gpd::BroadcastFrequencyReference::address(&old, TransportKind::Rtu).unwrap(),
        0x0001
    );

    // o2-09 = 0 (the default, line 400): the 00h / 01h layout (map conflict, reading chosen).
    let zero = gpd::Settings {
        initial_mode_select: Some(0),
        ..settings(100.0)
    };
    assert_eq!(
        gpd::OperationCommand::address(&zero, TransportKind::Rtu).unwrap(),
        0x0000
    );
    assert_eq!(
        gpd::FrequencyReference::address(&zero, TransportKind::Rtu).unwrap(),
        0x0001
    );

    // o2-09 not read: no address at all, never a guess (with o2-09 = 1 the printed 0001h of
    // the frequency reference is the operation command).
    let unread = gpd::Settings {
        initial_mode_select: None,
        ..settings(100.0)
    };
    for address in [
        gpd::OperationCommand::address(&unread, TransportKind::Rtu),
        gpd::FrequencyReference::address(&unread, TransportKind::Rtu),
    ] {
        let e = address.unwrap_err();
        assert_eq!(e.setting, "o2-09");
        assert!(
            e.to_string()
                .contains("nothing is sent to a guessed address")
        );
    }
    // Older flash keeps 00h/01h whatever o2-09 holds: its alternative decides without it.
    let old_unread = gpd::Settings {
        firmware: gpd::Firmware::FlashLt1024,
        initial_mode_select: None,
        ..settings(100.0)
    };
    assert_eq!(
        gpd::FrequencyReference::address(&old_unread, TransportKind::Rtu),
        Ok(0x0001)
    );

    // o2-09 itself is at 50Dh (line 394).
    assert_eq!(gpd::InitialModeSelect::ADDRESS, 0x050D);
}

#[test]
fn broadcast_operation_signals_bits() {
    // Bit 0: 0 Stop / 1 Run; bit 1: 0 Forward / 1 Reverse; bit 4 External Fault; bit 5 Fault
    // Reset (lines 972-981).
    let s = settings(100.0);
    let run_reverse = gpd::BroadcastOperationSignalsBits::new()
        .with_run(true)
        .with_reverse(true);
    assert_eq!(
        gpd::BroadcastOperationSignals::encode(&run_reverse, &s),
        Ok(0x0003)
    );
    let reset = gpd::BroadcastOperationSignalsBits::new().with_fault_reset(true);
    assert_eq!(
        gpd::BroadcastOperationSignals::encode(&reset, &s),
        Ok(0x0020)
    );
    // Only broadcast with 10h (lines 782-787).
    let b = gpd::PROFILE.broadcast.as_ref().unwrap();
    assert_eq!(b.functions, &[0x10]);
}

#[test]
fn accel_time_scale_follows_c1_10() {
    // C1-10 = 0: 0.01 s, 0.00-600.00 s; C1-10 = 1 (default): 0.1 s, 0.0-6000.0 s
    // (lines 1157, 1169-1178, 1210). Default C1-01 = 10.0 s (line 1189).
    let mut s = settings(100.0);
    assert!(
        gpd::AccelTime1::decode(100, &s).is_err(),
        "C1-10 unknown: no conversion"
    );
    s.accel_decel_time_setting_unit = Some(gpd::AccelDecelTimeSettingUnitValue::Unit01S);
    assert_eq!(gpd::AccelTime1::decode(100, &s), Ok(10.0));
    assert_eq!(gpd::AccelTime1::encode(&6000.0, &s), Ok(60000));
    s.accel_decel_time_setting_unit = Some(gpd::AccelDecelTimeSettingUnitValue::Unit001S);
    assert_eq!(gpd::AccelTime1::decode(1000, &s), Ok(10.0));
    assert_eq!(gpd::AccelTime1::encode(&600.0, &s), Ok(60000));
    assert!(
        gpd::AccelTime1::encode(&600.01, &s).is_err(),
        "above 600.00 s at 0.01 s"
    );
}

#[test]
fn enter_and_accept() {
    // ACCEPT: write 0 to FFDDh; ENTER: write 0 to FFFDh, wears the EEPROM (lines 421-425, 440).
    let enter = gpd::PROFILE.command("enter").unwrap();
    assert_eq!(enter.kind, CommandKind::Persist);
    assert_eq!(enter.writes, &[(0xFFFD, 0x0000)]);
    let accept = gpd::PROFILE.command("accept").unwrap();
    assert_eq!(accept.kind, CommandKind::Accept);
    assert_eq!(accept.writes, &[(0xFFDD, 0x0000)]);
    assert_eq!(gpd::PROFILE.eeprom_write_endurance, Some(100_000));
    assert_eq!(gpd::Enter::ADDRESS, 0xFFFD);
    assert_eq!(gpd::Accept::ADDRESS, 0xFFDD);
}

#[test]
fn h5_01_refuses_the_broadcast_address() {
    // H5-01 1-1Fh (lines 345, 514), not 0-1Fh (line 1400): see the register's conflict.
    let s = settings(100.0);
    assert!(gpd::SerialCommunicationAddress::encode(&0, &s).is_err());
    assert_eq!(gpd::SerialCommunicationAddress::encode(&0x1F, &s), Ok(0x1F));
    assert_eq!(gpd::PROFILE.slave_min, 1);
    assert_eq!(gpd::PROFILE.slave_max, 31);
}

#[test]
fn d4_02_is_at_290h() {
    // Printed at 280h (line 1267); between 28Fh and 291h it is 290h (map conflict).
    assert_eq!(gpd::SpeedLimits::ADDRESS, 0x0290);
}

// ---- o2-09 not known: no address guessed (issue 23, item 8) ----------------------------------

/// With o2-09 unknown, the typed client, the drive trait and `Vfd::connect` refuse before
/// anything reaches the drive: with o2-09 = 1 the printed 0001h of the frequency reference is
/// the operation command, so the printed address is never a safe default.
#[test]
fn an_unknown_o2_09_sends_nothing() {
    use drivemap_runtime::vfd::{VariableFrequencyDrive, Vfd};
    use drivemap_runtime::{client::Client, client::ClientOptions, error::Error, error::Refusal};
    use drivemap_sim::{FaultyLink, SimulatedSlave};
    use std::time::Duration;

    let options = ClientOptions {
        retries: 0,
        timeout: Duration::from_millis(50),
        ..ClientOptions::default()
    };
    let mut slave = SimulatedSlave::new(1, &gpd::PROFILE);
    slave.set_holding(0x0303, 600); // E1-04 = 60.0 Hz
    slave.fail_at(0x050D, 0x02); // o2-09 cannot be read
    slave.set_holding(0x0180, 2); // b1-01: reference from serial communication
    slave.set_holding(0x0181, 2); // b1-02: run commands from serial communication
    let link = FaultyLink::new(TransportKind::Rtu, slave);
    let mut c = Client::with_options(link, &gpd::PROFILE, options);
    let unread = gpd::Settings {
        initial_mode_select: None,
        ..settings(100.0)
    };
    let refused = |e: Error| match e {
        Error::Refused(Refusal::AddressUnknown(a)) => a.setting == "o2-09",
        _ => false,
    };
    // The typed client.
    let e = c
        .write::<gpd::FrequencyReference>(1, &30.0, &unread)
        .unwrap_err();
    assert!(refused(e));
    assert!(c.transport().sent.is_empty(), "a frame was sent");
    // The drive trait, built with settings that lack o2-09.
    {
        let mut d = Vfd::new::<gpd::Drive>(&mut c, 1, unread.clone());
        assert!(refused(d.set_reference(30.0).unwrap_err()));
        assert!(refused(d.run().unwrap_err()));
    }
    // The trait read the command sources and the maximum frequency E1-04; nothing was written.
    assert!(
        c.transport().slave.writes.is_empty(),
        "a write reached the drive"
    );
    assert!(
        c.transport()
            .sent
            .iter()
            .all(|frame| frame.get(1) == Some(&0x03)),
        "only reads were sent"
    );
    // Connecting reads o2-09; its failure is the error, not a layout by default.
    let e = Vfd::connect::<gpd::Drive>(
        &mut c,
        1,
        gpd::Settings::default(),
        &[("drive_rated_current", 10.0)],
    )
    .err()
    .expect("o2-09 unreadable");
    assert_eq!(e.exception().map(|x| x.code), Some(0x02), "{e}");
    assert!(
        c.transport().slave.writes.is_empty(),
        "a write reached the drive"
    );
}
