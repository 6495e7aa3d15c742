//! Several simulated drives on one link ([`Line`]), as on an RS-485 line or behind a TCP
//! gateway: the drive at a frame's address answers it, a broadcast is executed by every drive
//! whose map allows it and answered by none, a frame for an address no drive has gets silence.

use drivemap_test_support::paths;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::pdu::Request;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{client::Client, rtu, tcp};
use drivemap_sim::server::lock;
use drivemap_sim::{Line, Outcome, SimOptions, Simulator, server::TcpFraming, server::TcpServer};

fn sim(id: &str, slave: u8) -> Simulator {
    let path = paths::shipped_map(id);
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    Simulator::new(drive, SimOptions::new().slave(slave)).unwrap()
}

fn rtu_frame(slave: u8, request: &Request<'_>) -> Vec<u8> {
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(slave, request, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// The words of a normal 03h reply over RTU framing.
fn words(reply: &[u8]) -> Vec<u16> {
    assert_eq!(reply[1], 0x03, "not a normal read reply: {reply:02X?}");
    let n = usize::from(reply[2]) / 2;
    (0..n)
        .map(|i| u16::from_be_bytes([reply[3 + 2 * i], reply[4 + 2 * i]]))
        .collect()
}

#[test]
fn each_slave_is_answered_by_its_own_drive_and_an_empty_address_by_none() {
    let mut line = Line::new();
    let v7 = line.add(sim("yaskawa-v7", 1)).unwrap();
    let tds = line.add(sim("ptlk-tds-v8", 2)).unwrap();
    lock(&v7).set_raw("frequency_reference", 300).unwrap();
    lock(&tds).set_raw("frequency_command", 15000).unwrap();
    let read = |slave, address| {
        let mut out = [0u8; tcp::MAX_FRAME];
        let h = line.handle(
            TransportKind::Rtu,
            &rtu_frame(
                slave,
                &Request::ReadHolding {
                    address,
                    quantity: 1,
                },
            ),
            &mut out,
        );
        (h.reply.map(|n| out[..n].to_vec()), h.record)
    };
    // V7 0002h frequency reference; TDS-V8 0001h frequency command.
    let (reply, record) = read(1, 0x0002);
    assert_eq!(words(&reply.unwrap()), [300]);
    assert_eq!((record.slave, record.outcome), (1, Outcome::Ok));
    let (reply, _) = read(2, 0x0001);
    assert_eq!(words(&reply.unwrap()), [15000]);
    // Nobody at 3: silence.
    let (reply, record) = read(3, 0x0001);
    assert_eq!(reply, None);
    assert_eq!((record.slave, record.outcome), (3, Outcome::NotAddressed));
    // Each drive counted only its own requests.
    assert_eq!(lock(&v7).stats().replies, 1);
    assert_eq!(lock(&tds).stats().replies, 1);
    // A second drive at a taken address is refused, naming both.
    let e = line.add(sim("yaskawa-j7", 2)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "slave address 2 is taken on this line by ptlk-tds-v8; cannot add yaskawa-j7 there"
    );
    assert_eq!(line.len(), 2);
}

/// Slave 0: every drive whose map allows the write executes it, none answers.
#[test]
fn a_broadcast_reaches_every_drive_and_gets_no_reply() {
    let mut line = Line::new();
    let a = line.add(sim("yaskawa-v7", 1)).unwrap();
    let tds = line.add(sim("ptlk-tds-v8", 2)).unwrap();
    let b = line.add(sim("yaskawa-v7", 3)).unwrap();
    let mut out = [0u8; tcp::MAX_FRAME];
    // 0002h: the V7's broadcast frequency reference (Table 4.2); the TDS-V8 takes broadcasts
    // at 0000h/0001h only.
    let frame = rtu_frame(
        0,
        &Request::WriteSingle {
            address: 0x0002,
            value: 15000,
        },
    );
    let h = line.handle(TransportKind::Rtu, &frame, &mut out);
    assert_eq!(h.reply, None);
    assert_eq!(h.record.outcome, Outcome::Broadcast { executed: true });
    for v7 in [&a, &b] {
        assert_eq!(
            lock(v7).raw("broadcast_frequency_reference").unwrap(),
            15000
        );
        assert_eq!(lock(v7).stats().broadcasts_executed, 1);
    }
    assert_eq!(lock(&tds).stats().broadcasts_refused, 1);
    // 0001h on the TDS-V8 is its frequency command: executed there, refused by the V7s (15000
    // sets reserved bits of their broadcast run command word).
    let frame = rtu_frame(
        0,
        &Request::WriteSingle {
            address: 0x0001,
            value: 15000,
        },
    );
    let h = line.handle(TransportKind::Rtu, &frame, &mut out);
    assert_eq!(h.reply, None);
    assert_eq!(h.record.outcome, Outcome::Broadcast { executed: true });
    assert_eq!(lock(&tds).raw("frequency_command").unwrap(), 15000);
    assert_eq!(lock(&a).stats().broadcasts_refused, 1);
}

/// Served over RTU over TCP (one connection, the whole line) and as a Modbus TCP to RTU gateway
/// (the unit id picks the drive), with a runtime client per drive on the gateway.
#[test]
fn a_served_line_answers_per_address_over_rtu_over_tcp_and_a_gateway() {
    let mut line = Line::new();
    let v7 = line.add(sim("yaskawa-v7", 1)).unwrap();
    let tds = line.add(sim("ptlk-tds-v8", 2)).unwrap();
    lock(&v7).set_raw("frequency_reference", 450).unwrap();
    lock(&tds).set_raw("frequency_command", 6000).unwrap();

    let server =
        TcpServer::spawn(line.clone(), "127.0.0.1:0", TcpFraming::RtuOverTcp, None).unwrap();
    let mut s = TcpStream::connect(server.local_addr()).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(400)))
        .unwrap();
    let mut ask = |slave: u8, address: u16| -> Option<Vec<u16>> {
        s.write_all(&rtu_frame(
            slave,
            &Request::ReadHolding {
                address,
                quantity: 1,
            },
        ))
        .unwrap();
        let mut buf = [0u8; 7];
        match s.read_exact(&mut buf) {
            Ok(()) => {
                assert_eq!(buf[0], slave, "answered by another slave: {buf:02X?}");
                Some(words(&buf))
            }
            Err(_) => None,
        }
    };
    assert_eq!(ask(1, 0x0002), Some(vec![450]));
    assert_eq!(ask(2, 0x0001), Some(vec![6000]));
    assert_eq!(ask(9, 0x0001), None, "nobody is at 9");
    assert_eq!(
        ask(1, 0x0002),
        Some(vec![450]),
        "the line goes on after silence"
    );
    drop(server);

    let server = TcpServer::spawn(line, "127.0.0.1:0", TcpFraming::Gateway, None).unwrap();
    let link = TcpTransport::connect_gateway(server.local_addr(), Duration::from_secs(1)).unwrap();
    let tds_profile = lock(&tds).profile();
    let mut client = Client::new(link, tds_profile);
    let mut w = [0u16; 1];
    client.read_holding(2, 0x0001, &mut w).unwrap();
    assert_eq!(w, [6000]);
    let link = TcpTransport::connect_gateway(server.local_addr(), Duration::from_secs(1)).unwrap();
    let mut client = Client::new(link, lock(&v7).profile());
    client.read_holding(1, 0x0002, &mut w).unwrap();
    assert_eq!(w, [450]);
}

/// A shared simulator served as before is a line of one: its frames for other units are still
/// its own to count.
#[test]
fn a_single_drive_is_a_line_of_one() {
    let line = Line::from(sim("yaskawa-v7", 4));
    assert_eq!(line.slaves().collect::<Vec<_>>(), [4]);
    let mut out = [0u8; tcp::MAX_FRAME];
    let frame = rtu_frame(
        5,
        &Request::ReadHolding {
            address: 2,
            quantity: 1,
        },
    );
    assert_eq!(
        line.handle(TransportKind::Rtu, &frame, &mut out).reply,
        None
    );
    let mut damaged = rtu_frame(
        4,
        &Request::ReadHolding {
            address: 2,
            quantity: 1,
        },
    );
    damaged[7] ^= 0xFF;
    let h = line.handle(TransportKind::Rtu, &damaged, &mut out);
    assert_eq!((h.reply, h.record.outcome), (None, Outcome::Damaged));
    let d = lock(&line.drives()[0]).stats();
    assert_eq!((d.not_addressed, d.damaged), (1, 1));
}
