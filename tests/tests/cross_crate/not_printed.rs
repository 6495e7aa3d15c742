//! A drive whose manual prints no register count per write (`max_write: {unknown: ..}`): the
//! lowered profile carries the Modbus limit, so the client's write gate lets a 123-register
//! write through, the simulated drive (serving the same map) receives all 123, and 124 are
//! refused before anything is sent. The map is the fixture `tests/fixtures/halden-h1`
//! (fictional manual printing no protocol figure), with 130 plain holding registers appended so
//! that a long write has registers to land on.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_runtime::core::stated::{ProtocolFact, Stated};
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{client::Client, error::Error, error::Refusal};
use drivemap_sim::{
    SimOptions, Simulator, clock::ManualClock, server::TcpFraming, server::TcpServer,
};

const FIRST: u16 = 0x0100;
const BLOCK: u16 = 130;

fn map(max_write_line: Option<&str>) -> drivemap_map::Map {
    let path = paths::fixture("halden-h1/halden-h1.yaml");
    let mut text = std::fs::read_to_string(path).unwrap();
    if let Some(line) = max_write_line {
        let old = text
            .lines()
            .find(|l| l.starts_with("  max_write:"))
            .unwrap()
            .to_owned();
        text = text.replace(&old, line);
    }
    text += "  - id: block\n    name: A block of plain words\n    access: rw\n    registers:\n";
    for i in 0..BLOCK {
        text += &format!(
            "      - {{id: word_{i}, name: Word {i}, address: 0x{:04X}, source: \"halden-h1.txt:13\"}}\n",
            FIRST + i
        );
    }
    drivemap_map::Loader::new()
        .load_str("halden-h1.yaml", &text)
        .unwrap_or_else(|d| panic!("{d}"))
}

struct Bench {
    server: TcpServer,
    client: Client<TcpTransport>,
    sim: drivemap_sim::server::SharedSim,
}

fn bench(map: drivemap_map::Map) -> Bench {
    let sim = Simulator::new(
        map.clone(),
        SimOptions::new()
            .slave(1)
            .clock(Arc::new(ManualClock::new())),
    )
    .unwrap();
    let sim = drivemap_sim::server::shared(sim);
    let server =
        TcpServer::spawn(Arc::clone(&sim), "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
    let link =
        TcpTransport::connect(server.local_addr().to_string(), Duration::from_secs(2)).unwrap();
    let client = Client::new(link, drivemap_live::leak_profile(&map));
    Bench {
        server,
        client,
        sim,
    }
}

#[test]
fn an_unprinted_max_write_lets_123_registers_through_to_the_drive_and_refuses_124() {
    let mut b = bench(map(None));
    let profile = b.client.profile();
    assert_eq!(profile.max_write, 123);
    assert_eq!(
        profile.max_write_stated(),
        Stated::NotPrinted("the note prints no register count for function 10H")
    );
    assert!(profile.why_not_printed(ProtocolFact::MaxWrite).is_some());

    let values: Vec<u16> = (0..123).map(|i| 1000 + i).collect();
    b.client.write_registers(1, FIRST, &values).unwrap();
    {
        let sim = b.sim.lock().unwrap();
        for i in [0u16, 61, 122] {
            assert_eq!(
                sim.raw(&format!("word_{i}")).unwrap(),
                u32::from(1000 + i),
                "the drive holds word {i}"
            );
        }
        assert_eq!(sim.raw("word_123").unwrap(), 0, "nothing beyond the write");
    }

    let values: Vec<u16> = (0..124).collect();
    match b.client.write_registers(1, FIRST, &values) {
        Err(Error::Refused(Refusal::TooManyRegisters { quantity, max, .. })) => {
            assert_eq!((quantity, max), (124, 123))
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        b.sim.lock().unwrap().raw("word_0").unwrap(),
        1000,
        "the refused write sent nothing"
    );
    // Reads: the Modbus 125 likewise.
    let mut words = [0u16; 125];
    b.client.read_holding(1, FIRST, &mut words).unwrap();
    assert_eq!(words[122], 1122);
    b.server.stop();
}

/// The same drive with a printed limit of 16: the gate holds the write to 16.
#[test]
fn a_printed_max_write_holds_the_gate_to_it() {
    let mut b = bench(map(Some(
        "  max_write: {value: 16, source: \"halden-h1.txt:6\"}",
    )));
    assert_eq!(b.client.profile().max_write_stated(), Stated::Printed(16));
    let values: Vec<u16> = (0..123).collect();
    match b.client.write_registers(1, FIRST, &values) {
        Err(Error::Refused(Refusal::TooManyRegisters { max, .. })) => assert_eq!(max, 16),
        other => panic!("{other:?}"),
    }
    b.client.write_registers(1, FIRST, &values[..16]).unwrap();
    b.server.stop();
}
