//! A bare simulated drive for the runtime's tests and benches: the slave side of the protocol,
//! answering from plain register memory as a [`Profile`] says the drive would, with no map.
//! The fault-injection link of [`crate::fault`] puts one behind a client. (A drive simulated
//! from its map, with its rules and its model, is [`crate::Simulator`].)

use std::io;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::pdu::{self, BitValues, Request, Response, Words, function};
use drivemap_runtime::rtu;
use drivemap_runtime::transport::Transport;

use crate::framing::{self, Decoded, Origin};
use crate::server::{self, Answer, FrameLimits};

/// A drive simulated in memory. Addresses are PDU addresses.
pub struct SimulatedSlave {
    /// The slave address it answers to (and executes broadcasts).
    pub address: u8,
    profile: &'static Profile,
    holding: Vec<u16>,
    input: Vec<u16>,
    coils: Vec<bool>,
    discrete_inputs: Vec<bool>,
    faults: Vec<(u16, u8)>,
    /// Requests executed (broadcasts included), for tests.
    pub executed: u32,
    /// Register writes executed, for tests.
    pub writes: Vec<(u16, u16)>,
    /// Reads executed (first address, quantity; registers, coils or discrete inputs), for
    /// tests: `None` (the default) records nothing, so a long-running slave does not grow; set
    /// `Some(Vec::new())` to record.
    pub reads: Option<Vec<(u16, u16)>>,
    /// Index/value register pairs served as the drive does ([`SimulatedSlave::with_indexed`]).
    pub indexed: crate::indexed::IndexedBank,
}

impl SimulatedSlave {
    /// A drive at `address` implementing what `profile` says, all registers 0.
    pub fn new(address: u8, profile: &'static Profile) -> SimulatedSlave {
        SimulatedSlave {
            address,
            profile,
            holding: vec![0; 0x1_0000],
            input: vec![0; 0x1_0000],
            coils: vec![false; 0x1_0000],
            discrete_inputs: vec![false; 0x1_0000],
            faults: Vec::new(),
            executed: 0,
            writes: Vec::new(),
            reads: None,
            indexed: crate::indexed::IndexedBank::default(),
        }
    }

    /// Serves the index/value register pairs `pairs` (a map's `MapPlan::indexed`): each value
    /// register shows and takes the value of the entry its index register selects. This slave
    /// knows PDU addresses only: the pairs' addresses are taken as such (right for a map without
    /// address offsets; the map-driven [`crate::Simulator`] places them on every link).
    pub fn with_indexed(
        mut self,
        pairs: &'static [drivemap_runtime::core::indexed::Indexed],
    ) -> SimulatedSlave {
        self.indexed = crate::indexed::IndexedBank::new(pairs);
        self
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

    /// Sets a coil.
    pub fn set_coil(&mut self, address: u16, on: bool) {
        self.coils[usize::from(address)] = on;
    }

    /// A coil.
    pub fn coil(&self, address: u16) -> bool {
        self.coils[usize::from(address)]
    }

    /// Sets a discrete input.
    pub fn set_discrete_input(&mut self, address: u16, on: bool) {
        self.discrete_inputs[usize::from(address)] = on;
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

    /// Executes `request` (a broadcast too) and frames the response for `origin` into `out`:
    /// `None` when nothing is to be sent (a broadcast).
    fn execute(
        &mut self,
        origin: Origin,
        request: &Request<'_>,
        out: &mut [u8],
        reply_as: Option<u8>,
    ) -> Option<usize> {
        self.executed += 1;
        let f = request.function();
        let exception = |code| Response::Exception { function: f, code };
        let p = self.profile;
        let mut words = [0u16; pdu::MAX_READ as usize];
        let mut bits = [false; pdu::MAX_READ_BITS as usize];
        let max = match f {
            function::READ_HOLDING | function::READ_INPUT => usize::from(p.max_read),
            function::WRITE_MULTIPLE => usize::from(p.max_write),
            function::READ_COILS | function::READ_DISCRETE_INPUTS => usize::from(p.max_read_bits),
            function::WRITE_COILS => usize::from(p.max_write_bits),
            _ => usize::MAX,
        };
        let response = if !p.supports(f) {
            exception(0x01)
        } else if request.quantity() > max {
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
                    if f == function::READ_HOLDING {
                        let holding = &self.holding;
                        for (k, w) in words[..q].iter_mut().enumerate() {
                            let at = address.wrapping_add(k as u16);
                            if let Some(v) = self.indexed.shown(at, |i| holding[usize::from(i)]) {
                                *w = v;
                            }
                        }
                    }
                    if let Some(reads) = &mut self.reads {
                        reads.push((address, quantity));
                    }
                    Response::Registers(Words::Native(&words[..q]))
                }
                Request::WriteSingle { address, value } => {
                    let holding = &self.holding;
                    self.indexed
                        .store(address, value, |i| holding[usize::from(i)]);
                    self.holding[usize::from(address)] = value;
                    self.writes.push((address, value));
                    Response::WriteSingle { address, value }
                }
                Request::LoopBack { data } => Response::LoopBack { data },
                Request::WriteMultiple { address, values } => {
                    for (i, v) in values.iter().enumerate() {
                        let a = address.wrapping_add(i as u16);
                        let holding = &self.holding;
                        self.indexed.store(a, v, |i| holding[usize::from(i)]);
                        self.holding[usize::from(a)] = v;
                        self.writes.push((a, v));
                    }
                    Response::WriteMultiple {
                        address,
                        quantity: values.len() as u16,
                    }
                }
                Request::ReadCoils { address, quantity }
                | Request::ReadDiscreteInputs { address, quantity } => {
                    let table = if f == function::READ_COILS {
                        &self.coils
                    } else {
                        &self.discrete_inputs
                    };
                    let (a, q) = (usize::from(address), usize::from(quantity));
                    bits[..q].copy_from_slice(&table[a..a + q]);
                    if let Some(reads) = &mut self.reads {
                        reads.push((address, quantity));
                    }
                    Response::Bits(BitValues::Native(&bits[..q]))
                }
                Request::WriteCoil { address, value } => {
                    self.coils[usize::from(address)] = value;
                    self.writes.push((address, u16::from(value)));
                    Response::WriteCoil { address, value }
                }
                Request::WriteCoils { address, values } => {
                    for (i, v) in values.iter().enumerate() {
                        let a = address.wrapping_add(i as u16);
                        self.coils[usize::from(a)] = v;
                        self.writes.push((a, u16::from(v)));
                    }
                    Response::WriteCoils {
                        address,
                        quantity: values.len() as u16,
                    }
                }
                // A function the runtime learns to encode before this slave serves it.
                _ => exception(0x01),
            }
        };
        if origin.slave() != self.address {
            return None;
        }
        origin.from(reply_as).reply(f, &response, out)
    }

    /// Answers a complete request frame of `kind`: `Some(length)` of the reply written to `out`
    /// (framed by the runtime's `encode_response`, see [`crate::framing`]), or `None` when a
    /// drive stays silent (damaged frame, another slave, broadcast).
    pub fn respond(&mut self, kind: TransportKind, frame: &[u8], out: &mut [u8]) -> Option<usize> {
        self.answer(kind, frame, out, None)
    }

    /// [`SimulatedSlave::respond`], the reply framed as if slave (unit) `reply_as` sent it when
    /// given: the wrong-slave fault of [`crate::fault`].
    pub(crate) fn answer(
        &mut self,
        kind: TransportKind,
        frame: &[u8],
        out: &mut [u8],
        reply_as: Option<u8>,
    ) -> Option<usize> {
        match framing::decode(kind, frame) {
            Decoded::Damaged => None,
            Decoded::Refused { origin, error } => {
                let (f, code) = framing::refusal(error, 0x01, 0x03)?;
                if origin.slave() != self.address {
                    return None;
                }
                let response = Response::Exception { function: f, code };
                origin.from(reply_as).reply(f, &response, out)
            }
            Decoded::Request { origin, request } => {
                let slave = origin.slave();
                if slave != self.address && slave != rtu::BROADCAST {
                    return None;
                }
                self.execute(origin, &request, out, reply_as)
            }
        }
    }

    /// Answers an RTU request frame ([`SimulatedSlave::respond`] on an RTU link).
    pub fn respond_rtu(&mut self, frame: &[u8], out: &mut [u8]) -> Option<usize> {
        self.respond(TransportKind::Rtu, frame, out)
    }

    /// Answers a Modbus TCP request frame (the unit id must be this slave's address; unit 0 is
    /// executed as a broadcast).
    pub fn respond_tcp(&mut self, frame: &[u8], out: &mut [u8]) -> Option<usize> {
        self.respond(TransportKind::Tcp, frame, out)
    }

    /// Serves requests arriving on `link` until `until` or until the master closes the link,
    /// answering each; returns the number of replies sent. The loop is the simulator's own
    /// ([`crate::server::serve_link_with`]): frames cut by the same framer, an incomplete RTU
    /// frame dropped after [`SERVE_LIMITS`]' silence, a frame that does not arrive whole within
    /// its deadline dropped (RTU) or the link left (Modbus TCP, out of step).
    pub fn serve(&mut self, link: &mut impl Transport, until: Instant) -> io::Result<u32> {
        let stop = AtomicBool::new(false);
        server::serve_frames(
            link,
            SERVE_LIMITS,
            &stop,
            Some(until),
            |kind, frame, out| Answer {
                reply: self.respond(kind, frame, out),
                request: true,
            },
        )
    }
}

/// The limits [`SimulatedSlave::serve`] serves a link with: 100 ms silence (as RTU over TCP),
/// 1 s per frame, no idle timeout (the caller's `until` ends serving).
pub const SERVE_LIMITS: FrameLimits = FrameLimits {
    silence: Duration::from_millis(100),
    frame_deadline: Duration::from_secs(1),
    idle_timeout: None,
};
