//! Errors of the clients. Each names what was sent and what was waited for.

use std::fmt;
use std::io;
use std::time::Duration;

use crate::exception::Exception;
use crate::pdu::function;
use crate::reply::Discarded;
use drivemap_core::scale::ValueError;

/// A request as the user asked for it: the manual's communication address and, where the
/// profile maps it elsewhere, the PDU address that went on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct Sent {
    /// Slave address (0: broadcast).
    pub slave: u8,
    /// Function code.
    pub function: u8,
    /// Communication address as printed in the manual.
    pub address: Option<u16>,
    /// Address in the PDU after the profile's per-transport offset.
    pub pdu_address: Option<u16>,
    /// Registers read or written.
    pub quantity: usize,
    /// Value written (06h) or looped back (08h).
    pub value: Option<u16>,
}

impl fmt::Display for Sent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.function {
            function::READ_HOLDING => "read",
            function::READ_INPUT => "read of input",
            function::READ_COILS => "read of coil",
            function::READ_DISCRETE_INPUTS => "read of discrete input",
            function::WRITE_SINGLE | function::WRITE_MULTIPLE => "write",
            function::WRITE_COIL | function::WRITE_COILS => "write of coil",
            function::LOOP_BACK => "loop-back",
            _ => "request",
        };
        write!(f, "{:02X}h {what}", self.function)?;
        if let Some(a) = self.address {
            write!(f, " of {a:04X}h")?;
            if let Some(p) = self.pdu_address.filter(|&p| p != a) {
                write!(f, " (PDU {p:04X}h)")?;
            }
        }
        match (self.function, self.value) {
            (function::LOOP_BACK, Some(v)) => write!(f, " of {v:04X}h"),
            (_, Some(v)) => write!(f, " = {v:04X}h"),
            _ => write!(f, " x{}", self.quantity),
        }
    }
}

/// Why a request was not sent at all.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Refusal {
    /// The drive does not implement the function.
    #[error("{drive} does not implement function {function:02X}h")]
    UnsupportedFunction {
        /// The drive's map id.
        drive: &'static str,
        /// The function code asked for.
        function: u8,
    },
    /// More registers than the drive accepts in one request.
    #[error(
        "{drive} accepts at most {max} registers per {function:02X}h request; {quantity} asked"
    )]
    TooManyRegisters {
        /// The drive's map id.
        drive: &'static str,
        /// The function code.
        function: u8,
        /// The registers asked for.
        quantity: usize,
        /// The most the drive accepts in one request.
        max: u16,
    },
    /// More coils or discrete inputs than the drive accepts in one request (01h, 02h, 0Fh).
    #[error(
        "{drive} accepts at most {max} coils or inputs per {function:02X}h request; {quantity} asked"
    )]
    TooManyBits {
        /// The drive's map id.
        drive: &'static str,
        /// The function code.
        function: u8,
        /// The coils or inputs asked for.
        quantity: usize,
        /// The most the drive accepts in one request.
        max: u16,
    },
    /// A write of one table's register sent as another table's: a coil's rule with a register
    /// function, or a register's with a coil function (coil 0001h and holding register 0001h
    /// are two things).
    #[error(
        "{register} is a {}, so it is not written as a {}",
        table.item(),
        requested.item()
    )]
    WrongTable {
        /// The register's id.
        register: &'static str,
        /// The table it is in.
        table: drivemap_core::register::Table,
        /// The table the request writes.
        requested: drivemap_core::register::Table,
    },
    /// A raw coil write (05h/0Fh) to an address where the map has no writable coil on this
    /// link.
    #[error(
        "{drive} has no writable coil at {address:04X}h on {transport:?}{}",
        if *broadcast { " for a broadcast" } else { "" }
    )]
    NoWritableCoil {
        /// The drive's map id.
        drive: &'static str,
        /// The communication address written.
        address: u16,
        /// The client's transport kind.
        transport: drivemap_core::profile::TransportKind,
        /// Whether the write is a broadcast (slave 0).
        broadcast: bool,
    },
    /// A request for zero registers.
    #[error("{function:02X}h request for no registers")]
    NoRegisters {
        /// The function code.
        function: u8,
    },
    /// A slave address outside the drive's range.
    #[error("slave address {slave} is outside {drive}'s range {min} ..= {max} (0 is broadcast)")]
    Slave {
        /// The drive's map id.
        drive: &'static str,
        /// The slave address given.
        slave: u8,
        /// The lowest address of the drive's range.
        min: u8,
        /// The highest address of the drive's range.
        max: u8,
    },
    /// Broadcast cannot read: nobody replies to slave 0.
    #[error("broadcast (slave 0) gets no reply, so it cannot read ({function:02X}h)")]
    BroadcastRead {
        /// The function code.
        function: u8,
    },
    /// Broadcast cannot loop back: nobody replies to slave 0.
    #[error("broadcast (slave 0) gets no reply, so loop-back (08h) is meaningless")]
    BroadcastLoopBack,
    /// The drive has no broadcast, or not for this function.
    #[error("{drive} does not execute function {function:02X}h as a broadcast")]
    BroadcastFunction {
        /// The drive's map id.
        drive: &'static str,
        /// The function code.
        function: u8,
    },
    /// A serial line set to a character format the drive's map does not list (`serial.formats`:
    /// the ACN offers 8N1, 8N2, 8E1 and 8O1 only).
    #[error("{0}")]
    SerialFormat(drivemap_core::profile::FormatNotListed),
    /// The drive has a broadcast, but its manual does not print the rules (which functions,
    /// which registers): nothing is broadcast, since no one can say what the drives would do.
    #[error(
        "{drive} has a broadcast whose rules its manual does not print ({why}): drivemap sends it no broadcast; address each slave instead"
    )]
    BroadcastRulesNotPrinted {
        /// The drive's map id.
        drive: &'static str,
        /// Why the manual prints none, as the map says.
        why: &'static str,
    },
    /// The drive does not accept this register in a broadcast.
    #[error("{drive} does not accept register {address:04X}h in a broadcast")]
    BroadcastAddress {
        /// The drive's map id.
        drive: &'static str,
        /// The communication address.
        address: u16,
    },
    /// The address cannot be mapped to a PDU address on this transport.
    #[error("communication address {address:04X}h with offset {offset} is outside 0000h ..= FFFFh")]
    AddressMapping {
        /// The communication address.
        address: u16,
        /// The profile's offset for the transport.
        offset: i32,
    },
    /// The registers would run past FFFFh.
    #[error("{quantity} registers from {address:04X}h run past FFFFh")]
    AddressOverflow {
        /// The first address.
        address: u16,
        /// The number of registers.
        quantity: usize,
    },
    /// A plain write to a command register (ENTER, ACCEPT, save) that must go through
    /// [`Client::persist`](crate::client::Client::persist).
    #[error(
        "{address:04X}h is the command register of {command:?} ({name}); use persist(slave, {command:?}), which counts EEPROM writes"
    )]
    CommandRegister {
        /// The communication address.
        address: u16,
        /// The command's id in the map.
        command: &'static str,
        /// The command's name as printed in the manual.
        name: &'static str,
    },
    /// The profile has no command of that id.
    #[error("{drive} has no command {id:?}")]
    UnknownCommand {
        /// The drive's map id.
        drive: &'static str,
        /// The id asked for.
        id: String,
    },
    /// The EEPROM write budget for the last hour is spent.
    #[error(
        "EEPROM write budget spent: {used} of {budget} writes in the last hour; the next is allowed in {} s",
        next_in.as_secs()
    )]
    EepromBudget {
        /// EEPROM writes in the last hour.
        used: u32,
        /// EEPROM writes allowed per hour.
        budget: u32,
        /// Time until the next write is allowed.
        next_in: Duration,
    },
    /// Registers requested together are not consecutive or not in one table.
    #[error(
        "{register} is at {got:04X}h, not {expected:04X}h right after {first}: they cannot be read in one request"
    )]
    NotContiguous {
        /// The first register of the set.
        first: &'static str,
        /// The register out of place.
        register: &'static str,
        /// The address it would need.
        expected: u16,
        /// The address it has.
        got: u16,
    },
    /// The register does not exist on the client's transport (the map's `transports`).
    #[error(
        "{register} does not exist on {transport:?}: the map lists it for other transports only"
    )]
    NotOnTransport {
        /// The register's id.
        register: &'static str,
        /// The client's transport kind.
        transport: drivemap_core::profile::TransportKind,
    },
    /// The drive's map gives no register or field for a role of the drive trait (on this link).
    #[error("{drive}'s map gives no {what} for `{role}`{}", match transport { Some(t) => format!(" usable on {t:?}"), None => String::new() })]
    NoRole {
        /// The drive's map id.
        drive: &'static str,
        /// The role's id (or the command profile path's).
        role: &'static str,
        /// What was looked for: "register", "field", "way to run in reverse".
        what: &'static str,
        /// Set when the map gives the role on other transports only.
        transport: Option<drivemap_core::profile::TransportKind>,
    },
    /// Two roles that are one register on this drive (the map's `shared_with`), asked for
    /// different values: whichever is written last would hold for both.
    #[error(
        "{drive}: {role} and {other} are one register ({register}) on this drive, so they cannot be {asked}; give one value for both"
    )]
    SharedRegister {
        /// The drive's map id.
        drive: &'static str,
        /// The first role's id.
        role: &'static str,
        /// The other role's id.
        other: &'static str,
        /// The register's id.
        register: &'static str,
        /// The two values asked for, with their unit ("2 s and 1 s").
        asked: String,
    },
    /// The drive takes run commands (or its frequency reference) from somewhere other than the
    /// network, as its source parameter says: a command sent now would be accepted on the wire
    /// and ignored by the drive, so it is not sent.
    #[error("{drive}: the drive takes {what} from {now}; {fix}")]
    NotNetworkSource {
        /// The drive's map id.
        drive: &'static str,
        /// "run commands" or "the frequency reference".
        what: &'static str,
        /// Where it takes them from, with the setting read: "the terminal strip (n003 = 1)".
        now: String,
        /// What to set: "set n003 = 2 for the network".
        fix: String,
    },
    /// A number role the map puts in a field of a register (part of a word) that cannot be
    /// written safely by reading the word and writing it back.
    #[error("{drive}: `{role}` is a field of {register} and is not written: {why}")]
    FieldNotWritable {
        /// The drive's map id.
        drive: &'static str,
        /// The role's id.
        role: &'static str,
        /// The id of the register that holds the field.
        register: &'static str,
        /// Why a read-modify-write is not safe there.
        why: &'static str,
    },
    /// A drive's plan used with a client made for another drive's profile.
    #[error(
        "the client speaks to {client}, not to {drive}: build the client with {drive}'s profile"
    )]
    OtherDrive {
        /// The drive id of the client's profile.
        client: &'static str,
        /// The drive id of the plan.
        drive: &'static str,
    },
    /// An external quantity the map does not have, or one not supplied.
    #[error("{drive} has no external quantity {name}")]
    UnknownExternal {
        /// The drive's map id.
        drive: &'static str,
        /// The name given.
        name: String,
    },
    /// An external quantity the application has not supplied.
    #[error(
        "{drive}: the external quantity {name} is not set; the application supplies it (Vfd::connect's externals)"
    )]
    ExternalNotSet {
        /// The drive's map id.
        drive: &'static str,
        /// The external quantity's name.
        name: &'static str,
    },
    /// Bits outside a bit-field register's fields.
    #[error("{register}: bits {bits:04X}h are reserved")]
    ReservedBits {
        /// The register's id.
        register: &'static str,
        /// The reserved bits asked for.
        bits: u16,
    },
    /// A function the register at `address` does not accept (its map's `function_codes`): the
    /// drive would answer it with an exception.
    #[error(
        "{register} at {address:04X}h accepts only {} (`{citation}`): a {function:02X}h request there would be refused by the drive; write each register with a function it accepts",
        function_list(accepted)
    )]
    FunctionNotAccepted {
        /// The register's id.
        register: &'static str,
        /// The register's communication address.
        address: u16,
        /// The function code of the request.
        function: u8,
        /// The function codes the register accepts.
        accepted: &'static [u8],
        /// `file:line` of the manual's statement.
        citation: &'static str,
    },
    /// A write to a register the manual makes read-only.
    #[error("{register} is read-only")]
    ReadOnly {
        /// The register's id.
        register: &'static str,
    },
    /// A read of a register or indexed entry the manual makes write-only.
    #[error("{register} is write-only")]
    WriteOnly {
        /// The register's id.
        register: &'static str,
    },
    /// A broadcast-only register addressed to one slave.
    #[error("{register} is a broadcast register: it is written to slave 0 only")]
    BroadcastOnly {
        /// The register's id.
        register: &'static str,
    },
    /// A register a broadcast may not write, addressed to slave 0.
    #[error(
        "{drive} does not accept {register} in a broadcast: slave 0 addresses the broadcast registers, which have their own layout"
    )]
    NotBroadcast {
        /// The drive's map id.
        drive: &'static str,
        /// The register's id.
        register: &'static str,
    },
    /// A write that covers one word of a 32-bit pair without the other: the drive would take
    /// half a value.
    #[error(
        "{register} is a 32-bit value in two registers: write both words in one request, from its first address (not from {address:04X}h)"
    )]
    SplitPair {
        /// The register's id.
        register: &'static str,
        /// The address the write starts at.
        address: u16,
    },
    /// A write to a string (text in registers): text is read-only (`string:` in the map).
    #[error("{register} holds text, which is read-only: it is not written")]
    Text {
        /// The register's id.
        register: &'static str,
    },
    /// A register written at an address it does not occupy.
    #[error("{register} is not at {address:04X}h")]
    NotAtAddress {
        /// The register's id.
        register: &'static str,
        /// The address written.
        address: u16,
    },
    /// A raw write to an address where the map has no writable register on this link.
    #[error(
        "{drive} has no writable register at {address:04X}h on {transport:?}{}",
        if *broadcast { " in the broadcast space" } else { "" }
    )]
    NoWritableRegister {
        /// The drive's map id.
        drive: &'static str,
        /// The communication address written.
        address: u16,
        /// The client's transport kind.
        transport: drivemap_core::profile::TransportKind,
        /// Whether the write is a broadcast (slave 0).
        broadcast: bool,
    },
    /// A word outside every range the map gives the register.
    #[error("{register}: raw value {raw} is outside {min} ..= {max}, the map's range for it")]
    RawOutOfRange {
        /// The register's id.
        register: &'static str,
        /// The raw value.
        raw: i64,
        /// The lowest raw value of the map's range.
        min: i64,
        /// The highest raw value of the map's range.
        max: i64,
    },
    /// The register's address depends on a setting that is not known (GPD 515 o2-09 not
    /// read): nothing is sent to a guessed address.
    #[error("{0}")]
    AddressUnknown(#[from] drivemap_core::plan::AddressUnknown),
}

impl From<drivemap_core::plan::AddressUnknown> for Error {
    fn from(e: drivemap_core::plan::AddressUnknown) -> Error {
        Error::Refused(e.into())
    }
}

/// An error of a client call.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No acceptable reply arrived in time, on any attempt.
    #[error(
        "no reply from slave {} to {sent} within {} ms{}{}{}",
        sent.slave,
        waited.as_millis(),
        if *attempts > 1 { format!(" ({attempts} attempts)") } else { String::new() },
        if discarded.is_empty() { String::new() } else { format!("; {discarded}") },
        match settle { Some(q) => format!("; the next request to slave {} waits until the line has been silent for {} ms, so that a late reply is not taken for its answer", sent.slave, q.as_millis()), None => String::new() }
    )]
    Timeout {
        /// The request.
        sent: Sent,
        /// Time waited on each attempt.
        waited: Duration,
        /// Attempts made.
        attempts: u8,
        /// What arrived but was not the answer, on the last attempt.
        discarded: Discarded,
        /// On an RTU-framed link (no transaction id): the silence the next request to the same
        /// slave (or a broadcast) waits for first, counted from the end of this attempt, so that
        /// a late reply to this one is not taken for its answer.
        settle: Option<Duration>,
    },
    /// On an RTU-framed link after an unanswered request, the line did not fall silent long
    /// enough to be sure no late reply was still on its way; the request was not sent.
    #[error(
        "{sent} to slave {}: held back because the line never fell silent: after an unanswered request it must be silent for {} ms before the next request, so that a late reply is not taken for its answer, but bytes kept arriving for {} ms ({bytes} byte(s) discarded)",
        sent.slave,
        quiet.as_millis(),
        waited.as_millis()
    )]
    Unsettled {
        /// The request.
        sent: Sent,
        /// The silence waited for.
        quiet: Duration,
        /// Time waited.
        waited: Duration,
        /// Bytes that arrived meanwhile.
        bytes: usize,
    },
    /// The drive answered with an exception.
    #[error("slave {} answered {sent} with {exception}", sent.slave)]
    Exception {
        /// The request.
        sent: Sent,
        /// The drive's exception.
        exception: Exception,
    },
    /// The link failed.
    #[error("{sent} to slave {}: {source}", sent.slave)]
    Io {
        /// The request.
        sent: Sent,
        #[source]
        /// The link's error.
        source: io::Error,
    },
    /// The link failed outside a request (connecting, reconnecting, setting up a line): the
    /// `?` of an [`io::Error`] in a function that returns this error.
    #[error("the link failed: {0}")]
    Link(#[from] io::Error),
    /// The request was refused before anything was sent.
    #[error("refused before sending: {0}")]
    Refused(#[from] Refusal),
    /// A path of the drive's command profile (run, stop, coast, quick stop, fault reset) did
    /// not reach its end: the status word showed no state of the profile, no transition of the
    /// path leaves the state the drive is in, the drive did not show the state a transition
    /// leads to within its time limit, or it tripped on the way. Names the state it is in.
    #[error("{drive}: {path} did not complete: {why}; the drive is in state {state}")]
    StateMachine {
        /// The drive's map id.
        drive: &'static str,
        /// The path (`run`, `stop`, `coast`, `quick_stop`, `reset_fault`).
        path: &'static str,
        /// The state the status word showed last (`switch_on_disabled`), or the word itself
        /// where it showed none (`no state (status word 0x0012)`).
        state: String,
        /// What went wrong.
        why: String,
    },
    /// A value could not be converted (out of range before writing, or a missing setting).
    #[error(transparent)]
    Value(#[from] ValueError),
    /// An indexed access ([`crate::indexed`]) found the index register showing another index
    /// than the one just written (another master or the keypad selected another entry): the
    /// value was not attributed to the entry, and nothing was written to it.
    #[error(
        "{register}: {index_register} shows index {shown}, not {selected} as just written (another master or the keypad selected another entry); the value was not taken as entry {selected}'s"
    )]
    IndexChanged {
        /// The value register.
        register: &'static str,
        /// The index register.
        index_register: &'static str,
        /// The index written.
        selected: u16,
        /// The index the drive showed.
        shown: u16,
    },
    /// More than [`MAX_UNANSWERED_BYTES`](crate::client::MAX_UNANSWERED_BYTES) arrived in one
    /// attempt without the answer among them: the peer floods the link. Not retried.
    #[error(
        "no answer from slave {} to {sent} in {bytes} byte(s) received: the peer floods the link; {discarded}",
        sent.slave
    )]
    Overrun {
        /// The request.
        sent: Sent,
        /// Bytes received in the attempt.
        bytes: usize,
        /// What was skipped.
        discarded: Discarded,
    },
}

/// `03h, 06h`.
fn function_list(codes: &[u8]) -> String {
    codes
        .iter()
        .map(|c| format!("{c:02X}h"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl Error {
    /// The exception, if the drive answered with one.
    pub fn exception(&self) -> Option<&Exception> {
        match self {
            Error::Exception { exception, .. } => Some(exception),
            _ => None,
        }
    }

    /// Whether nothing was sent.
    pub fn is_refusal(&self) -> bool {
        matches!(self, Error::Refused(_) | Error::Value(_))
    }
}

/// An [`Error`] as an [`io::Error`], for code that returns `io::Result` (a tokio task, a
/// `Read`/`Write` adapter): the kind says what happened ([`io::ErrorKind::TimedOut`] for a
/// drive that did not answer, the link's own kind for a link that failed,
/// [`io::ErrorKind::InvalidInput`] for a request refused before sending, [`io::ErrorKind::Other`]
/// for an exception), and the error itself stays the source, with its message.
impl From<Error> for io::Error {
    fn from(e: Error) -> io::Error {
        let kind = match &e {
            Error::Timeout { .. } | Error::Unsettled { .. } => io::ErrorKind::TimedOut,
            Error::Io { source, .. } | Error::Link(source) => source.kind(),
            Error::Refused(_) | Error::Value(_) => io::ErrorKind::InvalidInput,
            Error::Exception { .. }
            | Error::Overrun { .. }
            | Error::IndexChanged { .. }
            | Error::StateMachine { .. } => io::ErrorKind::Other,
        };
        io::Error::new(kind, e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timeout_names_what_was_sent_and_waited_for() {
        let e = Error::Timeout {
            sent: Sent {
                slave: 1,
                function: 3,
                address: Some(0x20),
                pdu_address: Some(0x20),
                quantity: 1,
                value: None,
            },
            waited: Duration::from_millis(200),
            attempts: 1,
            discarded: Discarded::default(),
            settle: None,
        };
        assert_eq!(
            e.to_string(),
            "no reply from slave 1 to 03h read of 0020h x1 within 200 ms"
        );
        let s = Sent {
            slave: 1,
            function: 0x10,
            address: Some(0x1103),
            pdu_address: Some(0x1102),
            quantity: 2,
            value: None,
        };
        assert_eq!(s.to_string(), "10h write of 1103h (PDU 1102h) x2");
    }

    /// The link's errors and the client's convert both ways, and keep what caused them as their
    /// source.
    #[test]
    fn io_errors_convert_both_ways_and_keep_their_source() {
        use std::error::Error as _;
        fn connect() -> Result<(), Error> {
            Err(io::Error::new(
                io::ErrorKind::ConnectionRefused,
                "port 502 closed",
            ))?;
            Ok(())
        }
        let e = connect().unwrap_err();
        assert_eq!(e.to_string(), "the link failed: port 502 closed");
        assert!(matches!(e, Error::Link(ref io) if io.kind() == io::ErrorKind::ConnectionRefused));
        let sent = Sent {
            slave: 1,
            function: 3,
            address: Some(0x20),
            pdu_address: Some(0x20),
            quantity: 1,
            value: None,
        };
        let e = Error::Io {
            sent,
            source: io::Error::new(io::ErrorKind::BrokenPipe, "pipe"),
        };
        let source = e.source().expect("the link's error is the source");
        assert_eq!(source.to_string(), "pipe");
        fn in_a_task(e: Error) -> io::Result<()> {
            Err(e)?;
            Ok(())
        }
        let io = in_a_task(e).unwrap_err();
        assert_eq!(io.kind(), io::ErrorKind::BrokenPipe);
        assert_eq!(io.to_string(), "03h read of 0020h x1 to slave 1: pipe");
        let inner = io.get_ref().expect("the client's error inside");
        assert!(inner.downcast_ref::<Error>().is_some());
        let timeout = Error::Timeout {
            sent,
            waited: Duration::from_millis(5),
            attempts: 1,
            discarded: Discarded::default(),
            settle: None,
        };
        assert_eq!(io::Error::from(timeout).kind(), io::ErrorKind::TimedOut);
        let refused: io::Error = Error::Refused(Refusal::BroadcastLoopBack).into();
        assert_eq!(refused.kind(), io::ErrorKind::InvalidInput);
        let refusal = Error::Refused(Refusal::BroadcastLoopBack);
        assert!(
            refusal
                .source()
                .is_some_and(|s| s.downcast_ref::<Refusal>().is_some())
        );
    }
}
