//! Serving a simulator over real links: Modbus TCP and RTU-over-TCP listeners, serial ports, or
//! any [`Transport`].
//!
//! RTU frames are found by their length (the function code says it), checked by CRC, and a
//! frame left incomplete for longer than the silence limit is dropped, as a drive does after the
//! 3.5-character gap. A frame with an unknown function code is taken whole when the CRC of the
//! usual 8-byte request matches, or after the silence otherwise, and answered 01h.

use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
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

/// Serves requests arriving on `link` until `stop` is set or the peer hangs up. `silence` is
/// how long an incomplete RTU frame may wait for its remaining bytes before it is dropped.
pub fn serve_link<T: Transport>(
    sim: &SharedSim,
    link: &mut T,
    stop: &AtomicBool,
    log: Option<&Logger>,
    silence: Duration,
) -> io::Result<()> {
    let kind = link.kind();
    let mut buf: Vec<u8> = Vec::with_capacity(2 * tcp::MAX_FRAME);
    let mut chunk = [0u8; tcp::MAX_FRAME];
    let mut out = [0u8; tcp::MAX_FRAME];
    let mut last_byte = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        let n = match link.recv(&mut chunk, Instant::now() + POLL) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e),
        };
        if n > 0 {
            buf.extend_from_slice(&chunk[..n]);
            last_byte = Instant::now();
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
}

impl TcpServer {
    /// Binds `addr` and serves `sim` there, one thread per connection.
    pub fn spawn(
        sim: SharedSim,
        addr: impl ToSocketAddrs,
        framing: TcpFraming,
        log: Option<Logger>,
    ) -> io::Result<TcpServer> {
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let local_addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let accept = thread::Builder::new()
            .name(format!("sim-accept-{local_addr}"))
            .spawn(move || accept_loop(listener, sim, framing, log, flag))?;
        Ok(TcpServer {
            local_addr,
            stop,
            accept: Some(accept),
        })
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

fn accept_loop(
    listener: TcpListener,
    sim: SharedSim,
    framing: TcpFraming,
    log: Option<Logger>,
    stop: Arc<AtomicBool>,
) {
    let mut connections: Vec<JoinHandle<()>> = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                let (sim, log, stop) = (sim.clone(), log.clone(), stop.clone());
                let spawned =
                    thread::Builder::new()
                        .name("sim-connection".into())
                        .spawn(move || {
                            let _ = serve_stream(stream, &sim, framing, log.as_ref(), &stop);
                        });
                if let Ok(h) = spawned {
                    connections.push(h);
                }
                connections.retain(|h| !h.is_finished());
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
) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    match framing {
        TcpFraming::ModbusTcp => {
            let mut link = TcpTransport::from_stream(stream)?;
            serve_link(sim, &mut link, stop, log, Duration::from_millis(500))
        }
        TcpFraming::RtuOverTcp => {
            let mut link = RtuOverTcpTransport::from_stream(stream)?;
            serve_link(sim, &mut link, stop, log, Duration::from_millis(100))
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
            .spawn(move || serve_link(&sim, &mut link, &flag, log.as_ref(), silence))?;
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
