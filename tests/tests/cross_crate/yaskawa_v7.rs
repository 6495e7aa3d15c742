//! Yaskawa V7 / V74X and VS mini J7 through the generated modules `drivemap_drives::yaskawa_v7`
//! and `drivemap_drives::yaskawa_j7`.
//!
//! Sources: `000_032dced3a1e91a75.txt` (TM.V7.11, Chapter 2 example frames, Tables 4.1-4.6) and
//! `003_8bcf5d50afb8e230.txt` (VS-606V7 / VS mini J7 MEMOBUS manual, section 7 example frames).
//! CRC-16: initial FFFFh, polynomial A001h, low byte first. 000 labels the first CRC byte
//! "Upper"; it is the low byte, and with that reading every printed CRC checks except 003's
//! loop-back fault response.

use drivemap_drives::runtime::core::register::{Register, Writable};
use drivemap_drives::runtime::core::scale::ValueError;
use drivemap_drives::runtime::pdu::{Request, Response, Words};
use drivemap_drives::runtime::rtu;
use drivemap_drives::{yaskawa_j7 as j7, yaskawa_v7 as v7};

type Unit = v7::ModbusFrequencyReferenceUnitSelectionValue;
type TimeUnit = v7::AccelDecelTimeUnitSelectionValue;

fn settings(unit: Unit, max_hz: f64) -> v7::Settings {
    v7::Settings {
        modbus_frequency_reference_unit_selection: Some(unit),
        max_output_frequency: Some(max_hz),
        accel_decel_time_unit_selection: Some(TimeUnit::Unit01S),
        ..v7::Settings::default()
    }
}

fn frame(slave: u8, request: &Request<'_>) -> Vec<u8> {
    let mut out = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(slave, request, &mut out).unwrap();
    out[..n].to_vec()
}

fn words(response: Response<'_>) -> Vec<u16> {
    match response {
        Response::Registers(w) => w.iter().collect(),
        other => panic!("expected registers, got {other:?}"),
    }
}

// ---- 03h (000 Tables 2.2-2.4, lines 310-367; 003 7.1, lines 306-349) ---------------------------

/// Slave 2, 03h, start 0020h, quantity 4, CRC 45h F0h (000 lines 312-319, 003 lines 315-322).
const READ_COMMAND: [u8; 8] = [0x02, 0x03, 0x00, 0x20, 0x00, 0x04, 0x45, 0xF0];

#[test]
fn read_command_starts_at_status_signal_1() {
    // "Reads out status signal, fault contents, data link status and frequency reference"
    // (003 line 312): the four registers 0020h-0023h.
    assert_eq!(v7::StatusSignal1::ADDRESS, 0x0020);
    assert_eq!(v7::FaultContent1::ADDRESS, 0x0021);
    assert_eq!(v7::DataLinkStatus::ADDRESS, 0x0022);
    assert_eq!(v7::FrequencyReferenceMonitor::ADDRESS, 0x0023);
    let request = Request::ReadHolding {
        address: v7::StatusSignal1::ADDRESS,
        quantity: 4,
    };
    assert_eq!(frame(2, &request), READ_COMMAND);
    assert!(4 <= v7::PROFILE.max_read);
}

#[test]
fn memobus_read_response_decodes() {
    // 003 lines 326-338: 0065h, 0000h, 0000h, 01F4h, CRC AFh 82h.
    let response = [
        0x02, 0x03, 0x08, 0x00, 0x65, 0x00, 0x00, 0x00, 0x00, 0x01, 0xF4, 0xAF, 0x82,
    ];
    let request = Request::ReadHolding {
        address: 0x0020,
        quantity: 4,
    };
    let w = words(rtu::decode_response(2, &request, &response).unwrap());
    assert_eq!(w, [0x0065, 0x0000, 0x0000, 0x01F4]);
    let s = settings(Unit::Unit01Hz, 60.0);

    let status = v7::StatusSignal1::decode(w[0].into(), &s).unwrap();
    assert!(status.during_run());
    assert!(!status.reverse_direction());
    assert!(status.inverter_ready());
    assert!(!status.fault());
    assert!(!status.data_set_error());
    assert!(status.output_ma_mc());
    assert!(status.output_p1_pc());
    assert!(!status.output_p2_pc());

    assert_eq!(v7::FaultContent1::decode(w[1].into(), &s).unwrap().raw(), 0);
    assert_eq!(
        v7::DataLinkStatus::decode(w[2].into(), &s).unwrap().raw(),
        0
    );
    // 01F4h = 500: 50.0 Hz at n152 = 0 (0.1 Hz), 5.00 Hz at n152 = 1 (0.01 Hz).
    assert_eq!(
        v7::FrequencyReferenceMonitor::decode(w[3].into(), &s),
        Ok(50.0)
    );
    let s1 = settings(Unit::Unit001Hz, 60.0);
    assert_eq!(
        v7::FrequencyReferenceMonitor::decode(w[3].into(), &s1),
        Ok(5.0)
    );
}

#[test]
fn tm_v7_read_response_is_a_framing_vector() {
    // 000 Table 2.3 (lines 335-349): 1770h, 1770h, 0109h, 0000h, CRC 38h ACh. The data set
    // reserved status bits (see the map's conflict "Read example data"); only framing is checked,
    // and decoding the status drops the reserved bits.
    let response = [
        0x02, 0x03, 0x08, 0x17, 0x70, 0x17, 0x70, 0x01, 0x09, 0x00, 0x00, 0x38, 0xAC,
    ];
    let request = Request::ReadHolding {
        address: 0x0020,
        quantity: 4,
    };
    let w = words(rtu::decode_response(2, &request, &response).unwrap());
    assert_eq!(w, [0x1770, 0x1770, 0x0109, 0x0000]);
    let status = v7::StatusSignal1::decode(w[0].into(), &v7::Settings::default()).unwrap();
    assert_eq!(status.raw(), 0x1770 & 0x00FF);
}

#[test]
fn read_fault_response_names_the_error() {
    // 000 Table 2.4 (lines 361-367): 02h 83h 02h, CRC 30h F1h: invalid register.
    let request = Request::ReadHolding {
        address: 0x0020,
        quantity: 4,
    };
    let fault = [0x02, 0x83, 0x02, 0x30, 0xF1];
    assert_eq!(
        rtu::decode_response(2, &request, &fault).unwrap(),
        Response::Exception {
            function: 0x03,
            code: 0x02
        }
    );
    assert_eq!(
        v7::PROFILE.exception(0x02).unwrap().name,
        "Invalid Register"
    );
    // 003 line 343-347: 02h 83h 03h, CRC F1h 31h: improper quantity.
    let fault = [0x02, 0x83, 0x03, 0xF1, 0x31];
    assert_eq!(
        rtu::decode_response(2, &request, &fault).unwrap(),
        Response::Exception {
            function: 0x03,
            code: 0x03
        }
    );
}

// ---- 06h (000 Tables 2.5-2.7, lines 381-431) ---------------------------------------------------

#[test]
fn write_single_sets_run_and_reverse() {
    // 01h 06h 0001h 0003h, CRC 98h 0Bh; the response echoes it (lines 383-417).
    let bits = v7::DigitalInputCommandBits::new()
        .with_run_command(true)
        .with_reverse(true);
    let s = v7::Settings::default();
    let value = v7::DigitalInputCommand::encode(&bits, &s).unwrap() as u16;
    assert_eq!(value, 0x0003);
    let request = Request::WriteSingle {
        address: v7::DigitalInputCommand::ADDRESS,
        value,
    };
    let expected = [0x01, 0x06, 0x00, 0x01, 0x00, 0x03, 0x98, 0x0B];
    assert_eq!(frame(1, &request), expected);
    assert_eq!(
        rtu::decode_response(1, &request, &expected).unwrap(),
        Response::WriteSingle {
            address: 0x0001,
            value: 0x0003
        }
    );
    // Fault response 01h 86h 21h, CRC 82h 78h (lines 425-431): data out of range.
    let fault = [0x01, 0x86, 0x21, 0x82, 0x78];
    assert_eq!(
        rtu::decode_response(1, &request, &fault).unwrap(),
        Response::Exception {
            function: 0x06,
            code: 0x21
        }
    );
    assert_eq!(
        v7::PROFILE.exception(0x21).unwrap().name,
        "Data Limits Exceeded"
    );
    assert!(v7::PROFILE.function_codes.contains(&0x06));
    assert!(!j7::PROFILE.function_codes.contains(&0x06));
}

// ---- 08h (000 Tables 2.8-2.10, lines 447-493; 003 7.2, lines 351-386) -------------------------

#[test]
fn loop_back_frames() {
    let request = Request::LoopBack { data: 0xA537 };
    let expected = [0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D];
    assert_eq!(frame(1, &request), expected);
    assert_eq!(
        rtu::decode_response(1, &request, &expected).unwrap(),
        Response::LoopBack { data: 0xA537 }
    );
    // 000 Table 2.10: 01h 88h 01h, CRC 87h C0h.
    let fault = [0x01, 0x88, 0x01, 0x87, 0xC0];
    assert_eq!(
        rtu::decode_response(1, &request, &fault).unwrap(),
        Response::Exception {
            function: 0x08,
            code: 0x01
        }
    );
    // 003 line 382-386 prints the same fault with CRC 86h 50h, which does not check.
    let misprinted = [0x01, 0x88, 0x01, 0x86, 0x50];
    assert!(rtu::decode_response(1, &request, &misprinted).is_err());
}

// ---- 10h (000 Tables 2.11-2.13, lines 505-566; 003 7.3, lines 388-411) ------------------------

#[test]
fn write_multiple_forward_run_at_60_hz() {
    // "Set forward run at frequency reference 60.0 Hz to slave 1" (003 line 394): 0001h = 0001h,
    // 0002h = 0258h, CRC 63h 39h. 000 Table 2.11 lost the byte 02h; its CRC needs it.
    let s = settings(Unit::Unit01Hz, 60.0);
    let run = v7::DigitalInputCommandBits::new().with_run_command(true);
    let values = [
        v7::DigitalInputCommand::encode(&run, &s).unwrap() as u16,
        v7::FrequencyReference::encode(&60.0, &s).unwrap() as u16,
    ];
    assert_eq!(values, [0x0001, 0x0258]);
    assert_eq!(
        v7::FrequencyReference::ADDRESS,
        v7::DigitalInputCommand::ADDRESS + 1
    );
    let request = Request::WriteMultiple {
        address: v7::DigitalInputCommand::ADDRESS,
        values: Words::Native(&values),
    };
    assert_eq!(
        frame(1, &request),
        [
            0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x02, 0x58, 0x63, 0x39
        ]
    );
    let response = [0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x10, 0x08];
    assert_eq!(
        rtu::decode_response(1, &request, &response).unwrap(),
        Response::WriteMultiple {
            address: 0x0001,
            quantity: 2
        }
    );
    let fault = [0x01, 0x90, 0x02, 0xCD, 0xC1];
    assert_eq!(
        rtu::decode_response(1, &request, &fault).unwrap(),
        Response::Exception {
            function: 0x10,
            code: 0x02
        }
    );
    // The decoded frame reads back as forward run at 60.0 Hz.
    let bits = v7::DigitalInputCommand::decode(0x0001, &s).unwrap();
    assert!(bits.run_command() && !bits.reverse());
    assert_eq!(v7::FrequencyReference::decode(0x0258, &s), Ok(60.0));
}

// ---- Frequency in Hz under each n152 setting (000 lines 1345-1348, 003 line 102) ---------------

#[test]
fn frequency_reference_under_each_n152_setting() {
    let hz = 60.0;
    // 0: 1 = 0.1 Hz.
    assert_eq!(
        v7::FrequencyReference::encode(&hz, &settings(Unit::Unit01Hz, 60.0)),
        Ok(600)
    );
    // 1: 1 = 0.01 Hz.
    assert_eq!(
        v7::FrequencyReference::encode(&hz, &settings(Unit::Unit001Hz, 60.0)),
        Ok(6000)
    );
    // 2: 30000 = n011.
    let full = settings(Unit::FullScale30000, 60.0);
    assert_eq!(v7::FrequencyReference::encode(&hz, &full), Ok(30000));
    assert_eq!(v7::FrequencyReference::encode(&30.0, &full), Ok(15000));
    assert_eq!(
        v7::FrequencyReference::encode(&hz, &settings(Unit::FullScale30000, 120.0)),
        Ok(15000)
    );
    // 3: 1 = 0.1 % of n011.
    let pct = settings(Unit::Unit01Percent, 60.0);
    assert_eq!(v7::FrequencyReference::encode(&hz, &pct), Ok(1000));
    assert_eq!(v7::FrequencyReference::encode(&30.0, &pct), Ok(500));
    // The monitors use the same unit.
    assert_eq!(v7::OutputFrequency::decode(500, &pct), Ok(30.0));
    // Without n152 the conversion refuses rather than guesses.
    let unknown = v7::Settings {
        max_output_frequency: Some(60.0),
        ..v7::Settings::default()
    };
    assert!(matches!(
        v7::FrequencyReference::encode(&hz, &unknown),
        Err(ValueError::MissingSetting { .. })
    ));
}

#[test]
fn broadcast_frequency_is_fixed_at_30000_whatever_n152_says() {
    // 000 lines 892-898: send 1000h = 4096: 13.65 % of 60 Hz = 8.19 Hz.
    for unit in [
        Unit::Unit01Hz,
        Unit::Unit001Hz,
        Unit::FullScale30000,
        Unit::Unit01Percent,
    ] {
        let s = settings(unit, 60.0);
        let hz = v7::BroadcastFrequencyReference::decode(0x1000, &s).unwrap();
        assert!((hz - 4096.0 * 60.0 / 30000.0).abs() < 1e-9, "{hz}");
        assert!((hz - 8.19).abs() < 0.005, "{hz}");
        assert_eq!(
            v7::BroadcastFrequencyReference::encode(&60.0, &s),
            Ok(30000)
        );
    }
    let b = v7::PROFILE.broadcast.as_ref().unwrap();
    assert_eq!(b.functions, &[0x06, 0x10]);
    assert_eq!(j7::PROFILE.broadcast.as_ref().unwrap().functions, &[0x10]);
}

// ---- Accel time under each n018 setting (000 lines 1015, 1068-1072) ---------------------------

#[test]
fn accel_time_under_each_n018_setting() {
    let mut s = settings(Unit::Unit01Hz, 60.0);
    // n018 = 0: 0.1 s. "If n019 is read and a value of 600 returned, the actual value is 60.0
    // seconds. If n019 is to be set to 30 seconds, a value of 300 must be sent" (line 1015).
    s.accel_decel_time_unit_selection = Some(TimeUnit::Unit01S);
    assert_eq!(v7::AccelTime1::decode(600, &s), Ok(60.0));
    assert_eq!(v7::AccelTime1::encode(&30.0, &s), Ok(300));
    assert_eq!(v7::AccelTime1::encode(&6000.0, &s), Ok(60000));
    assert_eq!(v7::AccelTime1::encode(&1234.5, &s), Ok(12345));
    // n018 = 1: 0.01 s, at most 600.0 s.
    s.accel_decel_time_unit_selection = Some(TimeUnit::Unit001S);
    assert_eq!(v7::AccelTime1::encode(&30.0, &s), Ok(3000));
    assert_eq!(v7::AccelTime1::decode(600, &s), Ok(6.0));
    assert_eq!(v7::AccelTime1::encode(&600.0, &s), Ok(60000));
    assert!(matches!(
        v7::AccelTime1::encode(&6000.0, &s),
        Err(ValueError::OutOfRange { .. })
    ));
    // Decel 1, accel/decel 2-4 follow the same selector.
    assert_eq!(v7::DecelTime4::encode(&12.34, &s), Ok(1234));
}

// ---- 230 V / 460 V (000 lines 1062, 1320) ------------------------------------------------------

#[test]
fn voltage_limits_differ_by_class() {
    let v230 = v7::Settings::default();
    let v460 = v7::Settings {
        voltage_class: v7::VoltageClass::V460,
        ..v7::Settings::default()
    };
    // n012 Maximum Voltage: 0.1 - 255.0 (230 V), 0.2 - 510.0 (460 V), 0.1 V per count.
    assert_eq!(v7::MaxVoltage::encode(&230.0, &v230), Ok(2300));
    assert!(matches!(
        v7::MaxVoltage::encode(&460.0, &v230),
        Err(ValueError::OutOfRange { .. })
    ));
    assert_eq!(v7::MaxVoltage::encode(&460.0, &v460), Ok(4600));
    assert!(matches!(
        v7::MaxVoltage::encode(&0.1, &v460),
        Err(ValueError::OutOfRange { .. })
    ));
    // n147 Motor Rated Voltage: 150.0 - 255.0 / 300.0 - 510.0.
    assert!(v7::MotorRatedVoltage::encode(&400.0, &v230).is_err());
    assert_eq!(v7::MotorRatedVoltage::encode(&400.0, &v460), Ok(4000));
    assert!(v7::MotorRatedVoltage::encode(&200.0, &v460).is_err());
}

// ---- Magnitude-dependent resolution: the register carries the finest increment -----------------

#[test]
fn frequency_parameters_carry_0_01_hz_throughout() {
    let s = v7::Settings::default();
    assert_eq!(v7::FrequencyReference1::encode(&6.0, &s), Ok(600)); // default 6.00 Hz
    assert_eq!(v7::FrequencyReference1::encode(&99.99, &s), Ok(9999));
    assert_eq!(v7::FrequencyReference1::encode(&100.0, &s), Ok(10000));
    assert_eq!(v7::FrequencyReference1::encode(&400.0, &s), Ok(40000));
    assert!(v7::FrequencyReference1::encode(&400.01, &s).is_err());
    assert_eq!(v7::MotorLineToLineResistance::encode(&65.5, &s), Ok(65500));
    assert_eq!(
        v7::TorqueCompensationIronLoss::encode(&6550.0, &s),
        Ok(65500)
    );
}

// ---- Addresses chosen where the tables disagree ------------------------------------------------

#[test]
fn reconciled_addresses() {
    assert_eq!(v7::ProhibitFrequency2::ADDRESS, 0x0154);
    assert_eq!(v7::ProhibitFrequency3::ADDRESS, 0x0155); // Table 4.4 prints 0154h twice
    assert_eq!(v7::SearchVoltageLimiter::ADDRESS, 0x0190);
    assert_eq!(v7::SearchStepAt100Percent::ADDRESS, 0x0191);
    assert_eq!(v7::SearchStepAt5Percent::ADDRESS, 0x0192);
    assert_eq!(v7::DriveSoftwareNumber::ADDRESS, 0x01B3); // Table 5.1 says 01B4h
    assert_eq!(v7::EnterCommand::ADDRESS, 0x0900);
    assert_eq!(v7::AcceptCommand::ADDRESS, 0x0910);
    assert_eq!(v7::PROFILE.max_read, 8);
    assert_eq!(j7::PROFILE.max_read, 16);
}

/// n011 bounds the frequency reference, whose rows print no range (000 :868, :1424): "30000 =
/// Max. output frequency" (003 :102). A value above it is refused on the value given, and one
/// that cannot be checked (n011 not in the settings) is refused, never sent unchecked.
#[test]
fn frequency_reference_is_bounded_by_n011() {
    type Unit = v7::ModbusFrequencyReferenceUnitSelectionValue;
    let s = v7::Settings {
        modbus_frequency_reference_unit_selection: Some(Unit::Unit01Hz),
        max_output_frequency: Some(60.0),
        ..v7::Settings::default()
    };
    assert_eq!(v7::TcpFrequencyReference::encode(&60.0, &s), Ok(600));
    assert_eq!(v7::FrequencyReference::encode(&60.0, &s), Ok(600));
    let e = v7::TcpFrequencyReference::encode(&500.0, &s).unwrap_err();
    assert_eq!(
        e.to_string(),
        "tcp_frequency_reference: 500 Hz is above 60 Hz, 100 % of n011"
    );
    assert!(matches!(
        v7::FrequencyReference::encode(&60.1, &s),
        Err(ValueError::AboveLimit { .. })
    ));
    let unknown = v7::Settings {
        max_output_frequency: None,
        ..s
    };
    assert_eq!(
        v7::FrequencyReference::encode(&10.0, &unknown),
        Err(ValueError::LimitNotKnown {
            register: "frequency_reference",
            setting: "n011"
        })
    );
}

/// A value is sent as given or refused (issue 23, item 4): 35.75 Hz to a register that counts
/// 0.1 Hz names 35.7 and 35.8; rounding is asked for (`Rounding::Nearest`), and limits apply
/// to the value given. The typed API, the client and the drive trait.
#[test]
fn a_value_between_steps_is_refused_unless_rounding_is_asked_for() {
    use drivemap_drives::runtime::core::scale::Rounding;
    use drivemap_runtime::vfd::{VariableFrequencyDrive, Vfd};
    use drivemap_runtime::{client::Client, error::Error};
    use drivemap_sim::{FaultyLink, SimulatedSlave};
    type Unit = v7::ModbusFrequencyReferenceUnitSelectionValue;
    type Time = v7::AccelDecelTimeUnitSelectionValue;
    let s = v7::Settings {
        modbus_frequency_reference_unit_selection: Some(Unit::Unit01Hz),
        accel_decel_time_unit_selection: Some(Time::Unit01S),
        max_output_frequency: Some(60.0),
        ..v7::Settings::default()
    };
    let e = v7::FrequencyReference::encode(&35.75, &s).unwrap_err();
    assert_eq!(
        e,
        ValueError::NotAStep {
            register: "frequency_reference",
            value: 35.75,
            below: 35.7,
            above: 35.8,
            step: 0.1,
            unit: "Hz"
        }
    );
    assert_eq!(
        e.to_string(),
        "frequency_reference: 35.75 Hz is between 35.7 and 35.8 Hz; the register counts 0.1 Hz"
    );
    assert_eq!(
        v7::FrequencyReference::encode_rounded(&35.75, &s, Rounding::Nearest),
        Ok(358)
    );
    // n019 = 0.04 s: refused; -0.04 s is below the range, rounded or not.
    assert!(matches!(
        v7::AccelTime1::encode(&0.04, &s),
        Err(ValueError::NotAStep { .. })
    ));
    for rounding in [Rounding::Exact, Rounding::Nearest] {
        assert!(matches!(
            v7::AccelTime1::encode_rounded(&-0.04, &s, rounding),
            Err(ValueError::OutOfRange { .. })
        ));
        // 60.04 Hz is above n011 although it rounds to 60.0 Hz.
        assert!(matches!(
            v7::FrequencyReference::encode_rounded(&60.04, &s, rounding),
            Err(ValueError::AboveLimit { .. })
        ));
    }
    // The client: nothing sent for a refused value; write_rounded sends the nearest.
    let mut slave = SimulatedSlave::new(2, &v7::PROFILE);
    slave.set_holding(0x010B, 600); // n011 = 60.0 Hz
    slave.set_holding(0x0103, 2); // n003: run commands from Modbus RTU
    slave.set_holding(0x0104, 6); // n004: reference from Modbus RTU
    let link = FaultyLink::new(
        drivemap_drives::runtime::core::profile::TransportKind::Rtu,
        slave,
    );
    let mut c = Client::new(link, &v7::PROFILE);
    assert!(matches!(
        c.write::<v7::FrequencyReference>(2, &35.75, &s),
        Err(Error::Value(ValueError::NotAStep { .. }))
    ));
    assert!(c.transport().sent.is_empty());
    c.write_rounded::<v7::FrequencyReference>(2, &35.75, &s, Rounding::Nearest)
        .unwrap();
    assert_eq!(c.transport().slave.writes, vec![(0x0002, 358)]);
    // The drive trait: refused by default, the nearest when the Vfd is told to round.
    {
        let mut d = Vfd::new::<v7::Drive>(&mut c, 2, s.clone());
        assert!(matches!(
            d.set_reference(12.34),
            Err(Error::Value(ValueError::NotAStep { .. }))
        ));
    }
    assert_eq!(c.transport().slave.writes.len(), 1, "nothing more written");
    let mut d = Vfd::new::<v7::Drive>(&mut c, 2, s).rounding(Rounding::Nearest);
    d.set_reference(12.34).unwrap();
    drop(d);
    assert_eq!(c.transport().slave.writes[1], (0x0002, 123));
}

// ---- J7 --------------------------------------------------------------------------------------

#[test]
fn j7_frequency_unit_follows_n69_and_its_reserved_bits_stay_zero() {
    type J7Unit = j7::ModbusFrequencyReferenceUnitSelectionValue;
    let s = j7::Settings {
        modbus_frequency_reference_unit_selection: Some(J7Unit::FullScale30000),
        max_output_frequency: Some(50.0),
    };
    assert_eq!(
        j7::ModbusFrequencyReferenceUnitSelection::PARAM,
        Some("n69")
    );
    assert_eq!(j7::FrequencyReference::encode(&25.0, &s), Ok(15000));
    let s0 = j7::Settings {
        modbus_frequency_reference_unit_selection: Some(J7Unit::Unit01Hz),
        ..s
    };
    // Same frame as the V7: forward run at 60.0 Hz (003 line 394), on a drive whose maximum
    // output frequency n09 allows it.
    let s60 = j7::Settings {
        max_output_frequency: Some(60.0),
        ..s0
    };
    assert_eq!(j7::FrequencyReference::encode(&60.0, &s60), Ok(0x0258));
    // Above the maximum output frequency (30000 = Max. output frequency, 003 line 102): refused.
    assert!(matches!(
        j7::FrequencyReference::encode(&60.0, &s0),
        Err(ValueError::AboveLimit { max, .. }) if max == 50.0
    ));
    // 0001H on the J7: bits 4, 9, A reserved (003 lines 535-547).
    assert_eq!(j7::DigitalInputCommandBits::MASK, 0x01EF);
    let all = j7::DigitalInputCommand::decode(0xFFFF, &s0).unwrap();
    assert_eq!(j7::DigitalInputCommand::encode(&all, &s0), Ok(0x01EF));
    // 0021H bit D is a ground fault on the J7 (003 line 617).
    let faults = j7::FaultContent1::decode(0x2000, &s0).unwrap();
    assert!(faults.ground_fault());
    assert_eq!(j7::PROFILE.commands.len(), 1);
}

// ---- The write gate on the typed API (000 Tables 4.1, 4.2, 4.5) -------------------------------

/// The V7's 0001h is three registers: the RTU run command (Table 4.1, :853), the broadcast
/// operation signal in the broadcast space (Table 4.2, :882), and the Modbus TCP option card's
/// digital inputs (Table 4.5, :1403). The typed API writes each only where it exists.
#[test]
fn typed_writes_reach_0001h_only_as_the_register_of_that_link() {
    use drivemap_drives::runtime::core::profile::TransportKind;
    use drivemap_drives::runtime::{
        client::Client, client::ClientOptions, error::Error, error::Refusal,
    };
    use drivemap_sim::FaultyLink;
    use drivemap_sim::SimulatedSlave;

    let s = settings(Unit::Unit01Hz, 60.0);
    let client = |kind| {
        Client::with_options(
            FaultyLink::new(kind, SimulatedSlave::new(1, &v7::PROFILE)),
            &v7::PROFILE,
            ClientOptions {
                retries: 0,
                ..ClientOptions::default()
            },
        )
    };
    let run = v7::DigitalInputCommandBits::new().with_run_command(true);
    let broadcast_run = v7::BroadcastDigitalInputCommandBits::new().with_run_command(true);
    let s1 = v7::TcpDigitalInputCommandBits::new().with_terminal_s1(true);

    let mut rtu = client(TransportKind::Rtu);
    let refused = [
        rtu.write::<v7::TcpDigitalInputCommand>(1, &s1, &s),
        rtu.write::<v7::DigitalInputCommand>(0, &run, &s),
        rtu.write::<v7::BroadcastDigitalInputCommand>(1, &broadcast_run, &s),
    ];
    let refused: Vec<Refusal> = refused
        .into_iter()
        .map(|r| match r {
            Err(Error::Refused(e)) => e,
            other => panic!("expected a refusal, got {other:?}"),
        })
        .collect();
    assert!(matches!(
        refused[0],
        Refusal::NotOnTransport {
            register: "tcp_digital_input_command",
            transport: TransportKind::Rtu
        }
    ));
    assert!(matches!(
        refused[1],
        Refusal::NotBroadcast {
            register: "digital_input_command",
            ..
        }
    ));
    assert!(matches!(
        refused[2],
        Refusal::BroadcastOnly {
            register: "broadcast_digital_input_command"
        }
    ));
    assert_eq!(rtu.transport().requests, 0, "nothing refused was sent");
    rtu.write::<v7::DigitalInputCommand>(1, &run, &s).unwrap();
    rtu.write::<v7::BroadcastDigitalInputCommand>(0, &broadcast_run, &s)
        .unwrap();
    assert_eq!(rtu.transport().requests, 2);

    let mut tcp = client(TransportKind::Tcp);
    let e = tcp
        .write::<v7::DigitalInputCommand>(1, &run, &s)
        .unwrap_err();
    assert!(
        matches!(e, Error::Refused(Refusal::NotOnTransport { .. })),
        "{e}"
    );
    tcp.write::<v7::TcpDigitalInputCommand>(1, &s1, &s).unwrap();
    assert_eq!(tcp.transport().requests, 1);
}

// ---- Timing on the wire: the request gap (003 7.1, line 284) ------------------------------------

/// A transport that notes when each request leaves and each reply byte arrives.
struct Stamped {
    link: drivemap_drives::runtime::transport::memory::MemoryTransport,
    sent: Vec<std::time::Instant>,
    received: Vec<std::time::Instant>,
}

impl drivemap_drives::runtime::transport::Transport for Stamped {
    fn kind(&self) -> drivemap_drives::runtime::core::profile::TransportKind {
        self.link.kind()
    }
    fn send(&mut self, frame: &[u8]) -> std::io::Result<()> {
        self.sent.push(std::time::Instant::now());
        self.link.send(frame)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: std::time::Instant) -> std::io::Result<usize> {
        let n = self.link.recv(buf, deadline)?;
        if n > 0 {
            self.received.push(std::time::Instant::now());
        }
        Ok(n)
    }
}

/// With `ClientOptions::for_profile` (what the CLI uses by default) a V7 master leaves the
/// manual's 24 bit times + 10 ms after each reply before its next request
/// (`003_8bcf5d50afb8e230.txt:284`; 24 bits at 9600 baud are 2.5 ms). Measured on the
/// transport: from the last byte of the first reply to the second request.
#[test]
fn two_requests_to_a_v7_keep_the_manuals_request_gap() {
    use drivemap_drives::runtime::core::profile::TransportKind;
    use drivemap_drives::runtime::transport::memory::MemoryTransport;
    use drivemap_drives::runtime::{client::Client, client::ClientOptions};
    use drivemap_sim::SimulatedSlave;
    use std::time::{Duration, Instant};

    let manual_gap = Duration::from_micros(2_500) + Duration::from_millis(10);
    let options = ClientOptions::for_profile(&v7::PROFILE);
    assert!(
        options.request_gap >= manual_gap,
        "{:?}",
        options.request_gap
    );
    // The default (no profile) keeps no gap: the reason `for_profile` exists.
    assert_eq!(ClientOptions::default().request_gap, Duration::ZERO);

    let (master, mut link) = MemoryTransport::pair(TransportKind::Rtu);
    let mut slave = SimulatedSlave::new(1, &v7::PROFILE);
    let drive = std::thread::spawn(move || {
        slave
            .serve(&mut link, Instant::now() + Duration::from_secs(2))
            .unwrap();
    });
    let stamped = Stamped {
        link: master,
        sent: Vec::new(),
        received: Vec::new(),
    };
    let mut client = Client::with_options(stamped, &v7::PROFILE, options);
    let mut word = [0u16; 1];
    client.read_holding(1, 0x0020, &mut word).unwrap();
    client.read_holding(1, 0x0020, &mut word).unwrap();
    let t = client.into_transport();
    drop(t.link);
    drive.join().unwrap();
    assert_eq!(t.sent.len(), 2);
    let first_reply_end = *t
        .received
        .iter()
        .filter(|&&r| r < t.sent[1])
        .max()
        .expect("the first reply arrived before the second request");
    let gap = t.sent[1] - first_reply_end;
    assert!(gap >= manual_gap, "second request {gap:?} after the reply");
}
