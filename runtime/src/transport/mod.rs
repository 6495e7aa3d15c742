//! Links that carry frames: the [`Transport`] trait and its implementations.
//!
//! A transport moves bytes; it does not interpret them. The client frames requests, checks
//! replies and keeps time. A transport adds what only the link can do: the 3.5-character silence
//! before a serial frame, RS-485 direction control, discarding bytes that arrived while nobody
//! was waiting for them.

use std::io;
use std::time::{Duration, Instant};

use drivemap_core::profile::TransportKind;

pub mod ascii_over_tcp;
pub mod memory;
pub mod rtu_over_tcp;
#[cfg(feature = "serial")]
pub mod serial;
pub mod tcp;

/// A link to one or more drives that the blocking [`Client`](crate::client::Client) talks
/// over. Implement it for a link the crate does not know (a USB bridge, a radio modem).
pub trait Transport {
    /// How frames are framed on this link, which also selects the profile's address offset.
    fn kind(&self) -> TransportKind;

    /// Sends one whole frame. A serial transport waits for the inter-frame silence first.
    fn send(&mut self, frame: &[u8]) -> io::Result<()>;

    /// Receives whatever bytes are available into `buf`, waiting until at least one byte
    /// arrives or `deadline` passes. Returns 0 when the deadline passed with nothing received.
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize>;

    /// Throws away bytes received but not yet read: stale or late replies. Called before each
    /// request. It must not wait for more input, and should stop after about
    /// [`DISCARD_BUDGET`] bytes against a peer that keeps sending (the reply matching skips the
    /// rest, within the reply's deadline). The default does nothing.
    fn discard_input(&mut self) -> io::Result<()> {
        Ok(())
    }

    /// Re-establishes a connection the peer closed or reset (see
    /// [`ClientOptions::reconnect`](crate::client::ClientOptions::reconnect)); waits at most the
    /// transport's connect timeout. The default returns [`io::ErrorKind::Unsupported`]: links
    /// without connections (serial lines) have nothing to re-establish.
    fn reconnect(&mut self) -> io::Result<()> {
        Err(io::ErrorKind::Unsupported.into())
    }

    /// The longest gap allowed between two bytes of one frame; a frame broken off by a longer
    /// gap is discarded. `None` (the default) for links that do not keep byte timing (TCP).
    fn inter_char_timeout(&self) -> Option<Duration> {
        None
    }
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn kind(&self) -> TransportKind {
        (**self).kind()
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        (**self).send(frame)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        (**self).recv(buf, deadline)
    }
    fn discard_input(&mut self) -> io::Result<()> {
        (**self).discard_input()
    }
    fn reconnect(&mut self) -> io::Result<()> {
        (**self).reconnect()
    }
    fn inter_char_timeout(&self) -> Option<Duration> {
        (**self).inter_char_timeout()
    }
}

/// Most bytes a transport's [`Transport::discard_input`] takes before a request: a peer that
/// sends without pause is not drained for ever.
pub const DISCARD_BUDGET: usize = 64 * 1024;

/// Whether an I/O error means the connection is gone (closed or reset by the peer), so that
/// only a new connection can carry the next request.
pub fn is_connection_loss(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::UnexpectedEof
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::BrokenPipe
            | io::ErrorKind::NotConnected
    )
}

/// Time remaining until `deadline`, or `None` when it has passed.
pub(crate) fn remaining(deadline: Instant) -> Option<Duration> {
    deadline
        .checked_duration_since(Instant::now())
        .filter(|d| !d.is_zero())
}
