//! Modbus TCP framing: the 7-byte MBAP header (transaction id, protocol 0, length, unit id)
//! followed by the PDU. The transaction id ties a reply to its request, so a late reply to an
//! earlier request is recognised and discarded.

use crate::pdu::{self, FrameError, Request, RequestDecodeError, RequestError, Response};

/// Length of the MBAP header.
pub const HEADER_LEN: usize = 7;
/// Largest Modbus TCP frame: header and a 253-byte PDU.
pub const MAX_FRAME: usize = HEADER_LEN + pdu::MAX_PDU;

/// The MBAP header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Transaction identifier, echoed by the server.
    pub transaction: u16,
    /// Protocol identifier: 0 for Modbus.
    pub protocol: u16,
    /// Number of bytes that follow the length field (unit id + PDU).
    pub length: u16,
    /// Unit identifier (the slave address behind a gateway).
    pub unit: u8,
}

impl Header {
    /// Parses a header from the first 7 bytes of `buf`, checking protocol and length.
    pub fn parse(buf: &[u8]) -> Result<Option<Header>, FrameError> {
        let Some(h) = buf.get(..HEADER_LEN) else {
            return Ok(None);
        };
        let header = Header {
            transaction: u16::from_be_bytes([h[0], h[1]]),
            protocol: u16::from_be_bytes([h[2], h[3]]),
            length: u16::from_be_bytes([h[4], h[5]]),
            unit: h[6],
        };
        if header.protocol != 0 {
            return Err(FrameError::Protocol(header.protocol));
        }
        if !(2..=1 + pdu::MAX_PDU as u16).contains(&header.length) {
            return Err(FrameError::MbapLength(header.length));
        }
        Ok(Some(header))
    }

    /// Total frame length this header announces.
    pub fn frame_len(&self) -> usize {
        6 + usize::from(self.length)
    }

    fn write(&self, out: &mut [u8]) {
        out[0..2].copy_from_slice(&self.transaction.to_be_bytes());
        out[2..4].copy_from_slice(&self.protocol.to_be_bytes());
        out[4..6].copy_from_slice(&self.length.to_be_bytes());
        out[6] = self.unit;
    }
}

/// How many more bytes the frame at the start of `buf` needs: 0 when complete.
pub fn bytes_needed(buf: &[u8]) -> Result<usize, FrameError> {
    Ok(match Header::parse(buf)? {
        Some(h) => h.frame_len().saturating_sub(buf.len()),
        None => HEADER_LEN - buf.len(),
    })
}

fn encode_with(
    transaction: u16,
    unit: u8,
    pdu_len: usize,
    out: &mut [u8],
    encode: impl FnOnce(&mut [u8]) -> Result<usize, RequestError>,
) -> Result<usize, RequestError> {
    let needed = HEADER_LEN + pdu_len;
    if out.len() < needed {
        return Err(RequestError::Buffer {
            needed,
            available: out.len(),
        });
    }
    let n = encode(&mut out[HEADER_LEN..])?;
    Header {
        transaction,
        protocol: 0,
        length: (n + 1) as u16,
        unit,
    }
    .write(out);
    Ok(HEADER_LEN + n)
}

/// Encodes `request` with transaction id `transaction` to `unit` into `out`.
pub fn encode_request(
    transaction: u16,
    unit: u8,
    request: &Request<'_>,
    out: &mut [u8],
) -> Result<usize, RequestError> {
    encode_with(transaction, unit, request.pdu_len(), out, |o| {
        request.encode(o)
    })
}

/// Encodes a response frame (server side).
pub fn encode_response(
    transaction: u16,
    unit: u8,
    function: u8,
    response: &Response<'_>,
    out: &mut [u8],
) -> Result<usize, RequestError> {
    encode_with(transaction, unit, response.pdu_len(), out, |o| {
        response.encode(function, o)
    })
}

/// Checks a complete response frame (header, transaction id, unit, PDU echoes) and decodes it.
pub fn decode_response<'a>(
    transaction: u16,
    unit: u8,
    request: &Request<'_>,
    frame: &'a [u8],
) -> Result<Response<'a>, FrameError> {
    let header = Header::parse(frame)?.ok_or(FrameError::Length {
        expected: HEADER_LEN + request.response_pdu_len(),
        got: frame.len(),
    })?;
    if header.frame_len() != frame.len() {
        return Err(FrameError::Length {
            expected: header.frame_len(),
            got: frame.len(),
        });
    }
    if header.transaction != transaction {
        return Err(FrameError::Transaction {
            expected: transaction,
            got: header.transaction,
        });
    }
    if header.unit != unit {
        return Err(FrameError::Unit {
            expected: unit,
            got: header.unit,
        });
    }
    pdu::decode_response(request, &frame[HEADER_LEN..])
}

/// Why a server does not act on a request frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RequestFrameError {
    /// The header is invalid: the stream is out of step.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// The request is not acceptable: the server answers an exception.
    #[error("unit {}: {error}", header.unit)]
    Request {
        /// The request's MBAP header.
        header: Header,
        /// Why the request is not acceptable.
        error: RequestDecodeError,
    },
}

/// Decodes a complete request frame (server side).
pub fn decode_request(frame: &[u8]) -> Result<(Header, Request<'_>), RequestFrameError> {
    let header = Header::parse(frame)?.ok_or(FrameError::Length {
        expected: HEADER_LEN + 5,
        got: frame.len(),
    })?;
    if header.frame_len() != frame.len() {
        return Err(FrameError::Length {
            expected: header.frame_len(),
            got: frame.len(),
        }
        .into());
    }
    let request = pdu::decode_request(&frame[HEADER_LEN..])
        .map_err(|error| RequestFrameError::Request { header, error })?;
    Ok((header, request))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mbap_round_trip_and_transaction_check() {
        let req = Request::ReadHolding {
            address: 0x0300,
            quantity: 1,
        };
        let mut buf = [0u8; MAX_FRAME];
        let n = encode_request(0x1234, 1, &req, &mut buf).unwrap();
        assert_eq!(
            &buf[..n],
            &[0x12, 0x34, 0, 0, 0, 6, 1, 0x03, 0x03, 0x00, 0x00, 0x01]
        );
        assert_eq!(bytes_needed(&buf[..3]), Ok(4));
        assert_eq!(bytes_needed(&buf[..8]), Ok(4));
        assert_eq!(bytes_needed(&buf[..n]), Ok(0));
        let reply = [0x12, 0x34, 0, 0, 0, 5, 1, 0x03, 0x02, 0x00, 0x06];
        assert!(decode_response(0x1234, 1, &req, &reply).is_ok());
        assert_eq!(
            decode_response(0x1235, 1, &req, &reply),
            Err(FrameError::Transaction {
                expected: 0x1235,
                got: 0x1234
            })
        );
        assert_eq!(
            decode_response(0x1234, 2, &req, &reply),
            Err(FrameError::Unit {
                expected: 2,
                got: 1
            })
        );
        assert_eq!(
            bytes_needed(&[0, 0, 0, 1, 0, 6, 1]),
            Err(FrameError::Protocol(1))
        );
        assert_eq!(
            bytes_needed(&[0, 0, 0, 0, 1, 0, 1]),
            Err(FrameError::MbapLength(256))
        );
    }
}
