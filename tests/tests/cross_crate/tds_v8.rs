//! The TDS-V8 manual's example values and frames, through the generated module
//! (`002_661580cce154f322.txt`, section 9, lines 641-828).

use drivemap_drives::ptlk_tds_v8 as tds;
use drivemap_runtime::core::register::{Bits, Register, Writable};
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::pdu::{Request, Words};
use drivemap_runtime::rtu;

fn settings() -> tds::Settings {
    // Cn-02 (max output frequency) = 60.0 Hz: 100 % = 30000 counts.
    tds::Settings {
        max_output_frequency: Some(60.0),
        ..Default::default()
    }
}

#[test]
fn frequency_command_is_relative_to_cn_02() {
    let s = settings();
    // 5DC0h = 80 % of Cn-02 (line 701); 3A98h = 50 % (line 749).
    assert_eq!(tds::FrequencyCommand::decode(0x5DC0, &s), Ok(48.0));
    assert_eq!(tds::FrequencyCommand::encode(&48.0, &s), Ok(0x5DC0));
    assert_eq!(tds::FrequencyCommand::decode(0x3A98, &s), Ok(30.0));
    assert_eq!(tds::FrequencyCommand::encode(&30.0, &s), Ok(0x3A98));
    // 7530h = 100 % (line 337).
    assert_eq!(tds::FrequencyCommand::encode(&60.0, &s), Ok(0x7530));
    // Without Cn-02 the conversion cannot be made and says so.
    assert!(matches!(
        tds::FrequencyCommand::encode(&48.0, &tds::Settings::new()),
        Err(ValueError::MissingSetting {
            setting: "Cn-02",
            ..
        })
    ));
    // The map reads Cn-02 itself when asked (0301h, 0.1 Hz).
    let mut read = tds::Settings::new();
    assert!(drivemap_runtime::core::register::DriveSettings::absorb(
        &mut read, 0x0301, 600
    ));
    assert_eq!(read.max_output_frequency, Some(60.0));
}

/// Step `n` of the PLC example: 10h write of 0000h-0007h with the run word, the frequency
/// word and the output-terminal word; the rest 0 (reserved 0002h-0006h).
fn step_frame(
    run: tds::OperationCommandBits,
    hz: f64,
    terminals: tds::OutputTerminalCommandBits,
) -> Vec<u8> {
    let s = settings();
    let mut words = [0u16; 8];
    words[0] = tds::OperationCommand::encode(&run, &s).unwrap() as u16;
    words[1] = tds::FrequencyCommand::encode(&hz, &s).unwrap() as u16;
    words[7] = tds::OutputTerminalCommand::encode(&terminals, &s).unwrap() as u16;
    let request = Request::WriteMultiple {
        address: tds::OperationCommand::ADDRESS,
        values: Words::Native(&words),
    };
    let mut out = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(1, &request, &mut out).unwrap();
    out[..n].to_vec()
}

#[test]
fn plc_example_frames_encode_byte_for_byte() {
    let forward = tds::OperationCommandBits::new().with_run(true);
    let r1 = tds::OutputTerminalCommandBits::new().with_r1_output(true);
    // Step 1 (lines 659-685): forward run at 80 %, R1 on. The manual labels the CRC bytes
    // "High 44H, Low 91H"; on the wire the low byte comes first and is 44h: the labels are
    // swapped, the bytes are right (recorded as a conflict in the map).
    let mut step1 = vec![
        0x01, 0x10, 0x00, 0x00, 0x00, 0x08, 0x10, 0x00, 0x01, 0x5D, 0xC0,
    ];
    step1.extend_from_slice(&[0; 10]);
    step1.extend_from_slice(&[0x00, 0x01, 0x44, 0x91]);
    assert_eq!(step_frame(forward, 48.0, r1), step1);
    // Step 2 (lines 707-733): 50 %, CRC FDh 2Eh.
    let step2 = step_frame(forward, 30.0, r1);
    assert_eq!(&step2[9..11], &[0x3A, 0x98]);
    assert_eq!(&step2[step2.len() - 2..], &[0xFD, 0x2E]);
    // Step 3 (lines 755-779): reverse run 0003h at 50 %; printed CRC 7Fh 2Fh, which matches
    // only with the Access Count 0008h the printed table dropped.
    let reverse = forward.with_reverse(true);
    assert_eq!(reverse.bits(), 0x0003);
    let step3 = step_frame(reverse, 30.0, r1);
    assert_eq!(&step3[4..6], &[0x00, 0x08]);
    assert_eq!(&step3[step3.len() - 2..], &[0x7F, 0x2F]);
}

#[test]
fn status_word_of_the_read_example_decodes_by_name() {
    // 03h reply (lines 200-208) carries 0802h for 0020h: zero speed and LCD operator.
    let status = tds::InverterStatus::decode(0x0802, &settings()).unwrap();
    assert!(status.zero_speed() && status.lcd_operator());
    assert!(!status.running() && !status.fault());
    assert_eq!(
        status.setting_error(),
        tds::InverterStatusSettingError::Unknown(0)
    );
    // Bits 12-15: a 4-bit error code (line 365).
    let bad = tds::InverterStatus::decode(0x4000, &settings()).unwrap();
    assert_eq!(
        bad.setting_error(),
        tds::InverterStatusSettingError::VfPatternSettingInvalid
    );
}

#[test]
fn parameters_scale_and_range_check_before_encoding() {
    let s = settings();
    // Bn-01 Acceleration time 1: 0.1 s, 0.0-6000.0 s (line 455).
    assert_eq!(tds::AccelTime1::encode(&6000.0, &s), Ok(60000));
    assert_eq!(tds::AccelTime1::decode(60000, &s), Ok(6000.0));
    assert_eq!(tds::AccelTime1::decode(6000, &s), Ok(600.0));
    assert!(matches!(
        tds::AccelTime1::encode(&6000.1, &s),
        Err(ValueError::OutOfRange { .. })
    ));
    assert!(matches!(
        tds::AccelTime1::encode(&-0.1, &s),
        Err(ValueError::OutOfRange { .. })
    ));
    // Cn-01 Input voltage: 150.0-255.0 V for 220 V, doubled for 440 V (lines 496, 550).
    assert!(tds::InputVoltage::encode(&300.0, &s).is_err());
    let s440 = tds::Settings {
        voltage_class: tds::VoltageClass::V440,
        ..settings()
    };
    assert_eq!(tds::InputVoltage::encode(&300.0, &s440), Ok(3000));
    assert!(tds::InputVoltage::encode(&510.1, &s440).is_err());
}

#[test]
fn profile_matches_the_manual() {
    let p = &tds::PROFILE;
    assert_eq!(p.function_codes, &[0x03, 0x06, 0x08, 0x10]);
    assert_eq!((p.max_read, p.max_write), (16, 16));
    assert_eq!((p.slave_min, p.slave_max), (1, 31));
    assert_eq!(p.broadcast.unwrap().addresses, &[0x0000, 0x0001]);
    assert_eq!(p.exception(0x21).unwrap().name, "Device Busy");
    assert_eq!(p.exception(0x22).unwrap().name, "Device Fail");
    assert_eq!(p.exception(0x04).unwrap().name, "CRC_16 Error");
    let save = p
        .commands
        .iter()
        .find(|c| c.writes == [(0x0500, 0)])
        .expect("EEPROM save command");
    assert_eq!(
        save.kind,
        drivemap_runtime::core::profile::CommandKind::Persist
    );
}

#[test]
fn client_loads_settings_then_writes_in_hz() {
    use drivemap_runtime::client::Client;
    use drivemap_runtime::core::profile::TransportKind;
    use drivemap_runtime::core::register::DriveSettings;
    use drivemap_runtime::transport::memory::MemoryTransport;
    use drivemap_sim::SimulatedSlave;
    use std::time::{Duration, Instant};

    let (master, mut link) = MemoryTransport::pair(TransportKind::Rtu);
    let mut slave = SimulatedSlave::new(1, &tds::PROFILE);
    slave.set_holding(0x0301, 500); // Cn-02 = 50.0 Hz
    let drive = std::thread::spawn(move || {
        slave
            .serve(&mut link, Instant::now() + Duration::from_secs(2))
            .unwrap();
        slave
    });
    let mut client = Client::new(master, &tds::PROFILE);
    let mut s = tds::Settings::new();
    assert_eq!(tds::Settings::DEPENDENCIES, &[0x0301]);
    client.load_settings(1, &mut s).unwrap();
    assert_eq!(s.max_output_frequency, Some(50.0));
    client.write::<tds::FrequencyCommand>(1, &40.0, &s).unwrap(); // 80 % of 50 Hz
    assert!(
        client
            .write::<tds::FrequencyCommand>(1, &f64::NAN, &s)
            .is_err()
    );
    drop(client);
    let slave = drive.join().unwrap();
    assert_eq!(slave.holding(0x0001), 0x5DC0);
}
