//! An in-memory link to a [`Simulator`] (a drive simulated from its map) that loses, delays and
//! refuses frames on request and records what reached the wire: fault injection at the
//! transport for tests of the drive trait, with no socket and no real time.
//!
//! Each request takes the next [`LinkFault`] of the script (none once it is used up). Every
//! frame the client sends is recorded in [`SimLink::log`] with the tag the test set
//! ([`SimLink::tag`]), whether the drive executed it, the simulator's settings before it and the
//! drive model's run command after it, so a test can check invariants on what reached the wire
//! and on the drive.
//!
//! Time does not pass here: a lost reply times out as soon as the client's deadline has passed
//! (give the client a short timeout), and a late reply arrives as soon as the client listens
//! again after giving up on it.

use std::collections::VecDeque;
use std::io;
use std::time::{Duration, Instant};

use drivemap_live::LiveSettings;
use drivemap_runtime::async_client::AsyncTransport;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::pdu::Response;
use drivemap_runtime::tcp;
use drivemap_runtime::transport::Transport;
use drivemap_sim::Simulator;
use drivemap_sim::framing::{self, Decoded};

/// What happens to one request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkFault {
    /// The request never reaches the drive.
    LoseRequest,
    /// The drive executes the request; its reply is lost.
    LoseReply,
    /// The drive executes the request; its reply arrives after the client stopped waiting for
    /// it: when the client next listens with another deadline (its wait for silence on an RTU
    /// link, or the next request's receive, before that request's reply), or with the next
    /// frame sent if it does not listen before.
    LateReply,
    /// The drive does not execute the request and answers with exception `code` (a busy
    /// drive, a gateway that cannot reach it).
    Exception(u8),
    /// The connection breaks: the request is lost (`executed: false`) or executed with its
    /// reply lost (`executed: true`), and the link reports the connection reset until the client
    /// reconnects.
    Disconnect {
        /// Whether the drive executed the request before the connection broke.
        executed: bool,
    },
}

/// One frame the client sent.
#[derive(Debug, Clone)]
pub struct Sent {
    /// The test's tag when it was sent ([`SimLink::tag`]).
    pub tag: u32,
    /// The frame as sent.
    pub frame: Vec<u8>,
    /// Whether the drive executed it.
    pub executed: bool,
    /// The simulator's settings just before the frame (for checking values against limits in
    /// force).
    pub settings: Option<LiveSettings>,
    /// The drive model's run command after the frame (`None` without a model).
    pub run_command: Option<bool>,
}

/// The client's end of an in-memory link to a [`Simulator`].
pub struct SimLink {
    kind: TransportKind,
    /// The simulated drive.
    pub sim: Simulator,
    script: VecDeque<Option<LinkFault>>,
    /// Bytes that arrived and were not yet read.
    pending: VecDeque<Vec<u8>>,
    /// A late reply, and the deadline of the receive it missed (set at that receive's first
    /// call): it arrives when the client listens again with another deadline (a wait for
    /// silence, the next request's receive), or with the next frame sent.
    held: Option<(Vec<u8>, Option<Instant>)>,
    /// The connection is broken until [`Transport::reconnect`].
    broken: bool,
    /// Tag recorded with each frame sent.
    pub tag: u32,
    /// Every frame sent, in order.
    pub log: Vec<Sent>,
    /// Record the settings in force before each frame (costs a clone per frame).
    pub record_settings: bool,
    /// Connections re-established.
    pub reconnects: u32,
}

impl SimLink {
    /// A link of `kind` (RTU framing for [`TransportKind::Rtu`] and
    /// [`TransportKind::RtuOverTcp`], Modbus TCP for [`TransportKind::Tcp`]) to `sim`.
    pub fn new(kind: TransportKind, sim: Simulator) -> SimLink {
        SimLink {
            kind,
            sim,
            script: VecDeque::new(),
            pending: VecDeque::new(),
            held: None,
            broken: false,
            tag: 0,
            log: Vec::new(),
            record_settings: false,
            reconnects: 0,
        }
    }

    /// What happens to the next requests, one entry each (`None`: delivered and answered).
    pub fn script(&mut self, faults: impl IntoIterator<Item = Option<LinkFault>>) {
        self.script.extend(faults);
    }

    /// Applies `fault` to the next request without an entry in the script yet.
    pub fn inject(&mut self, fault: LinkFault) {
        self.script.push_back(Some(fault));
    }

    /// Requests still scripted.
    pub fn scripted(&self) -> usize {
        self.script.len()
    }

    /// Drops the faults still scripted: the next requests are delivered and answered.
    pub fn clear_script(&mut self) {
        self.script.clear();
    }

    fn execute(&mut self, frame: &[u8]) -> Option<Vec<u8>> {
        let mut out = [0u8; tcp::MAX_FRAME];
        let handled = self.sim.handle(self.kind, frame, &mut out);
        handled.reply.map(|n| out[..n].to_vec())
    }

    /// An exception reply to `frame` with `code`, framed as the drive would send it (none to a
    /// broadcast or a damaged frame).
    fn exception(&self, frame: &[u8], code: u8) -> Option<Vec<u8>> {
        let Decoded::Request { origin, request } = framing::decode(self.kind, frame) else {
            return None;
        };
        if origin.slave() == 0 {
            return None;
        }
        let function = request.function();
        let mut out = [0u8; tcp::MAX_FRAME];
        let n = origin.reply(function, &Response::Exception { function, code }, &mut out)?;
        Some(out[..n].to_vec())
    }
}

impl Transport for SimLink {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        if self.broken {
            return Err(io::ErrorKind::ConnectionReset.into());
        }
        if let Some((late, _)) = self.held.take() {
            self.pending.push_back(late);
        }
        let fault = self.script.pop_front().flatten();
        let settings = self.record_settings.then(|| self.sim.settings());
        let executed = !matches!(
            fault,
            Some(
                LinkFault::LoseRequest
                    | LinkFault::Exception(_)
                    | LinkFault::Disconnect { executed: false }
            )
        );
        let reply = if executed { self.execute(frame) } else { None };
        self.log.push(Sent {
            tag: self.tag,
            frame: frame.to_vec(),
            executed,
            settings,
            run_command: self.sim.state().map(|s| s.run_command),
        });
        match fault {
            None => self.pending.extend(reply),
            Some(LinkFault::LoseRequest | LinkFault::LoseReply) => {}
            Some(LinkFault::LateReply) => self.held = reply.map(|r| (r, None)),
            Some(LinkFault::Exception(code)) => {
                let reply = self.exception(frame, code);
                self.pending.extend(reply);
            }
            Some(LinkFault::Disconnect { .. }) => self.broken = true,
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        if let Some(got) = self.arrived(buf, deadline) {
            return got;
        }
        // Nothing arrives before the deadline: sleep until then (at most 100 ms a call), so that
        // many links can wait side by side.
        let now = Instant::now();
        if deadline > now {
            std::thread::sleep((deadline - now).min(Duration::from_millis(100)));
        }
        Ok(0)
    }

    fn discard_input(&mut self) -> io::Result<()> {
        self.discard()
    }

    fn reconnect(&mut self) -> io::Result<()> {
        self.reconnect_link()
    }
}

/// The same link for the async client: the same script, log and timing, where waiting for a
/// deadline is a tokio sleep.
impl AsyncTransport for SimLink {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    async fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        Transport::send(self, frame)
    }

    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        if let Some(got) = self.arrived(buf, deadline) {
            return got;
        }
        let now = Instant::now();
        if deadline > now {
            tokio::time::sleep((deadline - now).min(Duration::from_millis(100))).await;
        }
        Ok(0)
    }

    async fn discard_input(&mut self) -> io::Result<()> {
        self.discard()
    }

    async fn reconnect(&mut self) -> io::Result<()> {
        self.reconnect_link()
    }
}

impl SimLink {
    /// What a receive until `deadline` gets without waiting: bytes, a broken connection, or
    /// `None` (nothing before the deadline).
    fn arrived(&mut self, buf: &mut [u8], deadline: Instant) -> Option<io::Result<usize>> {
        match &mut self.held {
            Some((_, missed @ None)) => *missed = Some(deadline),
            Some((_, Some(missed))) if *missed != deadline => {
                let (late, _) = self.held.take().expect("held");
                self.pending.push_back(late);
            }
            _ => {}
        }
        if let Some(bytes) = self.pending.front_mut() {
            let n = buf.len().min(bytes.len());
            buf[..n].copy_from_slice(&bytes[..n]);
            bytes.drain(..n);
            if bytes.is_empty() {
                self.pending.pop_front();
            }
            return Some(Ok(n));
        }
        if self.broken {
            return Some(Err(io::ErrorKind::ConnectionReset.into()));
        }
        None
    }

    fn discard(&mut self) -> io::Result<()> {
        if self.broken {
            return Err(io::ErrorKind::ConnectionReset.into());
        }
        self.pending.clear();
        Ok(())
    }

    fn reconnect_link(&mut self) -> io::Result<()> {
        if !self.kind.is_rtu_framed() || self.kind == TransportKind::RtuOverTcp {
            // A new connection: nothing of the old one arrives on it.
            self.broken = false;
            self.pending.clear();
            self.held = None;
            self.reconnects += 1;
            return Ok(());
        }
        Err(io::ErrorKind::Unsupported.into())
    }
}
