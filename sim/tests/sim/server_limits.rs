//! The simulator as a server on a plant network: a connection cap, an idle timeout and a
//! per-frame deadline, and a well-behaved master still served while connections flood in and
//! slowloris peers trickle bytes. Loopback only; every loop bounded in count and time.

use drivemap_test_support::paths;

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_sim::{
    SimOptions, Simulator, clock::ManualClock, server::ServerOptions, server::TcpFraming,
    server::TcpServer,
};

/// Generous bound for anything the server must do "soon".
const SOON: Duration = Duration::from_secs(10);

fn server(framing: TcpFraming, options: ServerOptions) -> TcpServer {
    let path = paths::shipped_map("ptlk-tds-v8");
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    let clock = ManualClock::new();
    let sim = Simulator::new(drive, SimOptions::new().clock(Arc::new(clock))).unwrap();
    TcpServer::spawn_with(
        drivemap_sim::server::shared(sim),
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

/// Slowloris over RTU framing: one byte each 20 ms (well inside the 100 ms silence, even on a
/// loaded machine) of a 10h request announcing 246 bytes, so the frame is never whole before the
/// deadline. The connection is closed at the frame deadline (400 ms), long before the idle
/// timeout (60 s here); before, the partial frame was only dropped and the slot held until
/// the idle timeout. (Trickling `01 03 ...` made an 8-byte 03h frame every 400 ms, complete
/// right at the deadline: the test then depended on the machine's load.)
#[test]
fn rtu_over_tcp_a_frame_trickled_past_its_deadline_closes_the_connection() {
    let options = ServerOptions {
        frame_deadline: Duration::from_millis(400),
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::RtuOverTcp, options);
    let mut s = connect(srv.local_addr());
    let started = Instant::now();
    let mut closed = false;
    // Slave 1, 10h, 123 registers from 0000h, 246 bytes announced: 255 bytes in all.
    let header = [0x01, 0x10, 0x00, 0x00, 0x00, 0x7B, 0xF6];
    for i in 0..250usize {
        if s.write_all(&[header.get(i).copied().unwrap_or(0x00)])
            .is_err()
        {
            closed = true;
            break;
        }
        if closed_by_server(&mut s, Duration::from_millis(20)) {
            closed = true;
            break;
        }
    }
    assert!(closed, "closed within 250 bytes of a 255-byte frame");
    assert!(
        started.elapsed() < Duration::from_secs(8),
        "closed at the frame deadline, not the 60 s idle timeout: {:?}",
        started.elapsed()
    );
}

/// RTU over TCP: one read of 0020h x16 to unit `unit` (CRC included).
fn rtu_read16(unit: u8) -> Vec<u8> {
    let mut f = vec![unit, 0x03, 0x00, 0x20, 0x00, 0x10];
    let crc = drivemap_runtime::crc::crc16(&f);
    f.extend_from_slice(&crc.to_le_bytes());
    f
}

/// A peer that keeps talking to another unit (its frames well-formed, but not for this drive)
/// is idle as far as this drive is concerned: it is closed at the idle timeout. Before, every
/// frame to any unit reset the timer and such a peer held its slot for ever.
#[test]
fn frames_to_another_unit_do_not_keep_a_connection_alive() {
    let options = ServerOptions {
        idle_timeout: Duration::from_millis(600),
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::RtuOverTcp, options);
    let mut s = connect(srv.local_addr());
    let frame = rtu_read16(9);
    let started = Instant::now();
    let mut closed = false;
    // A frame every 150 ms (well inside the idle timeout) for at most 5 s.
    while started.elapsed() < Duration::from_secs(5) {
        if s.write_all(&frame).is_err() || closed_by_server(&mut s, Duration::from_millis(150)) {
            closed = true;
            break;
        }
    }
    assert!(
        closed,
        "closed: only requests to this drive count as activity"
    );
    assert!(
        started.elapsed() < Duration::from_secs(3),
        "{:?}",
        started.elapsed()
    );
    // A master talking to the drive's own unit (1) is kept over the same time.
    let mut m = connect(srv.local_addr());
    let mine = rtu_read16(1);
    for _ in 0..10 {
        m.write_all(&mine).unwrap();
        let mut reply = [0u8; 37];
        m.read_exact(&mut reply)
            .expect("the drive's own master is answered");
        thread::sleep(Duration::from_millis(150));
    }
}

/// Idle connections up to the cap do not lock everyone out until the idle timeout (60 s): a
/// new master takes the place of the connection that has gone longest without a request
/// (idle at least `ROOM_AFTER`); busy ones are never closed for it, and the cap still holds.
#[test]
fn a_new_master_takes_the_place_of_the_longest_idle_connection() {
    let options = ServerOptions {
        max_connections: 4,
        ..ServerOptions::default()
    };
    let srv = server(TcpFraming::ModbusTcp, options);
    // Three idle peers, oldest first, then a busy master.
    let mut idle: Vec<TcpStream> = Vec::new();
    for _ in 0..3 {
        idle.push(connect(srv.local_addr()));
        thread::sleep(Duration::from_millis(100));
    }
    let mut busy = connect(srv.local_addr());
    exchange(&mut busy, 1).unwrap();
    // Past ROOM_AFTER for the idle ones; the busy master keeps asking.
    let end = Instant::now() + drivemap_sim::server::ROOM_AFTER + Duration::from_millis(300);
    let mut tid = 2;
    while Instant::now() < end {
        exchange(&mut busy, tid).unwrap();
        tid += 1;
        thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(srv.connections(), 4);
    let mut newcomer = connect(srv.local_addr());
    exchange(&mut newcomer, 100).expect("the new master is served");
    assert!(
        closed_by_server(&mut idle[0], SOON),
        "the longest-idle connection made room"
    );
    assert!(
        srv.connections() <= 4,
        "the cap holds: {}",
        srv.connections()
    );
    exchange(&mut busy, 101).expect("the busy master was not closed");
    for s in idle.iter_mut().skip(1) {
        assert!(
            !closed_by_server(s, Duration::from_millis(50)),
            "only one made room"
        );
    }
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
                        if let Ok(s) = TcpStream::connect_timeout(&addr, Duration::from_secs(1))
                            && (attempts + k).is_multiple_of(2)
                            && slow.len() < 100
                        {
                            slow.push(s);
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
