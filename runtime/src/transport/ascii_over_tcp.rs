//! Modbus ASCII frames (`:` ... LRC CR LF) carried over TCP, as serial gateways in transparent
//! mode forward them from a drive set to ASCII. There is no transaction id: late replies are
//! told apart by discarding stale input before each request and by the echo checks, as on a
//! serial line.

use std::io;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use super::Transport;
use super::tcp::TcpTransport;
use drivemap_core::profile::TransportKind;

/// A TCP connection to a transparent gateway in front of a Modbus ASCII line.
pub struct AsciiOverTcpTransport(TcpTransport);

impl AsciiOverTcpTransport {
    /// Connects to the gateway, waiting at most `timeout`.
    pub fn connect(addr: impl ToSocketAddrs, timeout: Duration) -> io::Result<Self> {
        TcpTransport::connect_as(addr, timeout, TransportKind::AsciiOverTcp).map(Self)
    }

    /// Wraps a connected stream.
    pub fn from_stream(stream: TcpStream) -> io::Result<Self> {
        TcpTransport::from_stream_as(stream, TransportKind::AsciiOverTcp).map(Self)
    }

    /// The TCP connection.
    pub fn tcp(&mut self) -> &mut TcpTransport {
        &mut self.0
    }
}

impl Transport for AsciiOverTcpTransport {
    fn kind(&self) -> TransportKind {
        TransportKind::AsciiOverTcp
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.0.send(frame)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.0.recv(buf, deadline)
    }
    fn discard_input(&mut self) -> io::Result<()> {
        self.0.discard_input()
    }
    fn reconnect(&mut self) -> io::Result<()> {
        self.0.reconnect()
    }
}
