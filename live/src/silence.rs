//! Failing fast on a silent peer: once a request has had every attempt the client makes
//! (`--retries` + 1) without a single byte coming back, the peer is taken as silent and every
//! later request of the command fails at once, without being sent, saying which request went
//! unanswered. A read that depends on settings (a scale selector, a reference) would otherwise
//! wait a timeout and its retries for each setting and then again for itself (issue 27: 9.3 s
//! for one register of a peer that never answers).
//!
//! Any byte received (a reply, an exception, even a garbled or late frame) means the peer is
//! there: the count starts again. `poll` re-arms the guard every cycle
//! ([`SilenceGuard::rearm`]), so a drive that comes back is read again.

use std::cell::RefCell;
use std::io;
use std::rc::Rc;
use std::time::Instant;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;

/// What the guard has seen; shared between the transport wrapper and the session.
#[derive(Debug, Default)]
struct State {
    /// Attempts the client makes per request: after this many unanswered in a row, silent.
    attempts: u32,
    /// Attempts in a row that got no byte back.
    unanswered: u32,
    /// The request of the latest attempt, as `03h read of 0301h x1`.
    last: String,
    /// Requests that went unanswered through every attempt, in order.
    tried: Vec<String>,
    /// Requests refused unsent because the peer was silent.
    not_sent: u32,
}

impl State {
    fn silent(&self) -> bool {
        self.attempts > 0 && self.unanswered >= self.attempts
    }

    /// Counts a request not sent and says why.
    fn refuse(&mut self) -> io::Error {
        self.not_sent += 1;
        io::Error::other(format!(
            "not sent: the peer gave no reply to {} ({} attempt(s)), so nothing more is sent to it in this command",
            self.last, self.attempts
        ))
    }
}

/// The session's handle on the guard of its transport.
#[derive(Debug, Clone, Default)]
pub struct SilenceGuard(Rc<RefCell<State>>);

impl SilenceGuard {
    /// A guard for a client that makes `attempts` attempts per request (0: never trips).
    pub fn new(attempts: u32) -> SilenceGuard {
        SilenceGuard(Rc::new(RefCell::new(State {
            attempts,
            ..State::default()
        })))
    }

    /// `transport`, refusing to send once this guard has seen the peer silent.
    pub fn wrap(&self, transport: Box<dyn Transport>) -> Box<dyn Transport> {
        Box::new(Guarded {
            inner: transport,
            guard: self.clone(),
        })
    }

    /// Never trips: every request is sent (`scan` identifying a slave, where a register
    /// another map's drive would not answer says something about the map, not the link).
    pub fn disable(&self) {
        self.0.borrow_mut().attempts = 0;
    }

    /// Lets requests through again (`poll`, before each cycle): the peer may be back.
    pub fn rearm(&self) {
        let mut s = self.0.borrow_mut();
        s.unanswered = 0;
    }

    /// Whether the peer has been taken as silent.
    pub fn tripped(&self) -> bool {
        self.0.borrow().silent()
    }

    /// What was tried and what was not sent, when the peer went silent: `no reply to 03h read
    /// of 0301h x1 (3 attempt(s) each); 2 later request(s) not sent`.
    pub fn report(&self) -> Option<String> {
        let s = self.0.borrow();
        if s.tried.is_empty() {
            return None;
        }
        let mut out = format!(
            "no reply to {} ({} attempt(s) each)",
            s.tried.join(", "),
            s.attempts
        );
        if s.not_sent > 0 {
            out += &format!("; {} later request(s) not sent", s.not_sent);
        }
        Some(out)
    }
}

struct Guarded {
    inner: Box<dyn Transport>,
    guard: SilenceGuard,
}

impl Transport for Guarded {
    fn kind(&self) -> TransportKind {
        self.inner.kind()
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        let what = describe(self.inner.kind(), frame);
        {
            let mut s = self.guard.0.borrow_mut();
            if s.silent() {
                return Err(s.refuse());
            }
            s.unanswered += 1;
            s.last = what;
            if s.silent() {
                let last = s.last.clone();
                s.tried.push(last);
            }
        }
        self.inner.send(frame)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        if n > 0 {
            let mut s = self.guard.0.borrow_mut();
            if s.silent() {
                // A reply after all (late): not silent; the request stays listed as tried.
                s.tried.pop();
            }
            s.unanswered = 0;
        }
        Ok(n)
    }

    /// The client calls this first in every attempt (before an RTU link's wait for silence and
    /// the send): a request after one that went unanswered through every attempt ends here,
    /// without waiting for the line.
    fn discard_input(&mut self) -> io::Result<()> {
        {
            let mut s = self.guard.0.borrow_mut();
            if s.silent() {
                return Err(s.refuse());
            }
        }
        self.inner.discard_input()
    }

    fn reconnect(&mut self) -> io::Result<()> {
        self.inner.reconnect()
    }

    fn inter_char_timeout(&self) -> Option<std::time::Duration> {
        self.inner.inter_char_timeout()
    }
}

/// A request frame as the client's errors say it: `03h read of 0301h x1` (PDU address),
/// `06h write of 0001h`, `10h write of 0001h x2`, else `08h request`.
fn describe(kind: TransportKind, frame: &[u8]) -> String {
    // A Modbus ASCII frame is described by the RTU frame it stands for.
    let mut rtu_frame = [0u8; drivemap_runtime::rtu::MAX_FRAME];
    let (kind, frame) = match drivemap_runtime::ascii::to_rtu(frame, &mut rtu_frame) {
        Ok(n) if kind.is_ascii() => (TransportKind::Rtu, &rtu_frame[..n]),
        _ => (kind, frame),
    };
    let pdu = frame
        .get(if kind.is_serial_framed() { 1 } else { 7 }..)
        .unwrap_or_default();
    let word = |i: usize| {
        pdu.get(i..i + 2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .unwrap_or_default()
    };
    match pdu.first() {
        Some(f @ (0x03 | 0x04)) => format!("{f:02X}h read of {:04X}h x{}", word(1), word(3)),
        Some(0x06) => format!("06h write of {:04X}h", word(1)),
        Some(0x10) => format!("10h write of {:04X}h x{}", word(1), word(3)),
        Some(f) => format!("{f:02X}h request"),
        None => "an empty frame".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A transport that never answers, counting what it was sent.
    struct Mute(Rc<RefCell<u32>>);

    impl Transport for Mute {
        fn kind(&self) -> TransportKind {
            TransportKind::Tcp
        }
        fn send(&mut self, _: &[u8]) -> io::Result<()> {
            *self.0.borrow_mut() += 1;
            Ok(())
        }
        fn recv(&mut self, _: &mut [u8], _: Instant) -> io::Result<usize> {
            Ok(0)
        }
    }

    const READ_0301: [u8; 12] = [0, 1, 0, 0, 0, 6, 1, 0x03, 0x03, 0x01, 0x00, 0x01];
    const READ_0024: [u8; 12] = [0, 2, 0, 0, 0, 6, 1, 0x03, 0x00, 0x24, 0x00, 0x01];

    #[test]
    fn after_every_attempt_of_one_request_unanswered_nothing_more_is_sent() {
        let sent = Rc::new(RefCell::new(0));
        let guard = SilenceGuard::new(3);
        let mut t = guard.wrap(Box::new(Mute(Rc::clone(&sent))));
        let mut buf = [0u8; 8];
        for _ in 0..3 {
            t.send(&READ_0301).unwrap();
            assert_eq!(t.recv(&mut buf, Instant::now()).unwrap(), 0);
        }
        assert!(guard.tripped());
        let e = t.discard_input().unwrap_err();
        assert!(
            e.to_string().contains(
                "not sent: the peer gave no reply to 03h read of 0301h x1 (3 attempt(s))"
            ),
            "{e}"
        );
        assert_eq!(*sent.borrow(), 3);
        assert_eq!(
            guard.report().unwrap(),
            "no reply to 03h read of 0301h x1 (3 attempt(s) each); 1 later request(s) not sent"
        );
        assert!(t.send(&READ_0024).is_err());
        assert_eq!(*sent.borrow(), 3);
        guard.rearm();
        t.discard_input().unwrap();
        t.send(&READ_0024).unwrap();
        assert_eq!(*sent.borrow(), 4);
    }

    /// Answers every other attempt with one byte.
    struct Sometimes(bool);

    impl Transport for Sometimes {
        fn kind(&self) -> TransportKind {
            TransportKind::RtuOverTcp
        }
        fn send(&mut self, _: &[u8]) -> io::Result<()> {
            self.0 = !self.0;
            Ok(())
        }
        fn recv(&mut self, buf: &mut [u8], _: Instant) -> io::Result<usize> {
            buf[0] = 1;
            Ok(usize::from(self.0))
        }
    }

    #[test]
    fn any_byte_back_means_the_peer_is_there() {
        let guard = SilenceGuard::new(2);
        let mut t = guard.wrap(Box::new(Sometimes(false)));
        let mut buf = [0u8; 8];
        for _ in 0..20 {
            t.send(&[1, 0x03, 0, 0x20, 0, 1, 0, 0]).unwrap();
            t.recv(&mut buf, Instant::now()).unwrap();
        }
        assert!(!guard.tripped());
        assert_eq!(guard.report(), None);
    }

    #[test]
    fn frames_are_described_as_the_client_says_them() {
        assert_eq!(
            describe(
                TransportKind::RtuOverTcp,
                &[1, 0x10, 0, 1, 0, 2, 4, 0, 0, 0, 0]
            ),
            "10h write of 0001h x2"
        );
        assert_eq!(
            describe(
                TransportKind::TcpGateway,
                &[0, 1, 0, 0, 0, 6, 1, 0x06, 0, 1, 0, 5]
            ),
            "06h write of 0001h"
        );
        assert_eq!(describe(TransportKind::Rtu, &[]), "an empty frame");
    }
}
