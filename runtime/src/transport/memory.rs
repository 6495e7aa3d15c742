//! An in-memory pair of connected transports, for tests and simulations.

use std::collections::VecDeque;
use std::io;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use super::Transport;
use drivemap_core::profile::TransportKind;

#[derive(Default)]
struct Pipe {
    bytes: Mutex<VecDeque<u8>>,
    ready: Condvar,
}

impl Pipe {
    fn lock(&self) -> std::sync::MutexGuard<'_, VecDeque<u8>> {
        self.bytes.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// One end of an in-memory link. Bytes sent on one end are received on the other, in order,
/// with no loss and no timing: `drivemap_sim::FaultyLink` adds faults.
pub struct MemoryTransport {
    kind: TransportKind,
    incoming: Arc<Pipe>,
    outgoing: Arc<Pipe>,
}

impl MemoryTransport {
    /// Two connected ends framing as `kind`.
    pub fn pair(kind: TransportKind) -> (MemoryTransport, MemoryTransport) {
        let a = Arc::new(Pipe::default());
        let b = Arc::new(Pipe::default());
        (
            MemoryTransport {
                kind,
                incoming: a.clone(),
                outgoing: b.clone(),
            },
            MemoryTransport {
                kind,
                incoming: b,
                outgoing: a,
            },
        )
    }

    /// Bytes received and not yet read.
    pub fn pending(&self) -> usize {
        self.incoming.lock().len()
    }
}

impl Transport for MemoryTransport {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.outgoing.lock().extend(frame.iter().copied());
        self.outgoing.ready.notify_all();
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let mut q = self.incoming.lock();
        loop {
            if !q.is_empty() {
                let n = buf.len().min(q.len());
                for (slot, b) in buf.iter_mut().zip(q.drain(..n)) {
                    *slot = b;
                }
                return Ok(n);
            }
            let Some(wait) = super::remaining(deadline) else {
                return Ok(0);
            };
            q = self
                .incoming
                .ready
                .wait_timeout(q, wait)
                .map(|(g, _)| g)
                .unwrap_or_else(|e| e.into_inner().0);
        }
    }

    fn discard_input(&mut self) -> io::Result<()> {
        self.incoming.lock().clear();
        Ok(())
    }
}
