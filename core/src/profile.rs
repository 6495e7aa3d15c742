//! A drive's protocol profile: what the manual says the drive accepts on the wire.
//!
//! Generated modules emit one `static PROFILE: Profile` per drive. The client consults it to
//! refuse requests the drive cannot serve (unsupported function, too many registers, broadcast to
//! a register the manual does not allow), to name the drive's own exception codes, and to map the
//! manual's communication addresses to PDU addresses per transport.

use crate::rule::WriteRule;
use crate::stated::{NotPrinted, ProtocolFact, Stated};

/// How a transport frames Modbus PDUs. Address offsets and some rules differ per kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum TransportKind {
    /// Modbus RTU on a serial line.
    Rtu,
    /// Modbus RTU frames carried over a TCP stream (a serial gateway in transparent mode).
    RtuOverTcp,
    /// Modbus TCP (MBAP header) to a drive with a Modbus TCP interface of its own.
    Tcp,
    /// Modbus TCP (MBAP header) to a Modbus TCP to RTU gateway, behind which the drive sits on
    /// a serial line: Modbus TCP framing (the gateway turns each request into an RTU frame and
    /// matches the answer to its transaction id), but the drive's RTU side — the map's RTU
    /// address offset, the registers it lists for RTU, the drive's RTU timing. A link of its
    /// own: a drive's `tcp` registers and addresses are those of a Modbus TCP interface it
    /// would have itself, never what a gateway reaches.
    TcpGateway,
    /// Modbus ASCII on a serial line: `:`, the slave address and PDU as hexadecimal
    /// characters, an LRC, CR LF (Delta's factory setting, usually 7 data bits). The drive's
    /// serial side, as [`TransportKind::Rtu`].
    Ascii,
    /// Modbus ASCII frames carried over a TCP stream (a serial gateway in transparent mode).
    AsciiOverTcp,
}

impl TransportKind {
    /// Whether frames of this transport carry RTU framing (slave address + CRC).
    pub const fn is_rtu_framed(self) -> bool {
        matches!(self, TransportKind::Rtu | TransportKind::RtuOverTcp)
    }

    /// Whether frames of this transport are Modbus ASCII (`:` ... LRC CR LF).
    pub const fn is_ascii(self) -> bool {
        matches!(self, TransportKind::Ascii | TransportKind::AsciiOverTcp)
    }

    /// Whether frames of this transport are serial-line frames (slave address, PDU, check;
    /// RTU or ASCII), with no transaction id: a late reply can be told from the answer only by
    /// its echoes and by silence.
    pub const fn is_serial_framed(self) -> bool {
        self.is_rtu_framed() || self.is_ascii()
    }

    /// Whether the link is a TCP stream (Modbus TCP, or serial frames carried over TCP).
    pub const fn is_tcp_stream(self) -> bool {
        !matches!(self, TransportKind::Rtu | TransportKind::Ascii)
    }

    /// Whether the drive at the far end of the link is reached on its serial (RTU) side:
    /// serial lines, RTU over TCP, and a Modbus TCP gateway to a serial line. These links use
    /// the map's RTU addressing, RTU registers and RTU timing.
    pub const fn reaches_rtu_side(self) -> bool {
        !matches!(self, TransportKind::Tcp)
    }

    /// A short name for messages: `RTU`, `RTU over TCP`, `Modbus TCP`, `Modbus TCP gateway`,
    /// `ASCII`, `ASCII over TCP`.
    pub const fn name(self) -> &'static str {
        match self {
            TransportKind::Rtu => "RTU",
            TransportKind::RtuOverTcp => "RTU over TCP",
            TransportKind::Tcp => "Modbus TCP",
            TransportKind::TcpGateway => "Modbus TCP gateway to RTU",
            TransportKind::Ascii => "ASCII",
            TransportKind::AsciiOverTcp => "ASCII over TCP",
        }
    }
}

/// One exception code as the drive's manual defines it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExceptionInfo {
    /// The code in the exception response (byte after `0x80 | function`).
    pub code: u8,
    /// Short name as printed ("Data setting error").
    pub name: &'static str,
    /// What the manual says causes it.
    pub description: &'static str,
}

/// What an explicit command does to the drive's memory (a map's command `kind`: `accept`,
/// `persist`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum CommandKind {
    /// Makes written parameters active without storing them (V7 ACCEPT 0910h).
    Accept,
    /// Stores parameters in non-volatile memory (EEPROM); wears it.
    Persist,
}

/// An explicit command made of register writes (ENTER, ACCEPT, save to EEPROM).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommandInfo {
    /// Identifier from the map (`enter`, `save_parameters`).
    pub id: &'static str,
    /// Name as printed in the manual.
    pub name: &'static str,
    /// Whether it only makes written values take effect, or stores them in EEPROM.
    pub kind: CommandKind,
    /// The writes in order: (communication address, value). ACN writes 0 then 1 to 0x03E0.
    pub writes: &'static [(u16, u16)],
    /// `file:line` of the manual passage.
    pub source: &'static str,
}

/// Broadcast (slave address 0) rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BroadcastInfo {
    /// Function codes the drive executes when addressed as slave 0.
    pub functions: &'static [u8],
    /// Communication addresses a broadcast may write. Empty: any writable register.
    pub addresses: &'static [u16],
    /// Set when the drive has a broadcast whose rules its manual does not print: why (the
    /// map's `broadcast.unknown`). `functions` and `addresses` are empty then, and the client's
    /// write gate refuses every broadcast: it cannot tell what the drives would do with one.
    pub not_printed: Option<&'static str>,
}

impl BroadcastInfo {
    /// Rules known: the given functions, to the given addresses (empty: any writable one).
    pub const fn new(functions: &'static [u8], addresses: &'static [u16]) -> BroadcastInfo {
        BroadcastInfo {
            functions,
            addresses,
            not_printed: None,
        }
    }

    /// A broadcast that exists but whose rules the manual does not print (`why`).
    pub const fn not_printed(why: &'static str) -> BroadcastInfo {
        BroadcastInfo {
            functions: &[],
            addresses: &[],
            not_printed: Some(why),
        }
    }
}

/// Parity of a serial line: the one definition, used by the map (`protocol.serial.parity`,
/// written `none`, `even`, `odd`), the run-time link and the profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Parity {
    /// No parity bit.
    #[default]
    None,
    /// Even parity.
    Even,
    /// Odd parity.
    Odd,
}

impl Parity {
    /// The letter of the usual notation (`8N1`, `8E1`, `8O1`).
    pub const fn letter(self) -> char {
        match self {
            Parity::None => 'N',
            Parity::Even => 'E',
            Parity::Odd => 'O',
        }
    }

    /// Every parity, in the order `None`, `Even`, `Odd`.
    pub const ALL: [Parity; 3] = [Parity::None, Parity::Even, Parity::Odd];

    /// The word a map and the command line write it as: `none`, `even`, `odd`.
    pub const fn name(self) -> &'static str {
        match self {
            Parity::None => "none",
            Parity::Even => "even",
            Parity::Odd => "odd",
        }
    }
}

/// One character format a drive's serial line offers, and the code of the parameter that
/// selects it on the drive (ACN CM.04 = 2: 8 data bits, even parity, 1 stop bit).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SerialFormat {
    /// The selecting parameter's code for this format.
    pub code: u16,
    /// Data bits per character.
    pub data_bits: u8,
    /// Parity.
    pub parity: Parity,
    /// Stop bits.
    pub stop_bits: u8,
}

impl SerialFormat {
    /// Whether this is the format `data_bits`, `parity`, `stop_bits`.
    pub fn is(&self, data_bits: u8, parity: Parity, stop_bits: u8) -> bool {
        (self.data_bits, self.parity, self.stop_bits) == (data_bits, parity, stop_bits)
    }
}

impl core::fmt::Display for SerialFormat {
    /// `8N1`, `8E1`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{}{}{}",
            self.data_bits,
            self.parity.letter(),
            self.stop_bits
        )
    }
}

/// The only character formats a drive's serial line offers, chosen on the drive by a parameter
/// (the map's `serial.formats`; ACN CM.04: 0 = 8N1, 1 = 8N2, 2 = 8E1, 3 = 8O1). A line set to
/// any other combination (8E2, 8O2 on the ACN) is refused by the runtime's serial
/// configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SerialFormats {
    /// The parameter that selects the format, as the map names it (`CM.04`).
    pub selected_by: &'static str,
    /// The formats, in the map's order.
    pub formats: &'static [SerialFormat],
    /// `file:line` of the manual's list.
    pub source: &'static str,
}

impl SerialFormats {
    /// The listed format `data_bits`, `parity`, `stop_bits`, if there is one.
    pub fn find(
        &self,
        data_bits: u8,
        parity: Parity,
        stop_bits: u8,
    ) -> Option<&'static SerialFormat> {
        self.formats
            .iter()
            .find(|f| f.is(data_bits, parity, stop_bits))
    }

    /// The stop bits of the formats with `parity`, when they all have the same (ACN: 1 with
    /// even or odd parity; none with no parity, which has 8N1 and 8N2).
    pub fn stop_bits_for(&self, parity: Parity) -> Option<u8> {
        only_stop_bits(self.formats, parity)
    }

    /// The listed format the line `data_bits`, `parity`, `stop_bits` uses, or why there is none.
    pub fn check(
        &self,
        drive: &'static str,
        data_bits: u8,
        parity: Parity,
        stop_bits: u8,
    ) -> Result<&'static SerialFormat, FormatNotListed> {
        self.find(data_bits, parity, stop_bits)
            .ok_or(FormatNotListed {
                drive,
                data_bits,
                parity,
                stop_bits,
                formats: *self,
            })
    }
}

/// The stop bits the formats with `parity` share, if any format has it and they all agree.
pub fn only_stop_bits(formats: &[SerialFormat], parity: Parity) -> Option<u8> {
    let mut with = formats.iter().filter(|f| f.parity == parity);
    let first = with.next()?.stop_bits;
    with.all(|f| f.stop_bits == first).then_some(first)
}

/// A serial line set to a character format the drive's map does not list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FormatNotListed {
    /// The drive's map id.
    pub drive: &'static str,
    /// Data bits per character of the line.
    pub data_bits: u8,
    /// Parity of the line.
    pub parity: Parity,
    /// Stop bits of the line.
    pub stop_bits: u8,
    /// What the map lists.
    pub formats: SerialFormats,
}

impl core::fmt::Display for FormatNotListed {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let asked = SerialFormat {
            code: 0,
            data_bits: self.data_bits,
            parity: self.parity,
            stop_bits: self.stop_bits,
        };
        write!(
            f,
            "{}'s serial line offers only the formats its map lists ({}:",
            self.drive, self.formats.selected_by
        )?;
        for (i, x) in self.formats.formats.iter().enumerate() {
            let sep = if i == 0 { " " } else { ", " };
            write!(f, "{sep}{} = {x}", x.code)?;
        }
        write!(
            f,
            "); {asked} is not one of them (`{}`)",
            self.formats.source
        )
    }
}

/// PDU address = communication address + offset, per transport kind.
///
/// The AutomationDirect ACN quotes "communication addresses" but its RTU example writes 0x1102 to
/// reach 0x1103 (offset -1), while its TCP decimals are one higher (offset 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AddressOffsets {
    /// The offset on RTU-framed links (serial, RTU over TCP).
    pub rtu: i32,
    /// The offset over Modbus TCP.
    pub tcp: i32,
}

impl AddressOffsets {
    /// The offset for a transport kind. RTU over TCP, a Modbus TCP gateway and Modbus ASCII
    /// reach the drive's serial side and use the RTU offset.
    pub const fn for_kind(&self, kind: TransportKind) -> i32 {
        if kind.reaches_rtu_side() {
            self.rtu
        } else {
            self.tcp
        }
    }

    /// Maps a communication address to the PDU address for `kind`, or `None` when the result
    /// falls outside 0..=0xFFFF.
    pub fn pdu_address(&self, address: u16, kind: TransportKind) -> Option<u16> {
        u16::try_from(i32::from(address) + self.for_kind(kind)).ok()
    }

    /// Maps a PDU address received on `kind` back to the manual's communication address.
    pub fn communication_address(&self, pdu: u16, kind: TransportKind) -> Option<u16> {
        u16::try_from(i32::from(pdu) - self.for_kind(kind)).ok()
    }
}

/// RTU timing the manual prescribes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Silence between frames, in character times (3.5 on every drive here).
    pub frame_gap_chars: f64,
    /// Least silence between frames in microseconds, when the manual states it in time ("at
    /// least 10 ms"); the gap kept is the larger of this and `frame_gap_chars` characters at the
    /// line's baud rate.
    pub frame_gap_us: Option<u32>,
    /// Maximum gap between characters of one frame, in microseconds, if the manual gives one
    /// (V7: 3.5 ms; J7: 24 bit times, converted at the configured baud by the transport).
    pub inter_char_timeout_us: Option<u32>,
    /// The same limit expressed in bit times, when the manual gives it that way.
    pub inter_char_timeout_bits: Option<u32>,
    /// The drive's typical or minimum delay before answering, in microseconds, if stated.
    pub response_delay_us: Option<u32>,
    /// Bit times the drive takes before answering, on top of the delay (V7/J7: 24 bits, then
    /// the n156/n73 delay).
    pub response_delay_bits: Option<u32>,
    /// The parameter that adds a configurable response delay (V7 n156, ACN CM.05), if any.
    pub response_delay_param: Option<&'static str>,
    /// That parameter's factory setting, in microseconds, when the map prints it.
    pub response_delay_param_default_us: Option<u32>,
    /// Least time the master leaves after a reply before the next request: bit times plus
    /// microseconds (V7/J7: 24 bits + 10 ms).
    pub request_gap_bits: Option<u32>,
    /// The microseconds of that gap (added to `request_gap_bits`).
    pub request_gap_us: Option<u32>,
    /// Bits per character when the manual fixes it whatever the parity (TDS-V8: 11).
    pub char_bits: Option<u8>,
}

impl Timing {
    /// The Modbus RTU rule alone: 3.5 characters between frames, nothing else stated.
    pub const MODBUS: Timing = Timing {
        frame_gap_chars: 3.5,
        frame_gap_us: None,
        inter_char_timeout_us: None,
        inter_char_timeout_bits: None,
        response_delay_us: None,
        response_delay_bits: None,
        response_delay_param: None,
        response_delay_param_default_us: None,
        request_gap_bits: None,
        request_gap_us: None,
        char_bits: None,
    };
}

impl Default for Timing {
    fn default() -> Self {
        Timing::MODBUS
    }
}

/// Everything the runtime needs to know about a drive's protocol.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    /// Drive identifier from the map (`ptlk-tds-v8`).
    pub drive_id: &'static str,
    /// Function codes the drive implements.
    pub function_codes: &'static [u8],
    /// Maximum registers per read (03h/04h); the Modbus 125 when the manual prints none (see
    /// [`Profile::not_printed`]).
    pub max_read: u16,
    /// Maximum registers per write (10h); the Modbus 123 when the manual prints none.
    pub max_write: u16,
    /// Maximum coils or discrete inputs per read (01h/02h); the Modbus 2000 when the manual
    /// prints none or the drive has no coils.
    pub max_read_bits: u16,
    /// Maximum coils per write (0Fh); the Modbus 1968 when the manual prints none.
    pub max_write_bits: u16,
    /// Valid slave addresses (excluding broadcast 0); the Modbus 1-247 when the manual prints
    /// no range.
    pub slave_min: u8,
    /// The highest valid slave address (see `slave_min`).
    pub slave_max: u8,
    /// The drive's broadcast (slave 0) rules; `None` when it executes no broadcast.
    pub broadcast: Option<BroadcastInfo>,
    /// The exception codes the manual lists.
    pub exceptions: &'static [ExceptionInfo],
    /// The explicit commands (ENTER, ACCEPT, save), by map id.
    pub commands: &'static [CommandInfo],
    /// The offset from communication address to PDU address, per transport kind.
    pub address_offsets: AddressOffsets,
    /// The drive's timing on its serial line.
    pub timing: Timing,
    /// The only serial character formats the drive offers, when its map lists them (a
    /// parameter selects one on the drive); `None`: any parity and stop bits.
    pub serial_formats: Option<SerialFormats>,
    /// Manufacturer's stated endurance of the parameter memory, in writes, if given.
    pub eeprom_write_endurance: Option<u32>,
    /// What the map allows for each writable register, for the write gate
    /// (the write gate of `drivemap_runtime::gate`). Empty: no register table, only the protocol is checked.
    pub writes: &'static [WriteRule],
    /// The protocol facts the manual does not print (the map's `unknown:`), with why. The
    /// figures above hold the Modbus ones in their place ([`ProtocolFact::fallback`]).
    pub not_printed: &'static [NotPrinted],
}

impl Profile {
    /// A permissive profile for generic Modbus devices: all five function codes, 125/123
    /// registers per request, standard exception names only.
    pub const GENERIC: Profile = Profile {
        drive_id: "generic",
        function_codes: &[0x03, 0x04, 0x06, 0x08, 0x10],
        max_read: 125,
        max_write: 123,
        max_read_bits: crate::stated::MODBUS_MAX_READ_BITS,
        max_write_bits: crate::stated::MODBUS_MAX_WRITE_BITS,
        slave_min: 1,
        slave_max: 247,
        broadcast: Some(BroadcastInfo::new(&[0x06, 0x10], &[])),
        exceptions: &[],
        commands: &[],
        address_offsets: AddressOffsets { rtu: 0, tcp: 0 },
        timing: Timing::MODBUS,
        serial_formats: None,
        eeprom_write_endurance: None,
        writes: &[],
        not_printed: &[],
    };

    /// Why the manual prints no `fact`, when it prints none.
    pub fn why_not_printed(&self, fact: ProtocolFact) -> Option<&NotPrinted> {
        self.not_printed.iter().find(|n| n.fact == fact)
    }

    /// Registers per write, or why the manual prints no limit ([`Profile::max_write`] is the
    /// Modbus 123 then).
    pub fn max_write_stated(&self) -> Stated<u16> {
        self.stated(ProtocolFact::MaxWrite, self.max_write)
    }

    /// Coils or discrete inputs per read (01h/02h), or why the manual prints no limit.
    pub fn max_read_bits_stated(&self) -> Stated<u16> {
        self.stated(ProtocolFact::MaxReadBits, self.max_read_bits)
    }

    /// Coils per write (0Fh), or why the manual prints no limit.
    pub fn max_write_bits_stated(&self) -> Stated<u16> {
        self.stated(ProtocolFact::MaxWriteBits, self.max_write_bits)
    }

    /// The most items one read of `table` may take: registers (03h/04h) or bits (01h/02h).
    pub fn max_read_of(&self, table: crate::register::Table) -> u16 {
        if table.is_bits() {
            self.max_read_bits
        } else {
            self.max_read
        }
    }

    /// Registers per read, or why the manual prints no limit.
    pub fn max_read_stated(&self) -> Stated<u16> {
        self.stated(ProtocolFact::MaxRead, self.max_read)
    }

    /// The slave-address range, or why the manual prints none.
    pub fn slave_range_stated(&self) -> Stated<(u8, u8)> {
        self.stated(ProtocolFact::SlaveAddress, (self.slave_min, self.slave_max))
    }

    fn stated<T>(&self, fact: ProtocolFact, value: T) -> Stated<T> {
        match self.why_not_printed(fact) {
            Some(n) => Stated::NotPrinted(n.why),
            None => Stated::Printed(value),
        }
    }

    /// Whether the drive implements `function`.
    pub fn supports(&self, function: u8) -> bool {
        self.function_codes.contains(&function)
    }

    /// The drive's own description of an exception code, if its manual defines one.
    pub fn exception(&self, code: u8) -> Option<&ExceptionInfo> {
        self.exceptions.iter().find(|e| e.code == code)
    }

    /// The write rule of a register by its map identifier.
    pub fn write_rule(&self, register: &str) -> Option<&WriteRule> {
        self.writes.iter().find(|w| w.register == register)
    }

    /// A command by its map identifier.
    pub fn command(&self, id: &str) -> Option<&CommandInfo> {
        self.commands.iter().find(|c| c.id == id)
    }
}
