//! The client over the in-memory pair and over real TCP sockets on the loopback interface, with
//! a simulated drive serving the other end in a thread.

use crate::common;

use std::net::TcpListener;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::memory::MemoryTransport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_sim::SimulatedSlave;

use common::{ACN, V7, strict};

fn drive(profile: &'static drivemap_runtime::core::profile::Profile) -> SimulatedSlave {
    let mut slave = SimulatedSlave::new(1, profile);
    slave.set_holding(0x0020, 0x1770);
    slave.set_input(0x02FF, 0x0006);
    slave
}

fn exercise<T: drivemap_runtime::transport::Transport>(client: &mut Client<T>) {
    let mut r = [0u16; 1];
    client.read_holding(1, 0x0020, &mut r).unwrap();
    assert_eq!(r, [0x1770]);
    client.write_registers(1, 0x0001, &[1, 600]).unwrap();
    let mut r = [0u16; 2];
    client.read_holding(1, 0x0001, &mut r).unwrap();
    assert_eq!(r, [1, 600]);
}

#[test]
fn memory_pair_rtu_and_tcp() {
    for kind in [TransportKind::Rtu, TransportKind::Tcp] {
        let (client_end, mut drive_end) = MemoryTransport::pair(kind);
        let server = thread::spawn(move || {
            drive(&V7)
                .serve(&mut drive_end, Instant::now() + Duration::from_millis(600))
                .unwrap()
        });
        let mut client = Client::with_options(client_end, &V7, strict());
        exercise(&mut client);
        client.loop_back(1, 0x1234).unwrap();
        assert_eq!(server.join().unwrap(), 4, "{kind:?}");
    }
}

fn tcp_server(kind: TransportKind) -> (u16, thread::JoinHandle<u32>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let handle = thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        let mut link: Box<dyn drivemap_runtime::transport::Transport> = match kind {
            TransportKind::Tcp => Box::new(TcpTransport::from_stream(stream).unwrap()),
            _ => Box::new(RtuOverTcpTransport::from_stream(stream).unwrap()),
        };
        drive(&ACN)
            .serve(&mut link, Instant::now() + Duration::from_millis(800))
            .unwrap()
    });
    (port, handle)
}

#[test]
fn modbus_tcp_over_a_socket() {
    let (port, server) = tcp_server(TransportKind::Tcp);
    let link = TcpTransport::connect(("127.0.0.1", port), Duration::from_secs(1)).unwrap();
    let mut client = Client::with_options(link, &ACN, strict());
    // The ACN's TCP offset is 0: communication address = PDU address.
    exercise(&mut client);
    let mut r = [0u16; 1];
    client.read_input(1, 0x02FF, &mut r).unwrap();
    assert_eq!(r, [6]);
    drop(client);
    assert_eq!(server.join().unwrap(), 4);
}

#[test]
fn rtu_over_tcp_over_a_socket() {
    let (port, server) = tcp_server(TransportKind::RtuOverTcp);
    let link = RtuOverTcpTransport::connect(("127.0.0.1", port), Duration::from_secs(1)).unwrap();
    let mut client = Client::with_options(link, &ACN, strict());
    // RTU framing uses the ACN's RTU offset (-1): communication 0x0021 is PDU 0x0020.
    let mut r = [0u16; 1];
    client.read_holding(1, 0x0021, &mut r).unwrap();
    assert_eq!(r, [0x1770]);
    client.write_register(1, 0x0002, 600).unwrap();
    let mut r = [0u16; 1];
    client.read_holding(1, 0x0002, &mut r).unwrap();
    assert_eq!(r, [600]);
    drop(client);
    assert_eq!(server.join().unwrap(), 3);
}
