//! Modbus TCP over a `std::net::TcpStream`.

use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use super::Transport;
use crate::profile::TransportKind;

/// A TCP connection carrying frames of `kind` (Modbus TCP, or RTU frames through a gateway).
pub struct TcpTransport {
    stream: TcpStream,
    kind: TransportKind,
}

impl TcpTransport {
    /// Connects to a Modbus TCP server (port 502 usually), waiting at most `timeout`.
    pub fn connect(addr: impl ToSocketAddrs, timeout: Duration) -> io::Result<TcpTransport> {
        Self::connect_as(addr, timeout, TransportKind::Tcp)
    }

    pub(crate) fn connect_as(
        addr: impl ToSocketAddrs,
        timeout: Duration,
        kind: TransportKind,
    ) -> io::Result<TcpTransport> {
        let mut last = io::Error::new(io::ErrorKind::InvalidInput, "no address to connect to");
        for a in addr.to_socket_addrs()? {
            match TcpStream::connect_timeout(&a, timeout) {
                Ok(stream) => return Self::from_stream_as(stream, kind),
                Err(e) => last = e,
            }
        }
        Err(last)
    }

    /// Wraps a connected stream for Modbus TCP.
    pub fn from_stream(stream: TcpStream) -> io::Result<TcpTransport> {
        Self::from_stream_as(stream, TransportKind::Tcp)
    }

    pub(crate) fn from_stream_as(
        stream: TcpStream,
        kind: TransportKind,
    ) -> io::Result<TcpTransport> {
        stream.set_nodelay(true)?;
        Ok(TcpTransport { stream, kind })
    }

    /// The underlying stream.
    pub fn stream(&self) -> &TcpStream {
        &self.stream
    }
}

impl Transport for TcpTransport {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.stream.write_all(frame)?;
        self.stream.flush()
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let Some(wait) = super::remaining(deadline) else {
            return Ok(0);
        };
        self.stream.set_read_timeout(Some(wait))?;
        match self.stream.read(buf) {
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the server closed the connection",
            )),
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
        self.stream.set_nonblocking(true)?;
        let mut scratch = [0u8; 256];
        let result = loop {
            match self.stream.read(&mut scratch) {
                Ok(0) => {
                    break Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the server closed the connection",
                    ));
                }
                Ok(_) => continue,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => break Err(e),
            }
        };
        self.stream.set_nonblocking(false)?;
        result
    }
}
