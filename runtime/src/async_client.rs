//! The async client (feature `tokio`): the same checks, framing, reply matching, retries,
//! broadcast rules, typed access and EEPROM budget as [`Client`](crate::client::Client), over an
//! [`AsyncTransport`].

use std::io;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

use crate::client::{
    Checked, ClientOptions, Core, MAX_SET, Purpose, Wait, client_methods, io_error, read_request,
};
use crate::error::{Error, Refusal};
use crate::gate::{WriteRule, WriteTarget};
use crate::pdu::{Request, Words};
use crate::persist::PersistBudget;
use crate::profile::{CommandKind, Profile, TransportKind};
use crate::register::{BitRegister, Bits, DriveSettings, Readable, Table, Writable};
use crate::reply::{Discarded, Framing};
use crate::transport::Transport;
use crate::typed::{ReadSet, WriteSet};

/// A link for the [`AsyncClient`]; see [`Transport`] for the meaning of each method.
#[allow(async_fn_in_trait)]
pub trait AsyncTransport {
    /// How frames are framed on this link.
    fn kind(&self) -> TransportKind;
    /// Sends one whole frame.
    async fn send(&mut self, frame: &[u8]) -> io::Result<()>;
    /// Receives available bytes, waiting until at least one arrives or `deadline` passes
    /// (then returns 0).
    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize>;
    /// Throws away bytes received but not yet read.
    async fn discard_input(&mut self) -> io::Result<()> {
        Ok(())
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
}

impl<S: AsyncRead + AsyncWrite + Unpin> AsyncStreamTransport<S> {
    /// Wraps `stream`.
    pub fn new(stream: S, kind: TransportKind) -> Self {
        AsyncStreamTransport { stream, kind }
    }

    /// The stream.
    pub fn get_mut(&mut self) -> &mut S {
        &mut self.stream
    }
}

impl AsyncStreamTransport<tokio::net::TcpStream> {
    /// Connects to a Modbus TCP server (`TransportKind::Tcp`) or a transparent RTU gateway
    /// (`TransportKind::RtuOverTcp`).
    pub async fn connect(
        addr: impl tokio::net::ToSocketAddrs,
        kind: TransportKind,
    ) -> io::Result<Self> {
        let stream = tokio::net::TcpStream::connect(addr).await?;
        stream.set_nodelay(true)?;
        Ok(Self::new(stream, kind))
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
        let at = tokio::time::Instant::from_std(deadline);
        match tokio::time::timeout_at(at, self.stream.read(buf)).await {
            Err(_) => Ok(0),
            Ok(Ok(0)) => Err(closed()),
            Ok(result) => result,
        }
    }

    async fn discard_input(&mut self) -> io::Result<()> {
        let mut scratch = [0u8; 256];
        loop {
            // A zero timeout polls the read once: it takes what is there and does not wait.
            match tokio::time::timeout(Duration::ZERO, self.stream.read(&mut scratch)).await {
                Err(_) => return Ok(()),
                Ok(Ok(0)) => return Err(closed()),
                Ok(Ok(_)) => continue,
                Ok(Err(e)) => return Err(e),
            }
        }
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
    /// A client with default options.
    pub fn new(transport: T, profile: &'static Profile) -> Self {
        Self::with_options(transport, profile, ClientOptions::default())
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

    async fn transact(
        &mut self,
        slave: u8,
        request: Request<'_>,
        out: &mut [u16],
        purpose: Purpose<'_>,
        retries: u8,
    ) -> Result<(), Error> {
        let checked = self.core.check(slave, request, purpose)?;
        let attempts = retries.saturating_add(1);
        for attempt in 1..=attempts {
            let framing = self.core.encode(&checked)?;
            if let Some(at) = self.core.ready_at() {
                tokio::time::sleep_until(tokio::time::Instant::from_std(at)).await;
            }
            let mut sent = self.transport.discard_input().await;
            if sent.is_ok() {
                sent = self.transport.send(self.core.frame()).await;
            }
            if let Err(e) = sent {
                self.core.mark_idle();
                return Err(io_error(&checked, e));
            }
            let Some(framing) = framing else {
                self.core.mark_idle();
                return Ok(());
            };
            let result = self.receive(framing, &checked, out).await;
            self.core.mark_idle();
            match result {
                Ok(Some(())) => return Ok(()),
                Ok(None) if attempt < attempts => continue,
                Ok(None) => return Err(self.core.timeout(&checked, attempts)),
                Err(e) => return Err(e),
            }
        }
        Err(self.core.timeout(&checked, attempts))
    }

    async fn receive(
        &mut self,
        framing: Framing,
        checked: &Checked<'_>,
        out: &mut [u16],
    ) -> Result<Option<()>, Error> {
        let mut wait = Wait::new(
            self.core.options.timeout,
            self.transport.inter_char_timeout(),
        );
        loop {
            let until = self.core.receive_until(&wait);
            let n = self
                .transport
                .recv(self.core.rx.space(), until)
                .await
                .map_err(|e| io_error(checked, e))?;
            if let Some(outcome) = self
                .core
                .received(n, until, &mut wait, framing, checked, out)
            {
                return outcome;
            }
        }
    }

    client_methods!([async] [.await]);
}
