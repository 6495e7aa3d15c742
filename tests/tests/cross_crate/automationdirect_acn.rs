//! The AutomationDirect ACN map through its generated module (`drivemap_drives::automationdirect_acn`):
//! the manual's Modbus-RTU example (004_c5cbf92472673495.txt:605-628) — Acc time (0x1103) 5.0 s
//! and Dec time (0x1104) 10.0 s written with one 10h request — encodes and decodes to the values
//! and bytes the manual prints, on RTU (offset -1) and on TCP (offset 0).

use drivemap_drives::automationdirect_acn as acn;
use drivemap_drives::runtime::client::Client;
use drivemap_drives::runtime::core::profile::TransportKind;
use drivemap_drives::runtime::core::register::{Register, Writable};
use drivemap_drives::runtime::pdu::{Request, Response, Words};
use drivemap_drives::runtime::{crc, rtu, tcp};
use drivemap_sim::FaultyLink;
use drivemap_sim::SimulatedSlave;

/// Request printed at 004_c5cbf92472673495.txt:616: station 01, function 10h, starting address
/// 0x1102 ("0x1103-1"), 2 registers, 4 bytes, 0x0032 (Acc 5.0 s), 0x0064 (Dec 10.0 s), CRC
/// printed "0x1202" = the wire bytes 12h 02h.
const REQUEST: [u8; 13] = [
    0x01, 0x10, 0x11, 0x02, 0x00, 0x02, 0x04, 0x00, 0x32, 0x00, 0x64, 0x12, 0x02,
];
/// Response printed at 004_c5cbf92472673495.txt:626, CRC printed "0xE534" (wire bytes E5h 34h).
const RESPONSE: [u8; 8] = [0x01, 0x10, 0x11, 0x02, 0x00, 0x02, 0xE5, 0x34];

fn settings() -> acn::Settings {
    acn::Settings::default()
}

#[test]
fn acc_and_dec_time_are_the_registers_of_the_example() {
    assert_eq!(acn::AccTime::ADDRESS, 0x1103);
    assert_eq!(acn::AccTime::PARAM, Some("dr.03"));
    assert_eq!(acn::DecTime::ADDRESS, 0x1104);
    assert_eq!(acn::DecTime::PARAM, Some("dr.04"));
    assert_eq!(acn::AccTime::UNIT, "s");
    assert_eq!(acn::DecTime::UNIT, "s");
}

#[test]
fn example_values_encode_and_decode() {
    let s = settings();
    // "50 (ACC time 5.0sec)", "100 (DEC time 10.0sec)" (004_c5cbf92472673495.txt:617-619).
    assert_eq!(acn::AccTime::encode(&5.0, &s), Ok(0x0032));
    assert_eq!(acn::DecTime::encode(&10.0, &s), Ok(0x0064));
    assert_eq!(acn::AccTime::decode(0x0032, &s), Ok(5.0));
    assert_eq!(acn::DecTime::decode(0x0064, &s), Ok(10.0));
}

#[test]
fn addressing_is_minus_one_on_rtu_and_zero_on_tcp() {
    let offsets = acn::PROFILE.address_offsets;
    assert_eq!(
        offsets.pdu_address(acn::AccTime::ADDRESS, TransportKind::Rtu),
        Some(0x1102)
    );
    assert_eq!(
        offsets.pdu_address(acn::AccTime::ADDRESS, TransportKind::RtuOverTcp),
        Some(0x1102)
    );
    assert_eq!(
        offsets.pdu_address(acn::AccTime::ADDRESS, TransportKind::Tcp),
        Some(0x1103)
    );
    // "Hex Address 0000 is unavailable with Modbus RTU" (004_c5cbf92472673495.txt:1125).
    assert_eq!(offsets.pdu_address(0x0000, TransportKind::Rtu), None);
}

#[test]
fn printed_frames_are_the_example_encoded() {
    let s = settings();
    let values = [
        acn::AccTime::encode(&5.0, &s).unwrap() as u16,
        acn::DecTime::encode(&10.0, &s).unwrap() as u16,
    ];
    let address = acn::PROFILE
        .address_offsets
        .pdu_address(acn::AccTime::ADDRESS, TransportKind::Rtu)
        .unwrap();
    let request = Request::WriteMultiple {
        address,
        values: Words::Native(&values),
    };
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(1, &request, &mut buf).unwrap();
    assert_eq!(&buf[..n], &REQUEST[..]);
    // Both printed CRCs are right when read as the two bytes in wire order; and they were computed
    // over 0x1102, not 0x1103, which confirms the -1 offset independently of the label.
    assert_eq!(crc::crc16(&REQUEST[..11]), 0x0212);
    assert_eq!(crc::crc16(&RESPONSE[..6]), 0x34E5);
    assert_eq!(
        rtu::decode_response(1, &request, &RESPONSE),
        Ok(Response::WriteMultiple {
            address: 0x1102,
            quantity: 2
        })
    );
}

#[test]
fn example_through_the_client_on_rtu() {
    let link = FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &acn::PROFILE));
    let mut client = Client::new(link, &acn::PROFILE);
    let s = settings();
    client
        .write_many::<(acn::AccTime, acn::DecTime)>(1, &(5.0, 10.0), &s)
        .unwrap();
    assert_eq!(client.transport().sent, vec![REQUEST.to_vec()]);
    // The simulated drive holds PDU addresses: 0x1103 is PDU 0x1102 on RTU.
    assert_eq!(client.transport().slave.holding(0x1102), 0x0032);
    assert_eq!(client.transport().slave.holding(0x1103), 0x0064);
    let (acc, dec) = client
        .read_many::<(acn::AccTime, acn::DecTime)>(1, &s)
        .unwrap();
    assert_eq!((acc, dec), (5.0, 10.0));
    assert_eq!(client.read::<acn::AccTime>(1, &s).unwrap(), 5.0);
}

#[test]
fn example_through_the_client_on_tcp() {
    let link = FaultyLink::new(TransportKind::Tcp, SimulatedSlave::new(1, &acn::PROFILE));
    let mut client = Client::new(link, &acn::PROFILE);
    let s = settings();
    client
        .write_many::<(acn::AccTime, acn::DecTime)>(1, &(5.0, 10.0), &s)
        .unwrap();
    let sent = client.transport().sent.clone();
    assert_eq!(sent.len(), 1);
    let (_, request) = tcp::decode_request(&sent[0]).unwrap();
    match request {
        Request::WriteMultiple { address, values } => {
            // TCP decimal 44356 = 40001 + 0x1103 (004_c5cbf92472673495.txt:1133): PDU 0x1103.
            assert_eq!(address, 0x1103);
            assert_eq!(values.iter().collect::<Vec<_>>(), vec![0x0032, 0x0064]);
        }
        other => panic!("expected a 10h request, got {other:?}"),
    }
    assert_eq!(client.transport().slave.holding(0x1103), 0x0032);
    assert_eq!(client.transport().slave.holding(0x1104), 0x0064);
    let (acc, dec) = client
        .read_many::<(acn::AccTime, acn::DecTime)>(1, &s)
        .unwrap();
    assert_eq!((acc, dec), (5.0, 10.0));
}

#[test]
fn save_parameters_is_zero_then_one_to_03e0() {
    let save = acn::PROFILE
        .command("save_parameters")
        .expect("save command");
    assert_eq!(save.writes, &[(0x03E0, 0), (0x03E0, 1)]);
    let link = FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &acn::PROFILE));
    let mut client = Client::new(link, &acn::PROFILE);
    client.persist(1, "save_parameters").unwrap();
    // On RTU 0x03E0 goes out as PDU 0x03DF (RTU decimal 40992, 004_c5cbf92472673495.txt:1030).
    assert_eq!(
        client.transport().slave.writes,
        vec![(0x03DF, 0), (0x03DF, 1)]
    );
}

#[test]
fn busy_is_exception_06h() {
    let busy = acn::PROFILE.exception(0x06).expect("06h in the profile");
    assert_eq!(busy.name, "SLAVE DEVICE BUSY");
    assert!(acn::PROFILE.supports(0x04));
    assert_eq!(acn::PROFILE.timing.response_delay_param, Some("CM.05"));
}

#[test]
fn operation_state_0305_packs_three_nibbles() {
    // 0x0305 (004_c5cbf92472673495.txt:682-700): B0-B3 direction state, B4-B7 operation state,
    // B12-B15 normal / warning / fault; B8-B11 printed "-" (reserved, dropped on read).
    let s = settings();
    let state = acn::DriveOperationState::decode(0x8F31, &s).unwrap();
    assert_eq!(
        state.run_direction_state(),
        acn::DriveOperationStateRunDirectionState::OperatingForward
    );
    assert_eq!(
        state.operation_state(),
        acn::DriveOperationStateOperationState::ConstantRate
    );
    assert_eq!(state.trip_state(), acn::DriveOperationStateTripState::Fault);
    assert_eq!(state.raw(), 0x8031);
    let warning = acn::DriveOperationState::decode(0x4042, &s).unwrap();
    assert_eq!(
        warning.run_direction_state(),
        acn::DriveOperationStateRunDirectionState::OperatingReverse
    );
    assert_eq!(
        warning.operation_state(),
        acn::DriveOperationStateOperationState::Decelerating
    );
    assert_eq!(
        warning.trip_state(),
        acn::DriveOperationStateTripState::Warning
    );
}

#[test]
fn operation_command_examples() {
    // "Forward operation command 0003h, Reverse operation command 0001h"
    // (004_c5cbf92472673495.txt:952-953).
    let s = settings();
    let forward = acn::OperationCommand::decode(0x0003, &s).unwrap();
    assert!(forward.run() && forward.forward());
    let reverse = acn::OperationCommand::decode(0x0001, &s).unwrap();
    assert!(reverse.run() && !reverse.forward());
    assert_eq!(acn::OperationCommand::encode(&forward, &s), Ok(0x0003));
    assert_eq!(acn::OperationCommand::encode(&reverse, &s), Ok(0x0001));
}

/// 0h03E8 Lock parameter mode through the generated module: a write takes the password (a
/// word), a read gives the read enumeration (0 Unlock, 1 Lock; 004_c5cbf92472673495.txt:1076-1080),
/// and every write of a value other than 0 is preceded by 0, because "when the same parameter
/// value is entered continuously, the parameter is executed just once" (:1111-1115).
#[test]
fn lock_parameter_mode_writes_a_password_after_zero_and_reads_the_lock_state() {
    use drivemap_drives::runtime::core::plan::RepeatNeedsChange;
    assert_eq!(
        <acn::LockParameterMode as Writable>::REPEAT_NEEDS_CHANGE,
        Some(RepeatNeedsChange {
            between: 0,
            source: "004_c5cbf92472673495.txt:1115"
        })
    );
    let s = settings();
    assert_eq!(acn::LockParameterMode::encode(&244u16, &s), Ok(244));
    assert_eq!(
        acn::LockParameterMode::decode(1, &s),
        Ok(acn::LockParameterModeRead::Lock)
    );
    assert_eq!(
        acn::HideParameterMode::decode(0, &s),
        Ok(acn::HideParameterModeRead::Unlock)
    );
    let link = FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &acn::PROFILE));
    let mut client = Client::new(link, &acn::PROFILE);
    client.write::<acn::LockParameterMode>(1, &244, &s).unwrap();
    client.write::<acn::LockParameterMode>(1, &244, &s).unwrap();
    // RTU: 0x03E8 is PDU 0x03E7. The intermediate goes first each time, so the drive sees a
    // change and executes the password twice.
    assert_eq!(
        client.transport().slave.writes,
        vec![(0x03E7, 0), (0x03E7, 244), (0x03E7, 0), (0x03E7, 244)]
    );
    // The intermediate value itself is written once.
    client.write::<acn::LockParameterMode>(1, &0, &s).unwrap();
    assert_eq!(client.transport().slave.writes.len(), 5);
    // A read means the lock state, whatever was written.
    client.transport().slave.set_holding(0x03E7, 1);
    let state: acn::LockParameterModeRead = client.read::<acn::LockParameterMode>(1, &s).unwrap();
    assert_eq!(state, acn::LockParameterModeRead::Lock);
    assert_eq!(state.to_string(), "Lock");
    // A register without the rule is written once.
    client
        .write::<acn::EasyStartOn>(1, &acn::EasyStartOnValue::Yes, &s)
        .unwrap();
    assert_eq!(client.transport().slave.writes[5..], [(0x03E8, 1)]);
}

/// `Client::write_changed` passes the value through the write gate before it sends the
/// intermediate: a value the rule refuses sends nothing at all.
#[test]
fn a_refused_value_sends_no_intermediate() {
    use drivemap_drives::runtime::core::rule::WriteRule;
    let link = FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &acn::PROFILE));
    let mut client = Client::new(link, &acn::PROFILE);
    // The map's rule with a narrower raw range, as a tool interpreting another map would pass.
    let rule = WriteRule {
        raw: drivemap_drives::runtime::core::scale::RawRange { min: 0, max: 100 },
        ..<acn::LockParameterMode as Writable>::RULE
    };
    let e = client.write_changed(1, &rule, 0x03E8, 0, 244).unwrap_err();
    assert!(e.to_string().contains("244"), "{e}");
    assert!(client.transport().slave.writes.is_empty());
}
