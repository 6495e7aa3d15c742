//! [`InstantLink`]: an in-memory RTU link on which a [`SimulatedSlave`] answers inside `send`,
//! into a fixed buffer: no thread, no clock, no allocation per request (for the benches and
//! the allocation tests of the client and the poller).

use std::io;
use std::time::Instant;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_sim::SimulatedSlave;

/// The simulated drive answers each request as it is sent; `recv` hands the reply over.
pub struct InstantLink {
    /// The drive on the other end.
    pub drive: SimulatedSlave,
    reply: [u8; 256],
    len: usize,
}

impl InstantLink {
    /// A link to `drive`.
    pub fn new(drive: SimulatedSlave) -> InstantLink {
        InstantLink {
            drive,
            reply: [0; 256],
            len: 0,
        }
    }
}

impl Transport for InstantLink {
    fn kind(&self) -> TransportKind {
        TransportKind::Rtu
    }

    #[inline]
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.len = self.drive.respond_rtu(frame, &mut self.reply).unwrap_or(0);
        Ok(())
    }

    #[inline]
    fn recv(&mut self, buf: &mut [u8], _: Instant) -> io::Result<usize> {
        let n = self.len.min(buf.len());
        buf[..n].copy_from_slice(&self.reply[..n]);
        self.reply.copy_within(n..self.len, 0);
        self.len -= n;
        Ok(n)
    }
}
