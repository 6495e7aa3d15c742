//! The simulator as a server among hostile peers on loopback: a connection cap, an idle
//! timeout, a deadline for a started frame, and a well-behaved master served throughout a flood
//! of connections and a slowloris. Every loop here is bounded in count and time.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{Client, ClientOptions};
use drivemap_sim::{Limits, SimOptions, Simulator, TcpFraming, TcpServer, shared};

fn server(limits: Limits) -> (TcpServer, &'static drivemap_runtime::Profile) {
    let path = format!("{}/../maps/ptlk-tds-v8.yaml", env!("CARGO_MANIFEST_DIR"));
    let drive = drivemap_codegen::read_map(path.as_ref(), &Default::default()).unwrap();
    let profile = drivemap_live::leak_profile(&drive);
    let sim = Simulator::new(drive, SimOptions::default()).unwrap();
    let server = TcpServer::spawn_with(
        shared(sim),
        "127.0.0.1:0",
        TcpFraming::ModbusTcp,
        None,
        limits,
    )
    .unwrap();
    (server, profile)
}

/// Whether the server closed `stream` within `within` (reads EOF or a reset).
fn closed_within(stream: &mut TcpStream, within: Duration) -> bool {
    stream
        .set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let deadline = Instant::now() + within;
    let mut buf = [0u8; 64];
    while Instant::now() < deadline {
        match stream.read(&mut buf) {
            Ok(0) => return true,
            Ok(_) => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return true,
        }
    }
    false
}

/// A read of 0020h (inverter status), as a master polls it.
const READ_STATUS: [u8; 12] = [
    0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x03, 0x00, 0x20, 0x00, 0x01,
];

#[test]
fn connections_beyond_the_cap_are_closed_at_once() {
    let (server, _) = server(Limits {
        max_connections: 4,
        ..Limits::default()
    });
    let addr = server.local_addr();
    let held: Vec<TcpStream> = (0..4).map(|_| TcpStream::connect(addr).unwrap()).collect();
    let deadline = Instant::now() + Duration::from_secs(5);
    while server.connections() < 4 {
        assert!(Instant::now() < deadline, "4 connections not served");
        thread::sleep(Duration::from_millis(5));
    }
    let mut fifth = TcpStream::connect(addr).unwrap();
    assert!(
        closed_within(&mut fifth, Duration::from_secs(2)),
        "the fifth connection was kept"
    );
    assert_eq!(server.connections(), 4);
    // A slot freed is a slot served.
    drop(held);
    let deadline = Instant::now() + Duration::from_secs(5);
    while server.connections() > 0 {
        assert!(
            Instant::now() < deadline,
            "closed connections still counted"
        );
        thread::sleep(Duration::from_millis(5));
    }
    let mut again = TcpStream::connect(addr).unwrap();
    again.write_all(&READ_STATUS).unwrap();
    again
        .set_read_timeout(Some(Duration::from_secs(2)))
        .unwrap();
    let mut reply = [0u8; 11];
    again.read_exact(&mut reply).unwrap();
    assert_eq!(&reply[..2], &[0x00, 0x01], "answered transaction 1");
}

#[test]
fn an_idle_connection_is_closed_after_the_idle_timeout() {
    let (server, _) = server(Limits {
        idle_timeout: Some(Duration::from_millis(300)),
        ..Limits::default()
    });
    let mut idle = TcpStream::connect(server.local_addr()).unwrap();
    let t = Instant::now();
    assert!(closed_within(&mut idle, Duration::from_secs(3)));
    assert!(
        t.elapsed() >= Duration::from_millis(250),
        "closed too early"
    );
}

#[test]
fn a_frame_left_half_sent_closes_its_connection() {
    let (server, _) = server(Limits {
        frame_timeout: Some(Duration::from_millis(500)),
        ..Limits::default()
    });
    let mut half = TcpStream::connect(server.local_addr()).unwrap();
    half.write_all(&READ_STATUS[..7]).unwrap();
    assert!(closed_within(&mut half, Duration::from_secs(3)));
    // Trickling one byte per 100 ms never completes a frame in time either.
    let mut trickle = TcpStream::connect(server.local_addr()).unwrap();
    let t = Instant::now();
    let mut closed = false;
    for b in READ_STATUS.iter().cycle().take(60) {
        if trickle.write_all(&[*b]).is_err() {
            closed = true;
            break;
        }
        thread::sleep(Duration::from_millis(100));
        if t.elapsed() > Duration::from_secs(3) {
            break;
        }
    }
    assert!(
        closed || closed_within(&mut trickle, Duration::from_secs(1)),
        "a trickling peer held its connection for {:?}",
        t.elapsed()
    );
}

/// 5,000 connection attempts and 100 slowloris peers against a server with the default limits,
/// while a master that connected first polls every 20 ms: every poll is answered, none waits
/// long, and the server never serves more connections than its cap.
#[test]
fn a_master_is_served_through_a_connection_flood_and_a_slowloris() {
    let limits = Limits::default();
    let (server, profile) = server(limits);
    let addr: SocketAddr = server.local_addr();
    let link = TcpTransport::connect(addr, Duration::from_secs(1)).unwrap();
    let mut master = Client::with_options(
        link,
        profile,
        ClientOptions {
            timeout: Duration::from_millis(500),
            retries: 0,
            ..ClientOptions::default()
        },
    );
    let stop = Arc::new(AtomicBool::new(false));
    let flood = {
        let stop = stop.clone();
        thread::spawn(move || {
            let mut held = Vec::new();
            for i in 0..5_000 {
                if stop.load(Ordering::Relaxed) {
                    break;
                }
                if let Ok(s) = TcpStream::connect_timeout(&addr, Duration::from_millis(200)) {
                    // Keep some open to fill the cap; let the rest go.
                    if i % 50 == 0 {
                        held.push(s);
                    }
                }
            }
            held.len()
        })
    };
    let slowloris: Vec<_> = (0..100)
        .map(|_| {
            let stop = stop.clone();
            thread::spawn(move || {
                let Ok(mut s) = TcpStream::connect_timeout(&addr, Duration::from_millis(200))
                else {
                    return;
                };
                for b in READ_STATUS.iter().cycle().take(100) {
                    if stop.load(Ordering::Relaxed) || s.write_all(&[*b]).is_err() {
                        return;
                    }
                    thread::sleep(Duration::from_millis(100));
                }
            })
        })
        .collect();
    let mut worst = Duration::ZERO;
    let mut most = 0;
    let until = Instant::now() + Duration::from_secs(6);
    let mut polls = 0;
    while Instant::now() < until {
        let mut words = [0u16; 1];
        let t = Instant::now();
        master
            .read_holding(1, 0x0020, &mut words)
            .unwrap_or_else(|e| panic!("poll {polls} during the attack: {e}"));
        worst = worst.max(t.elapsed());
        most = most.max(server.connections());
        polls += 1;
        thread::sleep(Duration::from_millis(20));
    }
    stop.store(true, Ordering::Relaxed);
    let held = flood.join().unwrap();
    for s in slowloris {
        s.join().unwrap();
    }
    eprintln!(
        "{polls} polls answered, worst {worst:?}; at most {most} connections served; flood held {held}"
    );
    assert!(polls > 100, "only {polls} polls in 6 s");
    assert!(
        worst < Duration::from_millis(400),
        "a poll waited {worst:?}"
    );
    assert!(
        most <= limits.max_connections,
        "{most} connections served, cap {}",
        limits.max_connections
    );
    let _ = TransportKind::Tcp;
}
