//! Request dispatch: one frame in, the reply out through [`crate::framing`], what happened for
//! the log ([`RequestRecord`]) and the counters ([`Stats`]).

use std::fmt;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::pdu::{
    self, BitValues, Request, RequestDecodeError, Response, Words, function,
};
use drivemap_runtime::{rtu, tcp};

use crate::framing::{self, Decoded, Origin};

use super::Simulator;

/// What became of one request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Executed and answered normally.
    Ok,
    /// Answered with an exception.
    Exception {
        /// The drive's code.
        code: u8,
        /// Its name in the drive's manual, or the Modbus name.
        name: &'static str,
    },
    /// Addressed to slave 0: never answered; executed only where the drive allows broadcast.
    Broadcast {
        /// Whether the writes were executed.
        executed: bool,
    },
    /// Addressed to another slave: ignored.
    NotAddressed,
    /// CRC error or a frame that cannot be a request: ignored, as the manuals prescribe.
    Damaged,
}

/// One request as the log shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RequestRecord {
    /// The transport it came on.
    pub transport: TransportKind,
    /// Slave address or unit id (0: broadcast).
    pub slave: u8,
    /// Function code, if the frame got that far.
    pub function: Option<u8>,
    /// First register address in the PDU.
    pub address: Option<u16>,
    /// Registers read or written (0 for loop-back).
    pub quantity: usize,
    /// What happened.
    pub outcome: Outcome,
}

impl fmt::Display for RequestRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "slave {:>3}", self.slave)?;
        match self.function {
            Some(func) => write!(f, "  {func:02X}h")?,
            None => write!(f, "  --h")?,
        }
        match self.address {
            Some(a) => write!(f, "  {a:04X}h x{:<3}", self.quantity)?,
            None => write!(f, "  {:11}", "")?,
        }
        match self.outcome {
            Outcome::Ok => write!(f, "  ok"),
            Outcome::Exception { code, name } => write!(f, "  exception {code:02X}h ({name})"),
            Outcome::Broadcast { executed: true } => write!(f, "  broadcast executed, no reply"),
            Outcome::Broadcast { executed: false } => write!(f, "  broadcast refused, no reply"),
            Outcome::NotAddressed => write!(f, "  another slave's address, no reply"),
            Outcome::Damaged => write!(f, "  CRC or framing error, no reply"),
        }
    }
}

/// The result of [`Simulator::handle`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Handled {
    /// Length of the reply frame written to `out`, or `None` when the drive stays silent.
    pub reply: Option<usize>,
    /// What happened, for the log.
    pub record: RequestRecord,
}

/// Counters since start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Frames handled.
    pub requests: u32,
    /// Normal replies sent.
    pub replies: u32,
    /// Exception replies sent.
    pub exceptions: u32,
    /// Broadcasts executed.
    pub broadcasts_executed: u32,
    /// Broadcasts not executed (function or register not allowed, bad value).
    pub broadcasts_refused: u32,
    /// Frames for other slaves.
    pub not_addressed: u32,
    /// Damaged frames (CRC, length).
    pub damaged: u32,
}

impl Simulator {
    /// Answers one complete frame of `kind`. Returns the reply length written to `out` (at least
    /// [`tcp::MAX_FRAME`] bytes), or `None` when the drive stays silent. The frame is decoded
    /// and the reply framed by [`crate::framing`], the runtime's `decode_request` and
    /// `encode_response`. On Modbus ASCII ([`TransportKind::is_ascii`]) `frame` is the RTU
    /// frame the ASCII frame stands for, and so is the reply (the serving loop converts both).
    pub fn handle(&mut self, kind: TransportKind, frame: &[u8], out: &mut [u8]) -> Handled {
        self.stats.requests += 1;
        let mut record = RequestRecord {
            transport: kind,
            slave: 0,
            function: None,
            address: None,
            quantity: 0,
            outcome: Outcome::Damaged,
        };
        if kind.is_serial_framed() {
            record.slave = frame.first().copied().unwrap_or(0);
            record.function = frame.get(1).copied();
        } else {
            record.function = frame.get(tcp::HEADER_LEN).copied();
        }
        let reply = match framing::decode(kind, frame) {
            Decoded::Damaged => None,
            Decoded::Refused { origin, error } => {
                record.slave = origin.slave();
                self.reject(origin, error, &mut record, out)
            }
            Decoded::Request { origin, request } => {
                record.slave = origin.slave();
                describe(&request, &mut record);
                self.dispatch(kind, origin, &request, &mut record, out)
            }
        };
        match record.outcome {
            Outcome::Ok => self.stats.replies += 1,
            Outcome::Exception { .. } => self.stats.exceptions += 1,
            Outcome::Broadcast { executed: true } => self.stats.broadcasts_executed += 1,
            Outcome::Broadcast { executed: false } => self.stats.broadcasts_refused += 1,
            Outcome::NotAddressed => self.stats.not_addressed += 1,
            Outcome::Damaged => self.stats.damaged += 1,
        }
        Handled { reply, record }
    }

    pub(super) fn exception(&self, code: u8) -> Outcome {
        let name = match self.profile.exception(code) {
            Some(e) => e.name,
            None => drivemap_runtime::exception::standard(code)
                .map(|(n, _)| n)
                .unwrap_or("exception"),
        };
        Outcome::Exception { code, name }
    }

    /// A request the PDU decoder refused: an exception when addressed to this drive.
    pub(super) fn reject(
        &mut self,
        origin: Origin,
        error: RequestDecodeError,
        record: &mut RequestRecord,
        out: &mut [u8],
    ) -> Option<usize> {
        let slave = origin.slave();
        if slave == rtu::BROADCAST {
            record.outcome = Outcome::Broadcast { executed: false };
            return None;
        }
        if slave != self.slave {
            record.outcome = Outcome::NotAddressed;
            return None;
        }
        let Some((f, code)) = framing::refusal(
            error,
            self.plan.illegal_function,
            self.plan.illegal_quantity,
        ) else {
            record.outcome = Outcome::Damaged;
            return None;
        };
        record.function = Some(f);
        record.outcome = self.exception(code);
        origin.reply(f, &Response::Exception { function: f, code }, out)
    }

    pub(super) fn dispatch(
        &mut self,
        kind: TransportKind,
        origin: Origin,
        request: &Request<'_>,
        record: &mut RequestRecord,
        out: &mut [u8],
    ) -> Option<usize> {
        let slave = origin.slave();
        if slave == rtu::BROADCAST {
            let executed = self.broadcast(kind, request);
            record.outcome = Outcome::Broadcast { executed };
            return None;
        }
        if slave != self.slave {
            record.outcome = Outcome::NotAddressed;
            return None;
        }
        let f = request.function();
        let mut words = [0u16; pdu::MAX_READ as usize];
        let mut bits = [false; pdu::MAX_READ_BITS as usize];
        let response = match self.execute(kind, request, &mut words, &mut bits) {
            Ok(r) => {
                record.outcome = Outcome::Ok;
                r
            }
            Err(code) => {
                record.outcome = self.exception(code);
                Response::Exception { function: f, code }
            }
        };
        origin.reply(f, &response, out)
    }

    pub(super) fn broadcast(&mut self, kind: TransportKind, request: &Request<'_>) -> bool {
        let Some(b) = self.profile.broadcast else {
            return false;
        };
        let f = request.function();
        if !b.functions.contains(&f) {
            return false;
        }
        self.tick();
        let mut values = [0u16; pdu::MAX_WRITE_BITS as usize];
        let (table, address, n) = match *request {
            Request::WriteSingle { address, value } => {
                values[0] = value;
                (Table::Holding, address, 1)
            }
            Request::WriteMultiple { address, values: v } => {
                (Table::Holding, address, v.copy_to(&mut values))
            }
            Request::WriteCoil { address, value } => {
                values[0] = u16::from(value);
                (Table::Coil, address, 1)
            }
            Request::WriteCoils { address, values: v } => {
                (Table::Coil, address, v.copy_to(&mut values))
            }
            _ => return false,
        };
        if (f == function::WRITE_MULTIPLE && n > usize::from(self.profile.max_write))
            || (f == function::WRITE_COILS && n > usize::from(self.profile.max_write_bits))
        {
            return false;
        }
        self.write_in(kind, table, address, &values[..n], true)
            .is_ok()
    }

    pub(super) fn execute<'w>(
        &mut self,
        kind: TransportKind,
        request: &Request<'_>,
        words: &'w mut [u16; pdu::MAX_READ as usize],
        bits: &'w mut [bool; pdu::MAX_READ_BITS as usize],
    ) -> Result<Response<'w>, u8> {
        self.tick();
        let f = request.function();
        if !self.profile.supports(f) {
            return Err(self.plan.illegal_function);
        }
        if let (Some(address), false) = (request.address(), f == function::LOOP_BACK) {
            self.function_refused(kind, f, address, request.quantity())?;
        }
        match *request {
            Request::ReadHolding { address, quantity }
            | Request::ReadInput { address, quantity } => {
                let q = usize::from(quantity);
                if q == 0 || q > usize::from(self.profile.max_read) || q > words.len() {
                    return Err(self.plan.illegal_quantity);
                }
                let table = if f == function::READ_HOLDING {
                    Table::Holding
                } else {
                    Table::Input
                };
                for (k, w) in words.iter_mut().take(q).enumerate() {
                    *w = self.read_one(kind, table, u32::from(address) + k as u32, k == 0)?;
                }
                Ok(Response::Registers(Words::Native(&words[..q])))
            }
            Request::WriteSingle { address, value } => {
                self.write(kind, address, &[value], false)?;
                Ok(Response::WriteSingle { address, value })
            }
            Request::WriteMultiple { address, values } => {
                let q = values.len();
                if q == 0 || q > usize::from(self.profile.max_write) {
                    return Err(self.plan.illegal_quantity);
                }
                let mut buf = [0u16; pdu::MAX_WRITE as usize];
                let n = values.copy_to(&mut buf);
                self.write(kind, address, &buf[..n], false)?;
                Ok(Response::WriteMultiple {
                    address,
                    quantity: n as u16,
                })
            }
            Request::ReadCoils { address, quantity }
            | Request::ReadDiscreteInputs { address, quantity } => {
                let q = usize::from(quantity);
                if q == 0 || q > usize::from(self.profile.max_read_bits) || q > bits.len() {
                    return Err(self.plan.illegal_quantity);
                }
                let table = if f == function::READ_COILS {
                    Table::Coil
                } else {
                    Table::DiscreteInput
                };
                for (k, b) in bits.iter_mut().take(q).enumerate() {
                    *b = self.read_one(kind, table, u32::from(address) + k as u32, k == 0)? != 0;
                }
                Ok(Response::Bits(BitValues::Native(&bits[..q])))
            }
            Request::WriteCoil { address, value } => {
                self.write_in(kind, Table::Coil, address, &[u16::from(value)], false)?;
                Ok(Response::WriteCoil { address, value })
            }
            Request::WriteCoils { address, values } => {
                let q = values.len();
                if q == 0 || q > usize::from(self.profile.max_write_bits) {
                    return Err(self.plan.illegal_quantity);
                }
                let mut buf = [0u16; pdu::MAX_WRITE_BITS as usize];
                let n = values.copy_to(&mut buf);
                self.write_in(kind, Table::Coil, address, &buf[..n], false)?;
                Ok(Response::WriteCoils {
                    address,
                    quantity: n as u16,
                })
            }
            Request::LoopBack { data } => Ok(Response::LoopBack { data }),
            // A function the runtime learns to encode before the simulator serves it.
            _ => Err(self.plan.illegal_function),
        }
    }
}

fn describe(request: &Request<'_>, record: &mut RequestRecord) {
    record.function = Some(request.function());
    record.address = request.address();
    record.quantity = request.quantity();
}
