//! The write gate: every write of the client, typed, by rule or by raw address, is checked
//! against the map's rule for its register before anything is framed.
//!
//! The profile is a V7-like drive (`000_032dced3a1e91a75.txt`): the RTU run command at 0001h
//! (Table 4.1), the Modbus TCP option card's digital-input command at 0001h on TCP only
//! (Table 4.5), the broadcast operation signal at 0001h in the broadcast space (Table 4.2), the
//! frequency reference at 0002h, and n001 at 0101h (0-4).

use crate::common;

use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::core::rule::{Broadcast, Transports, WriteRule};
use drivemap_runtime::core::width::WordOrder;
use drivemap_runtime::error::{Error, Refusal};
use drivemap_runtime::gate::{self, WriteTarget};
use drivemap_sim::FaultyLink;
use drivemap_sim::SimulatedSlave;

const RUN_COMMAND: WriteRule = WriteRule::rw("operation_command", 0x0001, 0, 65535)
    .on(Transports::RTU)
    .reserved(0xF800);
const TCP_INPUTS: WriteRule = WriteRule::rw("tcp_digital_input_command", 0x0001, 0, 65535)
    .on(Transports::TCP)
    .reserved(0xFF80);
const BROADCAST_SIGNAL: WriteRule =
    WriteRule::write_only("broadcast_operation_signal", 0x0001, 0, 65535)
        .broadcast(Broadcast::Only)
        .reserved(0xCFC0);
const FREQUENCY: WriteRule = WriteRule::rw("frequency_reference", 0x0002, 0, 40000);
const N001: WriteRule = WriteRule::rw("n001", 0x0101, 0, 4);
/// A signed 32-bit value in 0200h-0201h, high word first (not a V7 register: the gate's pair
/// rules on the same profile).
const POSITION: WriteRule =
    WriteRule::rw("position_setpoint", 0x0200, -1_000_000, 1_000_000).pair(WordOrder::HighFirst);
/// An unsigned 32-bit value in 0300h-0301h, low word first.
const COUNTER: WriteRule =
    WriteRule::rw("preset_counter", 0x0300, 0, 4_000_000_000).pair(WordOrder::LowFirst);

static V7: Profile = Profile {
    writes: &[
        RUN_COMMAND,
        TCP_INPUTS,
        BROADCAST_SIGNAL,
        FREQUENCY,
        N001,
        POSITION,
        COUNTER,
    ],
    ..common::V7
};

fn client(kind: TransportKind) -> Client<FaultyLink> {
    Client::with_options(
        FaultyLink::new(kind, SimulatedSlave::new(1, &V7)),
        &V7,
        common::strict(),
    )
}

fn refusal(e: Error) -> Refusal {
    match e {
        Error::Refused(r) => r,
        other => panic!("expected a refusal, got {other}"),
    }
}

#[test]
fn a_register_of_another_transport_is_refused_before_sending() {
    let mut rtu = client(TransportKind::RtuOverTcp);
    let e = refusal(rtu.write_rule(1, &TCP_INPUTS, 0x0001, 0x0001).unwrap_err());
    assert_eq!(
        e,
        Refusal::NotOnTransport {
            register: "tcp_digital_input_command",
            transport: TransportKind::RtuOverTcp
        }
    );
    let mut tcp = client(TransportKind::Tcp);
    let e = refusal(tcp.write_rule(1, &RUN_COMMAND, 0x0001, 0x0001).unwrap_err());
    assert!(matches!(
        e,
        Refusal::NotOnTransport {
            register: "operation_command",
            ..
        }
    ));
    assert_eq!(rtu.transport().requests + tcp.transport().requests, 0);

    // Each on its own transport goes through.
    rtu.write_rule(1, &RUN_COMMAND, 0x0001, 0x0001).unwrap();
    tcp.write_rule(1, &TCP_INPUTS, 0x0001, 0x0010).unwrap();
    assert_eq!(rtu.transport().slave.holding(0x0001), 1);
    assert_eq!(tcp.transport().slave.holding(0x0001), 0x0010);
}

#[test]
fn broadcast_space_and_unicast_space_do_not_mix() {
    let mut c = client(TransportKind::Rtu);
    let e = refusal(c.write_rule(0, &RUN_COMMAND, 0x0001, 0x0001).unwrap_err());
    assert_eq!(
        e,
        Refusal::NotBroadcast {
            drive: "yaskawa-v7",
            register: "operation_command"
        }
    );
    let e = refusal(
        c.write_rule(1, &BROADCAST_SIGNAL, 0x0001, 0x0001)
            .unwrap_err(),
    );
    assert_eq!(
        e,
        Refusal::BroadcastOnly {
            register: "broadcast_operation_signal"
        }
    );
    assert_eq!(c.transport().requests, 0, "nothing refused was sent");
    c.write_rule(0, &BROADCAST_SIGNAL, 0x0001, 0x0001).unwrap();
    assert_eq!(c.transport().requests, 1);
}

#[test]
fn words_outside_the_map_and_reserved_bits_are_refused() {
    let mut c = client(TransportKind::Rtu);
    let e = refusal(c.write_rule(1, &N001, 0x0101, 5).unwrap_err());
    assert_eq!(
        e,
        Refusal::RawOutOfRange {
            register: "n001",
            raw: 5,
            min: 0,
            max: 4
        }
    );
    let e = refusal(c.write_rule(1, &RUN_COMMAND, 0x0001, 0x8001).unwrap_err());
    assert_eq!(
        e,
        Refusal::ReservedBits {
            register: "operation_command",
            bits: 0x8000
        }
    );
    let e = refusal(c.write_rule(1, &N001, 0x0102, 1).unwrap_err());
    assert_eq!(
        e,
        Refusal::NotAtAddress {
            register: "n001",
            address: 0x0102
        }
    );
    assert_eq!(c.transport().requests, 0, "nothing refused was sent");
    c.write_rule(1, &N001, 0x0101, 4).unwrap();
    assert_eq!(c.transport().slave.holding(0x0101), 4);
}

#[test]
fn raw_addresses_must_be_writable_registers_of_the_link() {
    let mut tcp = client(TransportKind::Tcp);
    // 0003h holds nothing writable; 0101h refuses 9; 10h over 0001h-0002h checks each word.
    let e = refusal(tcp.write_register(1, 0x0003, 1).unwrap_err());
    assert_eq!(
        e,
        Refusal::NoWritableRegister {
            drive: "yaskawa-v7",
            address: 0x0003,
            transport: TransportKind::Tcp,
            broadcast: false
        }
    );
    let e = refusal(tcp.write_register(1, 0x0101, 9).unwrap_err());
    assert!(matches!(
        e,
        Refusal::RawOutOfRange {
            register: "n001",
            raw: 9,
            ..
        }
    ));
    let e = refusal(
        tcp.write_registers(1, 0x0001, &[0x0001, 40001])
            .unwrap_err(),
    );
    assert!(matches!(
        e,
        Refusal::RawOutOfRange {
            register: "frequency_reference",
            ..
        }
    ));
    // On TCP, 0001h is the option card's digital inputs, whose bit 7 up are reserved.
    let e = refusal(tcp.write_register(1, 0x0001, 0x0100).unwrap_err());
    assert!(matches!(
        e,
        Refusal::ReservedBits {
            register: "tcp_digital_input_command",
            ..
        }
    ));
    assert_eq!(tcp.transport().requests, 0, "nothing refused was sent");
    tcp.write_registers(1, 0x0001, &[0x0001, 6000]).unwrap();
    assert_eq!(tcp.transport().requests, 1);

    // Slave 0 addresses the broadcast space, where 0002h holds no register of this map.
    let mut rtu = client(TransportKind::Rtu);
    let e = refusal(rtu.write_register(0, 0x0002, 6000).unwrap_err());
    assert!(matches!(
        e,
        Refusal::NoWritableRegister {
            address: 2,
            broadcast: true,
            ..
        }
    ));
    rtu.write_register(0, 0x0001, 0x0001).unwrap();
}

#[test]
fn a_profile_without_a_write_table_checks_the_protocol_only() {
    assert!(
        gate::check(
            &Profile::GENERIC,
            TransportKind::Tcp,
            1,
            WriteTarget::Addresses,
            0x1234,
            [0xFFFF]
        )
        .is_ok()
    );
    assert_eq!(
        gate::check(
            &Profile::GENERIC,
            TransportKind::Tcp,
            1,
            WriteTarget::Rule(&N001),
            0x0101,
            [7]
        ),
        Err(Refusal::RawOutOfRange {
            register: "n001",
            raw: 7,
            min: 0,
            max: 4
        })
    );
}

#[test]
fn a_pair_is_written_whole_in_one_request_in_its_word_order() {
    let mut c = client(TransportKind::Rtu);
    c.write_rule(1, &POSITION, 0x0200, -5i32 as u32).unwrap();
    assert_eq!(c.transport().requests, 1, "both words in one 10h request");
    assert_eq!(
        c.transport().slave.holding(0x0200),
        0xFFFF,
        "high word first"
    );
    assert_eq!(c.transport().slave.holding(0x0201), 0xFFFB);
    c.write_rule(1, &COUNTER, 0x0300, 3_000_000_000).unwrap();
    assert_eq!(
        c.transport().slave.holding(0x0300),
        0x5E00,
        "low word first"
    );
    assert_eq!(c.transport().slave.holding(0x0301), 0xB2D0);
    // Raw writes that cover the whole pair pass the gate and its range as one value.
    c.write_registers(1, 0x0200, &[0x000F, 0x4240]).unwrap(); // 1,000,000
    assert_eq!(c.transport().requests, 3);
}

#[test]
fn half_a_pair_and_a_pair_out_of_range_are_refused_before_sending() {
    let mut c = client(TransportKind::Rtu);
    let split = |address| Refusal::SplitPair {
        register: "position_setpoint",
        address,
    };
    // Its first word alone, by 06h or 10h.
    assert_eq!(
        refusal(c.write_register(1, 0x0200, 1).unwrap_err()),
        split(0x0200)
    );
    assert_eq!(
        refusal(c.write_registers(1, 0x0200, &[0]).unwrap_err()),
        split(0x0200)
    );
    // Starting at its second word, even with a word after it.
    assert_eq!(
        refusal(c.write_registers(1, 0x0201, &[0, 1]).unwrap_err()),
        split(0x0201)
    );
    // Checked as one 32-bit value: 000Fh 4241h is 1,000,001.
    assert_eq!(
        refusal(c.write_registers(1, 0x0200, &[0x000F, 0x4241]).unwrap_err()),
        Refusal::RawOutOfRange {
            register: "position_setpoint",
            raw: 1_000_001,
            min: -1_000_000,
            max: 1_000_000
        }
    );
    assert_eq!(
        refusal(c.write_rule(1, &POSITION, 0x0200, 2_000_000).unwrap_err()),
        Refusal::RawOutOfRange {
            register: "position_setpoint",
            raw: 2_000_000,
            min: -1_000_000,
            max: 1_000_000
        }
    );
    assert_eq!(c.transport().requests, 0, "nothing refused was sent");
    assert_eq!(c.transport().slave.holding(0x0200), 0);
}

/// A drive whose manual says it has a broadcast but prints no rules for it (the map's
/// `broadcast: {unknown: ..}`): the gate refuses every broadcast, by rule, by raw address and
/// from [`gate::check`] itself, while writes to one slave go on.
#[test]
fn a_broadcast_whose_rules_are_not_printed_is_never_sent() {
    static UNPRINTED: Profile = Profile {
        broadcast: Some(drivemap_runtime::core::profile::BroadcastInfo::not_printed(
            "slave 0 is named broadcast; no functions or registers printed",
        )),
        writes: &[FREQUENCY, N001],
        ..common::V7
    };
    let refused = Refusal::BroadcastRulesNotPrinted {
        drive: "yaskawa-v7",
        why: "slave 0 is named broadcast; no functions or registers printed",
    };
    let e = gate::check(
        &UNPRINTED,
        TransportKind::Rtu,
        0,
        WriteTarget::Rule(&FREQUENCY),
        0x0002,
        [6000],
    )
    .unwrap_err();
    assert_eq!(e, refused);
    assert_eq!(
        gate::check_link(&UNPRINTED, TransportKind::Rtu, 0, &FREQUENCY).unwrap_err(),
        refused
    );
    assert!(
        e.to_string()
            .contains("has a broadcast whose rules its manual does not print (slave 0 is named broadcast; no functions or registers printed): drivemap sends it no broadcast"),
        "{e}"
    );
    let mut c = Client::with_options(
        FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &UNPRINTED)),
        &UNPRINTED,
        common::strict(),
    );
    assert_eq!(
        refusal(c.write_rule(0, &FREQUENCY, 0x0002, 6000).unwrap_err()),
        refused
    );
    assert_eq!(
        refusal(c.write_register(0, 0x0002, 6000).unwrap_err()),
        refused
    );
    assert_eq!(
        refusal(c.write_registers(0, 0x0101, &[1]).unwrap_err()),
        refused
    );
    assert_eq!(c.transport().requests, 0, "no broadcast was sent");
    // One slave at a time is the way.
    c.write_rule(1, &FREQUENCY, 0x0002, 6000).unwrap();
    assert_eq!(c.transport().slave.holding(0x0002), 6000);
    // Known rules: the same broadcast goes out.
    static PRINTED: Profile = Profile {
        broadcast: Some(drivemap_runtime::core::profile::BroadcastInfo::new(
            &[0x06],
            &[],
        )),
        ..UNPRINTED
    };
    assert!(
        gate::check(
            &PRINTED,
            TransportKind::Rtu,
            0,
            WriteTarget::Rule(&FREQUENCY),
            0x0002,
            [6000]
        )
        .is_ok()
    );
}
