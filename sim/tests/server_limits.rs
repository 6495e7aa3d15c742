//! The simulator as a server on a plant network: a connection cap, an idle timeout and a
//! per-frame deadline, and a well-behaved master still served while connections flood in and
//! slowloris peers trickle bytes. Loopback only; every loop bounded in count and time.

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_sim::{ManualClock, ServerOptions, SimOptions, Simulator, TcpFraming, TcpServer};

/// Generous bound for anything the server must do "soon".
const SOON: Duration = Duration::from_secs(10);

fn server(framing: TcpFraming, options: ServerOptions) -> TcpServer {
    let path = format!("{}/../maps/ptlk-tds-v8.yaml", env!("CARGO_MANIFEST_DIR"));
    let drive = drivemap_codegen::read_map(path.as_ref(), &Default::default()).unwrap();
    let clock = ManualClock::new();
    let sim = Simulator::new(drive, SimOptions::new().clock(Arc::new(clock))).unwrap();
    TcpServer::spawn_with(
        drivemap_sim::shared(sim),
        "127.0.0.1:0",
        framing,
        None,
        options,
    )
    .unwrap()
}

/// Modbus TCP: read 16 monitor registers from 0020h, unit 1.
fn read16(tid: u16) -> [u8; 12] {
    let t = tid.to_be_bytes();
    [t[0], t[1], 0, 0, 0, 6, 1, 0x03, 0x00, 0x20, 0x00, 0x10]
}

fn connect(addr: SocketAddr) -> TcpStream {
    let s = TcpStream::connect_timeout(&addr, SOON).unwrap();
    s.set_read_timeout(Some(SOON)).unwrap();
    s.set_nodelay(true).unwrap();
    s
}

/// One request, its whole 41-byte reply.
fn exchange(s: &mut TcpStream, tid: u16) -> std::io::Result<[u8; 41]> {
    s.write_all(&read16(tid))?;
    let mut reply = [0u8; 41];
    s.read_exact(&mut reply)?;
    assert_eq!(&reply[..2], &tid.to_be_bytes());
    assert_eq!(reply[7], 0x03, "a normal reply");
    Ok(reply)
}

/// True when the server closed `s` within `within` (a read returns end of stream or a reset).
fn closed_by_server(s: &mut TcpStream, within: Duration) -> bool {
    s.set_read_timeout(Some(within)).unwrap();
    let mut b = [0u8; 64];
    let end = Instant::now() + within;
    while Instant::now() < end {
        match s.read(&mut b) {
            Ok(0) => return true,
            Ok(_) => continue,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return false;
            }
            Err(_) => return true,
        }
    }
    false
}

#[test]
fn connections_over_the_cap_are_closed_at_once_and_the_others_served() {
    let options = ServerOptions {
        max_connections: 4,
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::ModbusTcp, options);
    let mut held: Vec<TcpStream> = (0..4).map(|_| connect(srv.local_addr())).collect();
    for (i, s) in held.iter_mut().enumerate() {
        exchange(s, i as u16).unwrap();
    }
    assert_eq!(srv.connections(), 4);
    let mut extra = connect(srv.local_addr());
    assert!(
        closed_by_server(&mut extra, SOON),
        "the fifth connection is refused"
    );
    assert!(
        exchange(&mut held[0], 99).is_ok(),
        "the first four are still served"
    );
    // Once one leaves, a new one is served.
    drop(held.pop());
    let end = Instant::now() + SOON;
    while srv.connections() > 3 && Instant::now() < end {
        thread::sleep(Duration::from_millis(10));
    }
    let mut late = connect(srv.local_addr());
    assert!(exchange(&mut late, 7).is_ok());
}

#[test]
fn an_idle_connection_is_closed_after_the_idle_timeout() {
    let options = ServerOptions {
        idle_timeout: Duration::from_millis(300),
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::ModbusTcp, options);
    let mut s = connect(srv.local_addr());
    exchange(&mut s, 1).unwrap();
    assert!(closed_by_server(&mut s, SOON));
    let end = Instant::now() + SOON;
    while srv.connections() > 0 && Instant::now() < end {
        thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(srv.connections(), 0, "its thread is gone");
}

#[test]
fn a_modbus_tcp_frame_not_finished_within_the_deadline_closes_the_connection() {
    let options = ServerOptions {
        frame_deadline: Duration::from_millis(400),
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::ModbusTcp, options);
    let mut s = connect(srv.local_addr());
    // Slowloris: a header announcing 254 bytes, then one byte every 100 ms: the frame would
    // take 26 s to complete; the loop gives up after 100 bytes (10 s).
    let header = [0x00, 0x05, 0x00, 0x00, 0x00, 0xFE];
    let started = Instant::now();
    let mut closed = false;
    for i in 0..100 {
        if s.write_all(&[header.get(i).copied().unwrap_or(0x01)])
            .is_err()
        {
            closed = true;
            break;
        }
        if closed_by_server(&mut s, Duration::from_millis(100)) {
            closed = true;
            break;
        }
    }
    assert!(closed, "the connection trickling one frame is closed");
    assert!(started.elapsed() < SOON);
}

#[test]
fn rtu_over_tcp_garbage_trickled_forever_is_closed_by_the_idle_timeout() {
    let options = ServerOptions {
        idle_timeout: Duration::from_millis(800),
        frame_deadline: Duration::from_millis(400),
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::RtuOverTcp, options);
    let mut s = connect(srv.local_addr());
    // One byte each 50 ms (inside the 100 ms silence), never a whole frame: the partial frame
    // is dropped at the deadline, and since nothing well-formed ever comes, the link goes.
    let mut closed = false;
    for i in 0..200u32 {
        if s.write_all(&[0x01, 0x03][i as usize % 2..][..1]).is_err() {
            closed = true;
            break;
        }
        if closed_by_server(&mut s, Duration::from_millis(50)) {
            closed = true;
            break;
        }
    }
    assert!(closed, "closed within 200 bytes (10 s)");
}

#[test]
fn a_master_is_served_through_a_flood_of_connections_and_slowloris_peers() {
    let options = ServerOptions {
        max_connections: 32,
        idle_timeout: Duration::from_secs(2),
        frame_deadline: Duration::from_secs(1),
    };
    let srv = server(TcpFraming::ModbusTcp, options);
    let addr = srv.local_addr();
    let mut master = connect(addr);
    exchange(&mut master, 0).unwrap();
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let attackers: Vec<_> = (0..2)
        .map(|k| {
            let stop = stop.clone();
            thread::spawn(move || {
                let mut slow: Vec<TcpStream> = Vec::new();
                let mut attempts = 0u32;
                let end = Instant::now() + Duration::from_secs(20);
                while !stop.load(std::sync::atomic::Ordering::Relaxed) && Instant::now() < end {
                    // Floods: connection attempts, half of them kept open trickling one byte
                    // per 100 ms; 2,500 attempts per thread, 5,000 in all.
                    for _ in 0..25 {
                        if attempts >= 2500 {
                            break;
                        }
                        attempts += 1;
                        if let Ok(s) = TcpStream::connect_timeout(&addr, Duration::from_secs(1)) {
                            if (attempts + k) % 2 == 0 && slow.len() < 100 {
                                slow.push(s);
                            }
                        }
                    }
                    slow.retain_mut(|s| s.write_all(&[0x00]).is_ok());
                    thread::sleep(Duration::from_millis(100));
                }
                attempts
            })
        })
        .collect();
    let mut latencies = Vec::new();
    let mut most = 0;
    for tid in 1..=1000u16 {
        let t = Instant::now();
        exchange(&mut master, tid).expect("the master is answered during the attack");
        latencies.push(t.elapsed());
        most = most.max(srv.connections());
        if attackers.iter().all(|h| h.is_finished()) {
            break;
        }
        thread::sleep(Duration::from_millis(20));
    }
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let attempts: u32 = attackers.into_iter().map(|h| h.join().unwrap()).sum();
    latencies.sort();
    let at = |q: usize| latencies[(latencies.len() - 1) * q / 100];
    eprintln!(
        "master under attack ({attempts} connection attempts, {} requests): latency median {:?}, \
         p99 {:?}, max {:?}; at most {most} connections served at once",
        latencies.len(),
        at(50),
        at(99),
        at(100)
    );
    assert!(
        most <= 32,
        "{most} connections served at once, over the cap"
    );
}
