//! The blocking client: checked Modbus transactions over any [`Transport`].
//!
//! Per request the client
//! 1. refuses what the drive cannot serve, before sending: a function the profile lacks, more
//!    registers than the drive's maximum, a read or loop-back to broadcast, a broadcast the
//!    drive does not execute, a plain write to an ENTER/ACCEPT/save register;
//! 2. maps the manual's communication address to the PDU address for the transport kind
//!    ([`drivemap_core::profile::AddressOffsets::pdu_address`]);
//! 3. on an RTU-framed link (serial, RTU over TCP) after an attempt that timed out or met a
//!    frame that was not its answer, waits until the line has been silent for the reply
//!    timeout (at least the drive's response time), so
//!    that a late reply is never taken for the next request's answer: RTU frames carry no
//!    transaction id, and two replies of the same shape cannot be told apart
//!    ([`Client::settled`] says what that wait took; [`Error::Timeout`] says it will come);
//! 4. discards stale input, sends, and for broadcast (slave 0) returns at once;
//! 5. waits at most [`ClientOptions::timeout`] for a reply that passes every check, discarding
//!    everything else (see [`crate::reply`]), and retries up to [`ClientOptions::retries`] times
//!    after a timeout. Exceptions are not retried: the drive answered.
//!
//! A transaction allocates nothing: frames are built and received in fixed buffers owned by the
//! client, and read results go to caller slices.

use std::io;
use std::time::{Duration, Instant};

use crate::ascii;
use crate::bus_time::{BusModel, SerialConfig};
use crate::error::{Error, Refusal, Sent};
use crate::exception::Exception;
use crate::gate::{self, WriteTarget};
use crate::pdu::{FrameError, Request, Response, Words, function};
use crate::persist::PersistBudget;
use crate::reply::{Discard, Discarded, Framing, ReplyBuffer};
use crate::transport::Transport;
use crate::typed::{ReadSet, WriteSet};
use crate::wire::{Blocking, Wire, block_on};
use crate::{rtu, tcp};
use drivemap_core::profile::{CommandInfo, CommandKind, Profile, TransportKind};
use drivemap_core::register::{BitRegister, Bits, DriveSettings, Readable, Table, Writable};
use drivemap_core::rule::WriteRule;

/// Per-client settings (not part of a drive's profile).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClientOptions {
    /// How long to wait for a reply to one attempt.
    pub timeout: Duration,
    /// Further attempts after a timeout (not after an exception, and never for a command that
    /// writes EEPROM, which could then be written twice).
    pub retries: u8,
    /// Least time between the end of one transaction and the next request, on top of the
    /// transport's frame gap. The V7 and J7 need 24 bit times + 10 ms
    /// (`003_8bcf5d50afb8e230.txt:284`).
    pub request_gap: Duration,
    /// EEPROM writes ([`CommandKind::Persist`] commands) allowed in any rolling hour.
    pub eeprom_writes_per_hour: u32,
    /// What to do when the peer closes or resets the connection (TCP transports): reconnect
    /// with back-off (the default) or never.
    pub reconnect: Reconnect,
}

impl Default for ClientOptions {
    fn default() -> Self {
        ClientOptions {
            timeout: Duration::from_secs(1),
            retries: 2,
            request_gap: Duration::ZERO,
            eeprom_writes_per_hour: 10,
            reconnect: Reconnect::default(),
        }
    }
}

impl ClientOptions {
    /// Options that know nothing of the drive: a 1 s timeout, two retries, no request gap.
    /// The same as [`ClientOptions::default`]; [`Client::with_options`] with these is the
    /// explicit choice of a client that ignores the drive's timing ([`Client::new`] applies
    /// it).
    pub fn generic() -> ClientOptions {
        ClientOptions::default()
    }

    /// The options [`Client::new`] takes for a link of `kind` to a drive with `profile`: on a
    /// link that reaches the drive's serial side (serial, RTU over TCP, a Modbus TCP gateway)
    /// [`ClientOptions::for_profile`], the manual's request gap and frame gap, and its response
    /// time in the timeout; on the drive's own Modbus TCP interface the same timeout but no
    /// request gap (the drive's network card keeps its own line), as the CLI does.
    pub fn for_link(profile: &Profile, kind: TransportKind) -> ClientOptions {
        let options = ClientOptions::for_profile(profile);
        if kind.reaches_rtu_side() {
            options
        } else {
            ClientOptions {
                request_gap: Duration::ZERO,
                ..options
            }
        }
    }

    /// The defaults with the timing the drive's manual prescribes, counted on a 9600 baud 8N1
    /// line (the default line of every shipped map; see [`ClientOptions::for_line`] for
    /// another):
    ///
    /// - [`request_gap`](ClientOptions::request_gap): the wait the manual asks of the master
    ///   after a reply (`timing.request_gap`; V7/J7 24 bit times + 10 ms,
    ///   `003_8bcf5d50afb8e230.txt:284`), or the frame gap (`timing.frame_gap_chars`, 3.5
    ///   characters) where that is longer or the manual prints no wait;
    /// - [`timeout`](ClientOptions::timeout): the default second plus the drive's stated time
    ///   to answer (`timing.response_time`, and the default of its response-delay parameter,
    ///   V7 n156).
    ///
    /// Override any field after: `ClientOptions { retries: 0, ..ClientOptions::for_profile(p) }`.
    pub fn for_profile(profile: &Profile) -> ClientOptions {
        ClientOptions::for_line(profile, SerialConfig::default())
    }

    /// [`ClientOptions::for_profile`] with bit and character times counted on `line` (its baud
    /// rate, parity and stop bits).
    pub fn for_line(profile: &Profile, line: SerialConfig) -> ClientOptions {
        let model = BusModel::new(profile, line);
        let ns = |ns: f64| Duration::from_nanos(ns.ceil() as u64);
        let defaults = ClientOptions::default();
        ClientOptions {
            request_gap: ns(model.turnaround_ns()),
            timeout: defaults.timeout + ns(model.latency_ns()),
            ..defaults
        }
    }
}

/// Whether and how often a client re-establishes a connection that the peer closed or reset,
/// through [`Transport::reconnect`] (TCP and RTU over TCP; a serial line has nothing to
/// re-establish and ignores it).
///
/// With [`Reconnect::Backoff`] a connection found closed *before* a request is sent (the
/// peer restarted between two requests) is re-established at once and the request goes out on
/// the new connection, unnoticed by the caller. A connection lost *after* the request went out
/// fails that attempt; the next attempt (within [`ClientOptions::retries`]) or the next
/// request reconnects. A reconnect that fails makes the request fail at once with the I/O
/// error, and no new attempt is made before the back-off has passed (the first wait, doubled
/// after each failure up to the longest); requests in between fail at once, without waiting,
/// saying when the next attempt is due. This is libmodbus's `MODBUS_ERROR_RECOVERY_LINK`,
/// without its unbounded retry of the send; tokio-modbus leaves reconnecting to the caller,
/// which [`Reconnect::Never`] does too.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Reconnect {
    /// Never reconnect: once the peer has closed the connection, every request fails with the
    /// I/O error.
    Never,
    /// Reconnect when the connection is found lost; after a failed attempt wait `first`, then
    /// twice as long after each further failure, at most `max`.
    Backoff {
        /// Wait after the first failed reconnect.
        first: Duration,
        /// Longest wait between two reconnect attempts.
        max: Duration,
    },
}

impl Default for Reconnect {
    /// Back-off from 100 ms to 5 s.
    fn default() -> Self {
        Reconnect::Backoff {
            first: Duration::from_millis(100),
            max: Duration::from_secs(5),
        }
    }
}

/// Most bytes taken in one attempt without finding the answer before the attempt gives up
/// with [`Error::Overrun`]: against a peer that floods the link, the client returns long before
/// the timeout instead of scanning for it. No drive sends that much unasked (64 KiB is 6 s of
/// a 115 200-baud line without a pause).
pub const MAX_UNANSWERED_BYTES: usize = 64 * 1024;

/// The state of the connection, for reconnecting.
#[derive(Debug, Default)]
pub(crate) struct Link {
    /// The connection was found closed or reset and not yet re-established.
    lost: bool,
    /// No reconnect attempt before this instant (after a failed one).
    next_try: Option<Instant>,
    /// Wait after the next failed attempt.
    backoff: Duration,
    /// Why the last reconnect failed.
    last_failure: Option<io::ErrorKind>,
    /// Connections re-established.
    reconnects: u32,
}

/// What a client did before a request to make sure that no late reply to an earlier attempt
/// was still on its way ([`Client::settled`]): it waited until the line had been silent for
/// `quiet`, throwing away what arrived meanwhile.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct Settled {
    /// Time spent waiting, over every attempt of the call.
    pub waited: Duration,
    /// The silence waited for.
    pub quiet: Duration,
    /// Bytes that arrived while waiting and were thrown away (a late reply, noise).
    pub bytes: u32,
}

impl std::fmt::Display for Settled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "waited {} ms for the line to be silent for {} ms after an unanswered request",
            self.waited.as_millis(),
            self.quiet.as_millis()
        )?;
        if self.bytes > 0 {
            write!(
                f,
                " and discarded {} byte(s) that arrived meanwhile (a late reply?)",
                self.bytes
            )?;
        }
        Ok(())
    }
}

/// An attempt that may still be answered late.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Unsettled {
    /// The slave it was addressed to: only its reply could pass for the answer to a later
    /// request (an RTU reply names its slave), so only a request to it, or a broadcast that
    /// nobody confirms, waits.
    slave: u8,
    /// When the attempt ended: the silence is counted from here.
    since: Instant,
}

/// Where a wait for silence stands.
pub(crate) struct Settle {
    started: Instant,
    last_byte: Instant,
    quiet: Duration,
    bytes: usize,
}

/// The transport-independent part of a client: checks, framing, reply matching, EEPROM budget.
/// Shared by the blocking and the async client.
pub(crate) struct Core {
    pub(crate) profile: &'static Profile,
    pub(crate) options: ClientOptions,
    pub(crate) kind: TransportKind,
    next_transaction: u16,
    tx: [u8; ascii::MAX_FRAME],
    tx_len: usize,
    pub(crate) rx: ReplyBuffer,
    /// Modbus ASCII links: the characters received, cut into frames, each turned into the RTU
    /// frame `rx` matches.
    ascii_in: Box<AsciiIn>,
    budget: PersistBudget,
    idle_since: Option<Instant>,
    link: Link,
    /// The line may still carry a reply to an earlier attempt (RTU framing only): the next
    /// attempt to that slave (or a broadcast) waits for silence first.
    unsettled: Option<Unsettled>,
    /// What the waits for silence of the current call took.
    settled: Option<Settled>,
}

/// Why a request is sent: what [`Core::check`] checks it against.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Purpose<'a> {
    /// A read or a loop-back: the profile's protocol rules.
    Read,
    /// A write: the protocol rules and the write gate.
    Write(WriteTarget<'a>),
    /// A write of a profile command (ENTER, ACCEPT, save): the protocol rules; the command's
    /// registers are the profile's.
    Command,
}

/// A request checked and mapped to the wire.
pub(crate) struct Checked<'a> {
    pub(crate) request: Request<'a>,
    pub(crate) sent: Sent,
}

impl Core {
    pub(crate) fn new(
        profile: &'static Profile,
        kind: TransportKind,
        options: ClientOptions,
    ) -> Core {
        Core {
            profile,
            options,
            kind,
            next_transaction: 1,
            tx: [0; ascii::MAX_FRAME],
            tx_len: 0,
            rx: ReplyBuffer::new(),
            ascii_in: Box::default(),
            budget: PersistBudget::new(options.eeprom_writes_per_hour),
            idle_since: None,
            link: Link::default(),
            unsettled: None,
            settled: None,
        }
    }

    /// The silence that proves no reply to an earlier attempt is still on its way: the reply
    /// timeout (no drive that keeps its timing answers later), and at least the drive's own
    /// response time on the default line should the timeout be set shorter.
    pub(crate) fn settle_quiet(&self) -> Duration {
        let model = BusModel::new(self.profile, SerialConfig::default());
        let response = Duration::from_nanos(model.latency_ns().ceil() as u64);
        self.options.timeout.max(response)
    }

    /// Called at the start of a call: forgets the previous call's wait for silence.
    pub(crate) fn begin_call(&mut self) {
        self.settled = None;
    }

    /// Records how an attempt to `slave` ended: on an RTU-framed link, an attempt that timed
    /// out, failed mid-reply or met anything that was not its answer may leave a reply on its
    /// way.
    pub(crate) fn attempt_ended(&mut self, slave: u8, answered: bool) {
        if self.kind.is_serial_framed() && (!answered || !self.rx.discarded().is_empty()) {
            self.unsettled = Some(Unsettled {
                slave,
                since: Instant::now(),
            });
        }
    }

    /// The wait for silence to run before sending to `slave`, if one is needed: after an
    /// unanswered attempt to the same slave, or before a broadcast (which no reply confirms).
    /// The silence is counted from the end of that attempt, so a caller that paused as long
    /// does not wait again.
    pub(crate) fn settle_start(&self, slave: u8) -> Option<Settle> {
        let u = self.unsettled?;
        if u.slave != slave && slave != rtu::BROADCAST {
            return None;
        }
        Some(Settle {
            started: Instant::now(),
            last_byte: u.since,
            quiet: self.settle_quiet(),
            bytes: 0,
        })
    }

    /// How long the next receive of a wait for silence may wait.
    pub(crate) fn settle_until(&self, settle: &Settle) -> Instant {
        (settle.last_byte + settle.quiet).min(settle.started + settle.quiet * 2)
    }

    /// Takes `n` bytes received while waiting for silence (0: none until the wait's deadline).
    /// Returns the outcome once the line has been silent for the whole quiet time, or the wait
    /// has to give up: after twice the quiet time (the line never falls silent) or
    /// [`MAX_UNANSWERED_BYTES`] (a peer that floods the link). Nothing is sent then.
    pub(crate) fn settle_step(
        &mut self,
        settle: &mut Settle,
        n: usize,
        checked: &Checked<'_>,
    ) -> Option<Result<(), Error>> {
        let now = Instant::now();
        if n > 0 {
            settle.bytes = settle.bytes.saturating_add(n);
            settle.last_byte = now;
        }
        self.rx.clear();
        self.ascii_in.assembler.clear();
        let silent = now.saturating_duration_since(settle.last_byte) >= settle.quiet;
        let record = |core: &mut Core| {
            let s = core.settled.get_or_insert(Settled {
                quiet: settle.quiet,
                ..Settled::default()
            });
            s.waited += now.saturating_duration_since(settle.started);
            s.bytes = s.bytes.saturating_add(settle.bytes as u32);
        };
        if silent {
            record(self);
            self.unsettled = None;
            return Some(Ok(()));
        }
        if settle.bytes > MAX_UNANSWERED_BYTES {
            record(self);
            return Some(Err(Error::Overrun {
                sent: checked.sent,
                bytes: settle.bytes,
                discarded: self.rx.discarded(),
            }));
        }
        if now >= settle.started + settle.quiet * 2 {
            record(self);
            return Some(Err(Error::Unsettled {
                sent: checked.sent,
                quiet: settle.quiet,
                waited: now.saturating_duration_since(settle.started),
                bytes: settle.bytes,
            }));
        }
        None
    }

    /// What the waits for silence of the current call took.
    pub(crate) fn settled(&self) -> Option<Settled> {
        self.settled
    }

    /// Checks `request` (communication addresses) against the profile, and a write against the
    /// map's rule for its register ([`gate::check`]), and maps it to the PDU. Every request of
    /// both clients passes here.
    pub(crate) fn check<'a>(
        &self,
        slave: u8,
        request: Request<'a>,
        purpose: Purpose<'_>,
    ) -> Result<Checked<'a>, Refusal> {
        let command = matches!(purpose, Purpose::Command);
        let p = self.profile;
        let f = request.function();
        if !p.supports(f) {
            return Err(Refusal::UnsupportedFunction {
                drive: p.drive_id,
                function: f,
            });
        }
        if slave != rtu::BROADCAST && !(p.slave_min..=p.slave_max).contains(&slave) {
            return Err(Refusal::Slave {
                drive: p.drive_id,
                slave,
                min: p.slave_min,
                max: p.slave_max,
            });
        }
        let quantity = request.quantity();
        let max = match f {
            function::READ_HOLDING | function::READ_INPUT => Some(p.max_read),
            function::WRITE_MULTIPLE => Some(p.max_write),
            function::READ_COILS | function::READ_DISCRETE_INPUTS => Some(p.max_read_bits),
            function::WRITE_COILS => Some(p.max_write_bits),
            _ => None,
        };
        if let Some(max) = max {
            if quantity == 0 {
                return Err(Refusal::NoRegisters { function: f });
            }
            if quantity > usize::from(max) {
                return Err(if request.is_bits() {
                    Refusal::TooManyBits {
                        drive: p.drive_id,
                        function: f,
                        quantity,
                        max,
                    }
                } else {
                    Refusal::TooManyRegisters {
                        drive: p.drive_id,
                        function: f,
                        quantity,
                        max,
                    }
                });
            }
        }
        let address = request.address();
        if let Some(a) = address
            && usize::from(a) + quantity.max(1) > 0x1_0000
        {
            return Err(Refusal::AddressOverflow {
                address: a,
                quantity,
            });
        }
        if slave == rtu::BROADCAST {
            self.check_broadcast(&request)?;
        }
        if !command
            && let Some(a) = address
            && !request.is_read()
        {
            for c in p.commands {
                if let Some(&(ca, _)) = c.writes.iter().find(|(ca, _)| {
                    (usize::from(a)..usize::from(a) + quantity).contains(&usize::from(*ca))
                }) {
                    return Err(Refusal::CommandRegister {
                        address: ca,
                        command: c.id,
                        name: c.name,
                    });
                }
            }
        }
        if let (Purpose::Write(target), Some(a)) = (purpose, address) {
            use drivemap_core::register::Table;
            let k = self.kind;
            match &request {
                Request::WriteSingle { value, .. } => {
                    gate::check_in(p, k, slave, target, Table::Holding, a, [*value])?
                }
                Request::WriteMultiple { values, .. } => {
                    gate::check_in(p, k, slave, target, Table::Holding, a, values.iter())?
                }
                Request::WriteCoil { value, .. } => {
                    gate::check_coils(p, k, slave, target, a, [*value])?
                }
                Request::WriteCoils { values, .. } => {
                    gate::check_coils(p, k, slave, target, a, values.iter())?
                }
                _ => {}
            }
            if !request.is_read() {
                gate::check_function(p, self.kind, target, f, a, quantity)?;
            }
        }
        let pdu_address = match address {
            None => None,
            Some(a) => {
                let offset = p.address_offsets.for_kind(self.kind);
                let mapped = p
                    .address_offsets
                    .pdu_address(a, self.kind)
                    .ok_or(Refusal::AddressMapping { address: a, offset })?;
                if usize::from(mapped) + quantity.max(1) > 0x1_0000 {
                    return Err(Refusal::AddressOverflow {
                        address: mapped,
                        quantity,
                    });
                }
                Some(mapped)
            }
        };
        let mapped = match request {
            Request::ReadHolding { quantity, .. } => Request::ReadHolding {
                address: pdu_address.unwrap_or(0),
                quantity,
            },
            Request::ReadInput { quantity, .. } => Request::ReadInput {
                address: pdu_address.unwrap_or(0),
                quantity,
            },
            Request::WriteSingle { value, .. } => Request::WriteSingle {
                address: pdu_address.unwrap_or(0),
                value,
            },
            Request::WriteMultiple { values, .. } => Request::WriteMultiple {
                address: pdu_address.unwrap_or(0),
                values,
            },
            Request::ReadCoils { quantity, .. } => Request::ReadCoils {
                address: pdu_address.unwrap_or(0),
                quantity,
            },
            Request::ReadDiscreteInputs { quantity, .. } => Request::ReadDiscreteInputs {
                address: pdu_address.unwrap_or(0),
                quantity,
            },
            Request::WriteCoil { value, .. } => Request::WriteCoil {
                address: pdu_address.unwrap_or(0),
                value,
            },
            Request::WriteCoils { values, .. } => Request::WriteCoils {
                address: pdu_address.unwrap_or(0),
                values,
            },
            r @ Request::LoopBack { .. } => r,
        };
        let value = match request {
            Request::WriteSingle { value, .. } => Some(value),
            Request::WriteCoil { value, .. } => Some(if value { crate::pdu::COIL_ON } else { 0 }),
            Request::LoopBack { data } => Some(data),
            _ => None,
        };
        Ok(Checked {
            request: mapped,
            sent: Sent {
                slave,
                function: f,
                address,
                pdu_address,
                quantity,
                value,
            },
        })
    }

    fn check_broadcast(&self, request: &Request<'_>) -> Result<(), Refusal> {
        let f = request.function();
        if request.is_read() {
            return Err(Refusal::BroadcastRead { function: f });
        }
        if f == function::LOOP_BACK {
            return Err(Refusal::BroadcastLoopBack);
        }
        let drive = self.profile.drive_id;
        gate::broadcast_known(self.profile, rtu::BROADCAST)?;
        let Some(b) = self.profile.broadcast else {
            return Err(Refusal::BroadcastFunction { drive, function: f });
        };
        if !b.functions.contains(&f) {
            return Err(Refusal::BroadcastFunction { drive, function: f });
        }
        // The listed addresses are the registers' and the coils' a broadcast may write: a
        // coil's is checked with its rule's broadcast use by the gate, in the coils' space.
        if !b.addresses.is_empty()
            && !request.is_bits()
            && let Some(a) = request.address()
        {
            for i in 0..request.quantity() {
                let address = a.wrapping_add(i as u16);
                if !b.addresses.contains(&address) {
                    return Err(Refusal::BroadcastAddress { drive, address });
                }
            }
        }
        Ok(())
    }

    /// Encodes one attempt into the transmit buffer; returns how its reply is framed, or `None`
    /// for a broadcast. Each attempt gets a new transaction id.
    pub(crate) fn encode(&mut self, checked: &Checked<'_>) -> Result<Option<Framing>, Error> {
        let slave = checked.sent.slave;
        let encoded = if self.kind.is_rtu_framed() {
            rtu::encode_request(slave, &checked.request, &mut self.tx)
                .map(|n| (n, Framing::Rtu { slave }))
        } else if self.kind.is_ascii() {
            // The reply is turned into an RTU frame on arrival ([`Core::received`]).
            ascii::encode_request(slave, &checked.request, &mut self.tx)
                .map(|n| (n, Framing::Rtu { slave }))
        } else {
            let transaction = self.next_transaction;
            self.next_transaction = self.next_transaction.wrapping_add(1);
            tcp::encode_request(transaction, slave, &checked.request, &mut self.tx).map(|n| {
                (
                    n,
                    Framing::Tcp {
                        transaction,
                        unit: slave,
                    },
                )
            })
        };
        // The checks above leave nothing for the encoder to refuse; keep the error anyway.
        let (n, framing) = encoded.map_err(|e| match e {
            crate::pdu::RequestError::AddressOverflow { address, quantity } => {
                Refusal::AddressOverflow { address, quantity }
            }
            _ => Refusal::TooManyRegisters {
                drive: self.profile.drive_id,
                function: checked.sent.function,
                quantity: checked.sent.quantity,
                max: crate::pdu::MAX_WRITE,
            },
        })?;
        self.tx_len = n;
        self.rx.clear();
        self.ascii_in.assembler.clear();
        Ok((slave != rtu::BROADCAST).then_some(framing))
    }

    pub(crate) fn frame(&self) -> &[u8] {
        &self.tx[..self.tx_len]
    }

    /// When the next request may be sent, if that is still to come (no clock read when there is
    /// no gap to keep).
    pub(crate) fn ready_at(&self) -> Option<Instant> {
        if self.options.request_gap.is_zero() {
            return None;
        }
        let at = self.idle_since? + self.options.request_gap;
        (at > Instant::now()).then_some(at)
    }

    pub(crate) fn mark_idle(&mut self) {
        self.idle_since = Some(Instant::now());
    }

    /// Decodes the located reply; copies read registers into `out`.
    pub(crate) fn finish(
        &self,
        framing: Framing,
        range: std::ops::Range<usize>,
        checked: &Checked<'_>,
        out: &mut [u16],
    ) -> Result<(), Error> {
        let frame = self.rx.frame(range);
        let decoded: Result<Response<'_>, FrameError> = match framing {
            Framing::Rtu { slave } => rtu::decode_response(slave, &checked.request, frame),
            Framing::Tcp { transaction, unit } => {
                tcp::decode_response(transaction, unit, &checked.request, frame)
            }
        };
        match decoded {
            Ok(Response::Registers(words)) => {
                words.copy_to(out);
                Ok(())
            }
            Ok(Response::Bits(bits)) => {
                bits.copy_to(out);
                Ok(())
            }
            Ok(Response::Exception { function, code }) => Err(Error::Exception {
                sent: checked.sent,
                exception: Exception::new(self.profile, function, code),
            }),
            Ok(_) => Ok(()),
            // scan() only locates frames that decode; report it as a timeout if that ever breaks.
            Err(_) => Err(self.timeout(checked, 1)),
        }
    }

    pub(crate) fn timeout(&self, checked: &Checked<'_>, attempts: u8) -> Error {
        Error::Timeout {
            sent: checked.sent,
            waited: self.options.timeout,
            attempts,
            discarded: self.rx.discarded(),
            settle: self.kind.is_serial_framed().then(|| self.settle_quiet()),
        }
    }

    /// The command `id`, with one EEPROM write taken from the budget if it persists.
    pub(crate) fn command(&mut self, id: &str) -> Result<&'static CommandInfo, Refusal> {
        let profile: &'static Profile = self.profile;
        let command = profile.command(id).ok_or_else(|| Refusal::UnknownCommand {
            drive: profile.drive_id,
            id: id.to_string(),
        })?;
        if command.kind == CommandKind::Persist {
            self.budget.take(Instant::now())?;
        }
        Ok(command)
    }

    pub(crate) fn budget(&self) -> &PersistBudget {
        &self.budget
    }

    /// The request for writing one register: 06h, or 10h with one register where the drive has
    /// no 06h (VS mini J7: 03h/08h/10h only, `003_8bcf5d50afb8e230.txt:226-231`).
    /// Refuses a register the map does not list on this client's transport.
    pub(crate) fn on_transport<R: drivemap_core::register::Register>(&self) -> Result<(), Refusal> {
        if R::on_transport(self.kind) {
            Ok(())
        } else {
            Err(Refusal::NotOnTransport {
                register: R::ID,
                transport: self.kind,
            })
        }
    }

    /// One word at `address` as a request: 06h, or 10h where the drive lacks 06h or the
    /// register there accepts only 10h ([`gate::single_write_function`]).
    pub(crate) fn single_write<'a>(
        &self,
        target: WriteTarget<'_>,
        address: u16,
        value: &'a [u16; 1],
    ) -> Request<'a> {
        if gate::single_write_function(self.profile, self.kind, target, address)
            == function::WRITE_SINGLE
        {
            Request::WriteSingle {
                address,
                value: value[0],
            }
        } else {
            Request::WriteMultiple {
                address,
                values: Words::Native(value),
            }
        }
    }
}

impl Core {
    /// One coil at `address` as a request: 05h, or 0Fh with one coil where the drive lacks 05h
    /// or the coil accepts only 0Fh ([`gate::single_coil_function`]).
    pub(crate) fn single_coil<'a>(
        &self,
        target: WriteTarget<'_>,
        address: u16,
        value: &'a [bool; 1],
    ) -> Request<'a> {
        if gate::single_coil_function(self.profile, self.kind, target, address)
            == function::WRITE_COIL
        {
            Request::WriteCoil {
                address,
                value: value[0],
            }
        } else {
            Request::WriteCoils {
                address,
                values: crate::pdu::BitValues::Native(value),
            }
        }
    }
}

/// What a Modbus ASCII link's replies pass through before the reply buffer.
pub(crate) struct AsciiIn {
    assembler: ascii::Assembler,
    /// Characters as the transport received them.
    chars: [u8; tcp::MAX_FRAME],
    /// The RTU frame an ASCII frame stands for.
    rtu_frame: [u8; rtu::MAX_FRAME],
}

impl Default for AsciiIn {
    fn default() -> Self {
        AsciiIn {
            assembler: ascii::Assembler::new(),
            chars: [0; tcp::MAX_FRAME],
            rtu_frame: [0; rtu::MAX_FRAME],
        }
    }
}

/// Where waiting for one reply stands: the deadline, the inter-character gap, the last byte.
pub(crate) struct Wait {
    deadline: Instant,
    gap: Option<Duration>,
    last_byte: Instant,
    /// Bytes received in this attempt.
    bytes: usize,
}

impl Wait {
    pub(crate) fn new(timeout: Duration, gap: Option<Duration>) -> Wait {
        let now = Instant::now();
        Wait {
            deadline: now + timeout,
            gap,
            last_byte: now,
            bytes: 0,
        }
    }
}

impl Core {
    /// How long the next receive may wait: the reply deadline, or sooner while a frame is
    /// partly received and the link keeps byte timing.
    pub(crate) fn receive_until(&self, wait: &Wait) -> Instant {
        match wait.gap {
            // An ASCII frame ends with its CR LF, not with a silence.
            Some(g) if self.rx.pending() > 0 && !self.kind.is_ascii() => {
                wait.deadline.min(wait.last_byte + g)
            }
            _ => wait.deadline,
        }
    }

    /// The buffer the transport receives into: the reply buffer, or on a Modbus ASCII link the
    /// characters' buffer ([`Core::received`] turns them into frames).
    pub(crate) fn space(&mut self) -> &mut [u8] {
        if self.kind.is_ascii() {
            &mut self.ascii_in.chars
        } else {
            self.rx.space()
        }
    }

    /// Modbus ASCII: cuts the `n` characters just received into frames and puts each intact
    /// one into the reply buffer as the RTU frame with the same address and PDU; counts what
    /// is thrown away.
    fn take_ascii(&mut self, n: usize) {
        let AsciiIn {
            assembler,
            chars,
            rtu_frame,
        } = &mut *self.ascii_in;
        for &c in &chars[..n.min(chars.len())] {
            match assembler.feed(c) {
                ascii::Feed::Pending => {}
                ascii::Feed::Skipped(k) => self
                    .rx
                    .discard_bytes(k, Discard::Ascii(ascii::AsciiError::Start)),
                ascii::Feed::Frame => match ascii::to_rtu(assembler.frame(), rtu_frame) {
                    Ok(m) => {
                        self.rx.push(&rtu_frame[..m]);
                    }
                    Err(e) => self.rx.discard_frame(Discard::Ascii(e)),
                },
            }
        }
    }

    /// Takes `n` bytes just received (0: the wait until `until` ended empty). Returns the
    /// outcome when the reply is complete (`Some(Ok(Some(())))`) or the deadline has passed
    /// (`Some(Ok(None))`), `None` to keep receiving.
    pub(crate) fn received(
        &mut self,
        n: usize,
        until: Instant,
        wait: &mut Wait,
        framing: Framing,
        checked: &Checked<'_>,
        out: &mut [u16],
    ) -> Option<Result<Option<()>, Error>> {
        let now = Instant::now();
        if n == 0 {
            if now >= wait.deadline {
                self.rx.break_off();
                let partial = self.ascii_in.assembler.clear();
                self.rx
                    .discard_bytes(partial, Discard::Gap { bytes: partial });
                return Some(Ok(None));
            }
            if now >= until {
                self.rx.break_off();
            }
            return None;
        }
        wait.last_byte = now;
        wait.bytes = wait.bytes.saturating_add(n);
        if self.kind.is_ascii() {
            self.take_ascii(n);
        } else {
            self.rx.filled(n);
        }
        if let Some(range) = self.rx.scan(framing, &checked.request) {
            return Some(self.finish(framing, range, checked, out).map(Some));
        }
        // A peer that keeps sending must not hold the client past its deadline (the transport
        // may hand out bytes without looking at the clock), nor make it scan without end.
        if wait.bytes > MAX_UNANSWERED_BYTES {
            return Some(Err(Error::Overrun {
                sent: checked.sent,
                bytes: wait.bytes,
                discarded: self.rx.discarded(),
            }));
        }
        if now >= wait.deadline {
            self.rx.break_off();
            return Some(Ok(None));
        }
        None
    }

    /// Whether the connection must be re-established before the next request.
    pub(crate) fn link_lost(&self) -> bool {
        self.link.lost
    }

    /// Connections re-established so far.
    pub(crate) fn reconnects(&self) -> u32 {
        self.link.reconnects
    }

    /// Records an I/O error; returns whether it means the connection is lost and the options
    /// reconnect, in which case the next attempt or request re-establishes it.
    pub(crate) fn lost(&mut self, e: &io::Error) -> bool {
        if self.options.reconnect == Reconnect::Never || !crate::transport::is_connection_loss(e) {
            return false;
        }
        self.link.lost = true;
        true
    }

    /// Whether the back-off allows a reconnect attempt now; the error says when it will.
    pub(crate) fn may_reconnect(&self) -> io::Result<()> {
        let Some(at) = self.link.next_try else {
            return Ok(());
        };
        let now = Instant::now();
        if now >= at {
            return Ok(());
        }
        let why = self
            .link
            .last_failure
            .map(|k| format!(" (last attempt: {})", io::Error::from(k)))
            .unwrap_or_default();
        Err(io::Error::new(
            io::ErrorKind::NotConnected,
            format!(
                "the connection was lost; next reconnect attempt in {} ms{why}",
                (at - now).as_millis().max(1)
            ),
        ))
    }

    /// Takes the outcome of [`Transport::reconnect`]. `Ok(())` when the connection is back, or
    /// when the transport has none to re-establish (then the request goes on and fails as it
    /// would have).
    pub(crate) fn reconnected(&mut self, outcome: io::Result<()>) -> io::Result<()> {
        let (first, max) = match self.options.reconnect {
            Reconnect::Never => return outcome,
            Reconnect::Backoff { first, max } => (first, max),
        };
        match outcome {
            Ok(()) => {
                self.link = Link {
                    reconnects: self.link.reconnects.saturating_add(1),
                    ..Link::default()
                };
                Ok(())
            }
            Err(e) if e.kind() == io::ErrorKind::Unsupported => {
                self.link.lost = false;
                Ok(())
            }
            Err(e) => {
                let wait = if self.link.backoff.is_zero() {
                    first
                } else {
                    self.link.backoff
                };
                self.link.next_try = Some(Instant::now() + wait);
                self.link.backoff = (wait * 2).min(max.max(first));
                self.link.last_failure = Some(e.kind());
                Err(io::Error::new(
                    e.kind(),
                    format!(
                        "the connection was lost and reconnecting failed: {e}; next attempt in {} ms",
                        wait.as_millis()
                    ),
                ))
            }
        }
    }
}

pub(crate) fn read_request(table: Table, address: u16, quantity: usize) -> Request<'static> {
    let quantity = u16::try_from(quantity).unwrap_or(u16::MAX);
    match table {
        Table::Holding => Request::ReadHolding { address, quantity },
        Table::Input => Request::ReadInput { address, quantity },
        Table::Coil => Request::ReadCoils { address, quantity },
        Table::DiscreteInput => Request::ReadDiscreteInputs { address, quantity },
    }
}

pub(crate) fn io_error(checked: &Checked<'_>, source: std::io::Error) -> Error {
    Error::Io {
        sent: checked.sent,
        source,
    }
}

/// Largest number of words a typed multi-register call handles in one request (8 registers,
/// each of which may be a 32-bit pair).
pub const MAX_SET: usize = 16;

/// Most coil or discrete-input states one request of [`Client::read_coils`] and
/// [`Client::read_discrete_inputs`] asks for (fewer where the drive's `max_read_bits` is
/// lower): longer reads go out as several requests.
pub const MAX_BITS_CHUNK: usize = 256;

/// A client's link and protocol state, borrowed for one call: the requests and their
/// transactions, written once for the blocking [`Client`] (over [`Blocking`], run by
/// [`block_on`]) and the async client (over [`Tokio`](crate::wire::Tokio), awaited).
pub(crate) struct Session<'a, W> {
    pub(crate) wire: W,
    pub(crate) core: &'a mut Core,
}

impl<W: Wire> Session<'_, W> {
    /// One request: checked and mapped to the wire, then per attempt the request gap, the
    /// link prepared, the line settled, the frame sent and the answer awaited; retried after a
    /// timeout or a lost connection, up to `retries` times.
    async fn transact(
        &mut self,
        slave: u8,
        request: Request<'_>,
        out: &mut [u16],
        purpose: Purpose<'_>,
        retries: u8,
    ) -> Result<(), Error> {
        let checked = self.core.check(slave, request, purpose)?;
        self.core.begin_call();
        let attempts = retries.saturating_add(1);
        for attempt in 1..=attempts {
            let framing = self.core.encode(&checked)?;
            if let Some(at) = self.core.ready_at() {
                self.wire.sleep_until(at).await;
            }
            if let Err(e) = self.prepare().await {
                self.core.mark_idle();
                return Err(io_error(&checked, e));
            }
            if let Err(e) = self.settle(&checked).await {
                self.core.mark_idle();
                return Err(e);
            }
            if let Err(e) = self.wire.send(self.core.frame()).await {
                self.core.mark_idle();
                if self.core.lost(&e) && attempt < attempts {
                    continue;
                }
                return Err(io_error(&checked, e));
            }
            let Some(framing) = framing else {
                self.core.mark_idle();
                return Ok(());
            };
            let result = self.receive(framing, &checked, out).await;
            self.core.mark_idle();
            self.core.attempt_ended(
                checked.sent.slave,
                matches!(result, Ok(Some(())) | Err(Error::Exception { .. })),
            );
            match result {
                Ok(Some(())) => return Ok(()),
                Ok(None) if attempt < attempts => continue,
                Ok(None) => return Err(self.core.timeout(&checked, attempts)),
                Err(Error::Io { source, .. }) if self.core.lost(&source) && attempt < attempts => {
                    continue;
                }
                Err(e) => return Err(e),
            }
        }
        Err(self.core.timeout(&checked, attempts))
    }

    /// Before sending: re-establishes a lost connection and flushes stale input. Nothing has
    /// been sent yet, so a connection found closed here is re-established once and the request
    /// goes on over the new one.
    async fn prepare(&mut self) -> std::io::Result<()> {
        let mut reconnected = false;
        loop {
            if self.core.link_lost() {
                self.core.may_reconnect()?;
                let outcome = self.wire.reconnect().await;
                self.core.reconnected(outcome)?;
                reconnected = true;
            }
            match self.wire.discard_input().await {
                Err(e) if !reconnected && self.core.lost(&e) => continue,
                other => return other,
            }
        }
    }

    /// On an RTU-framed link after an attempt that was not answered cleanly: waits until the
    /// line has been silent for the reply timeout, throwing away what arrives.
    async fn settle(&mut self, checked: &Checked<'_>) -> Result<(), Error> {
        let Some(mut settle) = self.core.settle_start(checked.sent.slave) else {
            return Ok(());
        };
        loop {
            let until = self.core.settle_until(&settle);
            let n = self
                .wire
                .recv(self.core.space(), until)
                .await
                .map_err(|e| io_error(checked, e))?;
            if let Some(outcome) = self.core.settle_step(&mut settle, n, checked) {
                return outcome;
            }
        }
    }

    /// Waits for the answer; `Ok(None)` on timeout.
    async fn receive(
        &mut self,
        framing: Framing,
        checked: &Checked<'_>,
        out: &mut [u16],
    ) -> Result<Option<()>, Error> {
        let mut wait = Wait::new(self.core.options.timeout, self.wire.inter_char_timeout());
        loop {
            let until = self.core.receive_until(&wait);
            let n = self
                .wire
                .recv(self.core.space(), until)
                .await
                .map_err(|e| io_error(checked, e))?;
            if let Some(outcome) = self
                .core
                .received(n, until, &mut wait, framing, checked, out)
            {
                return outcome;
            }
        }
    }

    /// [`Client::read_holding`].
    pub(crate) async fn read_holding(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        self.read_table(slave, Table::Holding, address, out).await
    }

    /// [`Client::read_input`].
    pub(crate) async fn read_input(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        self.read_table(slave, Table::Input, address, out).await
    }

    /// [`Client::read_table`]: registers' words, or coils' and discrete inputs' states as 1
    /// and 0.
    pub(crate) async fn read_table(
        &mut self,
        slave: u8,
        table: Table,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        let retries = self.core.options.retries;
        self.transact(
            slave,
            read_request(table, address, out.len()),
            out,
            Purpose::Read,
            retries,
        )
        .await
    }

    /// [`Client::read_coils`] and [`Client::read_discrete_inputs`]: the states of `out.len()`
    /// bits of `table` from `address`, read in requests of at most [`MAX_BITS_CHUNK`] states
    /// (and the drive's limit).
    pub(crate) async fn read_bits(
        &mut self,
        slave: u8,
        table: Table,
        address: u16,
        out: &mut [bool],
    ) -> Result<(), Error> {
        if out.is_empty() {
            // Refused as a request for nothing, as a read of no registers is.
            return self.read_table(slave, table, address, &mut []).await;
        }
        let mut words = [0u16; MAX_BITS_CHUNK];
        let max = usize::from(self.core.profile.max_read_bits.max(1)).min(MAX_BITS_CHUNK);
        let quantity = out.len();
        for (i, chunk) in out.chunks_mut(max).enumerate() {
            let at = u16::try_from(usize::from(address) + i * max)
                .map_err(|_| Refusal::AddressOverflow { address, quantity })?;
            let words = &mut words[..chunk.len()];
            self.read_table(slave, table, at, words).await?;
            for (o, w) in chunk.iter_mut().zip(words.iter()) {
                *o = *w != 0;
            }
        }
        Ok(())
    }

    /// [`Client::write_coil`].
    pub(crate) async fn write_coil(
        &mut self,
        slave: u8,
        target: WriteTarget<'_>,
        address: u16,
        value: bool,
    ) -> Result<(), Error> {
        let value = [value];
        let request = self.core.single_coil(target, address, &value);
        let retries = self.core.options.retries;
        self.transact(slave, request, &mut [], Purpose::Write(target), retries)
            .await
    }

    /// [`Client::write_coils`].
    pub(crate) async fn write_coils(
        &mut self,
        slave: u8,
        address: u16,
        values: &[bool],
    ) -> Result<(), Error> {
        let request = Request::WriteCoils {
            address,
            values: crate::pdu::BitValues::Native(values),
        };
        let retries = self.core.options.retries;
        self.transact(
            slave,
            request,
            &mut [],
            Purpose::Write(WriteTarget::Addresses),
            retries,
        )
        .await
    }

    /// [`Client::write_register`].
    pub(crate) async fn write_register(
        &mut self,
        slave: u8,
        address: u16,
        value: u16,
    ) -> Result<(), Error> {
        self.write_single(slave, WriteTarget::Addresses, address, value)
            .await
    }

    /// [`Client::write_rule`].
    pub(crate) async fn write_rule(
        &mut self,
        slave: u8,
        rule: &WriteRule,
        address: u16,
        raw: u32,
    ) -> Result<(), Error> {
        if rule.table.is_bits() {
            // A coil: 05h (or 0Fh where the coil takes only that), raw 1 on and 0 off; the
            // gate refuses any other raw value with the rule's range.
            let target = WriteTarget::Rule(rule);
            if raw > 1 {
                crate::gate::check(
                    self.core.profile,
                    self.core.kind,
                    slave,
                    target,
                    address,
                    [raw as u16],
                )?;
            }
            return self.write_coil(slave, target, address, raw != 0).await;
        }
        match rule.width {
            drivemap_core::width::Width::Word => {
                self.write_single(slave, WriteTarget::Rule(rule), address, raw as u16)
                    .await
            }
            // Validation refuses a writable string; the gate refuses a write of text.
            drivemap_core::width::Width::Text(_) => {
                Err(Error::Refused(crate::error::Refusal::Text {
                    register: rule.register,
                }))
            }
            drivemap_core::width::Width::Pair(_) => {
                let words = rule.width.split(raw);
                let request = Request::WriteMultiple {
                    address,
                    values: Words::Native(&words),
                };
                let retries = self.core.options.retries;
                self.transact(
                    slave,
                    request,
                    &mut [],
                    Purpose::Write(WriteTarget::Rule(rule)),
                    retries,
                )
                .await
            }
        }
    }

    async fn write_single(
        &mut self,
        slave: u8,
        target: WriteTarget<'_>,
        address: u16,
        value: u16,
    ) -> Result<(), Error> {
        let value = [value];
        let request = self.core.single_write(target, address, &value);
        let retries = self.core.options.retries;
        self.transact(slave, request, &mut [], Purpose::Write(target), retries)
            .await
    }

    /// [`Client::write_registers`].
    pub(crate) async fn write_registers(
        &mut self,
        slave: u8,
        address: u16,
        values: &[u16],
    ) -> Result<(), Error> {
        let request = Request::WriteMultiple {
            address,
            values: Words::Native(values),
        };
        let retries = self.core.options.retries;
        self.transact(
            slave,
            request,
            &mut [],
            Purpose::Write(WriteTarget::Addresses),
            retries,
        )
        .await
    }

    /// [`Client::loop_back`].
    pub(crate) async fn loop_back(&mut self, slave: u8, data: u16) -> Result<(), Error> {
        let retries = self.core.options.retries;
        self.transact(
            slave,
            Request::LoopBack { data },
            &mut [],
            Purpose::Read,
            retries,
        )
        .await
    }

    /// [`Client::load_settings`].
    pub(crate) async fn load_settings<S: DriveSettings>(
        &mut self,
        slave: u8,
        settings: &mut S,
    ) -> Result<(), Error> {
        for &address in S::DEPENDENCIES {
            let mut raw = [0u16; 1];
            self.read_table(slave, Table::Holding, address, &mut raw)
                .await?;
            settings.absorb(address, raw[0]);
        }
        Ok(())
    }

    /// [`Client::read`].
    pub(crate) async fn read<R: Readable>(
        &mut self,
        slave: u8,
        settings: &R::Settings,
    ) -> Result<R::Value, Error> {
        self.core.on_transport::<R>()?;
        let address = R::address(settings, self.core.kind)?;
        // A pair's two words, or a string's (a map bounds it by `max_read`; a plan written by
        // hand beyond one request's 125 words is read up to those).
        let mut raw = [0u16; drivemap_core::width::Width::MAX_WORDS];
        let raw =
            &mut raw[..usize::from(R::WIDTH.count()).min(drivemap_core::width::Width::MAX_WORDS)];
        self.read_table(slave, R::TABLE, address, raw).await?;
        Ok(R::decode_words(raw, settings)?)
    }

    /// [`Client::write`].
    pub(crate) async fn write<R: Writable>(
        &mut self,
        slave: u8,
        value: &R::Input,
        settings: &R::Settings,
    ) -> Result<(), Error> {
        let raw = R::encode(value, settings)?;
        let address = R::address(settings, self.core.kind)?;
        match R::REPEAT_NEEDS_CHANGE {
            Some(rule) => {
                self.write_changed(slave, &R::RULE, address, rule.between, raw)
                    .await
            }
            None => self.write_rule(slave, &R::RULE, address, raw).await,
        }
    }

    /// [`Client::write_rounded`].
    pub(crate) async fn write_rounded<R: Writable>(
        &mut self,
        slave: u8,
        value: &R::Input,
        settings: &R::Settings,
        rounding: drivemap_core::scale::Rounding,
    ) -> Result<(), Error> {
        let raw = R::encode_rounded(value, settings, rounding)?;
        let address = R::address(settings, self.core.kind)?;
        match R::REPEAT_NEEDS_CHANGE {
            Some(rule) => {
                self.write_changed(slave, &R::RULE, address, rule.between, raw)
                    .await
            }
            None => self.write_rule(slave, &R::RULE, address, raw).await,
        }
    }

    /// [`Client::write_changed`].
    pub(crate) async fn write_changed(
        &mut self,
        slave: u8,
        rule: &WriteRule,
        address: u16,
        between: u32,
        raw: u32,
    ) -> Result<(), Error> {
        if raw != between {
            let target = WriteTarget::Rule(rule);
            let words = rule.width.split(raw);
            let words = words.iter().take(usize::from(rule.width.count())).copied();
            crate::gate::check(
                self.core.profile,
                self.core.kind,
                slave,
                target,
                address,
                words,
            )?;
            self.write_rule(slave, rule, address, between).await?;
        }
        self.write_rule(slave, rule, address, raw).await
    }

    /// [`Client::update`].
    pub(crate) async fn update<
        R: Readable + Writable<Input = <R as drivemap_core::register::Register>::Value>,
    >(
        &mut self,
        slave: u8,
        settings: &R::Settings,
        change: impl FnOnce(&mut R::Value),
    ) -> Result<R::Value, Error> {
        let mut value = self.read::<R>(slave, settings).await?;
        change(&mut value);
        self.write::<R>(slave, &value, settings).await?;
        Ok(value)
    }

    /// [`Client::modify_bits`].
    pub(crate) async fn modify_bits<R>(
        &mut self,
        slave: u8,
        settings: &R::Settings,
        set: u16,
        clear: u16,
    ) -> Result<R::Value, Error>
    where
        R: BitRegister
            + Readable
            + Writable<Input = <R as drivemap_core::register::Register>::Value>,
        R::Value: Bits,
    {
        let reserved = (set | clear) & !R::FIELD_MASK;
        if reserved != 0 {
            return Err(Refusal::ReservedBits {
                register: R::ID,
                bits: reserved,
            }
            .into());
        }
        self.update::<R>(slave, settings, |v| {
            let raw = ((v.bits() & !clear) | set) & R::FIELD_MASK;
            *v = R::Value::from_bits(raw);
        })
        .await
    }

    /// [`Client::read_many`].
    pub(crate) async fn read_many<S: ReadSet>(
        &mut self,
        slave: u8,
        settings: &S::Settings,
    ) -> Result<S::Values, Error> {
        let (address, table) = S::layout(settings, self.core.kind)?;
        let mut raw = [0u16; MAX_SET];
        let raw = &mut raw[..S::LEN.min(MAX_SET)];
        self.read_table(slave, table, address, raw).await?;
        Ok(S::decode(raw, settings)?)
    }

    /// [`Client::write_many`].
    pub(crate) async fn write_many<S: WriteSet>(
        &mut self,
        slave: u8,
        values: &S::Values,
        settings: &S::Settings,
    ) -> Result<(), Error> {
        let (address, _) = S::layout(settings, self.core.kind)?;
        let mut raw = [0u16; MAX_SET];
        let raw = &mut raw[..S::LEN.min(MAX_SET)];
        S::encode(values, settings, raw)?;
        self.write_registers(slave, address, raw).await
    }

    /// [`Client::persist`].
    pub(crate) async fn persist(&mut self, slave: u8, id: &str) -> Result<(), Error> {
        let command = self.core.command(id)?;
        let retries = match command.kind {
            CommandKind::Persist => 0,
            CommandKind::Accept => self.core.options.retries,
        };
        for &(address, value) in command.writes {
            let value = [value];
            let request = self
                .core
                .single_write(WriteTarget::Addresses, address, &value);
            self.transact(slave, request, &mut [], Purpose::Command, retries)
                .await?;
        }
        Ok(())
    }
}

/// A blocking Modbus client for drives described by a [`Profile`].
pub struct Client<T: Transport> {
    transport: T,
    core: Core,
}

impl<T: Transport> Client<T> {
    /// A client for a drive with `profile` over `transport`, with the drive's timing
    /// ([`ClientOptions::for_link`]: on a link to its serial side the manual's request gap and
    /// frame gap between requests, and its response time added to the 1 s timeout). A client
    /// that ignores the drive's timing is an explicit choice:
    /// `Client::with_options(transport, profile, ClientOptions::generic())`.
    pub fn new(transport: T, profile: &'static Profile) -> Client<T> {
        let options = ClientOptions::for_link(profile, transport.kind());
        Self::with_options(transport, profile, options)
    }

    /// A client with explicit options.
    pub fn with_options(
        transport: T,
        profile: &'static Profile,
        options: ClientOptions,
    ) -> Client<T> {
        let kind = transport.kind();
        Client {
            transport,
            core: Core::new(profile, kind, options),
        }
    }

    /// The drive's profile.
    pub fn profile(&self) -> &'static Profile {
        self.core.profile
    }

    /// The options in force.
    pub fn options(&self) -> &ClientOptions {
        &self.core.options
    }

    /// Talks to another drive on the same link from now on (several drives on one RS-485 line
    /// or behind one gateway, each with its own map): its `profile` (functions, limits, write
    /// gate, commands, slave range) and `options` (its timing:
    /// [`ClientOptions::for_link`]`(profile, kind)`). What belongs to the link is kept: the end
    /// of the last transaction, so the next request still waits the request gap after the
    /// last reply on the line whichever drive sent it; a late reply still expected; the
    /// transaction counter; and the EEPROM budget, counted for the whole link (fewer writes,
    /// never more, than per drive).
    pub fn switch_drive(&mut self, profile: &'static Profile, options: ClientOptions) {
        self.core.profile = profile;
        self.core.options = options;
    }

    /// The transport.
    pub fn transport(&mut self) -> &mut T {
        &mut self.transport
    }

    /// Gives the transport back.
    pub fn into_transport(self) -> T {
        self.transport
    }

    /// The EEPROM write budget and count.
    pub fn eeprom(&self) -> &PersistBudget {
        self.core.budget()
    }

    /// What arrived during the last transaction but was not its answer.
    pub fn discarded(&self) -> Discarded {
        self.core.rx.discarded()
    }

    /// Connections re-established after the peer closed or reset them
    /// ([`ClientOptions::reconnect`]).
    pub fn reconnects(&self) -> u32 {
        self.core.reconnects()
    }

    /// The wait for silence before the last call's request, if it needed one: after an
    /// attempt on an RTU-framed link timed out or met a frame that was not its answer, the
    /// next attempt or call first waits until the line has been silent for the reply timeout,
    /// so that a late reply is never taken for another request's answer. `None` when no such
    /// attempt preceded the last call (a wait already over when the call came reports 0 ms).
    pub fn settled(&self) -> Option<Settled> {
        self.core.settled()
    }

    /// The link and the protocol state, for one call.
    pub(crate) fn session(&mut self) -> Session<'_, Blocking<'_, T>> {
        Session {
            wire: Blocking(&mut self.transport),
            core: &mut self.core,
        }
    }

    /// Reads consecutive holding registers (03h) from communication address `address` into
    /// `out`; the quantity is `out.len()`.
    pub fn read_holding(&mut self, slave: u8, address: u16, out: &mut [u16]) -> Result<(), Error> {
        block_on(self.session().read_holding(slave, address, out))
    }

    /// Reads consecutive input registers (04h).
    pub fn read_input(&mut self, slave: u8, address: u16, out: &mut [u16]) -> Result<(), Error> {
        block_on(self.session().read_input(slave, address, out))
    }

    /// Reads `out.len()` consecutive items of `table` in one request: registers' words (03h,
    /// 04h), or coils' and discrete inputs' states as 1 (on) and 0 (off) (01h, 02h) — the raw
    /// values a register's plan decodes. At most the drive's `max_read` registers or
    /// `max_read_bits` states.
    pub fn read_table(
        &mut self,
        slave: u8,
        table: Table,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), Error> {
        block_on(self.session().read_table(slave, table, address, out))
    }

    /// Reads consecutive coils (01h) from communication address `address` into `out`, in as
    /// few requests as the drive's `max_read_bits` allows.
    pub fn read_coils(&mut self, slave: u8, address: u16, out: &mut [bool]) -> Result<(), Error> {
        block_on(self.session().read_bits(slave, Table::Coil, address, out))
    }

    /// Reads consecutive discrete inputs (02h), as [`Client::read_coils`].
    pub fn read_discrete_inputs(
        &mut self,
        slave: u8,
        address: u16,
        out: &mut [bool],
    ) -> Result<(), Error> {
        block_on(
            self.session()
                .read_bits(slave, Table::DiscreteInput, address, out),
        )
    }

    /// Writes one coil by communication address: 05h with FF00h (on) or 0000h (off), or 0Fh
    /// with one coil where the drive lacks 05h or the coil accepts only 0Fh. Slave 0
    /// broadcasts. The address must hold a writable coil of the profile's write table on this
    /// link ([`gate::check_coils`]).
    pub fn write_coil(&mut self, slave: u8, address: u16, value: bool) -> Result<(), Error> {
        block_on(
            self.session()
                .write_coil(slave, WriteTarget::Addresses, address, value),
        )
    }

    /// Writes consecutive coils (0Fh) from communication address `address`, in one request
    /// (at most the drive's `max_write_bits`); every address must hold a writable coil.
    pub fn write_coils(&mut self, slave: u8, address: u16, values: &[bool]) -> Result<(), Error> {
        block_on(self.session().write_coils(slave, address, values))
    }

    /// Writes one register by communication address (06h, or 10h where the drive lacks 06h or
    /// the register there accepts only 10h: its map's `function_codes`).
    /// Slave 0 broadcasts. The address must hold a writable register of the profile's write
    /// table that allows `value` on this link ([`gate`]).
    pub fn write_register(&mut self, slave: u8, address: u16, value: u16) -> Result<(), Error> {
        block_on(self.session().write_register(slave, address, value))
    }

    /// Writes the raw value of the register `rule` describes at `address` (its address under
    /// the settings in force), through the write gate: for tools that interpret a map at run
    /// time. Applications use [`write`](Self::write), which encodes and finds the rule itself.
    /// A word goes out with 06h (10h where the drive lacks 06h); a 32-bit pair as its two words
    /// in the map's order in one 10h request, so the drive never holds half a value.
    pub fn write_rule(
        &mut self,
        slave: u8,
        rule: &WriteRule,
        address: u16,
        raw: u32,
    ) -> Result<(), Error> {
        block_on(self.session().write_rule(slave, rule, address, raw))
    }

    /// Writes consecutive registers (10h). Slave 0 broadcasts. Refused, not split, when a
    /// register it covers does not accept 10h ([`Refusal::FunctionNotAccepted`]; see
    /// [`gate`]).
    pub fn write_registers(
        &mut self,
        slave: u8,
        address: u16,
        values: &[u16],
    ) -> Result<(), Error> {
        block_on(self.session().write_registers(slave, address, values))
    }

    /// Loop-back test (08h, sub-function 0000h): the drive must return `data`.
    pub fn loop_back(&mut self, slave: u8, data: u16) -> Result<(), Error> {
        block_on(self.session().loop_back(slave, data))
    }

    /// Reads the parameters the drive's conversions depend on (`S::DEPENDENCIES`: scale
    /// selectors such as V7 n152, reference quantities such as TDS-V8 Cn-02) and records them in
    /// `settings`, one holding register at a time.
    pub fn load_settings<S: DriveSettings>(
        &mut self,
        slave: u8,
        settings: &mut S,
    ) -> Result<(), Error> {
        block_on(self.session().load_settings::<S>(slave, settings))
    }

    /// Reads a register as its typed value.
    pub fn read<R: Readable>(
        &mut self,
        slave: u8,
        settings: &R::Settings,
    ) -> Result<R::Value, Error> {
        block_on(self.session().read::<R>(slave, settings))
    }

    /// Writes a typed value. The value is range-checked first; nothing out of range is sent.
    ///
    /// A register whose drive executes a value only when it differs from the previous write
    /// ([`Writable::REPEAT_NEEDS_CHANGE`], the ACN's password registers) is written twice: its
    /// intermediate value, then `value` ([`write_changed`](Self::write_changed)). The client
    /// cannot know what was written last (another master, a power cycle), so it always changes
    /// the word first: otherwise writing the same command twice would be silently ignored.
    pub fn write<R: Writable>(
        &mut self,
        slave: u8,
        value: &R::Input,
        settings: &R::Settings,
    ) -> Result<(), Error> {
        block_on(self.session().write::<R>(slave, value, settings))
    }

    /// [`write`](Self::write) with a choice for a number between two steps of the register:
    /// `write` refuses 35.75 Hz to a register that counts 0.1 Hz
    /// ([`ValueError::NotAStep`](drivemap_core::scale::ValueError::NotAStep), naming 35.7 and 35.8);
    /// `Rounding::Nearest` sends 35.8. Every limit is checked on the value given.
    pub fn write_rounded<R: Writable>(
        &mut self,
        slave: u8,
        value: &R::Input,
        settings: &R::Settings,
        rounding: drivemap_core::scale::Rounding,
    ) -> Result<(), Error> {
        block_on(
            self.session()
                .write_rounded::<R>(slave, value, settings, rounding),
        )
    }

    /// Writes `raw` to a register whose drive executes a value only when it differs from the
    /// previous write: `between` first (unless `raw` is `between` itself, which the drive then
    /// takes as it takes any other value), then `raw`, each through the write gate with `rule`.
    /// The manual's example: "if you want to enter 244 twice, enter it in the following order:
    /// 244 > 0 > 244" (`004_c5cbf92472673495.txt:1113`). Nothing is sent when the gate refuses
    /// either word.
    pub fn write_changed(
        &mut self,
        slave: u8,
        rule: &WriteRule,
        address: u16,
        between: u32,
        raw: u32,
    ) -> Result<(), Error> {
        block_on(
            self.session()
                .write_changed(slave, rule, address, between, raw),
        )
    }

    /// Read-modify-write: reads the register, lets `change` edit the typed value, writes it back.
    /// Returns the value written. Not for a register whose read meaning differs from its write
    /// form ([`ReadWriteAs`](drivemap_core::register::ReadWriteAs)): what it reads cannot be written.
    pub fn update<
        R: Readable + Writable<Input = <R as drivemap_core::register::Register>::Value>,
    >(
        &mut self,
        slave: u8,
        settings: &R::Settings,
        change: impl FnOnce(&mut R::Value),
    ) -> Result<R::Value, Error> {
        block_on(self.session().update::<R>(slave, settings, change))
    }

    /// Read-modify-write of a bit-field register: sets the bits of `set` and clears those of
    /// `clear`, keeping the other fields as read. Reserved bits are refused in the masks and
    /// written as 0.
    pub fn modify_bits<R>(
        &mut self,
        slave: u8,
        settings: &R::Settings,
        set: u16,
        clear: u16,
    ) -> Result<R::Value, Error>
    where
        R: BitRegister
            + Readable
            + Writable<Input = <R as drivemap_core::register::Register>::Value>,
        R::Value: Bits,
    {
        block_on(self.session().modify_bits::<R>(slave, settings, set, clear))
    }

    /// Reads consecutive registers in one request: `client.read_many::<(A, B, C)>(1, &s)`.
    pub fn read_many<S: ReadSet>(
        &mut self,
        slave: u8,
        settings: &S::Settings,
    ) -> Result<S::Values, Error> {
        block_on(self.session().read_many::<S>(slave, settings))
    }

    /// Writes consecutive registers in one 10h request, each value range-checked first.
    pub fn write_many<S: WriteSet>(
        &mut self,
        slave: u8,
        values: &S::Values,
        settings: &S::Settings,
    ) -> Result<(), Error> {
        block_on(self.session().write_many::<S>(slave, values, settings))
    }

    /// Runs a command of the profile (ENTER, ACCEPT, save parameters) by its map id. A command
    /// that stores to EEPROM ([`CommandKind::Persist`]) takes one write from the hourly budget,
    /// or is refused when the budget is spent; it is never retried, since a lost reply may
    /// follow a completed write. Plain writes to these registers are refused.
    pub fn persist(&mut self, slave: u8, id: &str) -> Result<(), Error> {
        block_on(self.session().persist(slave, id))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus_time::tests::v7;
    use drivemap_core::profile::Parity;

    #[test]
    fn options_for_a_profile_keep_its_timing() {
        let o = ClientOptions::for_profile(&v7());
        // 24 bits at 9600 baud (2.5 ms) + 10 ms after each reply.
        assert_eq!(o.request_gap, Duration::from_micros(12_500));
        // The drive answers after 24 bits + n156's default 10 ms: the timeout allows for it.
        assert_eq!(
            o.timeout,
            Duration::from_secs(1) + Duration::from_micros(12_500)
        );
        assert_eq!(o.retries, ClientOptions::default().retries);
        // At 1200 baud the bit times are eight times longer.
        let slow = ClientOptions::for_line(&v7(), SerialConfig::new(1200));
        assert_eq!(slow.request_gap, Duration::from_millis(30));
        // A manual that prints no wait: the frame gap, 3.5 characters (8E1: 11 bits).
        let g = ClientOptions::for_line(
            &Profile::GENERIC,
            SerialConfig::new(9600).parity(Parity::Even),
        );
        assert_eq!(g.request_gap, Duration::from_nanos(4_010_417));
        // A frame gap stated as at least 10 ms: the request gap and the timeout keep it.
        let mut ten = Profile::GENERIC;
        ten.timing.frame_gap_us = Some(10_000);
        let t = ClientOptions::for_profile(&ten);
        assert_eq!(t.request_gap, Duration::from_millis(10));
        assert_eq!(
            t.timeout,
            ClientOptions::default().timeout + Duration::from_millis(10)
        );
    }
}
