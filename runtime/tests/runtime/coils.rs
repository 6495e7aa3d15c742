//! Coils and discrete inputs (01h, 02h, 05h, 0Fh): their PDUs as the Modbus application
//! protocol specification prints its examples, the client's reads and writes through the gate
//! (coils and registers are two address spaces), and the read planner, which reads a table of
//! 100 coils in the fewest requests the drive's `max_read_bits` allows and never puts two tables
//! in one request.

use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::{BroadcastInfo, Profile};
use drivemap_runtime::core::register::{Access, RegisterInfo, Table};
use drivemap_runtime::core::rule::{Broadcast, WriteRule};
use drivemap_runtime::core::width::Width;
use drivemap_runtime::error::{Error, Refusal};
use drivemap_runtime::pdu::{
    self, BitValues, FrameError, Request, RequestDecodeError, RequestError, Response,
    decode_request, decode_response,
};
use drivemap_runtime::planner::Poller;
use drivemap_sim::SimulatedSlave;
use drivemap_test_support::instant_link::InstantLink;

/// Coils 0000h-0063h writable (0000h and 0001h also by broadcast), 0064h read-only; the
/// drive reads at most 32 bits and writes at most 16 per request.
static WRITES: [WriteRule; 100] = {
    let mut all = [WriteRule::rw("coil", 0, 0, 1).in_table(Table::Coil); 100];
    let mut i = 0;
    while i < 100 {
        all[i].address = i as u16;
        i += 1;
    }
    all[0] = all[0].broadcast(Broadcast::Also);
    all[1] = all[1].broadcast(Broadcast::Also);
    all
};

static PROFILE: Profile = Profile {
    function_codes: &[0x01, 0x02, 0x03, 0x05, 0x06, 0x0F, 0x10],
    max_read: 8,
    max_read_bits: 32,
    max_write_bits: 16,
    broadcast: Some(BroadcastInfo::new(&[0x05], &[0x0000, 0x0001])),
    writes: &WRITES,
    ..Profile::GENERIC
};

fn client() -> Client<InstantLink> {
    let mut drive = SimulatedSlave::new(1, &PROFILE);
    drive.reads = Some(Vec::new());
    Client::new(InstantLink::new(drive), &PROFILE)
}

fn encoded(request: Request<'_>) -> Vec<u8> {
    let mut buf = [0u8; pdu::MAX_PDU];
    let n = request.encode(&mut buf).unwrap();
    buf[..n].to_vec()
}

/// The examples of the Modbus application protocol specification (V1.1b3, 6.1, 6.2, 6.5, 6.11):
/// request and response bytes, and every echo checked.
#[test]
fn bit_pdus_are_the_specifications_examples_and_their_echoes_are_checked() {
    // 01h: coils 20-38 (PDU 0013h, 19 coils); the response's 3 bytes hold them.
    let read = Request::ReadCoils {
        address: 0x0013,
        quantity: 19,
    };
    assert_eq!(encoded(read), [0x01, 0x00, 0x13, 0x00, 0x13]);
    let Response::Bits(bits) = decode_response(&read, &[0x01, 0x03, 0xCD, 0x6B, 0x05]).unwrap()
    else {
        panic!("not bits");
    };
    // CD: coils 27-20 = 1100 1101; 6B: 35-28; 05: 38-36 = 101.
    let want = [
        true, false, true, true, false, false, true, true, // CDh, lowest bit first
        true, true, false, true, false, true, true, false, // 6Bh
        true, false, true, // 05h, three of its bits
    ];
    assert_eq!(bits, BitValues::Native(&want));
    assert_eq!(
        decode_response(&read, &[0x01, 0x02, 0xCD, 0x6B]),
        Err(FrameError::ByteCount {
            expected: 3,
            got: 2
        })
    );
    // 02h: discrete inputs 197-218 (PDU 00C4h, 22 inputs).
    let read = Request::ReadDiscreteInputs {
        address: 0x00C4,
        quantity: 22,
    };
    assert_eq!(encoded(read), [0x02, 0x00, 0xC4, 0x00, 0x16]);
    assert!(matches!(
        decode_response(&read, &[0x02, 0x03, 0xAC, 0xDB, 0x35]),
        Ok(Response::Bits(b)) if b.len() == 22 && b.get(0) == Some(false) && b.get(2) == Some(true)
    ));
    // 05h: coil 173 (PDU 00ACh) on; the echo is checked word for word.
    let write = Request::WriteCoil {
        address: 0x00AC,
        value: true,
    };
    assert_eq!(encoded(write), [0x05, 0x00, 0xAC, 0xFF, 0x00]);
    assert!(decode_response(&write, &[0x05, 0x00, 0xAC, 0xFF, 0x00]).is_ok());
    assert_eq!(
        decode_response(&write, &[0x05, 0x00, 0xAC, 0x00, 0x00]),
        Err(FrameError::ValueEcho {
            expected: 0xFF00,
            got: 0
        })
    );
    // 0Fh: coils 20-29 (PDU 0013h) as CDh 01h.
    let states = [
        true, false, true, true, false, false, true, true, true, false,
    ];
    let write = Request::WriteCoils {
        address: 0x0013,
        values: BitValues::Native(&states),
    };
    assert_eq!(
        encoded(write),
        [0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01]
    );
    assert!(decode_response(&write, &[0x0F, 0x00, 0x13, 0x00, 0x0A]).is_ok());
    assert_eq!(
        decode_response(&write, &[0x0F, 0x00, 0x13, 0x00, 0x09]),
        Err(FrameError::QuantityEcho {
            expected: 10,
            got: 9
        })
    );
    // The slave side reads them back; 05h with a value other than FF00h or 0000h is malformed
    // (answered 03h), and so is a 0Fh whose byte count does not fit its quantity.
    assert_eq!(
        decode_request(&[0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01]),
        Ok(write)
    );
    assert_eq!(
        decode_request(&[0x05, 0x00, 0xAC, 0x12, 0x34]),
        Err(RequestDecodeError::Malformed(0x05))
    );
    assert_eq!(
        decode_request(&[0x0F, 0x00, 0x13, 0x00, 0x0A, 0x01, 0xCD]),
        Err(RequestDecodeError::Malformed(0x0F))
    );
    // The Modbus limits: 2000 per read, 1968 per write.
    let mut buf = [0u8; pdu::MAX_PDU];
    assert!(matches!(
        Request::ReadCoils {
            address: 0,
            quantity: 2001
        }
        .encode(&mut buf),
        Err(RequestError::Quantity { max: 2000, .. })
    ));
    assert!(
        Request::ReadDiscreteInputs {
            address: 0,
            quantity: 2000
        }
        .encode(&mut buf)
        .is_ok()
    );
    assert!(matches!(
        Request::WriteCoils {
            address: 0,
            values: BitValues::Native(&[false; 1969])
        }
        .encode(&mut buf),
        Err(RequestError::Quantity { max: 1968, .. })
    ));
}

/// The client reads and writes coils and discrete inputs, each write through the gate in the
/// coils' space: 05h with FF00h or 0000h, 0Fh for several, reads split at `max_read_bits`.
#[test]
fn the_client_reads_and_writes_coils_in_their_own_space() {
    let mut c = client();
    c.write_coil(1, 0x0005, true).unwrap();
    c.write_coils(1, 0x000A, &[true, false, true]).unwrap();
    let drive = &c.transport().drive;
    assert!(drive.coil(0x0005) && drive.coil(0x000A) && !drive.coil(0x000B));
    assert!(drive.coil(0x000C));
    // The registers' space is not touched.
    assert_eq!(drive.holding(0x0005), 0);
    c.transport().drive.set_discrete_input(0x0003, true);
    let mut coils = [false; 40];
    c.read_coils(1, 0x0000, &mut coils).unwrap();
    let on: Vec<usize> = (0..40).filter(|&i| coils[i]).collect();
    assert_eq!(on, [5, 10, 12]);
    // 40 coils at 32 per request: two requests.
    assert_eq!(
        c.transport().drive.reads.as_deref(),
        Some(&[(0x0000, 32), (0x0020, 8)][..])
    );
    let mut inputs = [false; 4];
    c.read_discrete_inputs(1, 0x0000, &mut inputs).unwrap();
    assert_eq!(inputs, [false, false, false, true]);
    // One request of more than the drive's limit is refused before anything is sent.
    let e = c
        .read_table(1, Table::Coil, 0x0000, &mut [0u16; 33])
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::Refused(Refusal::TooManyBits {
                function: 0x01,
                max: 32,
                ..
            })
        ),
        "{e}"
    );
    let e = c.write_coils(1, 0x0000, &[false; 17]).unwrap_err();
    assert!(
        matches!(e, Error::Refused(Refusal::TooManyBits { max: 16, .. })),
        "{e}"
    );
}

/// The gate in the coils' space: a coil the map does not list, a register write at a coil's
/// address, a coil's rule sent as a register write, and the broadcast rules are refused before
/// anything is sent.
#[test]
fn the_gate_keeps_coils_and_registers_apart() {
    let mut c = client();
    let e = c.write_coil(1, 0x0064, true).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Refused(Refusal::NoWritableCoil {
                address: 0x0064,
                broadcast: false,
                ..
            })
        ),
        "{e}"
    );
    // A coil at 0005h is no holding register 0005h.
    let e = c.write_register(1, 0x0005, 1).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Refused(Refusal::NoWritableRegister {
                address: 0x0005,
                ..
            })
        ),
        "{e}"
    );
    // A coil's rule is written only as a coil: the raw value 2 is no state.
    let rule = &WRITES[7];
    let e = drivemap_runtime::gate::check(
        &PROFILE,
        drivemap_runtime::core::profile::TransportKind::Rtu,
        1,
        drivemap_runtime::gate::WriteTarget::Rule(rule),
        0x0007,
        [2],
    )
    .unwrap_err();
    assert!(matches!(e, Refusal::RawOutOfRange { raw: 2, .. }), "{e}");
    let e = c.write_rule(1, rule, 0x0007, 2).unwrap_err();
    assert!(
        matches!(e, Error::Refused(Refusal::RawOutOfRange { .. })),
        "{e}"
    );
    // Broadcast: 05h to the listed coils only; 0Fh is not a broadcast function here.
    c.write_coil(0, 0x0001, true).unwrap();
    assert!(c.transport().drive.coil(0x0001));
    let e = c.write_coil(0, 0x0002, true).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Refused(Refusal::NoWritableCoil {
                address: 0x0002,
                broadcast: true,
                ..
            })
        ),
        "{e}"
    );
    let e = c.write_coils(0, 0x0000, &[true, true]).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Refused(Refusal::BroadcastFunction { function: 0x0F, .. })
        ),
        "{e}"
    );
    assert!(!c.transport().drive.coil(0x0002));
    // Nothing refused reached the drive: the one write executed is the accepted broadcast.
    assert_eq!(c.transport().drive.writes, [(0x0001, 1)]);
}

/// 100 coils (reserved at 0032h, write-only at 0050h), discrete inputs and holding registers
/// at the same addresses: the planner reads the 100 coils wanted in the fewest requests the
/// drive's 32 per read allow, bridges only readable coils, and never mixes tables.
#[test]
fn the_planner_reads_100_coils_in_the_fewest_requests() {
    let coil = |address: u16| RegisterInfo {
        id: "c",
        name: "c",
        address,
        access: Access::ReadWrite,
        table: Table::Coil,
        ..RegisterInfo::DEFAULT
    };
    let mut registers: Vec<RegisterInfo> = (0..100).map(coil).collect();
    registers.extend((0..8).map(|a| RegisterInfo {
        table: Table::DiscreteInput,
        access: Access::Read,
        ..coil(a)
    }));
    registers.extend((0..8).map(|a| RegisterInfo {
        table: Table::Holding,
        access: Access::Read,
        width: Width::Word,
        ..coil(a)
    }));
    let wanted: Vec<(Table, u16)> = (0..100)
        .map(|a| (Table::Coil, a))
        .chain([(Table::DiscreteInput, 3), (Table::Holding, 3)])
        .collect();
    let poller = Poller::new(&PROFILE, &registers, wanted.clone()).unwrap();
    let plan: Vec<(Table, u16, u16)> = poller
        .plan()
        .map(|(t, r)| (t, r.address, r.quantity))
        .collect();
    let coil_reads: Vec<_> = plan.iter().filter(|p| p.0 == Table::Coil).collect();
    // The fewest: 100 / 32 rounded up.
    assert_eq!(coil_reads.len(), 100usize.div_ceil(32), "{plan:?}");
    assert!(coil_reads.iter().all(|p| p.2 <= 32));
    assert_eq!(
        coil_reads.iter().map(|p| usize::from(p.2)).sum::<usize>(),
        100
    );
    assert_eq!(
        plan.iter()
            .filter(|p| p.0 != Table::Coil)
            .collect::<Vec<_>>(),
        [&(Table::Holding, 3, 1), &(Table::DiscreteInput, 3, 1)]
    );
    // With the Modbus limit, one request.
    static WIDE: Profile = Profile {
        max_read_bits: 2000,
        ..PROFILE
    };
    let one = Poller::new(&WIDE, &registers, wanted.clone()).unwrap();
    assert_eq!(
        one.plan().filter(|(t, _)| *t == Table::Coil).count(),
        1,
        "one 01h request of 100 coils"
    );
    // The values read are the drive's, each table from its own space.
    let mut poller = poller;
    let mut drive = SimulatedSlave::new(1, &PROFILE);
    for a in (0..100).filter(|a| a % 3 == 0) {
        drive.set_coil(a, true);
    }
    drive.set_discrete_input(3, false);
    drive.set_holding(3, 0x1234);
    drive.reads = Some(Vec::new());
    let mut c = Client::new(InstantLink::new(drive), &PROFILE);
    let stats = poller.poll(&mut c, 1);
    assert_eq!(stats.requests, 6);
    for a in 0..100 {
        assert_eq!(
            poller.get(Table::Coil, a).unwrap().unwrap(),
            u16::from(a % 3 == 0),
            "coil {a}"
        );
    }
    assert_eq!(poller.get(Table::DiscreteInput, 3).unwrap().unwrap(), 0);
    assert_eq!(poller.get(Table::Holding, 3).unwrap().unwrap(), 0x1234);
    // A coil that may not be read (write-only) is not bridged: wanting 48 and 52 around a
    // write-only 50 takes two requests.
    registers[50].access = Access::Write;
    let apart = Poller::new(&PROFILE, &registers, [(Table::Coil, 48), (Table::Coil, 52)]).unwrap();
    let reads: Vec<_> = apart.plan().map(|(_, r)| (r.address, r.quantity)).collect();
    assert_eq!(reads.len(), 2, "{reads:?}");
    assert!(
        reads.iter().all(|&(a, q)| !(a..a + q).contains(&50)),
        "{reads:?}"
    );
}
