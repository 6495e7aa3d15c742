//! The seam between generated register types and the clients.
//!
//! Every register of a map becomes a zero-sized type implementing [`Register`]. Whether it may be
//! read or written is a trait ([`Readable`], [`Writable`]), so writing a read-only register is a
//! compile error, not a runtime one. Values are typed: bit-field structs, enums with an
//! `Unknown(u16)` fallback, `f64` engineering values for scaled quantities, `u16`/`i16` for plain
//! words.

use crate::profile::TransportKind;
use crate::scale::ValueError;

/// Which Modbus table a register lives in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Table {
    /// Holding registers: read with 03h, written with 06h/10h.
    Holding,
    /// Input registers: read with 04h.
    Input,
}

impl Table {
    /// The function code that reads this table.
    pub const fn read_function(self) -> u8 {
        match self {
            Table::Holding => 0x03,
            Table::Input => 0x04,
        }
    }
}

/// A register of a drive, as the map describes it.
pub trait Register {
    /// The typed value: a bit-field struct, an enum, `f64` in engineering units, `u16` or `i16`.
    type Value;
    /// The drive's settings that conversions depend on (variant, scale selectors, reference
    /// quantities). One type per drive, generated.
    type Settings;

    /// Identifier in the map (`accel_time_1`).
    const ID: &'static str;
    /// Parameter number exactly as printed (`Bn-01`), if the manual gives one.
    const PARAM: Option<&'static str>;
    /// Name as printed in the manual.
    const NAME: &'static str;
    /// Communication address as printed in the manual.
    const ADDRESS: u16;
    /// Modbus table.
    const TABLE: Table;
    /// `file:line` of the row in the manual.
    const SOURCE: &'static str;

    /// The communication address to use with these settings on this transport. Most registers
    /// live at [`Register::ADDRESS`]; a few move with a setting (GPD 515 o2-09), a model variant
    /// or the transport (V7 Modbus TCP option card). The client adds the profile's per-transport
    /// offset on top of this.
    fn address(settings: &Self::Settings, transport: TransportKind) -> u16 {
        let _ = (settings, transport);
        Self::ADDRESS
    }

    /// Whether the register exists on this transport. Most do; the V7's Modbus TCP option card
    /// has command registers of its own, and its RTU command registers are absent there. The
    /// client refuses a register on a transport it does not exist on.
    fn on_transport(transport: TransportKind) -> bool {
        let _ = transport;
        true
    }

    /// Decodes a raw word read from the drive. Data from the drive never makes this panic;
    /// it fails only when a conversion needs a setting that `settings` does not hold.
    fn decode(raw: u16, settings: &Self::Settings) -> Result<Self::Value, ValueError>;
}

/// A register the drive lets you read.
pub trait Readable: Register {}

/// A register the drive lets you write.
pub trait Writable: Register {
    /// When the drive accepts a write (exception 22h otherwise). Informational: the client
    /// cannot know the drive's state; the simulator enforces it.
    const WRITE_RESTRICTION: WriteRestriction = WriteRestriction::None;

    /// What the map allows on the wire for this register: transports, broadcast space,
    /// addresses, raw range, reserved bits. Every write passes [`crate::gate::check`] with it.
    const RULE: crate::gate::WriteRule;

    /// Encodes a value for the wire, checking it against the register's range first. A value
    /// that is out of range, not finite, or an unknown enumeration code is refused here and never
    /// reaches the wire.
    fn encode(value: &Self::Value, settings: &Self::Settings) -> Result<u16, ValueError>;
}

/// When a drive accepts writes to a register.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WriteRestriction {
    /// Any time.
    None,
    /// Only while the motor is stopped.
    Stopped,
    /// Only in program (PRG) mode (TDS-V8).
    PrgMode,
}

/// A register whose value is a set of bit fields; reserved bits are kept 0 by the value type.
pub trait BitRegister: Register {
    /// Mask of the bits that carry a field. Bits outside it are reserved.
    const FIELD_MASK: u16;
}

/// Typed value of a bit-field register.
pub trait Bits: Copy {
    /// The raw word, reserved bits 0.
    fn bits(&self) -> u16;
    /// Builds the value from a raw word; reserved bits are dropped.
    fn from_bits(raw: u16) -> Self;
}

/// Typed value of an enumeration register or field.
pub trait Code: Copy {
    /// The code on the wire.
    fn code(&self) -> u16;
    /// The value for a code; codes the map does not list become `Unknown`.
    fn from_code(code: u16) -> Self;
    /// Whether the code is one the manual lists.
    fn is_known(&self) -> bool;
}

/// Access as the manual states it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    Read,
    Write,
    ReadWrite,
}

impl Access {
    pub const fn readable(self) -> bool {
        matches!(self, Access::Read | Access::ReadWrite)
    }
    pub const fn writable(self) -> bool {
        matches!(self, Access::Write | Access::ReadWrite)
    }
}

/// Static description of one register, for code that works over a whole drive (read planner,
/// pollers, tools). Generated modules emit `pub static REGISTERS: &[RegisterInfo]` sorted by
/// address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterInfo {
    pub id: &'static str,
    pub param: Option<&'static str>,
    pub name: &'static str,
    pub address: u16,
    pub access: Access,
    pub table: Table,
    /// Only reachable as a broadcast (slave 0) write, in its own bit layout.
    pub broadcast_only: bool,
    pub source: &'static str,
}

/// The settings type of a drive: the values that conversions depend on (variant, scale
/// selectors such as V7 n152, reference quantities such as TDS-V8 Cn-02).
pub trait DriveSettings {
    /// Communication addresses of the parameters that conversions depend on, in the order a
    /// client should read them.
    const DEPENDENCIES: &'static [u16];

    /// Records a raw word read from one of [`DriveSettings::DEPENDENCIES`]. Words from other
    /// addresses are ignored. Returns whether the word was used.
    fn absorb(&mut self, address: u16, raw: u16) -> bool;
}
