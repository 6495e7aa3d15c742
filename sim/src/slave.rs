//! A bare simulated drive for the runtime's tests and benches: the slave side of the protocol,
//! answering from plain register memory as a [`Profile`] says the drive would, with no map.
//! The fault-injection link of [`crate::fault`] puts one behind a client. (A drive simulated
//! from its map, with its rules and its model, is [`crate::Simulator`].)

use std::io;
use std::time::Instant;

use drivemap_runtime::pdu::{
    self, FrameError, Request, RequestDecodeError, Response, Words, function,
};
use drivemap_runtime::profile::{Profile, TransportKind};
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{crc, rtu, tcp};

/// A drive simulated in memory. Addresses are PDU addresses.
pub struct SimulatedSlave {
    /// The slave address it answers to (and executes broadcasts).
    pub address: u8,
    profile: &'static Profile,
    holding: Vec<u16>,
    input: Vec<u16>,
    faults: Vec<(u16, u8)>,
    /// Requests executed (broadcasts included), for tests.
    pub executed: u32,
    /// Register writes executed, for tests.
    pub writes: Vec<(u16, u16)>,
}

impl SimulatedSlave {
    /// A drive at `address` implementing what `profile` says, all registers 0.
    pub fn new(address: u8, profile: &'static Profile) -> SimulatedSlave {
        SimulatedSlave {
            address,
            profile,
            holding: vec![0; 0x1_0000],
            input: vec![0; 0x1_0000],
            faults: Vec::new(),
            executed: 0,
            writes: Vec::new(),
        }
    }

    /// Sets a holding register.
    pub fn set_holding(&mut self, address: u16, value: u16) {
        self.holding[usize::from(address)] = value;
    }

    /// A holding register.
    pub fn holding(&self, address: u16) -> u16 {
        self.holding[usize::from(address)]
    }

    /// Sets an input register.
    pub fn set_input(&mut self, address: u16, value: u16) {
        self.input[usize::from(address)] = value;
    }

    /// Makes any request touching `address` answer exception `code`.
    pub fn fail_at(&mut self, address: u16, code: u8) {
        self.faults.push((address, code));
    }

    fn fault(&self, request: &Request<'_>) -> Option<u8> {
        let a = usize::from(request.address()?);
        let q = request.quantity().max(1);
        self.faults
            .iter()
            .find(|(fa, _)| (a..a + q).contains(&usize::from(*fa)))
            .map(|&(_, code)| code)
    }

    /// Executes `request` and encodes the response PDU into `out`; returns its length.
    fn execute(&mut self, request: &Request<'_>, out: &mut [u8]) -> usize {
        self.executed += 1;
        let f = request.function();
        let exception = |code| Response::Exception { function: f, code };
        let p = self.profile;
        let mut words = [0u16; pdu::MAX_READ as usize];
        let response = if !p.supports(f) {
            exception(0x01)
        } else if (request.is_read() && request.quantity() > usize::from(p.max_read))
            || (f == function::WRITE_MULTIPLE && request.quantity() > usize::from(p.max_write))
        {
            exception(0x03)
        } else if let Some(code) = self.fault(request) {
            exception(code)
        } else {
            match *request {
                Request::ReadHolding { address, quantity }
                | Request::ReadInput { address, quantity } => {
                    let table = if f == function::READ_HOLDING {
                        &self.holding
                    } else {
                        &self.input
                    };
                    let (a, q) = (usize::from(address), usize::from(quantity));
                    words[..q].copy_from_slice(&table[a..a + q]);
                    Response::Registers(Words::Native(&words[..q]))
                }
                Request::WriteSingle { address, value } => {
                    self.holding[usize::from(address)] = value;
                    self.writes.push((address, value));
                    Response::WriteSingle { address, value }
                }
                Request::LoopBack { data } => Response::LoopBack { data },
                Request::WriteMultiple { address, values } => {
                    for (i, v) in values.iter().enumerate() {
                        let a = address.wrapping_add(i as u16);
                        self.holding[usize::from(a)] = v;
                        self.writes.push((a, v));
                    }
                    Response::WriteMultiple {
                        address,
                        quantity: values.len() as u16,
                    }
                }
            }
        };
        response.encode(f, out).unwrap_or(0)
    }

    fn reject(error: RequestDecodeError) -> Option<(u8, u8)> {
        match error {
            RequestDecodeError::Function(f) => Some((f, 0x01)),
            RequestDecodeError::SubFunction(_) => Some((function::LOOP_BACK, 0x01)),
            RequestDecodeError::Malformed(f) => Some((f, 0x03)),
            RequestDecodeError::Empty => None,
        }
    }

    /// Answers an RTU request frame: `Some(length)` of the reply written to `out`, or `None`
    /// when a drive stays silent (damaged frame, another slave, broadcast).
    pub fn respond_rtu(&mut self, frame: &[u8], out: &mut [u8]) -> Option<usize> {
        let mut pdu = [0u8; pdu::MAX_PDU];
        let (slave, n) = match rtu::decode_request(frame) {
            Err(rtu::RequestFrameError::Frame(_)) => return None,
            Err(rtu::RequestFrameError::Request { slave, error }) => {
                let (f, code) = Self::reject(error)?;
                (
                    slave,
                    Response::Exception { function: f, code }
                        .encode(f, &mut pdu)
                        .ok()?,
                )
            }
            Ok((slave, request)) => {
                if slave != self.address && slave != rtu::BROADCAST {
                    return None;
                }
                (slave, self.execute(&request, &mut pdu))
            }
        };
        if slave != self.address || n == 0 || out.len() < n + 3 {
            return None;
        }
        out[0] = slave;
        out[1..=n].copy_from_slice(&pdu[..n]);
        let crc = crc::crc_bytes(&out[..=n]);
        out[n + 1..n + 3].copy_from_slice(&crc);
        Some(n + 3)
    }

    /// Answers a Modbus TCP request frame (the unit id must be this slave's address).
    pub fn respond_tcp(&mut self, frame: &[u8], out: &mut [u8]) -> Option<usize> {
        let mut pdu = [0u8; pdu::MAX_PDU];
        let (header, n) = match tcp::decode_request(frame) {
            Err(tcp::RequestFrameError::Frame(_)) => return None,
            Err(tcp::RequestFrameError::Request { header, error }) => {
                let (f, code) = Self::reject(error)?;
                (
                    header,
                    Response::Exception { function: f, code }
                        .encode(f, &mut pdu)
                        .ok()?,
                )
            }
            Ok((header, request)) => {
                if header.unit != self.address && header.unit != 0 {
                    return None;
                }
                (header, self.execute(&request, &mut pdu))
            }
        };
        if header.unit != self.address || n == 0 || out.len() < n + tcp::HEADER_LEN {
            return None;
        }
        out[..2].copy_from_slice(&header.transaction.to_be_bytes());
        out[2..4].copy_from_slice(&[0, 0]);
        out[4..6].copy_from_slice(&((n + 1) as u16).to_be_bytes());
        out[6] = header.unit;
        out[7..7 + n].copy_from_slice(&pdu[..n]);
        Some(tcp::HEADER_LEN + n)
    }

    /// Answers a frame of `kind`.
    pub fn respond(&mut self, kind: TransportKind, frame: &[u8], out: &mut [u8]) -> Option<usize> {
        if kind.is_rtu_framed() {
            self.respond_rtu(frame, out)
        } else {
            self.respond_tcp(frame, out)
        }
    }

    /// Serves requests arriving on `link` until `until`, answering each; returns the number of
    /// requests answered. Bytes that do not start a request are skipped one at a time. Ends
    /// early when the master closes the link.
    pub fn serve(&mut self, link: &mut impl Transport, until: Instant) -> io::Result<u32> {
        let kind = link.kind();
        let mut buf = [0u8; 2 * tcp::MAX_FRAME];
        let mut len = 0usize;
        let mut out = [0u8; tcp::MAX_FRAME];
        let mut answered = 0;
        loop {
            let n = match link.recv(&mut buf[len..], until) {
                Ok(n) => n,
                // The master hung up: serving is over.
                Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => 0,
                Err(e) => return Err(e),
            };
            if n == 0 {
                return Ok(answered);
            }
            len += n;
            loop {
                let needed: Result<Option<usize>, FrameError> = if kind.is_rtu_framed() {
                    rtu::request_frame_len(&buf[..len])
                } else {
                    tcp::Header::parse(&buf[..len]).map(|h| h.map(|h| h.frame_len()))
                };
                let total = match needed {
                    Ok(Some(total)) if total <= len => total,
                    Ok(_) => break,
                    Err(_) => 0,
                };
                let answer = match total {
                    0 => None,
                    _ => self.respond(kind, &buf[..total], &mut out),
                };
                let skip = match answer {
                    Some(m) => {
                        link.send(&out[..m])?;
                        answered += 1;
                        total
                    }
                    // Not a request, or a damaged one: step over one byte to resynchronise.
                    None if total == 0
                        || (kind.is_rtu_framed() && crc::check(&buf[..total]).is_err()) =>
                    {
                        1
                    }
                    None => total,
                };
                buf.copy_within(skip..len, 0);
                len -= skip;
            }
            if len == buf.len() {
                len = 0;
            }
        }
    }
}
