//! Protocol facts a drive's manual does not print.
//!
//! A map may say of any protocol fact — the registers per request, the slave-address range, the
//! serial settings, the exception list, the timing — that its manual prints none, with the
//! reason (`max_write: {unknown: "<why>"}` in the map). The generated [`Profile`] then lists the
//! fact in [`Profile::not_printed`] and carries the Modbus figure in its place (125 registers
//! per read, 123 per write, slaves 1-247, 3.5 characters between frames), so that a tool using
//! it can say which figures it relies on without the manual's word ([`ProtocolFact::fallback`]).
//!
//! [`Profile`]: crate::profile::Profile
//! [`Profile::not_printed`]: crate::profile::Profile::not_printed

/// The largest read the Modbus application protocol allows (03h/04h): 125 registers.
pub const MODBUS_MAX_READ: u16 = 125;
/// The largest write the Modbus application protocol allows (10h): 123 registers.
pub const MODBUS_MAX_WRITE: u16 = 123;
/// The most coils or discrete inputs one read may take (01h/02h): 2000.
pub const MODBUS_MAX_READ_BITS: u16 = 2000;
/// The most coils one write may take (0Fh): 1968.
pub const MODBUS_MAX_WRITE_BITS: u16 = 1968;
/// The lowest unicast slave address of the Modbus serial line.
pub const MODBUS_SLAVE_MIN: u8 = 1;
/// The highest unicast slave address of the Modbus serial line.
pub const MODBUS_SLAVE_MAX: u8 = 247;

/// A protocol fact a map can mark not printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[non_exhaustive]
pub enum ProtocolFact {
    /// `function_codes`: the functions the drive implements.
    FunctionCodes,
    /// `max_read`: registers per read.
    MaxRead,
    /// `max_write`: registers per write.
    MaxWrite,
    /// `max_read_bits`: coils or discrete inputs per read (01h/02h).
    MaxReadBits,
    /// `max_write_bits`: coils per write (0Fh).
    MaxWriteBits,
    /// `slave_address`: the range of slave addresses.
    SlaveAddress,
    /// `broadcast`: the rules of a broadcast (slave 0).
    Broadcast,
    /// `exceptions`: the drive's exception codes.
    Exceptions,
    /// `serial`: baud rates, parities, character format.
    Serial,
    /// `timing`: every timing figure at once.
    Timing,
    /// `timing.frame_gap`: the silence between frames.
    FrameGap,
    /// `timing.inter_char_timeout`: the longest gap inside a frame.
    InterCharTimeout,
    /// `timing.response_time`: how long the drive takes to answer.
    ResponseTime,
    /// `timing.request_gap`: the least time after a reply before the next request.
    RequestGap,
}

impl ProtocolFact {
    /// Every fact, in the order maps and reports list them.
    pub const ALL: [ProtocolFact; 14] = [
        ProtocolFact::FunctionCodes,
        ProtocolFact::MaxRead,
        ProtocolFact::MaxWrite,
        ProtocolFact::MaxReadBits,
        ProtocolFact::MaxWriteBits,
        ProtocolFact::SlaveAddress,
        ProtocolFact::Broadcast,
        ProtocolFact::Exceptions,
        ProtocolFact::Serial,
        ProtocolFact::Timing,
        ProtocolFact::FrameGap,
        ProtocolFact::InterCharTimeout,
        ProtocolFact::ResponseTime,
        ProtocolFact::RequestGap,
    ];

    /// The key of the fact under `protocol:` in a map (`max_write`, `timing.frame_gap`).
    pub const fn key(self) -> &'static str {
        match self {
            ProtocolFact::FunctionCodes => "function_codes",
            ProtocolFact::MaxRead => "max_read",
            ProtocolFact::MaxWrite => "max_write",
            ProtocolFact::MaxReadBits => "max_read_bits",
            ProtocolFact::MaxWriteBits => "max_write_bits",
            ProtocolFact::SlaveAddress => "slave_address",
            ProtocolFact::Broadcast => "broadcast",
            ProtocolFact::Exceptions => "exceptions",
            ProtocolFact::Serial => "serial",
            ProtocolFact::Timing => "timing",
            ProtocolFact::FrameGap => "timing.frame_gap",
            ProtocolFact::InterCharTimeout => "timing.inter_char_timeout",
            ProtocolFact::ResponseTime => "timing.response_time",
            ProtocolFact::RequestGap => "timing.request_gap",
        }
    }

    /// The fact named from its key, if it is one.
    pub fn from_key(key: &str) -> Option<ProtocolFact> {
        ProtocolFact::ALL.into_iter().find(|f| f.key() == key)
    }

    /// The fact in words (`registers per write`).
    pub const fn name(self) -> &'static str {
        match self {
            ProtocolFact::FunctionCodes => "function codes",
            ProtocolFact::MaxRead => "registers per read",
            ProtocolFact::MaxWrite => "registers per write",
            ProtocolFact::MaxReadBits => "coils or discrete inputs per read",
            ProtocolFact::MaxWriteBits => "coils per write",
            ProtocolFact::SlaveAddress => "slave-address range",
            ProtocolFact::Broadcast => "broadcast rules",
            ProtocolFact::Exceptions => "exception codes",
            ProtocolFact::Serial => "serial settings (baud rate, parity, character format)",
            ProtocolFact::Timing => "timing",
            ProtocolFact::FrameGap => "silence between frames",
            ProtocolFact::InterCharTimeout => "inter-character timeout",
            ProtocolFact::ResponseTime => "response time",
            ProtocolFact::RequestGap => "gap before the next request",
        }
    }

    /// What the tools use in the fact's place: the Modbus figure, or what they do without one.
    pub const fn fallback(self) -> &'static str {
        match self {
            ProtocolFact::FunctionCodes => "the map's working list",
            ProtocolFact::MaxRead => "125 registers, the Modbus limit",
            ProtocolFact::MaxWrite => "123 registers, the Modbus limit",
            ProtocolFact::MaxReadBits => "2000 bits, the Modbus limit",
            ProtocolFact::MaxWriteBits => "1968 coils, the Modbus limit",
            ProtocolFact::SlaveAddress => "1-247, the Modbus unicast range",
            ProtocolFact::Broadcast => "no broadcast is sent",
            ProtocolFact::Exceptions => "the standard Modbus exception names",
            ProtocolFact::Serial => {
                "the line's own settings (default 9600 baud, no parity, 8 data bits, 1 stop bit)"
            }
            ProtocolFact::Timing => "the Modbus RTU rule: 3.5 characters between frames",
            ProtocolFact::FrameGap => "3.5 characters, the Modbus RTU rule",
            ProtocolFact::InterCharTimeout => "1.5 characters, the Modbus RTU rule",
            ProtocolFact::ResponseTime => "the client's timeout alone",
            ProtocolFact::RequestGap => "the frame gap alone",
        }
    }
}

impl core::fmt::Display for ProtocolFact {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.key())
    }
}

/// A protocol fact the drive's manual does not print, and why (the map's `unknown:`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotPrinted {
    /// The protocol fact the manual does not print.
    pub fact: ProtocolFact,
    /// Why the manual prints none, as the map says.
    pub why: &'static str,
    /// `file:line` where the manual says so (defers to another document, says "not
    /// specified"), when it does.
    pub source: Option<&'static str>,
}

/// Whether the manual prints a fact: its value with the manual's word, or why it prints none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stated<T> {
    /// The manual prints it.
    Printed(T),
    /// The manual prints none: why.
    NotPrinted(&'static str),
}

impl<T: Copy> Stated<T> {
    /// The printed value, else `fallback` (the Modbus figure the tools use instead).
    pub fn or(self, fallback: T) -> T {
        match self {
            Stated::Printed(v) => v,
            Stated::NotPrinted(_) => fallback,
        }
    }

    /// Whether the manual prints it.
    pub const fn is_printed(&self) -> bool {
        matches!(self, Stated::Printed(_))
    }
}
