//! The seam between generated register types and the clients.
//!
//! Every register of a map becomes a zero-sized type implementing [`Register`]. Whether it may be
//! read or written is a trait ([`Readable`], [`Writable`]), so writing a read-only register is a
//! compile error, not a runtime one. Values are typed: bit-field structs, enums with an
//! `Unknown(u16)` fallback, `f64` engineering values for scaled quantities, `u16`/`i16` for plain
//! words.

use core::marker::PhantomData;

use crate::plan::{AddressUnknown, Label, RegisterPlan, RepeatNeedsChange, SettingsView, Value};
use crate::profile::TransportKind;
use crate::rule::WriteRule;
use crate::scale::{Rounding, ValueError};
use crate::width::Width;

/// Which Modbus table (address space) a register lives in (a map's `modbus_table`: `holding`,
/// `input`, `coil`, `discrete_input`). Coils and discrete inputs are one bit each: their raw
/// value is 0 or 1, and their addresses are another space than the registers' (coil 0001h and
/// holding register 0001h are two things).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Table {
    /// Holding registers: read with 03h, written with 06h/10h.
    Holding,
    /// Input registers: read with 04h.
    Input,
    /// Coils: one bit each, read with 01h, written with 05h (FF00h on, 0000h off) and 0Fh.
    Coil,
    /// Discrete inputs: one bit each, read with 02h; never written.
    DiscreteInput,
}

impl Table {
    /// Every table, registers first.
    pub const ALL: [Table; 4] = [
        Table::Holding,
        Table::Input,
        Table::Coil,
        Table::DiscreteInput,
    ];

    /// The function code that reads this table.
    pub const fn read_function(self) -> u8 {
        match self {
            Table::Holding => 0x03,
            Table::Input => 0x04,
            Table::Coil => 0x01,
            Table::DiscreteInput => 0x02,
        }
    }

    /// Whether the table holds bits (coils, discrete inputs) rather than 16-bit registers.
    pub const fn is_bits(self) -> bool {
        matches!(self, Table::Coil | Table::DiscreteInput)
    }

    /// Whether the Modbus table can be written at all (holding registers and coils).
    pub const fn writable(self) -> bool {
        matches!(self, Table::Holding | Table::Coil)
    }

    /// The functions that write this table: one item (06h, 05h) and several (10h, 0Fh); `None`
    /// for the read-only tables.
    pub const fn write_functions(self) -> Option<(u8, u8)> {
        match self {
            Table::Holding => Some((0x06, 0x10)),
            Table::Coil => Some((0x05, 0x0F)),
            Table::Input | Table::DiscreteInput => None,
        }
    }

    /// The table's name as the map writes it (`holding`, `input`, `coil`, `discrete_input`).
    pub const fn key(self) -> &'static str {
        match self {
            Table::Holding => "holding",
            Table::Input => "input",
            Table::Coil => "coil",
            Table::DiscreteInput => "discrete_input",
        }
    }

    /// What one item of the table is called (`holding register`, `coil`, ...).
    pub const fn item(self) -> &'static str {
        match self {
            Table::Holding => "holding register",
            Table::Input => "input register",
            Table::Coil => "coil",
            Table::DiscreteInput => "discrete input",
        }
    }

    /// The table of the function `function` reads or writes, if it reads or writes one.
    pub const fn of_function(function: u8) -> Option<Table> {
        match function {
            0x03 | 0x06 | 0x10 => Some(Table::Holding),
            0x04 => Some(Table::Input),
            0x01 | 0x05 | 0x0F => Some(Table::Coil),
            0x02 => Some(Table::DiscreteInput),
            _ => None,
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
    /// The registers the value occupies: one word, or a 32-bit pair read and written whole.
    const WIDTH: Width = Width::Word;

    /// The communication address to use with these settings on this transport. Most registers
    /// live at [`Register::ADDRESS`]; a few move with a setting (GPD 515 o2-09), a model variant
    /// or the transport (V7 Modbus TCP option card). The client adds the profile's per-transport
    /// offset on top of this. An address that depends on a setting `settings` does not hold is
    /// an error ([`AddressUnknown`]), never the printed address by default.
    fn address(settings: &Self::Settings, transport: TransportKind) -> Result<u16, AddressUnknown> {
        let _ = (settings, transport);
        Ok(Self::ADDRESS)
    }

    /// Whether the register exists on this transport. Most do; the V7's Modbus TCP option card
    /// has command registers of its own, and its RTU command registers are absent there. The
    /// client refuses a register on a transport it does not exist on.
    fn on_transport(transport: TransportKind) -> bool {
        let _ = transport;
        true
    }

    /// Decodes a raw value read from the drive: the word, or a pair's words joined in the map's
    /// order ([`Width::join`]). Data from the drive never makes this panic; it fails only when a
    /// conversion needs a setting that `settings` does not hold. A one-word register takes its
    /// word widened: `R::decode(word.into(), &settings)`.
    fn decode(raw: u32, settings: &Self::Settings) -> Result<Self::Value, ValueError>;

    /// Decodes the words read from the drive, all [`Register::WIDTH`] of them in wire order:
    /// [`Register::decode`] of them joined for a number, the text of a string register
    /// ([`crate::text`]). What the clients call.
    fn decode_words(words: &[u16], settings: &Self::Settings) -> Result<Self::Value, ValueError> {
        Self::decode(Self::WIDTH.join(words), settings)
    }
}

/// A register the drive lets you read.
#[diagnostic::on_unimplemented(
    message = "`{Self}` cannot be read: the manual makes it write-only",
    label = "write-only register"
)]
pub trait Readable: Register {}

/// A register the drive lets you write.
#[diagnostic::on_unimplemented(
    message = "`{Self}` cannot be written: the manual makes it read-only",
    label = "read-only register"
)]
pub trait Writable: Register {
    /// What a write takes: [`Register::Value`] for most registers; the write form (a plain
    /// word) for a register whose read meaning differs ([`ReadWriteAs`]), so the value read
    /// cannot be written back by mistake.
    type Input;

    /// When the drive accepts a write (exception 22h otherwise). Informational: the client
    /// cannot know the drive's state; the simulator enforces it.
    const WRITE_RESTRICTION: WriteRestriction = WriteRestriction::None;

    /// What the map allows on the wire for this register: transports, broadcast space,
    /// addresses, raw range, reserved bits. Every write passes the runtime's `gate::check` with it.
    const RULE: WriteRule;

    /// Set when the drive executes a written value only if it differs from the previous write:
    /// the client's `write` then writes [`RepeatNeedsChange::between`] first, so a repeated
    /// command is executed, not silently ignored.
    const REPEAT_NEEDS_CHANGE: Option<RepeatNeedsChange> = None;

    /// Encodes a value for the wire, checking it against the register's range first. A value
    /// that is out of range, not finite, or an unknown enumeration code is refused here and never
    /// reaches the wire. A pair's raw value goes out as its words in the map's order
    /// ([`Width::split`]).
    fn encode(value: &Self::Input, settings: &Self::Settings) -> Result<u32, ValueError>;

    /// [`Writable::encode`] with a choice for a number between two steps of the register
    /// (35.75 Hz to a register that counts 0.1 Hz): [`Rounding::Exact`] refuses it, as
    /// `encode` does; [`Rounding::Nearest`] sends the nearest step. Every limit is checked on
    /// the value given, before rounding.
    fn encode_rounded(
        value: &Self::Input,
        settings: &Self::Settings,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        let _ = rounding;
        Self::encode(value, settings)
    }
}

/// When a drive accepts writes to a register (a map's `write_restriction`: `none`,
/// `stopped`, `prg_mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
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

/// Typed value of a bit-field register. Its [`Code`] is the word, reserved bits 0.
pub trait Bits: Code {
    /// Mask of the bits that carry a field.
    const MASK: u16;
    /// The raw word, reserved bits 0.
    fn bits(&self) -> u16 {
        self.code()
    }
    /// Builds the value from a raw word; reserved bits are dropped.
    fn from_bits(raw: u16) -> Self {
        Self::from_code(raw & Self::MASK)
    }
}

/// Typed value of an enumeration register or field, and the word of a bit-field value.
pub trait Code: Copy {
    /// The code on the wire.
    fn code(&self) -> u16;
    /// The value for a code; codes the map does not list become `Unknown`.
    fn from_code(code: u16) -> Self;
    /// Whether the code is one the manual lists.
    fn is_known(&self) -> bool;
}

/// A generated enumeration of the codes a manual lists, with an `Unknown(u16)` fallback. Its
/// [`Code`] comes from [`Enumeration::ALL`] and [`Enumeration::LABELS`], which pair variants with
/// the plan's labels in order; the generated type only lists them.
pub trait Enumeration: Copy + PartialEq + 'static {
    /// Every listed variant, in the manual's order.
    const ALL: &'static [Self];
    /// The code, id and printed meaning of each variant of [`Enumeration::ALL`], in order.
    const LABELS: &'static [Label];
    /// The value of a code the manual does not list.
    fn unknown(code: u16) -> Self;
    /// The code of an `Unknown` value, `None` for a listed one.
    fn unknown_code(&self) -> Option<u16>;

    /// The plan's label of a listed value: found by variant (not by `==`, which compares
    /// codes: [`code_eq!`](crate::code_eq)).
    fn label(&self) -> Option<&'static Label> {
        if self.unknown_code().is_some() {
            return None;
        }
        let variant = core::mem::discriminant(self);
        let i = Self::ALL
            .iter()
            .position(|v| core::mem::discriminant(v) == variant)?;
        Self::LABELS.get(i)
    }

    /// The meaning as printed in the manual, or `None` for an unknown code.
    fn name(&self) -> Option<&'static str> {
        self.label().map(|l| l.name)
    }

    /// Writes the meaning, or `unknown code N`: the `Display` of generated enumerations.
    fn describe(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.label() {
            Some(l) => f.write_str(l.name),
            None => write!(f, "unknown code {}", self.code()),
        }
    }
}

/// `PartialEq`, `Eq` and `Hash` of an [`Enumeration`] by its code, as the drive sees it:
/// `Unknown(0)` (a code read from the device) equals the listed variant whose code is 0. The
/// generated enumerations use it in place of the derived, variant-by-variant comparison.
#[macro_export]
macro_rules! code_eq {
    ($t:ty) => {
        impl ::core::cmp::PartialEq for $t {
            fn eq(&self, other: &Self) -> bool {
                $crate::register::Code::code(self) == $crate::register::Code::code(other)
            }
        }
        impl ::core::cmp::Eq for $t {}
        impl ::core::hash::Hash for $t {
            fn hash<H: ::core::hash::Hasher>(&self, state: &mut H) {
                ::core::hash::Hash::hash(&$crate::register::Code::code(self), state)
            }
        }
    };
}

/// The impls of a generated enumeration, in one line of generated code: [`Enumeration`] (its
/// listed variants `[A, B, ...]` in the order of `labels`, and its `Unknown(u16)` variant),
/// `Display` (the manual's meaning, or `unknown code N`) and [`code_eq!`](crate::code_eq)
/// (equal by code).
#[macro_export]
macro_rules! enumeration {
    ($t:ident, $labels:expr, [$($variant:ident),* $(,)?]) => {
        impl $crate::register::Enumeration for $t {
            const ALL: &'static [Self] = &[$(Self::$variant),*];
            const LABELS: &'static [$crate::plan::Label] = $labels;
            fn unknown(code: u16) -> Self {
                Self::Unknown(code)
            }
            fn unknown_code(&self) -> ::core::option::Option<u16> {
                match self {
                    Self::Unknown(code) => ::core::option::Option::Some(*code),
                    _ => ::core::option::Option::None,
                }
            }
        }
        impl ::core::fmt::Display for $t {
            fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                $crate::register::Enumeration::describe(self, f)
            }
        }
        $crate::code_eq!($t);
    };
}

impl<T: Enumeration> Code for T {
    fn code(&self) -> u16 {
        match self.unknown_code() {
            Some(code) => code,
            None => self.label().map_or(0, |l| l.code),
        }
    }

    fn from_code(code: u16) -> Self {
        match T::LABELS.iter().position(|l| l.code == code) {
            Some(i) => T::ALL[i],
            None => T::unknown(code),
        }
    }

    fn is_known(&self) -> bool {
        self.unknown_code().is_none()
    }
}

/// Access as the manual states it (a map's `access`: `r`, `w`, `rw`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Access {
    /// Read only.
    #[cfg_attr(feature = "serde", serde(rename = "r"))]
    Read,
    /// Write only.
    #[cfg_attr(feature = "serde", serde(rename = "w"))]
    Write,
    /// Read and write.
    #[cfg_attr(feature = "serde", serde(rename = "rw"))]
    ReadWrite,
}

impl Access {
    /// Whether the register can be read.
    pub const fn readable(self) -> bool {
        matches!(self, Access::Read | Access::ReadWrite)
    }
    /// Whether the register can be written.
    pub const fn writable(self) -> bool {
        matches!(self, Access::Write | Access::ReadWrite)
    }
}

/// Static description of one register, for code that works over a whole drive (read planner,
/// pollers, tools). Generated modules emit `pub static REGISTERS: &[RegisterInfo]` sorted by
/// address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterInfo {
    /// The register's identifier in the map.
    pub id: &'static str,
    /// The parameter number as printed in the manual (`n011`), if any.
    pub param: Option<&'static str>,
    /// The name as printed in the manual.
    pub name: &'static str,
    /// The communication address as printed in the manual.
    pub address: u16,
    /// Read, write or both.
    pub access: Access,
    /// Holding or input register.
    pub table: Table,
    /// One register, or two holding one 32-bit value.
    pub width: Width,
    /// Only reachable as a broadcast (slave 0) write, in its own bit layout.
    pub broadcast_only: bool,
    /// Where the manual prints it.
    pub source: &'static str,
}

impl RegisterInfo {
    /// The base that generated plan rows complete (`..RegisterInfo::DEFAULT`): a holding
    /// register of one word, read-only, with no parameter number, not broadcast-only, and no
    /// id, name, address or citation (every row gives those).
    pub const DEFAULT: RegisterInfo = RegisterInfo {
        id: "",
        param: None,
        name: "",
        address: 0,
        access: Access::Read,
        table: Table::Holding,
        width: Width::Word,
        broadcast_only: false,
        source: "",
    };
}

impl AsRef<RegisterInfo> for RegisterInfo {
    fn as_ref(&self) -> &RegisterInfo {
        self
    }
}

/// The settings type of a drive: the values that conversions depend on (variant, scale
/// selectors such as V7 n152, reference quantities such as TDS-V8 Cn-02).
pub trait DriveSettings {
    /// Communication addresses of the parameters that conversions depend on, in the order a
    /// client should read them.
    const DEPENDENCIES: &'static [u16];

    /// Records a raw word read from one of [`DriveSettings::DEPENDENCIES`]. Width from other
    /// addresses are ignored. Returns whether the word was used.
    fn absorb(&mut self, address: u16, raw: u16) -> bool;

    /// Sets the external quantity `name` of the map (a value the application supplies, such as
    /// a drive rating). Returns false when the drive has no external quantity of that name.
    fn set_external(&mut self, name: &str, value: f64) -> bool {
        let _ = (name, value);
        false
    }
}

/// A generated drive: its settings type and the plan of every register, by address.
pub trait DrivePlan {
    /// What conversions depend on.
    type Settings: SettingsView;
    /// Every register's plan, sorted by address (broadcast-only registers last).
    const REGISTERS: &'static [RegisterPlan];
    /// What the drive accepts on the wire.
    const PROFILE: &'static crate::profile::Profile;
    /// Which registers and fields play the standard parts of a drive ([`Roles::NONE`] when the
    /// map gives none).
    ///
    /// [`Roles::NONE`]: crate::roles::Roles::NONE
    const ROLES: crate::roles::Roles;
}

/// Access marker of a register the manual makes read-only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ReadOnly;
/// Access marker of a register the manual makes write-only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct WriteOnly;
/// Access marker of a register the manual lets you read and write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ReadWrite;
/// Access marker of a register read and written with different meanings (ACN 0h03E7: a
/// password is written, 0 Unlock / 1 Lock is read): reads give the register's value type (the
/// read enumeration), writes take `W` (the write form, a plain word).
pub struct ReadWriteAs<W>(PhantomData<fn() -> W>);

/// The register at index `I` of drive `D`'s plan, with value type `V` and access `A`.
///
/// Generated modules name each register with a type alias of it
/// (`pub type OutputFrequency = Reg<Drive, f64, ReadOnly, 12>;`): every behaviour is in the
/// generic impls below and the data in [`DrivePlan::REGISTERS`], so a drive module is consts,
/// aliases and value types, and all drives share one conversion code.
pub struct Reg<D, V, A, const I: usize>(PhantomData<Marker<D, V, A>>);

/// `Reg`'s phantom: a function type, so `Reg` is `Send`, `Sync` and `Copy` whatever its parameters.
type Marker<D, V, A> = fn() -> (D, V, A);

impl<D, V, A, const I: usize> Clone for Reg<D, V, A, I> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<D, V, A, const I: usize> Copy for Reg<D, V, A, I> {}
impl<D, V, A, const I: usize> Default for Reg<D, V, A, I> {
    fn default() -> Self {
        Reg(PhantomData)
    }
}
impl<D: DrivePlan, V, A, const I: usize> core::fmt::Debug for Reg<D, V, A, I> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(Self::PLAN.info.id)
    }
}

impl<D: DrivePlan, V, A, const I: usize> Reg<D, V, A, I> {
    /// The register's plan.
    pub const PLAN: &'static RegisterPlan = &D::REGISTERS[I];
    /// Engineering unit of the value (`""` for none).
    pub const UNIT: &'static str = Self::PLAN.unit;
    /// The register's exact ratio scale (`3600 = 60.0 Hz`), if it has one.
    pub const RATIO: Option<crate::ratio::Ratio> = match Self::PLAN.conversion {
        crate::plan::Conversion::Ratio { ratio, .. } => Some(ratio),
        _ => None,
    };
}

impl<D: DrivePlan, V: Value, A, const I: usize> Register for Reg<D, V, A, I> {
    type Value = V;
    type Settings = D::Settings;
    const ID: &'static str = Self::PLAN.info.id;
    const PARAM: Option<&'static str> = Self::PLAN.info.param;
    const NAME: &'static str = Self::PLAN.info.name;
    const ADDRESS: u16 = Self::PLAN.info.address;
    const TABLE: Table = Self::PLAN.info.table;
    const SOURCE: &'static str = Self::PLAN.info.source;
    const WIDTH: Width = Self::PLAN.info.width;

    fn address(settings: &D::Settings, transport: TransportKind) -> Result<u16, AddressUnknown> {
        Self::PLAN.locate(settings, transport)
    }

    fn on_transport(transport: TransportKind) -> bool {
        Self::PLAN.transports.contains(transport)
    }

    fn decode(raw: u32, settings: &D::Settings) -> Result<V, ValueError> {
        V::decode(raw, Self::PLAN, settings)
    }

    fn decode_words(words: &[u16], settings: &D::Settings) -> Result<V, ValueError> {
        V::decode_words(words, Self::PLAN, settings)
    }
}

impl<D: DrivePlan, V: Value, const I: usize> Readable for Reg<D, V, ReadOnly, I> {}
impl<D: DrivePlan, V: Value, const I: usize> Readable for Reg<D, V, ReadWrite, I> {}

impl<D: DrivePlan, V: Value, W: Value, const I: usize> Readable for Reg<D, V, ReadWriteAs<W>, I> {}

// One impl per access marker, written out rather than by a macro: a write to a read-only
// register fails to compile, and rustc's message then points at these impls, not into a macro.
impl<D: DrivePlan, V: Value, const I: usize> Writable for Reg<D, V, WriteOnly, I> {
    type Input = V;
    const WRITE_RESTRICTION: WriteRestriction = Self::PLAN.restriction;
    const RULE: WriteRule = Self::PLAN.write_rule();
    const REPEAT_NEEDS_CHANGE: Option<RepeatNeedsChange> = Self::PLAN.repeat_needs_change;
    fn encode(value: &V, settings: &D::Settings) -> Result<u32, ValueError> {
        value.encode(Self::PLAN, settings)
    }
    fn encode_rounded(
        value: &V,
        settings: &D::Settings,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        value.encode_with(Self::PLAN, settings, rounding)
    }
}

impl<D: DrivePlan, V: Value, const I: usize> Writable for Reg<D, V, ReadWrite, I> {
    type Input = V;
    const WRITE_RESTRICTION: WriteRestriction = Self::PLAN.restriction;
    const RULE: WriteRule = Self::PLAN.write_rule();
    const REPEAT_NEEDS_CHANGE: Option<RepeatNeedsChange> = Self::PLAN.repeat_needs_change;
    fn encode(value: &V, settings: &D::Settings) -> Result<u32, ValueError> {
        value.encode(Self::PLAN, settings)
    }
    fn encode_rounded(
        value: &V,
        settings: &D::Settings,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        value.encode_with(Self::PLAN, settings, rounding)
    }
}

/// Writes take the write form `W`, encoded by the register's conversion; reads decode to `V`.
impl<D: DrivePlan, V: Value, W: Value, const I: usize> Writable for Reg<D, V, ReadWriteAs<W>, I> {
    type Input = W;
    const WRITE_RESTRICTION: WriteRestriction = Self::PLAN.restriction;
    const RULE: WriteRule = Self::PLAN.write_rule();
    const REPEAT_NEEDS_CHANGE: Option<RepeatNeedsChange> = Self::PLAN.repeat_needs_change;
    fn encode(value: &W, settings: &D::Settings) -> Result<u32, ValueError> {
        value.encode(Self::PLAN, settings)
    }
    fn encode_rounded(
        value: &W,
        settings: &D::Settings,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        value.encode_with(Self::PLAN, settings, rounding)
    }
}

impl<D: DrivePlan, V: Value + Bits, A, const I: usize> BitRegister for Reg<D, V, A, I> {
    const FIELD_MASK: u16 = V::MASK;
}
