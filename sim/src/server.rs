//! Serving a simulator over real links: Modbus TCP, RTU-over-TCP and ASCII-over-TCP listeners,
//! serial ports (RTU or ASCII), or any [`Transport`].
//!
//! Modbus ASCII frames run from `:` to LF; each is checked ([`ascii::to_rtu`]: hexadecimal
//! digits, LRC, CR LF) and handed to the drive as the RTU frame with the same address and PDU,
//! and the drive's reply is sent back as ASCII. A damaged ASCII frame, or characters outside a
//! frame, are a damaged frame: no reply.
//!
//! RTU frames are found by their length (the function code says it), checked by CRC, and a
//! frame left incomplete for longer than the silence limit is dropped, as a drive does after the
//! 3.5-character gap. A frame with an unknown function code is taken whole when the CRC of the
//! usual 8-byte request matches, or after the silence otherwise, and answered 01h.

use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::ascii_over_tcp::AsciiOverTcpTransport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{ascii, crc, rtu, tcp};

use crate::Line;
use crate::{Outcome, RequestRecord, Simulator};

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

/// The characters at the start of `buf` to hand over at once, in Modbus ASCII: a frame from
/// `:` through LF; what comes before a `:` (characters outside a frame), or a frame broken off
/// by the next `:`, as a damaged frame. `None` while a frame is still arriving.
fn ascii_frame(buf: &[u8]) -> Option<usize> {
    let first = buf.first()?;
    if *first != ascii::START {
        return Some(
            buf.iter()
                .position(|&c| c == ascii::START)
                .unwrap_or(buf.len()),
        );
    }
    for (i, &c) in buf.iter().enumerate().skip(1) {
        match c {
            ascii::START => return Some(i),
            b'\n' => return Some(i + 1),
            _ => {}
        }
    }
    None
}

/// Limits on how a connection or line may hold a partial frame or sit idle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameLimits {
    /// How long an incomplete RTU frame may wait for its next byte before it is dropped (the
    /// 3.5-character silence, plus transport latency).
    pub silence: Duration,
    /// How long a frame, once its first byte arrived, may take to arrive whole. Past it an RTU
    /// frame is dropped (as after a silence) and a Modbus TCP connection is closed (its stream
    /// cannot be put back in step).
    pub frame_deadline: Duration,
    /// A connection that sent no well-formed request for this long is closed (`None`: never;
    /// serial lines). Damaged frames and partial bytes do not count as activity, so a peer
    /// trickling bytes (slowloris) or garbage is closed too.
    pub idle_timeout: Option<Duration>,
}

impl Default for FrameLimits {
    /// 100 ms silence, 1 s per frame, 60 s idle.
    fn default() -> FrameLimits {
        FrameLimits {
            silence: Duration::from_millis(100),
            frame_deadline: Duration::from_secs(1),
            idle_timeout: Some(Duration::from_secs(60)),
        }
    }
}

/// The most bytes a framer holds: a partial frame cannot be longer than one frame, so more than
/// this is garbage and is dropped.
const BUF_BUDGET: usize = 2 * tcp::MAX_FRAME;

/// What a [`Framer`] has found in the bytes received so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Next {
    /// The first `n` bytes are one frame (or, on RTU, bytes to hand over whole as a damaged
    /// frame after a silence or the frame deadline): answer it, then [`Framer::consume`] it.
    Frame(usize),
    /// More bytes are needed.
    Wait,
    /// The stream is out of step (bad MBAP header, or a Modbus TCP frame past its deadline):
    /// close the connection.
    Close,
}

/// Cuts a byte stream into request frames: RTU by length and CRC, Modbus TCP by the MBAP
/// header, Modbus ASCII from `:` to LF; holds at most `BUF_BUDGET` bytes; time is passed in,
/// so it can be tested and fuzzed without waiting.
#[derive(Debug)]
pub struct Framer {
    rtu: bool,
    ascii: bool,
    limits: FrameLimits,
    buf: Vec<u8>,
    last_byte: Instant,
    frame_start: Instant,
}

impl Framer {
    /// A framer for `kind`, empty.
    pub fn new(kind: TransportKind, limits: FrameLimits, now: Instant) -> Framer {
        Framer {
            rtu: kind.is_rtu_framed(),
            ascii: kind.is_ascii(),
            limits,
            buf: Vec::with_capacity(BUF_BUDGET + tcp::MAX_FRAME),
            last_byte: now,
            frame_start: now,
        }
    }

    /// Bytes received at `now`. Past the budget, what is held is garbage and is dropped.
    pub fn push(&mut self, bytes: &[u8], now: Instant) {
        if bytes.is_empty() {
            return;
        }
        if self.buf.is_empty() {
            self.frame_start = now;
        }
        if self.buf.len() + bytes.len() > BUF_BUDGET {
            self.buf.clear();
            self.frame_start = now;
        }
        let take = bytes.len().min(BUF_BUDGET);
        self.buf.extend_from_slice(&bytes[bytes.len() - take..]);
        self.last_byte = now;
    }

    /// The next frame, if any, at `now`.
    pub fn next(&self, now: Instant) -> Next {
        if self.buf.is_empty() {
            return Next::Wait;
        }
        let late = now.saturating_duration_since(self.frame_start) >= self.limits.frame_deadline;
        if self.ascii {
            let quiet =
                late || now.saturating_duration_since(self.last_byte) >= self.limits.silence;
            return match ascii_frame(&self.buf) {
                Some(len) => Next::Frame(len),
                None if quiet => Next::Frame(self.buf.len()),
                None => Next::Wait,
            };
        }
        if self.rtu {
            let quiet =
                late || now.saturating_duration_since(self.last_byte) >= self.limits.silence;
            match rtu_frame(&self.buf) {
                Ok(Some(len)) => Next::Frame(len),
                Ok(None) | Err(()) if quiet => Next::Frame(self.buf.len()),
                Ok(None) | Err(()) => Next::Wait,
            }
        } else {
            match tcp::Header::parse(&self.buf) {
                Ok(Some(h)) if h.frame_len() <= self.buf.len() => Next::Frame(h.frame_len()),
                Ok(_) if late => Next::Close,
                Ok(_) => Next::Wait,
                Err(_) => Next::Close,
            }
        }
    }

    /// Whether an RTU frame has been arriving for longer than the frame deadline without being
    /// whole: a peer trickling bytes faster than the silence (slowloris over RTU framing).
    pub fn overdue(&self, now: Instant) -> bool {
        let whole = if self.ascii {
            ascii_frame(&self.buf).is_some()
        } else {
            matches!(rtu_frame(&self.buf), Ok(Some(_)))
        };
        (self.rtu || self.ascii)
            && !self.buf.is_empty()
            && now.saturating_duration_since(self.frame_start) >= self.limits.frame_deadline
            && !whole
    }

    /// The bytes held, from the start of the current frame.
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }

    /// Drops the first `n` bytes (a frame answered); what follows starts a new frame at `now`.
    pub fn consume(&mut self, n: usize, now: Instant) {
        self.buf.drain(..n.min(self.buf.len()));
        self.frame_start = now;
    }
}

/// Serves requests arriving on `link` to the drives of `sim` (a [`Line`]; a
/// [`SharedSim`] is a line of one: `&Line::from(sim)`) until `stop` is set or the peer hangs
/// up. `silence` is
/// how long an incomplete RTU frame may wait for its remaining bytes before it is dropped; no
/// idle timeout, a frame deadline of `max(silence, 1 s)`.
pub fn serve_link<T: Transport>(
    sim: &Line,
    link: &mut T,
    stop: &AtomicBool,
    log: Option<&Logger>,
    silence: Duration,
) -> io::Result<()> {
    let limits = FrameLimits {
        silence,
        frame_deadline: silence.max(Duration::from_secs(1)),
        idle_timeout: None,
    };
    serve_link_with(sim, link, stop, log, limits)
}

/// [`serve_link`] with every limit given. Returns `Ok` when the peer hangs up, the stream is
/// out of step, a frame misses its deadline (Modbus TCP) or the link stays idle too long.
pub fn serve_link_with<T: Transport>(
    sim: &Line,
    link: &mut T,
    stop: &AtomicBool,
    log: Option<&Logger>,
    limits: FrameLimits,
) -> io::Result<()> {
    serve_link_conn(sim, link, stop, log, limits, None)
}

/// [`serve_link_with`] for a connection of a [`TcpServer`]: `conn` closes it on request and
/// records when it last sent a request to this drive.
fn serve_link_conn<T: Transport>(
    sim: &Line,
    link: &mut T,
    stop: &AtomicBool,
    log: Option<&Logger>,
    limits: FrameLimits,
    conn: Option<&Conn>,
) -> io::Result<()> {
    serve_frames_conn(link, limits, stop, None, conn, |kind, frame, out| {
        let handled = sim.handle(kind, frame, out);
        if let Some(log) = log {
            log(&handled.record);
        }
        Answer {
            reply: handled.reply,
            // Activity is a request a drive of the line takes: a damaged frame is none, and
            // neither is a frame to a unit not there (a peer cannot keep a slot by talking to
            // no one).
            request: !matches!(
                handled.record.outcome,
                Outcome::Damaged | Outcome::NotAddressed
            ),
        }
    })?;
    Ok(())
}

/// A connection of a [`TcpServer`] as its accept loop sees it: when it last sent a request to
/// this drive, and a flag that closes it (to make room for a new master).
#[derive(Debug)]
pub(crate) struct Conn {
    /// The server's start, what `last_request_ms` counts from.
    epoch: Instant,
    last_request_ms: AtomicU64,
    close: AtomicBool,
}

impl Conn {
    fn new(epoch: Instant) -> Conn {
        let c = Conn {
            epoch,
            last_request_ms: AtomicU64::new(0),
            close: AtomicBool::new(false),
        };
        c.touch();
        c
    }

    /// A request arrived now (or the connection was accepted).
    fn touch(&self) {
        self.last_request_ms
            .store(self.epoch.elapsed().as_millis() as u64, Ordering::Relaxed);
    }

    /// How long since the last request (or the accept).
    fn idle(&self) -> Duration {
        let now = self.epoch.elapsed().as_millis() as u64;
        Duration::from_millis(now.saturating_sub(self.last_request_ms.load(Ordering::Relaxed)))
    }
}

/// What a drive made of one frame, for [`serve_frames`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Answer {
    /// Length of the reply written to the output buffer, or `None`: silence.
    pub reply: Option<usize>,
    /// The frame was a well-formed request (it counts as activity against the idle timeout).
    pub request: bool,
}

/// The one serve loop of this crate, behind [`serve_link_with`], [`TcpServer`],
/// [`SerialServer`](crate::server::SerialServer) and [`SimulatedSlave::serve`]: reads `link` in waits
/// of at most `POLL`, cuts the bytes into frames with a [`Framer`] (its byte budget, silence
/// and frame deadline), hands each frame to `answer` with an output buffer of
/// [`tcp::MAX_FRAME`] bytes and sends the reply it wrote. Ends, with the number of replies sent,
/// when `stop` is set, at `until`, when the peer hangs up, when the stream is out of step or
/// misses a frame deadline (Modbus TCP), or after `limits.idle_timeout` without a request.
/// Allocates nothing per frame.
///
/// [`SimulatedSlave::serve`]: crate::SimulatedSlave::serve
pub(crate) fn serve_frames<T: Transport>(
    link: &mut T,
    limits: FrameLimits,
    stop: &AtomicBool,
    until: Option<Instant>,
    answer: impl FnMut(TransportKind, &[u8], &mut [u8]) -> Answer,
) -> io::Result<u32> {
    serve_frames_conn(link, limits, stop, until, None, answer)
}

/// [`serve_frames`] for a server's connection (`conn`): it also ends when the accept loop closes
/// it, records each request, and closes on an RTU frame past its deadline (a peer trickling a
/// frame faster than the silence must not hold a slot until the idle timeout).
fn serve_frames_conn<T: Transport>(
    link: &mut T,
    limits: FrameLimits,
    stop: &AtomicBool,
    until: Option<Instant>,
    conn: Option<&Conn>,
    mut answer: impl FnMut(TransportKind, &[u8], &mut [u8]) -> Answer,
) -> io::Result<u32> {
    let kind = link.kind();
    let mut framer = Framer::new(kind, limits, Instant::now());
    let mut chunk = [0u8; tcp::MAX_FRAME];
    let mut out = [0u8; ascii::MAX_FRAME];
    // Modbus ASCII: the RTU frame a request stands for, and the drive's reply before it is
    // turned into ASCII.
    let mut rtu_in = [0u8; rtu::MAX_FRAME];
    let mut rtu_out = [0u8; tcp::MAX_FRAME];
    let mut last_request = Instant::now();
    let mut answered = 0u32;
    while !stop.load(Ordering::Relaxed) && !conn.is_some_and(|c| c.close.load(Ordering::Relaxed)) {
        let mut wait = POLL;
        if let Some(until) = until {
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(answered);
            }
            wait = wait.min(left);
        }
        if let Some(idle) = limits.idle_timeout {
            let left = idle.saturating_sub(last_request.elapsed());
            if left.is_zero() {
                return Ok(answered);
            }
            wait = wait.min(left);
        }
        let n = match link.recv(&mut chunk, Instant::now() + wait) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(answered),
            Err(e) => return Err(e),
        };
        framer.push(&chunk[..n], Instant::now());
        loop {
            let now = Instant::now();
            if conn.is_some() && framer.overdue(now) {
                return Ok(answered);
            }
            let len = match framer.next(now) {
                Next::Frame(len) => len,
                Next::Wait => break,
                Next::Close => return Ok(answered),
            };
            let a = if kind.is_ascii() {
                // A damaged frame is handed over empty: the drive stays silent.
                let n = ascii::to_rtu(&framer.bytes()[..len], &mut rtu_in).unwrap_or(0);
                let mut a = answer(kind, &rtu_in[..n], &mut rtu_out);
                a.reply = a
                    .reply
                    .and_then(|m| ascii::from_rtu(&rtu_out[..m], &mut out).ok());
                a
            } else {
                answer(kind, &framer.bytes()[..len], &mut out)
            };
            if a.request {
                last_request = now;
                if let Some(c) = conn {
                    c.touch();
                }
            }
            if let Some(m) = a.reply {
                link.send(&out[..m])?;
                answered = answered.saturating_add(1);
            }
            framer.consume(len, now);
        }
    }
    Ok(answered)
}

/// Framing of a TCP listener.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TcpFraming {
    /// Modbus TCP (MBAP header).
    ModbusTcp,
    /// RTU frames over TCP, as a transparent serial gateway forwards them.
    RtuOverTcp,
    /// Modbus TCP (MBAP header) served as a Modbus TCP to RTU gateway with the drive on its
    /// serial line ([`TransportKind::TcpGateway`]): the drive's RTU addressing (its map's RTU
    /// address offset) and only the registers its map lists for RTU, answered under the
    /// request's transaction and unit id.
    Gateway,
    /// Modbus ASCII frames over TCP, as a transparent serial gateway forwards them from a
    /// line set to ASCII ([`TransportKind::AsciiOverTcp`]).
    AsciiOverTcp,
}

/// Limits of a TCP listener, as a server on a plant network needs them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServerOptions {
    /// Connections served at once. One more closes the connection that has gone longest
    /// without a request to this drive, if that is at least [`ROOM_AFTER`] (so idle peers
    /// cannot lock new masters out until the idle timeout), and is otherwise closed at once.
    pub max_connections: usize,
    /// A connection with no request to this drive (a well-formed frame to its unit) for this
    /// long is closed.
    pub idle_timeout: Duration,
    /// A frame must arrive whole this long after its first byte: else the connection is closed
    /// (Modbus TCP and RTU framing alike: a peer trickling a frame cannot hold it).
    pub frame_deadline: Duration,
}

/// How long a connection must have gone without a request to this drive before a new
/// connection over the cap closes it to take its place.
pub const ROOM_AFTER: Duration = Duration::from_secs(1);

impl Default for ServerOptions {
    /// 64 connections, 60 s idle, 1 s per frame.
    fn default() -> ServerOptions {
        ServerOptions {
            max_connections: 64,
            idle_timeout: Duration::from_secs(60),
            frame_deadline: Duration::from_secs(1),
        }
    }
}

/// A listening TCP server; stops when dropped.
pub struct TcpServer {
    local_addr: SocketAddr,
    stop: Arc<AtomicBool>,
    active: Arc<AtomicUsize>,
    accept: Option<JoinHandle<()>>,
}

impl TcpServer {
    /// Binds `addr` and serves `sim` there (one drive, a [`SharedSim`] or [`Simulator`], or a
    /// [`Line`] of drives at their slave addresses: each request goes to the drive of its unit
    /// id), one thread per connection, with the default [`ServerOptions`].
    pub fn spawn(
        sim: impl Into<Line>,
        addr: impl ToSocketAddrs,
        framing: TcpFraming,
        log: Option<Logger>,
    ) -> io::Result<TcpServer> {
        TcpServer::spawn_with(sim, addr, framing, log, ServerOptions::default())
    }

    /// [`TcpServer::spawn`] with the connection cap and timeouts given.
    pub fn spawn_with(
        sim: impl Into<Line>,
        addr: impl ToSocketAddrs,
        framing: TcpFraming,
        log: Option<Logger>,
        options: ServerOptions,
    ) -> io::Result<TcpServer> {
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let local_addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let active = Arc::new(AtomicUsize::new(0));
        let shared = Accept {
            sim: sim.into(),
            framing,
            log,
            options,
            stop: stop.clone(),
            active: active.clone(),
        };
        let accept = thread::Builder::new()
            .name(format!("sim-accept-{local_addr}"))
            .spawn(move || accept_loop(listener, shared))?;
        Ok(TcpServer {
            local_addr,
            stop,
            active,
            accept: Some(accept),
        })
    }

    /// The address the server listens on (the port chosen when binding port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Connections being served now.
    pub fn connections(&self) -> usize {
        self.active.load(Ordering::Relaxed)
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

struct Accept {
    sim: Line,
    framing: TcpFraming,
    log: Option<Logger>,
    options: ServerOptions,
    stop: Arc<AtomicBool>,
    active: Arc<AtomicUsize>,
}

/// Counts a connection while its thread lives.
struct Slot(Arc<AtomicUsize>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Full: closes the connection longest without a request to this drive, if that is at least
/// [`ROOM_AFTER`], and waits (briefly) for its slot. Whether there is room now.
fn make_room(a: &Accept, connections: &[(JoinHandle<()>, Arc<Conn>)]) -> bool {
    let victim = connections
        .iter()
        .filter(|(h, c)| !h.is_finished() && !c.close.load(Ordering::Relaxed))
        .max_by_key(|(_, c)| c.idle());
    let Some((_, c)) = victim else {
        return false;
    };
    if c.idle() < ROOM_AFTER {
        return false;
    }
    c.close.store(true, Ordering::Relaxed);
    // Its loop sees the flag within one poll.
    let end = Instant::now() + POLL * 8;
    while a.active.load(Ordering::Acquire) >= a.options.max_connections && Instant::now() < end {
        thread::sleep(POLL / 5);
    }
    a.active.load(Ordering::Acquire) < a.options.max_connections
}

fn accept_loop(listener: TcpListener, a: Accept) {
    let epoch = Instant::now();
    let mut connections: Vec<(JoinHandle<()>, Arc<Conn>)> = Vec::new();
    while !a.stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                connections.retain(|(h, _)| !h.is_finished());
                if a.active.load(Ordering::Acquire) >= a.options.max_connections
                    && !make_room(&a, &connections)
                {
                    // Full of busy masters: refuse by closing at once, as a gateway at its
                    // connection limit does.
                    let _ = stream.shutdown(std::net::Shutdown::Both);
                    continue;
                }
                a.active.fetch_add(1, Ordering::AcqRel);
                let slot = Slot(a.active.clone());
                let conn = Arc::new(Conn::new(epoch));
                let (sim, log, stop) = (a.sim.clone(), a.log.clone(), a.stop.clone());
                let (framing, options) = (a.framing, a.options);
                let mine = conn.clone();
                let spawned =
                    thread::Builder::new()
                        .name("sim-connection".into())
                        .spawn(move || {
                            let _slot = slot;
                            let _ = serve_stream(
                                stream,
                                &sim,
                                framing,
                                options,
                                log.as_ref(),
                                &stop,
                                &mine,
                            );
                        });
                if let Ok(h) = spawned {
                    connections.push((h, conn));
                }
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => thread::sleep(POLL / 5),
            Err(_) => thread::sleep(POLL),
        }
    }
    for (h, _) in connections {
        let _ = h.join();
    }
}

fn serve_stream(
    stream: TcpStream,
    sim: &Line,
    framing: TcpFraming,
    options: ServerOptions,
    log: Option<&Logger>,
    stop: &AtomicBool,
    conn: &Conn,
) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    let _ = stream.set_nodelay(true);
    let limits = |silence| FrameLimits {
        silence,
        frame_deadline: options.frame_deadline,
        idle_timeout: Some(options.idle_timeout),
    };
    match framing {
        TcpFraming::ModbusTcp | TcpFraming::Gateway => {
            // The same Modbus TCP frames; a gateway's link addresses the drive's RTU side.
            let mut link = if framing == TcpFraming::Gateway {
                TcpTransport::from_gateway_stream(stream)?
            } else {
                TcpTransport::from_stream(stream)?
            };
            serve_link_conn(
                sim,
                &mut link,
                stop,
                log,
                limits(Duration::from_millis(500)),
                Some(conn),
            )
        }
        TcpFraming::RtuOverTcp => {
            let mut link = RtuOverTcpTransport::from_stream(stream)?;
            serve_link_conn(
                sim,
                &mut link,
                stop,
                log,
                limits(Duration::from_millis(100)),
                Some(conn),
            )
        }
        TcpFraming::AsciiOverTcp => {
            // A frame ends with its LF; the silence only drops one left incomplete.
            let mut link = AsciiOverTcpTransport::from_stream(stream)?;
            serve_link_conn(
                sim,
                &mut link,
                stop,
                log,
                limits(Duration::from_millis(500)),
                Some(conn),
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
    /// Opens the port and serves `sim` on it (one drive, or a [`Line`] of drives at their
    /// slave addresses). The line must be one of the character formats each drive's map lists,
    /// if it lists them (`Profile::serial_formats`): another is refused (`InvalidInput`) before
    /// the port is opened.
    pub fn spawn(
        sim: impl Into<Line>,
        options: drivemap_runtime::transport::serial::SerialOptions,
        log: Option<Logger>,
    ) -> io::Result<SerialServer> {
        SerialServer::spawn_on_line(sim, options, log, None)
    }

    /// [`SerialServer::spawn`], the drive answering after its response time on `line` (and,
    /// where `line.pace`, at the line's speed): see [`crate::timed`].
    pub fn spawn_on_line(
        sim: impl Into<Line>,
        mut options: drivemap_runtime::transport::serial::SerialOptions,
        log: Option<Logger>,
        line: Option<crate::timed::DriveLine>,
    ) -> io::Result<SerialServer> {
        use drivemap_runtime::transport::serial::{SerialTransport, USB_LATENCY};
        let sim: Line = sim.into();
        if options.formats.is_none() {
            // Every drive of the line must offer the line's format: each is checked here, the
            // first again when the port opens.
            for d in sim.drives() {
                let profile = lock(d).profile();
                options.formats = profile.serial_formats;
                options.drive_id = profile.drive_id;
                options
                    .check_format()
                    .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e.to_string()))?;
            }
            if let Some(first) = sim.drives().first() {
                let profile = lock(first).profile();
                options.formats = profile.serial_formats;
                options.drive_id = profile.drive_id;
            }
        }
        // Modbus ASCII ends a frame with its LF; a frame left incomplete for 1 s (the Modbus
        // serial line specification's inter-character timeout) is dropped.
        let silence = if options.ascii {
            Duration::from_secs(1)
        } else {
            options.frame_gap() + USB_LATENCY
        };
        let link = SerialTransport::open(options)?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread =
            thread::Builder::new()
                .name("sim-serial".into())
                .spawn(move || match line {
                    Some(line) => {
                        let mut link = crate::timed::TimedLink::new(link, sim.clone(), line);
                        serve_link(&sim, &mut link, &flag, log.as_ref(), silence)
                    }
                    None => {
                        let mut link = link;
                        serve_link(&sim, &mut link, &flag, log.as_ref(), silence)
                    }
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
        TcpFraming::Gateway => TransportKind::TcpGateway,
        TcpFraming::AsciiOverTcp => TransportKind::AsciiOverTcp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_frames_run_from_the_colon_to_the_lf() {
        assert_eq!(ascii_frame(b""), None);
        assert_eq!(ascii_frame(b":0103"), None);
        assert_eq!(ascii_frame(b":1103006B00037E\r\n:01"), Some(17));
        // Characters before a ':' are handed over alone (a damaged frame), and a frame broken
        // off by a new ':' too.
        assert_eq!(ascii_frame(b"xx:01"), Some(2));
        assert_eq!(ascii_frame(b"noise"), Some(5));
        assert_eq!(ascii_frame(b":0103:1103"), Some(5));
        let now = Instant::now();
        let limits = FrameLimits::default();
        let mut f = Framer::new(TransportKind::AsciiOverTcp, limits, now);
        f.push(b":1103006B", now);
        assert_eq!(f.next(now), Next::Wait);
        // Left incomplete past the silence: handed over whole, as damaged.
        assert_eq!(f.next(now + limits.silence), Next::Frame(9));
        f.push(b"00037E\r\n", now);
        assert_eq!(f.next(now), Next::Frame(17));
        assert!(!f.overdue(now + limits.frame_deadline));
        // A frame trickled past its deadline is overdue (a slowloris over ASCII framing).
        let mut f = Framer::new(TransportKind::AsciiOverTcp, limits, now);
        f.push(b":0103", now);
        assert!(!f.overdue(now));
        assert!(f.overdue(now + limits.frame_deadline));
    }

    #[test]
    fn rtu_frames_are_found_by_length_or_by_crc() {
        let read = [0x01, 0x03, 0x00, 0x20, 0x00, 0x01, 0x85, 0xC0];
        assert_eq!(rtu_frame(&read), Ok(Some(8)));
        assert_eq!(rtu_frame(&read[..5]), Ok(None));
        // 01h (read coils) is found by its length, as 03h is.
        let mut coils = [0x01, 0x01, 0x00, 0x00, 0x00, 0x01, 0, 0];
        let c = crc::crc_bytes(&coils[..6]);
        coils[6..].copy_from_slice(&c);
        assert_eq!(rtu_frame(&coils), Ok(Some(8)));
        assert_eq!(rtu_frame(&coils[..7]), Ok(None));
        // 41h (a user-defined function) is no drive function but has the usual 8-byte shape:
        // found by its CRC.
        let mut other = [0x01, 0x41, 0x00, 0x00, 0x00, 0x01, 0, 0];
        let c = crc::crc_bytes(&other[..6]);
        other[6..].copy_from_slice(&c);
        assert_eq!(rtu_frame(&other), Ok(Some(8)));
        assert_eq!(rtu_frame(&other[..7]), Err(()));
    }
}
