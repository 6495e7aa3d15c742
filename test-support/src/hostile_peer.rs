//! A scripted Modbus server on 127.0.0.1 that misbehaves on purpose: it floods, trickles, never
//! ends a frame, resets the connection mid-frame, announces an MBAP length of 65535, or answers
//! another transaction or unit.
//!
//! Bounded like every load test here: each connection is served for at most [`LIFETIME`], stops
//! when the client closes it or the `HostilePeer` is dropped, and only talks to loopback.

use std::io::{ErrorKind, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::{rtu, tcp};
use drivemap_sim::SimulatedSlave;

/// Longest a connection is served.
pub const LIFETIME: Duration = Duration::from_secs(20);

/// What the server does after each request it receives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Script {
    /// Answers correctly.
    Answer,
    /// Sends bytes without pause, as fast as the socket takes them, never the answer.
    Flood,
    /// Sends one byte every 100 ms, never the answer.
    Trickle,
    /// Sends the first half of the correct answer, then nothing.
    Unfinished,
    /// Sends the first half of the correct answer, then resets the connection (RST).
    ResetMidFrame,
    /// Modbus TCP: an MBAP header announcing 65535 bytes, then 100 bytes every 100 ms. RTU:
    /// a 03h header announcing 255 data bytes, then the same.
    LyingLength,
    /// The correct answer with another transaction id (Modbus TCP) or from another slave
    /// (RTU), twice, 50 ms apart.
    OtherTransaction,
    /// The correct answer from another unit id / slave address, twice, 50 ms apart.
    OtherUnit,
    /// The correct answer, but every `every`-th request of a connection (the 1st, the
    /// `every + 1`-th, ...) is answered `by_us` microseconds late: a slave answering just after
    /// the client's timeout. Requests that arrive meanwhile are answered after it, in order.
    Late {
        /// One request in this many is answered late.
        every: u32,
        /// How late, in microseconds.
        by_us: u64,
    },
}

/// A scripted server; stops serving when dropped.
pub struct HostilePeer {
    pub addr: SocketAddr,
    stop: Arc<AtomicBool>,
    script: Arc<Mutex<Script>>,
    /// Requests received, over all connections.
    pub requests: Arc<AtomicU32>,
    /// Connections accepted.
    pub connections: Arc<AtomicU32>,
    /// Whether to accept (false: accepted connections are closed at once).
    listener_stop: Arc<AtomicBool>,
}

impl HostilePeer {
    /// Serves `script` for a drive with `profile` at slave/unit 1, framing as `kind`, on a
    /// fresh loopback port. Holding register `a` holds `a`.
    pub fn start(kind: TransportKind, profile: &'static Profile, script: Script) -> HostilePeer {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        Self::serve(listener, kind, profile, script)
    }

    /// The same on a given address (a server restarted on its old port).
    pub fn start_at(
        addr: SocketAddr,
        kind: TransportKind,
        profile: &'static Profile,
        script: Script,
    ) -> HostilePeer {
        let deadline = Instant::now() + Duration::from_secs(5);
        let listener = loop {
            match TcpListener::bind(addr) {
                Ok(l) => break l,
                Err(e) if Instant::now() < deadline => {
                    let _ = e;
                    thread::sleep(Duration::from_millis(20));
                }
                Err(e) => panic!("binding {addr} again: {e}"),
            }
        };
        Self::serve(listener, kind, profile, script)
    }

    fn serve(
        listener: TcpListener,
        kind: TransportKind,
        profile: &'static Profile,
        script: Script,
    ) -> HostilePeer {
        let addr = listener.local_addr().unwrap();
        listener.set_nonblocking(true).unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let listener_stop = Arc::new(AtomicBool::new(false));
        let script = Arc::new(Mutex::new(script));
        let requests = Arc::new(AtomicU32::new(0));
        let connections = Arc::new(AtomicU32::new(0));
        let peer = HostilePeer {
            addr,
            stop: stop.clone(),
            script: script.clone(),
            requests: requests.clone(),
            connections: connections.clone(),
            listener_stop: listener_stop.clone(),
        };
        thread::spawn(move || {
            let until = Instant::now() + LIFETIME;
            while !stop.load(Ordering::Relaxed) && Instant::now() < until {
                match listener.accept() {
                    Ok((stream, _)) => {
                        connections.fetch_add(1, Ordering::Relaxed);
                        let (stop, script, requests) =
                            (stop.clone(), script.clone(), requests.clone());
                        thread::spawn(move || {
                            connection(stream, kind, profile, &script, &stop, &requests)
                        });
                    }
                    Err(e) if e.kind() == ErrorKind::WouldBlock => {
                        thread::sleep(Duration::from_millis(5))
                    }
                    Err(_) => thread::sleep(Duration::from_millis(5)),
                }
            }
            // The listener closes here: a restart can bind the port again.
            listener_stop.store(true, Ordering::Relaxed);
        });
        peer
    }

    /// Changes what the server does from the next request on.
    pub fn set_script(&self, script: Script) {
        *self.script.lock().unwrap() = script;
    }

    /// Stops the server: the listener and every connection close (FIN), as when the process
    /// ends. Returns once the port is free.
    pub fn shut_down(self) -> SocketAddr {
        let addr = self.addr;
        self.stop.store(true, Ordering::Relaxed);
        let deadline = Instant::now() + Duration::from_secs(5);
        while !self.listener_stop.load(Ordering::Relaxed) && Instant::now() < deadline {
            thread::sleep(Duration::from_millis(5));
        }
        // Connections notice the stop within their 20 ms read timeout.
        thread::sleep(Duration::from_millis(60));
        addr
    }
}

impl Drop for HostilePeer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

fn request_len(kind: TransportKind, buf: &[u8]) -> Option<usize> {
    if kind.is_rtu_framed() {
        rtu::request_frame_len(buf).ok().flatten()
    } else {
        tcp::Header::parse(buf)
            .ok()
            .flatten()
            .map(|h| h.frame_len())
    }
}

fn connection(
    mut stream: TcpStream,
    kind: TransportKind,
    profile: &'static Profile,
    script: &Mutex<Script>,
    stop: &AtomicBool,
    requests: &AtomicU32,
) {
    let until = Instant::now() + LIFETIME;
    let mut slave = SimulatedSlave::new(1, profile);
    for a in 0..64u16 {
        slave.set_holding(a, a);
        slave.set_input(a, a);
    }
    let _ = stream.set_nodelay(true);
    let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
    let _ = stream.set_write_timeout(Some(Duration::from_millis(20)));
    let mut buf: Vec<u8> = Vec::new();
    let mut chunk = [0u8; 512];
    let live = || !stop.load(Ordering::Relaxed) && Instant::now() < until;
    let mut served = 0u32;
    while live() {
        let Some(total) = request_len(kind, &buf).filter(|&t| t <= buf.len()) else {
            match stream.read(&mut chunk) {
                Ok(0) => return,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(_) => return,
            }
            continue;
        };
        let frame: Vec<u8> = buf.drain(..total).collect();
        requests.fetch_add(1, Ordering::Relaxed);
        let mut out = [0u8; tcp::MAX_FRAME];
        let n = slave.respond(kind, &frame, &mut out).unwrap_or(0);
        let answer = out[..n].to_vec();
        let script = *script.lock().unwrap();
        served += 1;
        let ok = match script {
            Script::Answer => stream.write_all(&answer).is_ok(),
            Script::Late { every, by_us } => {
                if (served - 1).is_multiple_of(every.max(1)) {
                    thread::sleep(Duration::from_micros(by_us));
                }
                stream.write_all(&answer).is_ok()
            }
            Script::Flood => {
                // Large writes, so the peer sends faster than a client reading a few hundred
                // bytes a call can take them.
                let noise: Vec<u8> = (0..65_536u32).map(|i| (i * 37 % 251) as u8).collect();
                let mut writes = 0u32;
                while live() {
                    match stream.write(&noise) {
                        Ok(_) => {}
                        Err(e)
                            if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                        Err(_) => return,
                    }
                    writes += 1;
                    if writes.is_multiple_of(64) {
                        drain_input(&mut stream);
                    }
                }
                return;
            }
            Script::Trickle => {
                while live() {
                    if stream.write_all(&[0x00]).is_err() {
                        return;
                    }
                    drain_input(&mut stream);
                    thread::sleep(Duration::from_millis(100));
                }
                return;
            }
            Script::Unfinished => stream.write_all(&answer[..answer.len() / 2]).is_ok(),
            Script::ResetMidFrame => {
                let _ = stream.write_all(&answer[..answer.len() / 2]);
                thread::sleep(Duration::from_millis(30));
                let _ = rustix::net::sockopt::set_socket_linger(&stream, Some(Duration::ZERO));
                return; // dropped with linger 0: RST
            }
            Script::LyingLength => {
                let header: Vec<u8> = if kind.is_rtu_framed() {
                    vec![1, 0x03, 0xFF]
                } else {
                    vec![frame[0], frame[1], 0, 0, 0xFF, 0xFF, frame[6], 0x03, 0xFF]
                };
                if stream.write_all(&header).is_err() {
                    return;
                }
                while live() {
                    if stream.write_all(&[0x5A; 100]).is_err() {
                        return;
                    }
                    drain_input(&mut stream);
                    thread::sleep(Duration::from_millis(100));
                }
                return;
            }
            // A request the slave does not answer (another unit, a broadcast): nothing to
            // disguise as another transaction's or unit's reply.
            Script::OtherTransaction | Script::OtherUnit if answer.is_empty() => true,
            Script::OtherTransaction | Script::OtherUnit => {
                let mut wrong = answer.clone();
                if kind.is_rtu_framed() {
                    // RTU has no transaction: another slave's answer, CRC intact.
                    wrong[0] = 2;
                    let c = drivemap_runtime::crc::crc_bytes(&wrong[..n - 2]);
                    wrong[n - 2..].copy_from_slice(&c);
                } else if script == Script::OtherTransaction {
                    // 256 ahead: not the id of the client's next attempt either.
                    wrong[0] = wrong[0].wrapping_add(1);
                } else {
                    wrong[6] = 2;
                }
                // Twice, then on to the next request (the client's retry gets its own).
                let once = stream.write_all(&wrong).is_ok();
                thread::sleep(Duration::from_millis(50));
                once && stream.write_all(&wrong).is_ok()
            }
        };
        if !ok {
            return;
        }
    }
    let _ = stream.shutdown(Shutdown::Both);
}

/// Reads and drops what the client sent meanwhile (its retries), so it never blocks on a full
/// socket; returns when nothing is there.
fn drain_input(stream: &mut TcpStream) {
    let mut chunk = [0u8; 512];
    let _ = stream.set_nonblocking(true);
    while let Ok(n) = stream.read(&mut chunk) {
        if n == 0 {
            break;
        }
    }
    let _ = stream.set_nonblocking(false);
}
