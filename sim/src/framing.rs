//! The one framing path of every simulated drive in this crate ([`Simulator`](crate::Simulator),
//! [`SimulatedSlave`](crate::SimulatedSlave), the replies [`FaultyLink`](crate::FaultyLink)
//! readdresses): request frames are decoded by [`rtu::decode_request`] and
//! [`tcp::decode_request`], replies framed by [`rtu::encode_response`] and
//! [`tcp::encode_response`]. No CRC and no MBAP header is written by hand. Nothing here
//! allocates.

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::pdu::{Request, RequestDecodeError, Response, function};
use drivemap_runtime::{rtu, tcp};

/// Where a request frame came from: what its reply must echo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// An RTU frame (serial line or RTU over TCP) addressed to `slave`.
    Rtu {
        /// The slave address (0: broadcast).
        slave: u8,
    },
    /// A Modbus TCP frame: the reply echoes its transaction id and unit id.
    Tcp(tcp::Header),
}

impl Origin {
    /// The slave address or unit id the request is addressed to (0: broadcast).
    pub fn slave(self) -> u8 {
        match self {
            Origin::Rtu { slave } => slave,
            Origin::Tcp(header) => header.unit,
        }
    }

    /// The same origin as slave (unit) `slave` would answer it, when given: a reply that claims
    /// to come from another drive, framed as intact.
    pub fn from(self, slave: Option<u8>) -> Origin {
        match (self, slave) {
            (_, None) => self,
            (Origin::Rtu { .. }, Some(slave)) => Origin::Rtu { slave },
            (Origin::Tcp(header), Some(unit)) => Origin::Tcp(tcp::Header { unit, ..header }),
        }
    }

    /// Frames `response`, the answer to a request of `function`, into `out` as this origin's
    /// framing needs it; `None` when it does not fit.
    pub fn reply(self, function: u8, response: &Response<'_>, out: &mut [u8]) -> Option<usize> {
        match self {
            Origin::Rtu { slave } => rtu::encode_response(slave, function, response, out).ok(),
            Origin::Tcp(h) => {
                tcp::encode_response(h.transaction, h.unit, function, response, out).ok()
            }
        }
    }
}

/// A complete request frame, decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decoded<'a> {
    /// A damaged frame (CRC, length, MBAP header): a drive stays silent.
    Damaged,
    /// An intact frame whose PDU is not an acceptable request: answered with an exception when
    /// addressed to the drive ([`refusal`]).
    Refused {
        /// Where it came from.
        origin: Origin,
        /// Why the PDU was refused.
        error: RequestDecodeError,
    },
    /// A request.
    Request {
        /// Where it came from.
        origin: Origin,
        /// The request.
        request: Request<'a>,
    },
}

/// Decodes one complete request frame of `kind`.
pub fn decode(kind: TransportKind, frame: &[u8]) -> Decoded<'_> {
    // Modbus ASCII frames reach here as the RTU frames they stand for (see `server`).
    if kind.is_serial_framed() {
        match rtu::decode_request(frame) {
            Err(rtu::RequestFrameError::Request { slave, error }) => Decoded::Refused {
                origin: Origin::Rtu { slave },
                error,
            },
            Ok((slave, request)) => Decoded::Request {
                origin: Origin::Rtu { slave },
                request,
            },
            // A frame that is not a request (its length, its check), or any other reason the
            // runtime tells.
            Err(_) => Decoded::Damaged,
        }
    } else {
        match tcp::decode_request(frame) {
            Err(tcp::RequestFrameError::Request { header, error }) => Decoded::Refused {
                origin: Origin::Tcp(header),
                error,
            },
            Ok((header, request)) => Decoded::Request {
                origin: Origin::Tcp(header),
                request,
            },
            // A frame that is not a request (its length, its check), or any other reason the
            // runtime tells.
            Err(_) => Decoded::Damaged,
        }
    }
}

/// The function code and exception code that answer a refused PDU, given the drive's codes for
/// an unknown function (or loop-back sub-function) and for a malformed request; `None` for an
/// empty PDU, which is a damaged frame.
pub fn refusal(
    error: RequestDecodeError,
    illegal_function: u8,
    illegal_quantity: u8,
) -> Option<(u8, u8)> {
    match error {
        RequestDecodeError::Function(f) => Some((f, illegal_function)),
        RequestDecodeError::SubFunction(_) => Some((function::LOOP_BACK, illegal_function)),
        RequestDecodeError::Malformed(f) => Some((f, illegal_quantity)),
        RequestDecodeError::Empty => None,
        // A reason the runtime learns to tell later: taken as a damaged frame (no reply).
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivemap_runtime::pdu::Words;

    #[test]
    fn replies_are_framed_by_the_runtime_encoders() {
        // V7 manual example: slave 2 reads 0020h x4; the reply carries 4 words.
        let words = [0x0001, 0x0002, 0x0003, 0x0004];
        let response = Response::Registers(Words::Native(&words));
        let mut out = [0u8; tcp::MAX_FRAME];
        let n = Origin::Rtu { slave: 2 }
            .reply(function::READ_HOLDING, &response, &mut out)
            .unwrap();
        let request = Request::ReadHolding {
            address: 0x20,
            quantity: 4,
        };
        assert_eq!(rtu::decode_response(2, &request, &out[..n]), Ok(response));
        let header = tcp::Header {
            transaction: 0x1234,
            protocol: 0,
            length: 6,
            unit: 7,
        };
        let n = Origin::Tcp(header)
            .reply(function::READ_HOLDING, &response, &mut out)
            .unwrap();
        assert_eq!(
            tcp::decode_response(0x1234, 7, &request, &out[..n]),
            Ok(response)
        );
        // Too small a buffer: no reply rather than a panic.
        assert_eq!(
            Origin::Rtu { slave: 2 }.reply(function::READ_HOLDING, &response, &mut out[..5]),
            None
        );
    }

    #[test]
    fn frames_decode_to_damaged_refused_or_request() {
        let read = [0x01, 0x03, 0x00, 0x20, 0x00, 0x01, 0x85, 0xC0];
        assert!(matches!(
            decode(TransportKind::Rtu, &read),
            Decoded::Request {
                origin: Origin::Rtu { slave: 1 },
                request: Request::ReadHolding {
                    address: 0x20,
                    quantity: 1
                }
            }
        ));
        let mut damaged = read;
        damaged[7] ^= 1;
        assert_eq!(decode(TransportKind::Rtu, &damaged), Decoded::Damaged);
        // Modbus TCP, function 2Bh: intact, refused.
        let frame = [0x00, 0x09, 0x00, 0x00, 0x00, 0x02, 0x01, 0x2B];
        let Decoded::Refused { origin, error } = decode(TransportKind::Tcp, &frame) else {
            panic!("not refused");
        };
        assert_eq!(origin.slave(), 1);
        assert_eq!(refusal(error, 0x01, 0x03), Some((0x2B, 0x01)));
        assert_eq!(refusal(RequestDecodeError::Empty, 0x01, 0x03), None);
    }
}
