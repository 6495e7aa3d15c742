//! The async client (feature `tokio`): the same checks, framing, reply matching, retries,
//! broadcast rules, typed access and EEPROM budget as [`Client`](crate::client::Client), over an
//! [`AsyncTransport`].

use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll, Waker};
use std::time::{Duration, Instant};

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, ReadBuf};

use crate::client::{ClientOptions, Core, Session};
use crate::error::Error;
use crate::persist::PersistBudget;
use crate::reply::Discarded;
use crate::transport::{DISCARD_BUDGET, Transport};
use crate::typed::{ReadSet, WriteSet};
use crate::wire::Tokio;
use drivemap_core::profile::{Profile, TransportKind};
use drivemap_core::register::{BitRegister, Bits, DriveSettings, Readable, Writable};
use drivemap_core::rule::WriteRule;

/// A link for the [`AsyncClient`]; see [`Transport`] for the meaning of each method.
// The futures are not promised `Send` (the lint's concern): the client is driven on one task
// (a current-thread runtime, as in `examples/async-poll` and the runtime's async tests).
#[allow(async_fn_in_trait)]
pub trait AsyncTransport {
    /// How frames are framed on this link.
    fn kind(&self) -> TransportKind;
    /// Sends one whole frame.
    async fn send(&mut self, frame: &[u8]) -> io::Result<()>;
    /// Receives available bytes, waiting until at least one arrives or `deadline` passes
    /// (then returns 0).
    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize>;
    /// Throws away bytes received but not yet read, without waiting for more and stopping
    /// after about [`DISCARD_BUDGET`] bytes.
    async fn discard_input(&mut self) -> io::Result<()> {
        Ok(())
    }
    /// Re-establishes a connection the peer closed or reset; see [`Transport::reconnect`].
    async fn reconnect(&mut self) -> io::Result<()> {
        Err(io::ErrorKind::Unsupported.into())
    }
    /// The longest gap allowed between two bytes of one frame, if the link keeps byte timing.
    fn inter_char_timeout(&self) -> Option<Duration> {
        None
    }
}

/// Any tokio byte stream (a `TcpStream`, one end of `tokio::io::duplex`) carrying frames of
/// `kind`.
pub struct AsyncStreamTransport<S> {
    stream: S,
    kind: TransportKind,
    /// How stale input is flushed: [`drain`] for any stream, the kernel's socket for a TCP
    /// stream made by [`AsyncStreamTransport::tcp`] or [`AsyncStreamTransport::connect`].
    flush: fn(&mut S) -> io::Result<()>,
}

impl<S: AsyncRead + AsyncWrite + Unpin> AsyncStreamTransport<S> {
    /// Wraps `stream`. Stale input is flushed as far as the stream reports it readable (see
    /// [`AsyncTransport::discard_input`]); wrap a `TcpStream` with
    /// [`AsyncStreamTransport::tcp`] instead, whose flush asks the kernel.
    pub fn new(stream: S, kind: TransportKind) -> Self {
        AsyncStreamTransport {
            stream,
            kind,
            flush: drain::<S>,
        }
    }

    /// The stream.
    pub fn get_mut(&mut self) -> &mut S {
        &mut self.stream
    }
}

impl AsyncStreamTransport<tokio::net::TcpStream> {
    /// Connects to a Modbus TCP server (`TransportKind::Tcp`) or a transparent RTU gateway
    /// (`TransportKind::RtuOverTcp`). A stream cannot be re-established: use
    /// [`AsyncTcpTransport`] to reconnect after the peer closes the connection.
    pub async fn connect(
        addr: impl tokio::net::ToSocketAddrs,
        kind: TransportKind,
    ) -> io::Result<Self> {
        let stream = tokio::net::TcpStream::connect(addr).await?;
        stream.set_nodelay(true)?;
        Ok(Self::tcp(stream, kind))
    }

    /// Wraps a connected TCP stream. Its flush of stale input asks the kernel, as
    /// [`AsyncTcpTransport`]'s does, rather than tokio, whose readiness of the socket misses
    /// what arrived since the reactor last looked.
    pub fn tcp(stream: tokio::net::TcpStream, kind: TransportKind) -> Self {
        AsyncStreamTransport {
            stream,
            kind,
            flush: flush_socket,
        }
    }
}

/// The flush of a tokio TCP stream: what [`AsyncTcpTransport`] does.
fn flush_socket(stream: &mut tokio::net::TcpStream) -> io::Result<()> {
    #[cfg(unix)]
    {
        crate::transport::tcp::drain_socket(&*stream)
    }
    #[cfg(not(unix))]
    {
        let mut scratch = [0u8; 512];
        let mut taken = 0usize;
        while taken < DISCARD_BUDGET {
            match stream.try_read(&mut scratch) {
                Ok(0) => return Err(closed()),
                Ok(n) => taken += n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

fn closed() -> io::Error {
    io::Error::new(
        io::ErrorKind::UnexpectedEof,
        "the peer closed the connection",
    )
}

impl<S: AsyncRead + AsyncWrite + Unpin> AsyncTransport for AsyncStreamTransport<S> {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    async fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.stream.write_all(frame).await?;
        self.stream.flush().await
    }

    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        recv_by(&mut self.stream, buf, deadline).await
    }

    async fn discard_input(&mut self) -> io::Result<()> {
        (self.flush)(&mut self.stream)
    }
}

/// Reads and drops what `stream` holds without waiting, up to [`DISCARD_BUDGET`] bytes: the
/// read is polled once with a waker that does nothing, so no timer is registered, and where
/// tokio already knows the socket has nothing (the usual case after a reply) no system call
/// is made either. It flushes only what the stream has reported: over a tokio `TcpStream`,
/// bytes that arrived since the reactor's last turn stay, and reach the reply matching (which
/// discards a late Modbus TCP reply by its transaction id, but cannot tell a late RTU reply
/// from the answer). [`AsyncTcpTransport`] and [`AsyncStreamTransport::tcp`] ask the kernel
/// instead.
fn drain<S: AsyncRead + Unpin>(stream: &mut S) -> io::Result<()> {
    let mut scratch = [0u8; 512];
    let mut cx = Context::from_waker(Waker::noop());
    let mut taken = 0usize;
    while taken < DISCARD_BUDGET {
        let mut buf = ReadBuf::new(&mut scratch);
        match Pin::new(&mut *stream).poll_read(&mut cx, &mut buf) {
            Poll::Pending => return Ok(()),
            Poll::Ready(Ok(())) if buf.filled().is_empty() => return Err(closed()),
            Poll::Ready(Ok(())) => taken += buf.filled().len(),
            Poll::Ready(Err(e)) if e.kind() == io::ErrorKind::Interrupted => {}
            Poll::Ready(Err(e)) => return Err(e),
        }
    }
    Ok(())
}

/// A Modbus TCP connection (or RTU frames through a transparent gateway) over tokio that
/// re-establishes itself when the peer closes it ([`AsyncTransport::reconnect`], driven by
/// [`ClientOptions::reconnect`]). The same as [`AsyncStreamTransport`] over a `TcpStream`
/// otherwise.
pub struct AsyncTcpTransport {
    stream: tokio::net::TcpStream,
    kind: TransportKind,
    peer: Vec<SocketAddr>,
    connect_timeout: Duration,
    /// The reply deadline's timer, kept armed across requests (see `recv`).
    timer: Pin<Box<tokio::time::Sleep>>,
}

impl AsyncTcpTransport {
    /// Connects to `addr` (every address it resolves to, in turn), waiting at most
    /// `connect_timeout`, which later reconnects wait at most too.
    pub async fn connect(
        addr: impl tokio::net::ToSocketAddrs,
        kind: TransportKind,
        connect_timeout: Duration,
    ) -> io::Result<Self> {
        let peer: Vec<SocketAddr> = tokio::net::lookup_host(addr).await?.collect();
        let stream = connect_any(&peer, connect_timeout).await?;
        Ok(AsyncTcpTransport {
            stream,
            kind,
            peer,
            connect_timeout,
            timer: Box::pin(tokio::time::sleep(Duration::ZERO)),
        })
    }

    /// The stream (a new one after a reconnect).
    pub fn get_mut(&mut self) -> &mut tokio::net::TcpStream {
        &mut self.stream
    }
}

async fn connect_any(peer: &[SocketAddr], timeout: Duration) -> io::Result<tokio::net::TcpStream> {
    let mut last = io::Error::new(io::ErrorKind::InvalidInput, "no address to connect to");
    for a in peer {
        match tokio::time::timeout(timeout, tokio::net::TcpStream::connect(a)).await {
            Ok(Ok(stream)) => {
                stream.set_nodelay(true)?;
                return Ok(stream);
            }
            Ok(Err(e)) => last = e,
            Err(_) => {
                last = io::Error::new(
                    io::ErrorKind::TimedOut,
                    format!(
                        "connecting to {a} took longer than {} ms",
                        timeout.as_millis()
                    ),
                )
            }
        }
    }
    Err(last)
}

impl AsyncTransport for AsyncTcpTransport {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    async fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        // TCP_NODELAY and no buffering: write_all is the whole send.
        self.stream.write_all(frame).await
    }

    /// Waits for bytes until `deadline` on one timer kept across requests: it stays armed as
    /// long as it fires no later than the deadline asked for, so consecutive requests (whose
    /// deadlines only move forward) do not insert a timer each into tokio's timer wheel and
    /// take it out again. When it fires before the deadline (armed for an earlier request),
    /// it is re-armed once for this one.
    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let at = tokio::time::Instant::from_std(deadline);
        if self.timer.is_elapsed() || self.timer.deadline() > at {
            self.timer.as_mut().reset(at);
        }
        let stream = &mut self.stream;
        let timer = &mut self.timer;
        std::future::poll_fn(|cx| {
            let mut rb = ReadBuf::new(&mut *buf);
            match Pin::new(&mut *stream).poll_read(cx, &mut rb) {
                Poll::Ready(Ok(())) if rb.filled().is_empty() => return Poll::Ready(Err(closed())),
                Poll::Ready(Ok(())) => return Poll::Ready(Ok(rb.filled().len())),
                Poll::Ready(Err(e)) => return Poll::Ready(Err(e)),
                Poll::Pending => {}
            }
            while timer.as_mut().poll(cx).is_ready() {
                if tokio::time::Instant::now() >= at {
                    return Poll::Ready(Ok(0));
                }
                timer.as_mut().reset(at);
            }
            Poll::Pending
        })
        .await
    }

    /// Reads and drops what the socket holds, without waiting, at most [`DISCARD_BUDGET`]
    /// bytes: one `recv(MSG_DONTWAIT)` when nothing is there, the same flush as the blocking
    /// [`TcpTransport`](crate::transport::tcp::TcpTransport)'s. It asks the kernel, not
    /// tokio: tokio's readiness of the socket dates from the reactor's last turn, so a
    /// `try_read` (free when tokio believes the socket empty) misses a late reply that arrived
    /// since then, and a reply without a transaction id (RTU over TCP) would then be taken as
    /// the next request's answer. Bytes read here behind tokio's back cost at most one empty
    /// read later, when tokio learns of them and finds them gone.
    async fn discard_input(&mut self) -> io::Result<()> {
        flush_socket(&mut self.stream)
    }

    async fn reconnect(&mut self) -> io::Result<()> {
        self.stream = connect_any(&self.peer, self.connect_timeout).await?;
        Ok(())
    }
}

/// Reads what arrives until `deadline`. The timer is only registered if the first poll of the
/// read finds nothing (`timeout_at` polls the read first).
async fn recv_by<S: AsyncRead + Unpin>(
    stream: &mut S,
    buf: &mut [u8],
    deadline: Instant,
) -> io::Result<usize> {
    let at = tokio::time::Instant::from_std(deadline);
    match tokio::time::timeout_at(at, stream.read(buf)).await {
        Err(_) => Ok(0),
        Ok(Ok(0)) => Err(closed()),
        Ok(result) => result,
    }
}

/// Runs a blocking [`Transport`] (the serial port) on tokio's blocking thread pool.
pub struct BlockingTransport<T> {
    inner: Arc<Mutex<T>>,
    kind: TransportKind,
    gap: Option<Duration>,
}

impl<T: Transport + Send + 'static> BlockingTransport<T> {
    /// Wraps `transport`.
    pub fn new(transport: T) -> Self {
        let kind = transport.kind();
        let gap = transport.inter_char_timeout();
        BlockingTransport {
            inner: Arc::new(Mutex::new(transport)),
            kind,
            gap,
        }
    }

    /// Runs `f` on the wrapped transport (waits while a call on the blocking pool holds it).
    pub fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> R {
        let mut t = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut t)
    }

    async fn run<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut T) -> io::Result<R> + Send + 'static,
    ) -> io::Result<R> {
        let inner = self.inner.clone();
        tokio::task::spawn_blocking(move || {
            let mut t = inner.lock().unwrap_or_else(|e| e.into_inner());
            f(&mut t)
        })
        .await
        .map_err(io::Error::other)?
    }
}

impl<T: Transport + Send + 'static> AsyncTransport for BlockingTransport<T> {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    async fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        let mut copy = [0u8; crate::tcp::MAX_FRAME];
        let n = frame.len().min(copy.len());
        copy[..n].copy_from_slice(&frame[..n]);
        self.run(move |t| t.send(&copy[..n])).await
    }

    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let want = buf.len().min(crate::tcp::MAX_FRAME);
        let (bytes, n) = self
            .run(move |t| {
                let mut bytes = [0u8; crate::tcp::MAX_FRAME];
                t.recv(&mut bytes[..want], deadline).map(|n| (bytes, n))
            })
            .await?;
        buf[..n].copy_from_slice(&bytes[..n]);
        Ok(n)
    }

    async fn discard_input(&mut self) -> io::Result<()> {
        self.run(|t| t.discard_input()).await
    }

    async fn reconnect(&mut self) -> io::Result<()> {
        self.run(|t| t.reconnect()).await
    }

    fn inter_char_timeout(&self) -> Option<Duration> {
        self.gap
    }
}

/// An async Modbus client for drives described by a [`Profile`].
pub struct AsyncClient<T: AsyncTransport> {
    transport: T,
    core: Core,
}

impl<T: AsyncTransport> AsyncClient<T> {
    /// A client with the drive's timing, as [`Client::new`](crate::client::Client::new)
    /// ([`ClientOptions::for_link`]); `AsyncClient::with_options(transport, profile,
    /// ClientOptions::generic())` is a client that ignores it.
    pub fn new(transport: T, profile: &'static Profile) -> Self {
        let options = ClientOptions::for_link(profile, transport.kind());
        Self::with_options(transport, profile, options)
    }

    /// A client with explicit options.
    pub fn with_options(transport: T, profile: &'static Profile, options: ClientOptions) -> Self {
        let kind = transport.kind();
        AsyncClient {
            transport,
            core: Core::new(profile, kind, options),
        }
    }

    /// The drive's profile.
    pub fn profile(&self) -> &'static Profile {
        self.core.profile
    }

    /// The options in force.
    pub fn options(&self) -> &ClientOptions {
        &self.core.options
    }

    /// Talks to another drive on the same link from now on, keeping the link's state, as
    /// [`Client::switch_drive`](crate::client::Client::switch_drive) does.
    pub fn switch_drive(&mut self, profile: &'static Profile, options: ClientOptions) {
        self.core.profile = profile;
        self.core.options = options;
    }

    /// The transport.
    pub fn transport(&mut self) -> &mut T {
        &mut self.transport
    }

    /// The EEPROM write budget and count.
    pub fn eeprom(&self) -> &PersistBudget {
        self.core.budget()
    }

    /// What arrived during the last transaction but was not its answer.
    pub fn discarded(&self) -> Discarded {
        self.core.rx.discarded()
    }

    /// Connections re-established after the peer closed or reset them
    /// ([`ClientOptions::reconnect`]).
    pub fn reconnects(&self) -> u32 {
        self.core.reconnects()
    }

    /// The wait for silence before the last call's request, if it needed one; see
    /// [`Client::settled`](crate::client::Client::settled).
    pub fn settled(&self) -> Option<crate::client::Settled> {
        self.core.settled()
    }

    /// The link and the protocol state, for one call.
    pub(crate) fn session(&mut self) -> Session<'_, Tokio<'_, T>> {
        Session {
            wire: Tokio(&mut self.transport),
            core: &mut self.core,
        }
    }

    /// As [`Client::read_holding`](crate::client::Client::read_holding).
    pub async fn read_holding(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        self.session().read_holding(slave, address, out).await
    }

    /// As [`Client::read_input`](crate::client::Client::read_input).
    pub async fn read_input(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        self.session().read_input(slave, address, out).await
    }

    /// As [`Client::read_table`](crate::client::Client::read_table).
    pub async fn read_table(
        &mut self,
        slave: u8,
        table: drivemap_core::register::Table,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        self.session().read_table(slave, table, address, out).await
    }

    /// As [`Client::read_coils`](crate::client::Client::read_coils).
    pub async fn read_coils(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [bool],
    ) -> Result<(), Error> {
        use drivemap_core::register::Table;
        self.session()
            .read_bits(slave, Table::Coil, address, out)
            .await
    }

    /// As [`Client::read_discrete_inputs`](crate::client::Client::read_discrete_inputs).
    pub async fn read_discrete_inputs(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [bool],
    ) -> Result<(), Error> {
        use drivemap_core::register::Table;
        self.session()
            .read_bits(slave, Table::DiscreteInput, address, out)
            .await
    }

    /// As [`Client::write_coil`](crate::client::Client::write_coil).
    pub async fn write_coil(&mut self, slave: u8, address: u16, value: bool) -> Result<(), Error> {
        self.session()
            .write_coil(slave, crate::gate::WriteTarget::Addresses, address, value)
            .await
    }

    /// As [`Client::write_coils`](crate::client::Client::write_coils).
    pub async fn write_coils(
        &mut self,
        slave: u8,
        address: u16,
        values: &[bool],
    ) -> Result<(), Error> {
        self.session().write_coils(slave, address, values).await
    }

    /// As [`Client::write_register`](crate::client::Client::write_register).
    pub async fn write_register(
        &mut self,
        slave: u8,
        address: u16,
        value: u16,
    ) -> Result<(), Error> {
        self.session().write_register(slave, address, value).await
    }

    /// As [`Client::write_rule`](crate::client::Client::write_rule).
    pub async fn write_rule(
        &mut self,
        slave: u8,
        rule: &WriteRule,
        address: u16,
        raw: u32,
    ) -> Result<(), Error> {
        self.session().write_rule(slave, rule, address, raw).await
    }

    /// As [`Client::write_registers`](crate::client::Client::write_registers).
    pub async fn write_registers(
        &mut self,
        slave: u8,
        address: u16,
        values: &[u16],
    ) -> Result<(), Error> {
        self.session().write_registers(slave, address, values).await
    }

    /// As [`Client::loop_back`](crate::client::Client::loop_back).
    pub async fn loop_back(&mut self, slave: u8, data: u16) -> Result<(), Error> {
        self.session().loop_back(slave, data).await
    }

    /// As [`Client::load_settings`](crate::client::Client::load_settings).
    pub async fn load_settings<S: DriveSettings>(
        &mut self,
        slave: u8,
        settings: &mut S,
    ) -> Result<(), Error> {
        self.session().load_settings::<S>(slave, settings).await
    }

    /// As [`Client::read`](crate::client::Client::read).
    pub async fn read<R: Readable>(
        &mut self,
        slave: u8,
        settings: &R::Settings,
    ) -> Result<R::Value, Error> {
        self.session().read::<R>(slave, settings).await
    }

    /// As [`Client::write`](crate::client::Client::write).
    pub async fn write<R: Writable>(
        &mut self,
        slave: u8,
        value: &R::Input,
        settings: &R::Settings,
    ) -> Result<(), Error> {
        self.session().write::<R>(slave, value, settings).await
    }

    /// As [`Client::write_rounded`](crate::client::Client::write_rounded).
    pub async fn write_rounded<R: Writable>(
        &mut self,
        slave: u8,
        value: &R::Input,
        settings: &R::Settings,
        rounding: drivemap_core::scale::Rounding,
    ) -> Result<(), Error> {
        self.session()
            .write_rounded::<R>(slave, value, settings, rounding)
            .await
    }

    /// As [`Client::write_changed`](crate::client::Client::write_changed).
    pub async fn write_changed(
        &mut self,
        slave: u8,
        rule: &WriteRule,
        address: u16,
        between: u32,
        raw: u32,
    ) -> Result<(), Error> {
        self.session()
            .write_changed(slave, rule, address, between, raw)
            .await
    }

    /// As [`Client::update`](crate::client::Client::update).
    pub async fn update<
        R: Readable + Writable<Input = <R as drivemap_core::register::Register>::Value>,
    >(
        &mut self,
        slave: u8,
        settings: &R::Settings,
        change: impl FnOnce(&mut R::Value),
    ) -> Result<R::Value, Error> {
        self.session().update::<R>(slave, settings, change).await
    }

    /// As [`Client::modify_bits`](crate::client::Client::modify_bits).
    pub async fn modify_bits<R>(
        &mut self,
        slave: u8,
        settings: &R::Settings,
        set: u16,
        clear: u16,
    ) -> Result<R::Value, Error>
    where
        R: BitRegister
            + Readable
            + Writable<Input = <R as drivemap_core::register::Register>::Value>,
        R::Value: Bits,
    {
        self.session()
            .modify_bits::<R>(slave, settings, set, clear)
            .await
    }

    /// As [`Client::read_many`](crate::client::Client::read_many).
    pub async fn read_many<S: ReadSet>(
        &mut self,
        slave: u8,
        settings: &S::Settings,
    ) -> Result<S::Values, Error> {
        self.session().read_many::<S>(slave, settings).await
    }

    /// As [`Client::write_many`](crate::client::Client::write_many).
    pub async fn write_many<S: WriteSet>(
        &mut self,
        slave: u8,
        values: &S::Values,
        settings: &S::Settings,
    ) -> Result<(), Error> {
        self.session()
            .write_many::<S>(slave, values, settings)
            .await
    }

    /// As [`Client::persist`](crate::client::Client::persist).
    pub async fn persist(&mut self, slave: u8, id: &str) -> Result<(), Error> {
        self.session().persist(slave, id).await
    }
}
