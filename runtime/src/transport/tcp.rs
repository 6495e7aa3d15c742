//! Modbus TCP over a `std::net::TcpStream`.
//!
//! Per request the transport makes three system calls where nothing is stale: one
//! non-blocking `recv` that finds the input empty (the flush of stale input), one `write`, and
//! one blocking `recv` that returns the reply. The socket stays in blocking mode; its receive
//! timeout (`SO_RCVTIMEO`) is set only when the wait asked for differs from the one in force by
//! more than `TIMEOUT_SLACK` (2 ms), and never longer than the wait, so a deadline is never overrun.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use super::{DISCARD_BUDGET, Transport};
use drivemap_core::profile::TransportKind;

/// How much shorter than the wait asked for the socket's receive timeout may be before it is
/// set again. A receive that ends up to this much early just waits again for the rest, so the
/// deadline is kept; the kernel rounds `SO_RCVTIMEO` to its tick (1-4 ms) anyway.
pub(crate) const TIMEOUT_SLACK: Duration = Duration::from_millis(2);

/// A TCP connection carrying frames of `kind` (Modbus TCP, or RTU frames through a gateway).
pub struct TcpTransport {
    stream: TcpStream,
    kind: TransportKind,
    /// Where [`Transport::reconnect`] connects to: the addresses the name resolved to, or the
    /// peer of a wrapped stream.
    peer: Vec<SocketAddr>,
    connect_timeout: Duration,
    /// The socket's receive timeout as last set.
    read_timeout: Option<Duration>,
}

fn closed() -> io::Error {
    io::Error::new(
        io::ErrorKind::UnexpectedEof,
        "the server closed the connection",
    )
}

impl TcpTransport {
    /// Connects to a Modbus TCP server (port 502 usually), waiting at most `timeout`.
    pub fn connect(addr: impl ToSocketAddrs, timeout: Duration) -> io::Result<TcpTransport> {
        Self::connect_as(addr, timeout, TransportKind::Tcp)
    }

    /// Connects to a Modbus TCP to RTU gateway with a serial drive behind it
    /// ([`TransportKind::TcpGateway`]): Modbus TCP frames, but the client addresses the drive
    /// as its map's RTU side (RTU address offset, RTU registers, RTU timing).
    pub fn connect_gateway(
        addr: impl ToSocketAddrs,
        timeout: Duration,
    ) -> io::Result<TcpTransport> {
        Self::connect_as(addr, timeout, TransportKind::TcpGateway)
    }

    /// Wraps a connected stream to a Modbus TCP to RTU gateway
    /// ([`TcpTransport::connect_gateway`]).
    pub fn from_gateway_stream(stream: TcpStream) -> io::Result<TcpTransport> {
        Self::from_stream_as(stream, TransportKind::TcpGateway)
    }

    pub(crate) fn connect_as(
        addr: impl ToSocketAddrs,
        timeout: Duration,
        kind: TransportKind,
    ) -> io::Result<TcpTransport> {
        let peer: Vec<SocketAddr> = addr.to_socket_addrs()?.collect();
        let stream = connect_any(&peer, timeout)?;
        let mut t = Self::from_stream_as(stream, kind)?;
        t.peer = peer;
        t.connect_timeout = timeout;
        Ok(t)
    }

    /// Wraps a connected stream for Modbus TCP. [`Transport::reconnect`] connects to the
    /// stream's peer address again.
    pub fn from_stream(stream: TcpStream) -> io::Result<TcpTransport> {
        Self::from_stream_as(stream, TransportKind::Tcp)
    }

    pub(crate) fn from_stream_as(
        stream: TcpStream,
        kind: TransportKind,
    ) -> io::Result<TcpTransport> {
        stream.set_nodelay(true)?;
        let peer = stream.peer_addr().ok().into_iter().collect();
        Ok(TcpTransport {
            stream,
            kind,
            peer,
            connect_timeout: Duration::from_secs(1),
            read_timeout: None,
        })
    }

    /// Sets how long [`Transport::reconnect`] waits for the connection (default: the timeout
    /// given to `connect`, else 1 s).
    pub fn set_connect_timeout(&mut self, timeout: Duration) {
        self.connect_timeout = timeout;
    }

    /// The underlying stream (a new one after a reconnect).
    pub fn stream(&self) -> &TcpStream {
        &self.stream
    }

    /// Sets the socket's receive timeout to at most `wait`, unless the one in force is already
    /// within [`TIMEOUT_SLACK`] below it.
    fn wait_at_most(&mut self, wait: Duration) -> io::Result<()> {
        if self
            .read_timeout
            .is_some_and(|t| t <= wait && wait - t <= TIMEOUT_SLACK)
        {
            return Ok(());
        }
        // Leave room on both sides, so the same setting serves the next request too although
        // a little more or less time passes before its receive.
        let half = TIMEOUT_SLACK / 2;
        let t = if wait > half * 2 { wait - half } else { wait };
        self.stream.set_read_timeout(Some(t))?;
        self.read_timeout = Some(t);
        Ok(())
    }
}

fn connect_any(peer: &[SocketAddr], timeout: Duration) -> io::Result<TcpStream> {
    let mut last = io::Error::new(io::ErrorKind::InvalidInput, "no address to connect to");
    for a in peer {
        match TcpStream::connect_timeout(a, timeout) {
            Ok(stream) => return Ok(stream),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// Reads and drops what the socket holds, without waiting, up to [`DISCARD_BUDGET`] bytes.
/// One `recv(MSG_DONTWAIT)` when nothing is there. It asks the kernel, whatever mode the socket
/// is in, so it also serves the async transport: tokio's idea of whether a socket is readable
/// dates from the reactor's last turn and misses what arrived since.
#[cfg(unix)]
fn drain(stream: &TcpStream) -> io::Result<()> {
    drain_socket(stream)
}

#[cfg(unix)]
pub(crate) fn drain_socket(socket: impl std::os::fd::AsFd) -> io::Result<()> {
    use rustix::net::{RecvFlags, recv};
    let mut scratch = [0u8; 512];
    let mut taken = 0usize;
    while taken < DISCARD_BUDGET {
        match recv(&socket, &mut scratch[..], RecvFlags::DONTWAIT) {
            Ok((0, _)) => return Err(closed()),
            Ok((n, _)) => taken += n,
            Err(rustix::io::Errno::INTR) => continue,
            Err(e) if e == rustix::io::Errno::AGAIN || e == rustix::io::Errno::WOULDBLOCK => {
                return Ok(());
            }
            Err(e) => return Err(e.into()),
        }
    }
    // A peer that keeps sending: stop here; the reply matching skips the rest, within the
    // reply's deadline and byte budget.
    Ok(())
}

#[cfg(not(unix))]
fn drain(stream: &TcpStream) -> io::Result<()> {
    let mut s = stream;
    s.set_nonblocking(true)?;
    let mut scratch = [0u8; 512];
    let mut taken = 0usize;
    let result = loop {
        if taken >= DISCARD_BUDGET {
            break Ok(());
        }
        match s.read(&mut scratch) {
            Ok(0) => break Err(closed()),
            Ok(n) => taken += n,
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => break Ok(()),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => break Err(e),
        }
    };
    s.set_nonblocking(false)?;
    result
}

impl Transport for TcpTransport {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        // No buffering and TCP_NODELAY: write_all is the whole send, no flush needed.
        self.stream.write_all(frame)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let Some(wait) = super::remaining(deadline) else {
            return Ok(0);
        };
        self.wait_at_most(wait)?;
        match self.stream.read(buf) {
            Ok(0) => Err(closed()),
            Ok(n) => Ok(n),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                Ok(0)
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn discard_input(&mut self) -> io::Result<()> {
        drain(&self.stream)
    }

    fn reconnect(&mut self) -> io::Result<()> {
        if self.peer.is_empty() {
            return Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "the peer's address is not known",
            ));
        }
        let stream = connect_any(&self.peer, self.connect_timeout)?;
        stream.set_nodelay(true)?;
        self.stream = stream;
        self.read_timeout = None;
        Ok(())
    }
}
