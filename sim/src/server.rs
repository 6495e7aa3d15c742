//! Serving a simulator over real links: Modbus TCP and RTU-over-TCP listeners, serial ports, or
//! any [`Transport`].
//!
//! RTU frames are found by their length (the function code says it), checked by CRC, and a
//! frame left incomplete for longer than the silence limit is dropped, as a drive does after the
//! 3.5-character gap. A frame with an unknown function code is taken whole when the CRC of the
//! usual 8-byte request matches, or after the silence otherwise, and answered 01h.
//!
//! On a network the simulator is a server among hostile peers, so a TCP listener has [`Limits`]:
//! at most [`Limits::max_connections`] connections served at once (one more is accepted and
//! closed at once, so nothing piles up in the kernel's backlog), each closed after
//! [`Limits::idle_timeout`] without a byte, or when a frame it started is not complete within
//! [`Limits::frame_timeout`] (a peer that trickles a byte at a time never holds a connection).
//! A master that keeps asking keeps its connection whatever the others do.

use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{crc, rtu, tcp};

use crate::simulator::{RequestRecord, Simulator};

/// A simulator shared between connections.
pub type SharedSim = Arc<Mutex<Simulator>>;

/// Receives one record per request handled.
pub type Logger = Arc<dyn Fn(&RequestRecord) + Send + Sync>;

/// Wraps a simulator for serving.
pub fn shared(sim: Simulator) -> SharedSim {
    Arc::new(Mutex::new(sim))
}

/// Locks a shared simulator; a panic in another connection does not poison it for the others.
pub fn lock(sim: &SharedSim) -> MutexGuard<'_, Simulator> {
    match sim.lock() {
        Ok(g) => g,
        Err(poisoned) => poisoned.into_inner(),
    }
}

/// What a listener allows its peers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Connections served at once; one more is closed as soon as it is accepted.
    pub max_connections: usize,
    /// A connection that sends nothing for this long is closed (`None`: never).
    pub idle_timeout: Option<Duration>,
    /// A frame whose first byte arrived this long ago and that is still incomplete closes its
    /// connection (`None`: no limit beyond the RTU silence).
    pub frame_timeout: Option<Duration>,
}

impl Limits {
    /// No limit: for a serial line, which has one master and no connections.
    pub const NONE: Limits = Limits {
        max_connections: usize::MAX,
        idle_timeout: None,
        frame_timeout: None,
    };
}

impl Default for Limits {
    /// 64 connections, 60 s idle, 2 s to complete a frame: a plant network's few masters poll
    /// far more often than once a minute, and a Modbus frame of at most 260 bytes takes
    /// milliseconds to arrive.
    fn default() -> Self {
        Limits {
            max_connections: 64,
            idle_timeout: Some(Duration::from_secs(60)),
            frame_timeout: Some(Duration::from_secs(2)),
        }
    }
}

/// How often a serving loop looks at its stop flag.
const POLL: Duration = Duration::from_millis(25);

/// The bytes of an RTU request frame at the start of `buf`, once complete: `Ok(Some(len))`.
/// `Ok(None)` while more bytes are needed; `Err(())` when the function code is unknown and the
/// length cannot be told.
fn rtu_frame(buf: &[u8]) -> Result<Option<usize>, ()> {
    match rtu::request_frame_len(buf) {
        Ok(Some(len)) if len <= buf.len() => Ok(Some(len)),
        Ok(_) => Ok(None),
        Err(_) => {
            // Unknown function: most Modbus requests are 8 bytes; take them when the CRC agrees.
            if buf.len() >= 8 && crc::check(&buf[..8]).is_ok() {
                Ok(Some(8))
            } else {
                Err(())
            }
        }
    }
}

/// Serves requests arriving on `link` until `stop` is set, the peer hangs up, or it breaks
/// `limits` (idle too long, a frame not completed in time). `silence` is how long an incomplete
/// RTU frame may wait for its remaining bytes before it is dropped.
pub fn serve_link<T: Transport>(
    sim: &SharedSim,
    link: &mut T,
    stop: &AtomicBool,
    log: Option<&Logger>,
    silence: Duration,
    limits: &Limits,
) -> io::Result<()> {
    let kind = link.kind();
    let mut buf: Vec<u8> = Vec::with_capacity(2 * tcp::MAX_FRAME);
    let mut chunk = [0u8; tcp::MAX_FRAME];
    let mut out = [0u8; tcp::MAX_FRAME];
    let mut last_byte = Instant::now();
    // When the oldest byte still waiting in `buf` arrived.
    let mut frame_started: Option<Instant> = None;
    while !stop.load(Ordering::Relaxed) {
        let n = match link.recv(&mut chunk, Instant::now() + POLL) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e),
        };
        let now = Instant::now();
        if n > 0 {
            buf.extend_from_slice(&chunk[..n]);
            last_byte = now;
            frame_started.get_or_insert(now);
        } else if limits
            .idle_timeout
            .is_some_and(|idle| now.duration_since(last_byte) >= idle)
        {
            return Ok(());
        }
        if let (Some(start), Some(limit)) = (frame_started, limits.frame_timeout) {
            if now.duration_since(start) >= limit {
                return Ok(());
            }
        }
        let quiet = last_byte.elapsed() >= silence;
        loop {
            let len = if kind.is_rtu_framed() {
                match rtu_frame(&buf) {
                    Ok(Some(len)) => len,
                    Ok(None) if quiet && !buf.is_empty() => buf.len(),
                    Ok(None) => break,
                    Err(()) if quiet => buf.len(),
                    Err(()) => break,
                }
            } else {
                match tcp::Header::parse(&buf) {
                    Ok(Some(h)) if h.frame_len() <= buf.len() => h.frame_len(),
                    Ok(_) => break,
                    // The stream is out of step: a Modbus TCP server closes the connection.
                    Err(_) => return Ok(()),
                }
            };
            if len == 0 {
                break;
            }
            let handled = lock(sim).handle(kind, &buf[..len], &mut out);
            if let Some(log) = log {
                log(&handled.record);
            }
            if let Some(m) = handled.reply {
                link.send(&out[..m])?;
            }
            buf.drain(..len);
            // The bytes left over start the next frame.
            frame_started = (!buf.is_empty()).then_some(now);
        }
        if buf.len() > 4 * tcp::MAX_FRAME {
            buf.clear();
        }
    }
    Ok(())
}

/// Framing of a TCP listener.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TcpFraming {
    /// Modbus TCP (MBAP header).
    ModbusTcp,
    /// RTU frames over TCP, as a transparent serial gateway forwards them.
    RtuOverTcp,
}

/// A listening TCP server; stops when dropped.
pub struct TcpServer {
    local_addr: SocketAddr,
    stop: Arc<AtomicBool>,
    accept: Option<JoinHandle<()>>,
    live: Arc<AtomicUsize>,
}

impl TcpServer {
    /// Binds `addr` and serves `sim` there, one thread per connection, with the default
    /// [`Limits`].
    pub fn spawn(
        sim: SharedSim,
        addr: impl ToSocketAddrs,
        framing: TcpFraming,
        log: Option<Logger>,
    ) -> io::Result<TcpServer> {
        Self::spawn_with(sim, addr, framing, log, Limits::default())
    }

    /// [`TcpServer::spawn`] with explicit limits.
    pub fn spawn_with(
        sim: SharedSim,
        addr: impl ToSocketAddrs,
        framing: TcpFraming,
        log: Option<Logger>,
        limits: Limits,
    ) -> io::Result<TcpServer> {
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let local_addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let live = Arc::new(AtomicUsize::new(0));
        let (flag, count) = (stop.clone(), live.clone());
        let accept = thread::Builder::new()
            .name(format!("sim-accept-{local_addr}"))
            .spawn(move || accept_loop(listener, sim, framing, log, flag, limits, count))?;
        Ok(TcpServer {
            local_addr,
            stop,
            accept: Some(accept),
            live,
        })
    }

    /// Connections being served now.
    pub fn connections(&self) -> usize {
        self.live.load(Ordering::Relaxed)
    }

    /// The address the server listens on (the port chosen when binding port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Serves until the process ends.
    pub fn wait(mut self) {
        if let Some(h) = self.accept.take() {
            let _ = h.join();
        }
    }

    /// Stops accepting and closes every connection.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.accept.take() {
            let _ = h.join();
        }
    }
}

impl Drop for TcpServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Decrements the live-connection count when a connection's thread ends, however it ends.
struct Live(Arc<AtomicUsize>);

impl Drop for Live {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::Relaxed);
    }
}

fn accept_loop(
    listener: TcpListener,
    sim: SharedSim,
    framing: TcpFraming,
    log: Option<Logger>,
    stop: Arc<AtomicBool>,
    limits: Limits,
    live: Arc<AtomicUsize>,
) {
    let mut connections: Vec<JoinHandle<()>> = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                connections.retain(|h| !h.is_finished());
                if live.load(Ordering::Relaxed) >= limits.max_connections {
                    // Full: close at once rather than leave the peer waiting in the backlog.
                    drop(stream);
                    continue;
                }
                live.fetch_add(1, Ordering::Relaxed);
                let guard = Live(live.clone());
                let (sim, log, stop) = (sim.clone(), log.clone(), stop.clone());
                let spawned =
                    thread::Builder::new()
                        .name("sim-connection".into())
                        .spawn(move || {
                            let _guard = guard;
                            let _ =
                                serve_stream(stream, &sim, framing, log.as_ref(), &stop, &limits);
                        });
                if let Ok(h) = spawned {
                    connections.push(h);
                }
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => thread::sleep(POLL / 2),
            Err(_) => thread::sleep(POLL),
        }
    }
    for h in connections {
        let _ = h.join();
    }
}

fn serve_stream(
    stream: TcpStream,
    sim: &SharedSim,
    framing: TcpFraming,
    log: Option<&Logger>,
    stop: &AtomicBool,
    limits: &Limits,
) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    match framing {
        TcpFraming::ModbusTcp => {
            let mut link = TcpTransport::from_stream(stream)?;
            serve_link(
                sim,
                &mut link,
                stop,
                log,
                Duration::from_millis(500),
                limits,
            )
        }
        TcpFraming::RtuOverTcp => {
            let mut link = RtuOverTcpTransport::from_stream(stream)?;
            serve_link(
                sim,
                &mut link,
                stop,
                log,
                Duration::from_millis(100),
                limits,
            )
        }
    }
}

/// A simulator serving a serial port in a thread; stops when dropped.
#[cfg(feature = "serial")]
pub struct SerialServer {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<io::Result<()>>>,
}

#[cfg(feature = "serial")]
impl SerialServer {
    /// Opens the port and serves `sim` on it.
    pub fn spawn(
        sim: SharedSim,
        options: drivemap_runtime::transport::serial::SerialOptions,
        log: Option<Logger>,
    ) -> io::Result<SerialServer> {
        use drivemap_runtime::transport::serial::{SerialTransport, USB_LATENCY};
        let silence = options.frame_gap() + USB_LATENCY;
        let mut link = SerialTransport::open(options)?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = thread::Builder::new()
            .name("sim-serial".into())
            .spawn(move || {
                serve_link(&sim, &mut link, &flag, log.as_ref(), silence, &Limits::NONE)
            })?;
        Ok(SerialServer {
            stop,
            thread: Some(thread),
        })
    }

    /// Serves until the port fails; returns its error.
    pub fn wait(mut self) -> io::Result<()> {
        match self.thread.take() {
            Some(h) => h
                .join()
                .unwrap_or_else(|_| Err(io::Error::other("the serving thread panicked"))),
            None => Ok(()),
        }
    }

    /// Stops serving.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.thread.take() {
            let _ = h.join();
        }
    }
}

#[cfg(feature = "serial")]
impl Drop for SerialServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Which transport kind a TCP framing carries.
pub fn kind_of(framing: TcpFraming) -> TransportKind {
    match framing {
        TcpFraming::ModbusTcp => TransportKind::Tcp,
        TcpFraming::RtuOverTcp => TransportKind::RtuOverTcp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rtu_frames_are_found_by_length_or_by_crc() {
        let read = [0x01, 0x03, 0x00, 0x20, 0x00, 0x01, 0x85, 0xC0];
        assert_eq!(rtu_frame(&read), Ok(Some(8)));
        assert_eq!(rtu_frame(&read[..5]), Ok(None));
        // 01h (read coils) is not a drive function but has the usual 8-byte shape.
        let mut coils = [0x01, 0x01, 0x00, 0x00, 0x00, 0x01, 0, 0];
        let c = crc::crc_bytes(&coils[..6]);
        coils[6..].copy_from_slice(&c);
        assert_eq!(rtu_frame(&coils), Ok(Some(8)));
        assert_eq!(rtu_frame(&coils[..7]), Err(()));
    }
}
