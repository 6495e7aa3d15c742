//! A link with a simulated drive behind it that damages replies on request: fault injection for
//! testing how a client copes with what real lines do.

use std::collections::VecDeque;
use std::io;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{ascii, rtu, tcp};

use crate::SimulatedSlave;

/// What happens to the reply to the next request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fault {
    /// The reply is lost.
    Drop,
    /// Only the first `keep` bytes arrive.
    Truncate {
        /// How many bytes arrive.
        keep: usize,
    },
    /// The reply's CRC (RTU) is damaged; on TCP the last byte is, on ASCII the LRC.
    CorruptCrc,
    /// The reply arrives after `delay`.
    Delay(Duration),
    /// The reply arrives twice.
    Duplicate,
    /// The reply claims to come from slave (unit) `slave`: framed as that slave would send it,
    /// so it is intact (RTU: its CRC matches).
    WrongSlave(u8),
    /// The reply is held back and arrives after the next request has been sent, just before
    /// the reply to that request: a late reply to the previous request.
    LateReply,
    /// These bytes arrive before the reply (line noise).
    Noise(Vec<u8>),
    /// The first `keep` bytes arrive, then nothing for `pause`, then the rest of the reply and
    /// the whole reply again (a transmitter that stalled mid-frame and repeated it).
    Gap {
        /// How many bytes arrive first.
        keep: usize,
        /// How long nothing arrives.
        pause: Duration,
    },
}

/// The client's end of a link to a [`SimulatedSlave`], with faults applied in order, one per
/// request.
pub struct FaultyLink {
    kind: TransportKind,
    /// The drive behind the link.
    pub slave: SimulatedSlave,
    faults: VecDeque<Fault>,
    deliveries: VecDeque<(Instant, Vec<u8>)>,
    held: Option<Vec<u8>>,
    /// Requests received.
    pub requests: u32,
    /// Every frame sent over the link, in order (broadcasts included).
    pub sent: Vec<Vec<u8>>,
    /// The inter-character timeout the link reports to the client (`None`: no byte timing).
    pub inter_char_timeout: Option<Duration>,
}

impl FaultyLink {
    /// A link of `kind` to `slave`.
    pub fn new(kind: TransportKind, slave: SimulatedSlave) -> FaultyLink {
        FaultyLink {
            kind,
            slave,
            faults: VecDeque::new(),
            deliveries: VecDeque::new(),
            held: None,
            requests: 0,
            sent: Vec::new(),
            inter_char_timeout: None,
        }
    }

    /// Applies `fault` to the reply to the next request without a fault yet.
    pub fn inject(&mut self, fault: Fault) {
        self.faults.push_back(fault);
    }

    /// Drops the faults injected and not yet applied.
    pub fn clear_faults(&mut self) {
        self.faults.clear();
    }

    fn deliver(&mut self, at: Instant, bytes: Vec<u8>) {
        let i = self
            .deliveries
            .iter()
            .position(|(t, _)| *t > at)
            .unwrap_or(self.deliveries.len());
        self.deliveries.insert(i, (at, bytes));
    }
}

/// The drive's answer to `frame` as the link frames it: on Modbus ASCII the request is turned
/// into the RTU frame it stands for (a damaged one is not answered) and the reply back into
/// ASCII.
fn answer_framed(
    slave: &mut SimulatedSlave,
    kind: TransportKind,
    frame: &[u8],
    out: &mut [u8],
    reply_as: Option<u8>,
) -> Option<usize> {
    if !kind.is_ascii() {
        return slave.answer(kind, frame, out, reply_as);
    }
    let mut request = [0u8; rtu::MAX_FRAME];
    let n = ascii::to_rtu(frame, &mut request).ok()?;
    let mut reply = [0u8; tcp::MAX_FRAME];
    let m = slave.answer(kind, &request[..n], &mut reply, reply_as)?;
    ascii::from_rtu(&reply[..m], out).ok()
}

impl Transport for FaultyLink {
    fn kind(&self) -> TransportKind {
        self.kind
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.requests += 1;
        self.sent.push(frame.to_vec());
        let now = Instant::now();
        if let Some(late) = self.held.take() {
            self.deliver(now, late);
        }
        let fault = self.faults.pop_front();
        // A reply from another slave is framed as that slave sends it (RTU: a matching CRC).
        let reply_as = match fault {
            Some(Fault::WrongSlave(s)) => Some(s),
            _ => None,
        };
        let mut out = [0u8; ascii::MAX_FRAME];
        let Some(n) = answer_framed(&mut self.slave, self.kind, frame, &mut out, reply_as) else {
            return Ok(());
        };
        let mut reply = out[..n].to_vec();
        match fault {
            None => self.deliver(now, reply),
            Some(Fault::Drop) => {}
            Some(Fault::Truncate { keep }) => {
                reply.truncate(keep);
                self.deliver(now, reply);
            }
            Some(Fault::CorruptCrc) if self.kind.is_ascii() => {
                // The LRC's last digit, changed to another hexadecimal digit.
                if let Some(d) = reply.len().checked_sub(3).and_then(|i| reply.get_mut(i)) {
                    *d = if *d == b'0' { b'1' } else { b'0' };
                }
                self.deliver(now, reply);
            }
            Some(Fault::CorruptCrc) => {
                if let Some(last) = reply.last_mut() {
                    *last ^= 0x5A;
                }
                self.deliver(now, reply);
            }
            Some(Fault::Delay(d)) => self.deliver(now + d, reply),
            Some(Fault::Duplicate) => {
                self.deliver(now, reply.clone());
                self.deliver(now, reply);
            }
            Some(Fault::WrongSlave(_)) => self.deliver(now, reply),
            Some(Fault::LateReply) => self.held = Some(reply),
            Some(Fault::Noise(mut noise)) => {
                noise.extend_from_slice(&reply);
                self.deliver(now, noise);
            }
            Some(Fault::Gap { keep, pause }) => {
                let keep = keep.min(reply.len());
                let mut rest = reply[keep..].to_vec();
                rest.extend_from_slice(&reply);
                self.deliver(now, reply[..keep].to_vec());
                self.deliver(now + pause, rest);
            }
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        loop {
            let now = Instant::now();
            if let Some((at, bytes)) = self.deliveries.front_mut()
                && *at <= now
            {
                let n = buf.len().min(bytes.len());
                buf[..n].copy_from_slice(&bytes[..n]);
                bytes.drain(..n);
                if bytes.is_empty() {
                    self.deliveries.pop_front();
                }
                return Ok(n);
            }
            let next = self.deliveries.front().map(|(at, _)| *at);
            let wake = next.map_or(deadline, |at| at.min(deadline));
            if now >= deadline {
                return Ok(0);
            }
            thread::sleep(wake.saturating_duration_since(now));
        }
    }

    fn inter_char_timeout(&self) -> Option<Duration> {
        self.inter_char_timeout
    }

    fn discard_input(&mut self) -> io::Result<()> {
        let now = Instant::now();
        self.deliveries.retain(|(at, _)| *at > now);
        Ok(())
    }
}
