//! Finding the answer to a request in a stream of received bytes, without I/O.
//!
//! Bytes arrive in arbitrary chunks. Before the answer there may be line noise, the tail of an
//! earlier frame, a reply from another slave, or a late reply to an earlier request; after it a
//! duplicate. [`ReplyBuffer::scan`] accepts only a frame that passes every check against the
//! request (CRC or MBAP header, slave or unit, transaction id, function echo, byte count, address,
//! quantity and value echoes), discards whole frames that are valid but not the answer, and
//! skips garbage byte by byte until it is back in step (resynchronisation). What it discarded is
//! counted and the first reason kept (the cause; what follows it is usually debris), so a timeout can say what was seen instead.

use ::core::ops::Range;

use crate::pdu::{self, FrameError, Request};
use crate::{crc, rtu, tcp};

/// Capacity of the receive buffer: twice the largest frame, so a frame that is still incomplete
/// never fills it.
pub(crate) const CAPACITY: usize = 2 * tcp::MAX_FRAME;

/// How replies are framed and addressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Framing {
    /// RTU frames (serial line or RTU over TCP) from `slave`.
    Rtu {
        /// The slave the reply must come from.
        slave: u8,
    },
    /// Modbus TCP frames with transaction id `transaction` from `unit`.
    Tcp {
        /// The request's transaction id.
        transaction: u16,
        /// The request's unit identifier.
        unit: u8,
    },
}

/// What was thrown away while waiting for the answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct Discarded {
    /// Complete, intact frames that were not the answer (other slave, late reply, bad echo).
    pub frames: u32,
    /// Bytes skipped to get back in step (noise, damaged frames, broken-off frames).
    pub bytes: u32,
    /// Why the first thing was discarded.
    pub first: Option<Discard>,
}

/// Why something was discarded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Discard {
    /// A frame or byte that failed a check.
    Frame(FrameError),
    /// A frame left incomplete: broken off by a gap longer than the inter-character timeout,
    /// or still incomplete when the reply timed out.
    Gap {
        /// The bytes of the incomplete frame.
        bytes: usize,
    },
    /// Modbus ASCII: characters that were not an intact frame (no `:` before them, a frame
    /// broken off by a new `:` or too long, bad hexadecimal digits or LRC).
    Ascii(crate::ascii::AsciiError),
}

impl Discarded {
    fn frame(&mut self, e: FrameError) {
        self.frames = self.frames.saturating_add(1);
        self.first.get_or_insert(Discard::Frame(e));
    }

    fn bytes(&mut self, n: usize, why: Discard) {
        self.bytes = self.bytes.saturating_add(n as u32);
        self.first.get_or_insert(why);
    }

    /// Whether nothing was discarded.
    pub fn is_empty(&self) -> bool {
        self.frames == 0 && self.bytes == 0
    }
}

impl ::core::fmt::Display for Discarded {
    fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
        write!(
            f,
            "discarded {} frame(s) and {} byte(s)",
            self.frames, self.bytes
        )?;
        match self.first {
            Some(Discard::Frame(e)) => write!(f, ", first: {e}"),
            Some(Discard::Gap { bytes }) => {
                write!(f, ", first: an incomplete frame of {bytes} byte(s)")
            }
            Some(Discard::Ascii(e)) => write!(f, ", first: {e}"),
            None => Ok(()),
        }
    }
}

enum Class {
    /// The answer, this many bytes long.
    Ours(usize),
    /// Not enough bytes yet to decide.
    Incomplete,
    /// An intact frame of this length that is not the answer.
    Foreign(FrameError, usize),
    /// Not the start of a frame.
    Garbage(FrameError),
}

/// A fixed receive buffer that locates the answer to one request.
pub struct ReplyBuffer {
    buf: [u8; CAPACITY],
    len: usize,
    discarded: Discarded,
}

impl Default for ReplyBuffer {
    fn default() -> Self {
        Self::new()
    }
}

impl ReplyBuffer {
    /// An empty buffer.
    pub const fn new() -> Self {
        ReplyBuffer {
            buf: [0; CAPACITY],
            len: 0,
            discarded: Discarded {
                frames: 0,
                bytes: 0,
                first: None,
            },
        }
    }

    /// Empties the buffer and the discard counts (before a new request).
    pub fn clear(&mut self) {
        self.len = 0;
        self.discarded = Discarded::default();
    }

    /// Bytes held that are not yet part of an answer.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Free space to receive into; call [`ReplyBuffer::filled`] with the count received.
    pub fn space(&mut self) -> &mut [u8] {
        if self.len == CAPACITY {
            // Cannot happen after scan (an incomplete frame is at most MAX_FRAME bytes), but
            // never hand out an empty buffer: drop the oldest byte.
            self.drop_front(1);
            self.discarded.bytes(
                1,
                Discard::Frame(FrameError::Length {
                    expected: CAPACITY,
                    got: CAPACITY,
                }),
            );
        }
        &mut self.buf[self.len..]
    }

    /// Records that `n` bytes were written into [`ReplyBuffer::space`].
    pub fn filled(&mut self, n: usize) {
        self.len = (self.len + n).min(CAPACITY);
    }

    /// Appends bytes (convenience for tests and fuzzing); returns how many fitted.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        let space = self.space();
        let n = bytes.len().min(space.len());
        space[..n].copy_from_slice(&bytes[..n]);
        self.filled(n);
        n
    }

    /// Throws away a partial frame after an inter-character gap.
    pub fn break_off(&mut self) {
        if self.len > 0 {
            let n = self.len;
            self.discarded.bytes(n, Discard::Gap { bytes: n });
            self.len = 0;
        }
    }

    /// Counts `n` bytes (characters, on Modbus ASCII) thrown away before they reached the
    /// buffer, for `why`.
    pub fn discard_bytes(&mut self, n: usize, why: Discard) {
        if n > 0 {
            self.discarded.bytes(n, why);
        }
    }

    /// Counts one frame thrown away before it reached the buffer, for `why`.
    pub fn discard_frame(&mut self, why: Discard) {
        self.discarded.frames = self.discarded.frames.saturating_add(1);
        self.discarded.first.get_or_insert(why);
    }

    /// What was discarded since the last [`ReplyBuffer::clear`].
    pub fn discarded(&self) -> Discarded {
        self.discarded
    }

    /// The bytes of a located frame.
    pub fn frame(&self, range: Range<usize>) -> &[u8] {
        self.buf.get(range).unwrap_or(&[])
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    /// Looks for the answer to `request` framed as `framing`. Returns its position when found;
    /// otherwise drops what can never become the answer and waits for more bytes.
    pub fn scan(&mut self, framing: Framing, request: &Request<'_>) -> Option<Range<usize>> {
        loop {
            if self.len == 0 {
                return None;
            }
            match classify(&self.buf[..self.len], framing, request) {
                Class::Ours(n) => return Some(0..n),
                Class::Incomplete => break,
                Class::Foreign(e, n)
                    if starts_inside(&self.buf[..self.len.min(n)], framing, request) =>
                {
                    // Noise before our reply can pass a CRC together with the reply's first
                    // bytes (`0D F3 46 25` + `01`): dropped whole, that "frame" would take the
                    // reply's start with it. Dropped a byte at a time, the reply is found.
                    self.discarded.bytes(1, Discard::Frame(e));
                    self.drop_front(1);
                }
                Class::Foreign(e, n) => {
                    self.discarded.frame(e);
                    self.drop_front(n);
                }
                Class::Garbage(e) => {
                    self.discarded.bytes(1, Discard::Frame(e));
                    self.drop_front(1);
                }
            }
        }
        // The front may be a frame still arriving, or noise that looks like a long frame's
        // header. Look past it for a complete answer.
        for off in 1..self.len {
            if let Class::Ours(n) = classify(&self.buf[off..self.len], framing, request) {
                self.discarded.bytes(
                    off,
                    Discard::Frame(FrameError::Length {
                        expected: n,
                        got: off,
                    }),
                );
                return Some(off..off + n);
            }
        }
        None
    }
}

/// Whether our reply could start inside `frame` (after its first byte): on an RTU-framed link,
/// a byte of our slave address followed by our function (or its exception), or at the end.
/// Modbus TCP frames carry a transaction id and are never cut from noise.
fn starts_inside(frame: &[u8], framing: Framing, request: &Request<'_>) -> bool {
    let Framing::Rtu { slave } = framing else {
        return false;
    };
    let f = request.function();
    (1..frame.len()).any(|off| {
        frame[off] == slave
            && frame
                .get(off + 1)
                .is_none_or(|&g| g == f || g == f | pdu::function::EXCEPTION_BIT)
    })
}

fn classify(b: &[u8], framing: Framing, request: &Request<'_>) -> Class {
    match framing {
        Framing::Rtu { slave } => classify_rtu(b, slave, request),
        Framing::Tcp { transaction, unit } => classify_tcp(b, transaction, unit, request),
    }
}

fn classify_rtu(b: &[u8], slave: u8, request: &Request<'_>) -> Class {
    let [address, function, ..] = *b else {
        return Class::Incomplete;
    };
    let f = request.function();
    if address == slave && (function == f || function == f | pdu::function::EXCEPTION_BIT) {
        let len = if function == f {
            rtu::expected_response_len(request)
        } else {
            rtu::EXCEPTION_FRAME_LEN
        };
        let Some(frame) = b.get(..len) else {
            return own_length(b, request).unwrap_or(Class::Incomplete);
        };
        return match rtu::decode_response(slave, request, frame) {
            Ok(_) => Class::Ours(len),
            Err(crc @ FrameError::Crc { .. }) => {
                own_length(b, request).unwrap_or(Class::Garbage(crc))
            }
            Err(e) => Class::Foreign(e, len),
        };
    }
    match rtu::response_frame_len(b) {
        Err(e) => Class::Garbage(e),
        Ok(None) => Class::Incomplete,
        Ok(Some(len)) => match b.get(..len) {
            None => Class::Incomplete,
            Some(frame) => match crc::check(frame) {
                Err((computed, received)) => Class::Garbage(FrameError::Crc { computed, received }),
                Ok(_) if address != slave => Class::Foreign(
                    FrameError::Slave {
                        expected: slave,
                        got: address,
                    },
                    len,
                ),
                Ok(_) => Class::Foreign(
                    FrameError::Function {
                        expected: f,
                        got: function,
                    },
                    len,
                ),
            },
        },
    }
}

/// Our slave and function, but not the length the request implies: an intact frame of the
/// length its own byte count gives is a reply to another request (a different quantity).
fn own_length(b: &[u8], request: &Request<'_>) -> Option<Class> {
    let len = rtu::response_frame_len(b).ok()??;
    let frame = b.get(..len)?;
    crc::check(frame).ok()?;
    Some(Class::Foreign(
        FrameError::ByteCount {
            expected: request.response_pdu_len().saturating_sub(2),
            got: len.saturating_sub(5),
        },
        len,
    ))
}

fn classify_tcp(b: &[u8], transaction: u16, unit: u8, request: &Request<'_>) -> Class {
    match tcp::Header::parse(b) {
        Err(e) => Class::Garbage(e),
        Ok(None) => Class::Incomplete,
        Ok(Some(h)) => {
            let len = h.frame_len();
            match b.get(..len) {
                None => Class::Incomplete,
                Some(frame) => match tcp::decode_response(transaction, unit, request, frame) {
                    Ok(_) => Class::Ours(len),
                    Err(e) => Class::Foreign(e, len),
                },
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const READ: Request<'static> = Request::ReadHolding {
        address: 0x20,
        quantity: 4,
    };
    const ANSWER: [u8; 13] = [
        0x02, 0x03, 0x08, 0x17, 0x70, 0x17, 0x70, 0x01, 0x09, 0x00, 0x00, 0x38, 0xAC,
    ];
    const RTU2: Framing = Framing::Rtu { slave: 2 };

    #[test]
    fn answer_in_single_bytes() {
        let mut rx = ReplyBuffer::new();
        for (i, b) in ANSWER.iter().enumerate() {
            assert_eq!(rx.scan(RTU2, &READ), None, "early at {i}");
            rx.push(&[*b]);
        }
        assert_eq!(rx.scan(RTU2, &READ), Some(0..13));
        assert!(rx.discarded().is_empty());
    }

    #[test]
    fn resynchronises_after_noise_that_looks_like_a_long_header() {
        let mut rx = ReplyBuffer::new();
        rx.push(&[0x05, 0x03, 0xFA, 0x11]);
        rx.push(&ANSWER);
        let r = rx.scan(RTU2, &READ).unwrap();
        assert_eq!(rx.frame(r), &ANSWER);
        assert_eq!(rx.discarded().bytes, 4);
    }

    #[test]
    fn foreign_frames_are_discarded_whole() {
        let mut rx = ReplyBuffer::new();
        // A reply from slave 1 (000_032dced3a1e91a75.txt:410-417), then ours.
        rx.push(&[0x01, 0x06, 0x00, 0x01, 0x00, 0x03, 0x98, 0x0B]);
        rx.push(&ANSWER);
        let r = rx.scan(RTU2, &READ).unwrap();
        assert_eq!(r, 0..13);
        let d = rx.discarded();
        assert_eq!((d.frames, d.bytes), (1, 0));
        assert_eq!(
            d.first,
            Some(Discard::Frame(FrameError::Slave {
                expected: 2,
                got: 1
            }))
        );
    }

    #[test]
    fn a_reply_for_another_quantity_is_not_the_answer() {
        let mut rx = ReplyBuffer::new();
        let mut other = [0u8; 9];
        other[..7].copy_from_slice(&[0x02, 0x03, 0x04, 0, 1, 0, 2]);
        let c = crc::crc_bytes(&other[..7]);
        other[7..].copy_from_slice(&c);
        rx.push(&other);
        assert_eq!(rx.scan(RTU2, &READ), None);
        rx.push(&ANSWER);
        assert_eq!(rx.scan(RTU2, &READ), Some(0..13));
        assert_eq!(rx.discarded().frames, 1);
    }

    #[test]
    fn tcp_late_reply_is_discarded_by_transaction_id() {
        let req = Request::ReadHolding {
            address: 0,
            quantity: 1,
        };
        let mut rx = ReplyBuffer::new();
        rx.push(&[0, 7, 0, 0, 0, 5, 1, 3, 2, 0, 0x11]);
        rx.push(&[0, 8, 0, 0, 0, 5, 1, 3, 2, 0, 0x22]);
        let f = Framing::Tcp {
            transaction: 8,
            unit: 1,
        };
        let r = rx.scan(f, &req).unwrap();
        assert_eq!(rx.frame(r), &[0, 8, 0, 0, 0, 5, 1, 3, 2, 0, 0x22]);
        assert_eq!(
            rx.discarded().first,
            Some(Discard::Frame(FrameError::Transaction {
                expected: 8,
                got: 7
            }))
        );
    }
}
