//! Modbus ASCII framing: `:`, the slave address and the PDU as pairs of hexadecimal characters,
//! the LRC (two's complement of the sum of those bytes), CR LF.
//!
//! The frame carries the same slave address and PDU as an RTU frame, so the rest of the crate
//! works on RTU frames: a request is encoded by [`rtu`] and turned into ASCII by
//! [`from_rtu`]; a received ASCII frame whose LRC holds is turned back by [`to_rtu`] (with a
//! CRC computed for it) and checked by the same reply matching as an RTU reply. [`Assembler`]
//! cuts a stream of characters into frames, holding at most [`MAX_FRAME`] characters.
//!
//! The hexadecimal characters are written and read by the `base16ct` crate (upper case out,
//! either case in).

use crate::crc;
use crate::pdu::{Request, RequestError, Response};
use crate::rtu;

/// The character that starts every frame.
pub const START: u8 = b':';

/// Largest ASCII frame: `:`, the address, a 253-byte PDU and the LRC as two characters each,
/// CR LF.
pub const MAX_FRAME: usize = 1 + 2 * (rtu::MAX_FRAME - 2 + 1) + 2;

/// The LRC of `bytes`: the two's complement of their sum, modulo 256.
pub fn lrc(bytes: &[u8]) -> u8 {
    bytes
        .iter()
        .fold(0u8, |sum, b| sum.wrapping_add(*b))
        .wrapping_neg()
}

/// Why characters are not an ASCII frame, or a frame does not fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum AsciiError {
    /// The frame does not start with `:`.
    #[error("an ASCII frame starts with ':'")]
    Start,
    /// The frame does not end with CR LF.
    #[error("an ASCII frame ends with CR LF")]
    End,
    /// A character between `:` and CR LF is not a hexadecimal digit, or their number is odd.
    #[error("an ASCII frame holds pairs of hexadecimal characters")]
    Hex,
    /// Fewer bytes than an address, a function code and the LRC, or more than a frame holds.
    #[error("an ASCII frame of {bytes} byte(s) between ':' and CR LF")]
    Length {
        /// Bytes the characters stand for (LRC included).
        bytes: u32,
    },
    /// The LRC does not match the bytes.
    #[error("LRC {received:02X}h, expected {computed:02X}h")]
    Lrc {
        /// The LRC of the bytes received.
        computed: u8,
        /// The LRC the frame carried.
        received: u8,
    },
    /// The output buffer is too small.
    #[error("{needed} bytes needed, {available} available")]
    Buffer {
        /// Bytes the output needs.
        needed: u32,
        /// Bytes the buffer has (at most `u32::MAX`).
        available: u32,
    },
}

/// A length as the errors carry it (32 bits keep them small inside every reply error).
fn n32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// Frames `body` (slave address and PDU) as ASCII into `out`; returns the frame's length.
pub fn encode(body: &[u8], out: &mut [u8]) -> Result<usize, AsciiError> {
    let needed = 1 + 2 * (body.len() + 1) + 2;
    if body.len() > rtu::MAX_FRAME - 2 {
        return Err(AsciiError::Length {
            bytes: n32(body.len() + 1),
        });
    }
    if out.len() < needed {
        return Err(AsciiError::Buffer {
            needed: n32(needed),
            available: n32(out.len()),
        });
    }
    out[0] = START;
    let n = 1 + 2 * body.len();
    base16ct::upper::encode(body, &mut out[1..n]).map_err(|_| AsciiError::Hex)?;
    base16ct::upper::encode(&[lrc(body)], &mut out[n..n + 2]).map_err(|_| AsciiError::Hex)?;
    out[n + 2..needed].copy_from_slice(b"\r\n");
    Ok(needed)
}

/// Checks an ASCII frame (`:`, hexadecimal pairs, LRC, CR LF) and writes the slave address
/// and PDU it carries into `out`; returns them (the LRC stripped).
pub fn decode<'a>(frame: &[u8], out: &'a mut [u8]) -> Result<&'a [u8], AsciiError> {
    let Some(rest) = frame.strip_prefix(&[START]) else {
        return Err(AsciiError::Start);
    };
    let Some(hex) = rest.strip_suffix(b"\r\n") else {
        return Err(AsciiError::End);
    };
    if hex.len() % 2 != 0 {
        return Err(AsciiError::Hex);
    }
    let bytes = hex.len() / 2;
    // An address, a function code and the LRC at least; at most an RTU frame's address and
    // PDU and the LRC.
    if !(3..=rtu::MAX_FRAME - 1).contains(&bytes) {
        return Err(AsciiError::Length { bytes: n32(bytes) });
    }
    if out.len() < bytes {
        return Err(AsciiError::Buffer {
            needed: n32(bytes),
            available: n32(out.len()),
        });
    }
    let decoded = base16ct::mixed::decode(hex, &mut out[..bytes]).map_err(|_| AsciiError::Hex)?;
    let (body, check) = decoded.split_at(bytes - 1);
    let computed = lrc(body);
    if check[0] != computed {
        return Err(AsciiError::Lrc {
            computed,
            received: check[0],
        });
    }
    Ok(&out[..bytes - 1])
}

/// Turns an RTU frame (address, PDU, CRC: the CRC is dropped, not checked) into an ASCII frame
/// in `out`; returns its length.
pub fn from_rtu(frame: &[u8], out: &mut [u8]) -> Result<usize, AsciiError> {
    let body = frame
        .len()
        .checked_sub(2)
        .filter(|&n| n >= 2)
        .map(|n| &frame[..n])
        .ok_or(AsciiError::Length {
            bytes: n32(frame.len().saturating_sub(1)),
        })?;
    encode(body, out)
}

/// Checks an ASCII frame and writes the RTU frame with the same address and PDU (and a CRC
/// computed for them) into `out`; returns its length.
pub fn to_rtu(frame: &[u8], out: &mut [u8]) -> Result<usize, AsciiError> {
    let n = decode(frame, out)?.len();
    let needed = n + 2;
    if out.len() < needed {
        return Err(AsciiError::Buffer {
            needed: n32(needed),
            available: n32(out.len()),
        });
    }
    let crc = crc::crc_bytes(&out[..n]);
    out[n..needed].copy_from_slice(&crc);
    Ok(needed)
}

/// Encodes `request` to `slave` as an ASCII frame into `out`; returns its length.
pub fn encode_request(
    slave: u8,
    request: &Request<'_>,
    out: &mut [u8],
) -> Result<usize, RequestError> {
    let mut rtu_frame = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(slave, request, &mut rtu_frame)?;
    from_rtu(&rtu_frame[..n], out).map_err(|_| RequestError::Buffer {
        needed: 1 + 2 * (n - 1) + 2,
        available: out.len(),
    })
}

/// Encodes a response frame (slave side) as ASCII into `out`; returns its length.
pub fn encode_response(
    slave: u8,
    function: u8,
    response: &Response<'_>,
    out: &mut [u8],
) -> Result<usize, RequestError> {
    let mut rtu_frame = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_response(slave, function, response, &mut rtu_frame)?;
    from_rtu(&rtu_frame[..n], out).map_err(|_| RequestError::Buffer {
        needed: 1 + 2 * (n - 1) + 2,
        available: out.len(),
    })
}

/// The function code of an ASCII request frame (the second pair of characters), if it has one.
pub fn function_code(frame: &[u8]) -> Option<u8> {
    let pair = frame.get(3..5)?;
    let mut out = [0u8; 1];
    base16ct::mixed::decode(pair, &mut out).ok()?;
    Some(out[0])
}

/// What [`Assembler::feed`] made of one character.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feed {
    /// Part of a frame still arriving.
    Pending,
    /// A frame is complete (`:` through LF): [`Assembler::frame`] holds it.
    Frame,
    /// This many characters were thrown away: outside any frame, a frame broken off by a new
    /// `:`, or a frame longer than [`MAX_FRAME`].
    Skipped(usize),
}

/// Cuts a stream of characters into ASCII frames: from a `:` to the next LF. A `:` always
/// starts a new frame (what came before it is thrown away), characters outside a frame are
/// thrown away, and so is a frame that grows past [`MAX_FRAME`]. Holds at most [`MAX_FRAME`]
/// characters, allocates nothing.
#[derive(Debug, Clone)]
pub struct Assembler {
    buf: [u8; MAX_FRAME],
    len: usize,
    complete: bool,
}

impl Default for Assembler {
    fn default() -> Self {
        Self::new()
    }
}

impl Assembler {
    /// An assembler outside any frame.
    pub const fn new() -> Assembler {
        Assembler {
            buf: [0; MAX_FRAME],
            len: 0,
            complete: false,
        }
    }

    /// Takes one character.
    pub fn feed(&mut self, c: u8) -> Feed {
        if self.complete {
            self.clear();
        }
        if c == START {
            let dropped = self.len;
            self.buf[0] = START;
            self.len = 1;
            return if dropped > 0 {
                Feed::Skipped(dropped)
            } else {
                Feed::Pending
            };
        }
        if self.len == 0 {
            return Feed::Skipped(1);
        }
        if self.len == MAX_FRAME {
            let dropped = self.len + 1;
            self.clear();
            return Feed::Skipped(dropped);
        }
        self.buf[self.len] = c;
        self.len += 1;
        if c == b'\n' {
            self.complete = true;
            Feed::Frame
        } else {
            Feed::Pending
        }
    }

    /// The complete frame after [`Feed::Frame`]; empty otherwise.
    pub fn frame(&self) -> &[u8] {
        if self.complete {
            &self.buf[..self.len]
        } else {
            &[]
        }
    }

    /// Characters of a frame still arriving (0 between frames).
    pub fn pending(&self) -> usize {
        if self.complete { 0 } else { self.len }
    }

    /// Throws away what is held; returns how many characters of an incomplete frame that was.
    pub fn clear(&mut self) -> usize {
        let dropped = self.pending();
        self.len = 0;
        self.complete = false;
        dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lrc_is_the_twos_complement_of_the_sum() {
        // Modbus over serial line specification, 6.2.1: slave 11h, 03h, 006Bh x3 -> LRC 7Eh.
        assert_eq!(lrc(&[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03]), 0x7E);
        assert_eq!(lrc(&[]), 0);
        assert_eq!(lrc(&[0x01]), 0xFF);
        assert_eq!(lrc(&[0x80, 0x80]), 0);
    }

    #[test]
    fn a_read_request_as_the_specification_prints_it() {
        let request = Request::ReadHolding {
            address: 0x006B,
            quantity: 3,
        };
        let mut out = [0u8; MAX_FRAME];
        let n = encode_request(0x11, &request, &mut out).unwrap();
        assert_eq!(&out[..n], b":1103006B00037E\r\n");
        let mut body = [0u8; rtu::MAX_FRAME];
        assert_eq!(
            decode(&out[..n], &mut body),
            Ok(&[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03][..])
        );
        // Lower-case digits are read too.
        assert_eq!(
            decode(b":1103006b00037e\r\n", &mut body),
            Ok(&[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03][..])
        );
        let mut rtu_frame = [0u8; rtu::MAX_FRAME];
        let m = to_rtu(&out[..n], &mut rtu_frame).unwrap();
        assert_eq!(rtu::decode_request(&rtu_frame[..m]), Ok((0x11, request)));
    }

    #[test]
    fn malformed_frames_say_why() {
        let mut body = [0u8; rtu::MAX_FRAME];
        assert_eq!(
            decode(b"1103006B00037E\r\n", &mut body),
            Err(AsciiError::Start)
        );
        assert_eq!(decode(b":1103006B00037E", &mut body), Err(AsciiError::End));
        assert_eq!(
            decode(b":1103006B00037\r\n", &mut body),
            Err(AsciiError::Hex)
        );
        assert_eq!(
            decode(b":1103006G00037E\r\n", &mut body),
            Err(AsciiError::Hex)
        );
        assert_eq!(
            decode(b":1103006B00037F\r\n", &mut body),
            Err(AsciiError::Lrc {
                computed: 0x7E,
                received: 0x7F
            })
        );
        assert_eq!(
            decode(b":0100\r\n", &mut body),
            Err(AsciiError::Length { bytes: 2 })
        );
        assert_eq!(decode(b"", &mut body), Err(AsciiError::Start));
        assert_eq!(
            decode(b":\r\n", &mut body),
            Err(AsciiError::Length { bytes: 0 })
        );
    }

    #[test]
    fn the_assembler_cuts_frames_and_throws_away_the_rest() {
        let mut a = Assembler::new();
        let mut frames = 0;
        let mut skipped = 0;
        for &c in b"xy:0103\r:1103006B00037E\r\nz" {
            match a.feed(c) {
                Feed::Frame => {
                    frames += 1;
                    assert_eq!(a.frame(), b":1103006B00037E\r\n");
                }
                Feed::Skipped(n) => skipped += n,
                Feed::Pending => {}
            }
        }
        assert_eq!(frames, 1);
        // x, y, the broken-off ":0103\r", z.
        assert_eq!(skipped, 2 + 6 + 1);
        assert_eq!(a.pending(), 0);
        // A frame that never ends is dropped at MAX_FRAME characters.
        let mut a = Assembler::new();
        a.feed(b':');
        let mut dropped = 0;
        for _ in 0..MAX_FRAME {
            if let Feed::Skipped(n) = a.feed(b'0') {
                dropped += n;
            }
        }
        assert_eq!(dropped, MAX_FRAME + 1);
        assert_eq!(a.pending(), 0);
    }
}
