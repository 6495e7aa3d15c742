//! Links that carry frames: the [`Transport`] trait and its implementations.
//!
//! A transport moves bytes; it does not interpret them. The client frames requests, checks
//! replies and keeps time. A transport adds what only the link can do: the 3.5-character silence
//! before a serial frame, RS-485 direction control, discarding bytes that arrived while nobody
//! was waiting for them.

use std::io;
use std::time::{Duration, Instant};

use crate::profile::TransportKind;

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
    /// request. The default does nothing.
    fn discard_input(&mut self) -> io::Result<()> {
        Ok(())
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
    fn inter_char_timeout(&self) -> Option<Duration> {
        (**self).inter_char_timeout()
    }
}

/// Time remaining until `deadline`, or `None` when it has passed.
pub(crate) fn remaining(deadline: Instant) -> Option<Duration> {
    deadline
        .checked_duration_since(Instant::now())
        .filter(|d| !d.is_zero())
}
