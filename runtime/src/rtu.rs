//! Modbus RTU framing: slave address, PDU, CRC-16 low byte first.
//!
//! A frame's length follows from its function code (and, for 03h/04h replies and 10h requests,
//! its byte count), so a streaming receiver can ask [`response_bytes_needed`] how many bytes it
//! still lacks instead of relying on the 3.5-character silence, which USB adapters and TCP
//! gateways do not preserve.

use crate::crc;
use crate::pdu::{self, FrameError, Request, RequestDecodeError, RequestError, Response};

/// Largest RTU frame: address, 253-byte PDU, CRC.
pub const MAX_FRAME: usize = 256;

/// The broadcast address: every slave executes, none replies.
pub const BROADCAST: u8 = 0;

/// Encodes `request` to `slave` into `out`; returns the frame length.
pub fn encode_request(
    slave: u8,
    request: &Request<'_>,
    out: &mut [u8],
) -> Result<usize, RequestError> {
    let needed = request.pdu_len() + 3;
    if out.len() < needed {
        return Err(RequestError::Buffer {
            needed,
            available: out.len(),
        });
    }
    out[0] = slave;
    let n = request.encode(&mut out[1..])? + 1;
    let crc = crc::crc_bytes(&out[..n]);
    out[n..n + 2].copy_from_slice(&crc);
    Ok(n + 2)
}

/// Encodes a response frame (slave side).
pub fn encode_response(
    slave: u8,
    function: u8,
    response: &Response<'_>,
    out: &mut [u8],
) -> Result<usize, RequestError> {
    let needed = response.pdu_len() + 3;
    if out.len() < needed {
        return Err(RequestError::Buffer {
            needed,
            available: out.len(),
        });
    }
    out[0] = slave;
    let n = response.encode(function, &mut out[1..])? + 1;
    let crc = crc::crc_bytes(&out[..n]);
    out[n..n + 2].copy_from_slice(&crc);
    Ok(n + 2)
}

/// Total length of the response frame at the start of `buf` as its own header says, or `None`
/// while fewer than 3 bytes are there to tell.
pub fn response_frame_len(buf: &[u8]) -> Result<Option<usize>, FrameError> {
    match buf.get(1..) {
        None => Ok(None),
        Some(pdu) => Ok(pdu::response_pdu_len(pdu)?.map(|n| n + 3)),
    }
}

/// How many more bytes the response frame at the start of `buf` needs: 0 when complete. While
/// the header is incomplete, the bytes needed to read it.
pub fn response_bytes_needed(buf: &[u8]) -> Result<usize, FrameError> {
    Ok(match response_frame_len(buf)? {
        Some(total) => total.saturating_sub(buf.len()),
        None => 3usize.saturating_sub(buf.len()).max(1),
    })
}

/// Total length of the request frame at the start of `buf`, or `None` while unknown (slave side).
pub fn request_frame_len(buf: &[u8]) -> Result<Option<usize>, FrameError> {
    match buf.get(1..) {
        None => Ok(None),
        Some(pdu) => Ok(pdu::request_pdu_len(pdu)?.map(|n| n + 3)),
    }
}

/// Length of the normal response frame `request` must get.
pub fn expected_response_len(request: &Request<'_>) -> usize {
    request.response_pdu_len() + 3
}

/// Length of an exception response frame.
pub const EXCEPTION_FRAME_LEN: usize = 5;

/// Checks a complete response frame (CRC, slave, then the PDU echoes) and decodes it.
pub fn decode_response<'a>(
    slave: u8,
    request: &Request<'_>,
    frame: &'a [u8],
) -> Result<Response<'a>, FrameError> {
    if frame.len() < 4 {
        return Err(FrameError::Length {
            expected: expected_response_len(request),
            got: frame.len(),
        });
    }
    let body =
        crc::check(frame).map_err(|(computed, received)| FrameError::Crc { computed, received })?;
    if body[0] != slave {
        return Err(FrameError::Slave {
            expected: slave,
            got: body[0],
        });
    }
    pdu::decode_response(request, &body[1..])
}

/// Why a slave does not act on a request frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RequestFrameError {
    /// The frame is damaged: the slave stays silent.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// The frame is intact but the request is not acceptable: the slave answers an exception.
    #[error("slave {slave}: {error}")]
    Request {
        /// The slave addressed.
        slave: u8,
        /// Why the request is not acceptable.
        error: RequestDecodeError,
    },
}

/// Checks and decodes a complete request frame (slave side). Returns the slave address and the
/// request.
pub fn decode_request(frame: &[u8]) -> Result<(u8, Request<'_>), RequestFrameError> {
    if frame.len() < 4 {
        return Err(FrameError::Length {
            expected: 8,
            got: frame.len(),
        }
        .into());
    }
    let body =
        crc::check(frame).map_err(|(computed, received)| FrameError::Crc { computed, received })?;
    let slave = body[0];
    let request = pdu::decode_request(&body[1..])
        .map_err(|error| RequestFrameError::Request { slave, error })?;
    Ok((slave, request))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pdu::Words;

    #[test]
    fn bytes_needed_follow_the_function_code() {
        let frame = [
            0x02, 0x03, 0x08, 0x17, 0x70, 0x17, 0x70, 0x01, 0x09, 0x00, 0x00, 0x38, 0xAC,
        ];
        assert_eq!(response_bytes_needed(&[]), Ok(3));
        assert_eq!(response_bytes_needed(&frame[..1]), Ok(2));
        assert_eq!(response_bytes_needed(&frame[..2]), Ok(1));
        assert_eq!(response_bytes_needed(&frame[..3]), Ok(10));
        assert_eq!(response_bytes_needed(&frame[..12]), Ok(1));
        assert_eq!(response_bytes_needed(&frame), Ok(0));
        assert_eq!(response_bytes_needed(&[0x01, 0x86]), Ok(3));
        assert_eq!(response_bytes_needed(&[0x01, 0x06]), Ok(6));
        assert_eq!(
            response_bytes_needed(&[0x01, 0x2B]),
            Err(FrameError::UnknownFunction(0x2B))
        );
        assert_eq!(request_frame_len(&[1, 0x10, 0, 1, 0, 2, 4]), Ok(Some(13)));
        assert_eq!(request_frame_len(&[1, 0x10, 0, 1]), Ok(None));
    }

    #[test]
    fn request_round_trip() {
        let values = [1u16, 0x0258];
        let req = Request::WriteMultiple {
            address: 1,
            values: Words::Native(&values),
        };
        let mut buf = [0u8; MAX_FRAME];
        let n = encode_request(1, &req, &mut buf).unwrap();
        assert_eq!(
            &buf[..n],
            &[
                0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x02, 0x58, 0x63, 0x39
            ]
        );
        assert_eq!(decode_request(&buf[..n]), Ok((1, req)));
        assert!(matches!(
            decode_request(&buf[..n - 1]),
            Err(RequestFrameError::Frame(FrameError::Crc { .. }))
        ));
    }
}
