//! The drive plan: what every register of a map means, decided once by the map front end's
//! lowering (`drivemap-map`) and then only read.
//!
//! Generated drive modules hold their plan as `const` data and implement the typed API on it
//! ([`crate::register::Reg`]); the run-time interpreter (`drivemap-live`) builds the same plan
//! from a map file. Both convert words with the one implementation below, so the generated code
//! and a map loaded at run time cannot disagree about a scale, a range or an address.
//!
//! Where a register's scale is decided: [`Conversion`], chosen by `drivemap-map`'s lowering (the
//! data flow: `ARCHITECTURE.md` at the repository root).

use crate::functions::Functions;
use crate::profile::TransportKind;
use crate::ratio::{self, Fraction, Ratio};
use crate::register::{RegisterInfo, WriteRestriction};
use crate::rule::{Broadcast, Transports, WriteRule};
use crate::scale::{self, Decimal, RawRange, Rounding, ValueError};
use crate::text::ByteOrder;

/// One register of a drive, fully decided.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegisterPlan {
    /// Identity, address as printed, access, table, citation.
    pub info: RegisterInfo,
    /// Engineering unit (`""` for none).
    pub unit: &'static str,
    /// How its word converts.
    pub conversion: Conversion,
    /// Where it lives under other settings, variants or transports.
    pub moves: &'static [Move],
    /// The transports it exists on.
    pub transports: Transports,
    /// Whether it may, or must, be written as a broadcast.
    pub broadcast: Broadcast,
    /// When the drive accepts a write.
    pub restriction: WriteRestriction,
    /// Raw values the map allows under some variant and selector case: the gate's envelope.
    pub envelope: RawRange,
    /// Every other address it may occupy (the targets of [`RegisterPlan::moves`]).
    pub also_at: &'static [u16],
    /// The drive executes a written value only when it differs from the previous write (ACN
    /// memory-control registers): writers put [`RepeatNeedsChange::between`] first.
    pub repeat_needs_change: Option<RepeatNeedsChange>,
    /// What a word read from it means when that differs from what a write means (ACN 0h03E7:
    /// a password is written, 0 Unlock / 1 Lock is read); empty for other registers. The
    /// write side is [`RegisterPlan::conversion`].
    pub read_values: &'static [Label],
    /// The parameter a read returns when it is not the one a write sets (Siemens BICO: a
    /// register read from r0055 bit 8 and written to P2200; [`RegisterInfo::param`] is the
    /// write side): a written value is not what the next read gives, so nothing verifies a
    /// write by reading it back, and parameter sets leave the register out. `None` for other
    /// registers.
    ///
    /// [`RegisterInfo::param`]: crate::register::RegisterInfo::param
    pub read_param: Option<&'static str>,
    /// An upper limit the manual states through another parameter or quantity (a reference
    /// at most the maximum output frequency n011), checked by [`RegisterPlan::encode_number`]
    /// on the value given, with that quantity's value from the settings.
    pub limit: Option<RelativeLimit>,
    /// The Modbus functions it accepts, where the map restricts them below the drive's list
    /// ([`Functions::ANY`] otherwise).
    pub functions: Functions,
}

/// An upper limit through another quantity: a value at most `percent` % of the quantity in
/// `reference` (a register read from the drive, or an external quantity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelativeLimit {
    /// The quantity slot, and its label (the parameter number when printed).
    pub reference: Setting,
    /// The limit in percent of the reference.
    pub percent: f64,
    /// `file:line` of the manual's statement.
    pub source: &'static str,
}

/// A register whose drive executes a written value only when it differs from the previous
/// write ("if you want to enter 244 twice, enter it in the following order: 244 > 0 > 244").
/// Writers write `between` first, then the value, so a repeated command is executed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RepeatNeedsChange {
    /// The raw value written first; the map checks it is a legal value of the register.
    pub between: u32,
    /// `file:line` of the manual's rule.
    pub source: &'static str,
}

impl core::ops::Deref for RegisterPlan {
    type Target = RegisterInfo;
    fn deref(&self) -> &RegisterInfo {
        &self.info
    }
}

impl AsRef<RegisterInfo> for RegisterPlan {
    fn as_ref(&self) -> &RegisterInfo {
        &self.info
    }
}

/// A register whose address depends on a setting that is not known: nothing is sent to a
/// guessed address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "{register}: its address depends on {setting}, which is not known; read {setting} from the drive (or set it) first: nothing is sent to a guessed address"
)]
pub struct AddressUnknown {
    /// The register's id.
    pub register: &'static str,
    /// The setting its address depends on (the parameter number when printed).
    pub setting: &'static str,
}

/// An alternative address: the register is at `address` when `when` holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// The condition under which the register is at `address`.
    pub when: Condition,
    /// The communication address that holds then.
    pub address: u16,
}

/// A condition on the drive's settings, its variant or the link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Condition {
    /// A selecting parameter holds one of `codes`.
    Setting {
        /// The selecting parameter.
        selector: Setting,
        /// The codes of it that make the condition hold.
        codes: &'static [u16],
    },
    /// The drive is of this variant.
    Variant(VariantOption),
    /// The link is of one of these transports.
    Transport(Transports),
}

/// A setting a register depends on (see [`RegisterPlan::depends_on`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dependency {
    /// A selecting parameter's code (a code slot).
    Code(Setting),
    /// A reference quantity (a quantity slot).
    Quantity(Setting),
}

impl Dependency {
    /// The setting depended on, a code's or a quantity's.
    pub const fn setting(self) -> Setting {
        match self {
            Dependency::Code(s) | Dependency::Quantity(s) => s,
        }
    }
}

/// A setting a conversion or an address depends on: its slot in the drive's settings and the
/// name errors give it (the parameter number when printed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Setting {
    /// The setting's slot in the drive's settings ([`SettingsView`]).
    pub slot: u8,
    /// The name errors give it: the parameter number when printed.
    pub label: &'static str,
}

/// One option of one variant axis (option 0 is the base variant).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VariantOption {
    /// The variant axis.
    pub axis: u8,
    /// The option on that axis (0: the base variant).
    pub option: u8,
}

/// How a register's word converts to a value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Conversion {
    /// A plain `u16` / `i16` word.
    Word {
        /// Whether the word is read as an `i16`.
        signed: bool,
        /// The raw range, per variant.
        range: Ranges,
    },
    /// An engineering value: raw × a decimal factor.
    Decimal {
        /// Whether the raw value is signed.
        signed: bool,
        /// The factor: engineering = raw × `scale`.
        scale: Decimal,
        /// The raw range, per variant.
        range: Ranges,
    },
    /// An engineering value relative to a reference: `full_scale` raw = 100 % of it.
    Relative {
        /// Whether the raw value is signed.
        signed: bool,
        /// The full-scale count and the reference quantity.
        relative: Relative,
    },
    /// An engineering value with an exact ratio scale: `counts` raw = `equals` ("60.0 Hz =
    /// 3600"), kept as integers ([`crate::ratio`]).
    Ratio {
        /// Whether the raw value is signed.
        signed: bool,
        /// The exact scale: `counts` raw = `equals`.
        ratio: Ratio,
        /// The raw range, per variant.
        range: Ranges,
    },
    /// The scale chosen by a parameter's code.
    Selected {
        /// Whether the raw value is signed.
        signed: bool,
        /// The parameter whose code chooses the scale.
        selector: Setting,
        /// The scale of each code.
        cases: &'static [Case],
    },
    /// An enumeration: the listed codes, and the range of codes the manual admits without
    /// listing their meaning.
    Enum {
        /// The listed codes and their meanings.
        values: &'static [Label],
        /// The codes the manual admits without listing their meaning, if any.
        unlisted: Option<RawRange>,
    },
    /// Bit fields; bits outside `mask` are reserved and kept 0.
    Bits {
        /// The bits of the fields (the others are reserved).
        mask: u16,
        /// The fields, each with its bits.
        fields: &'static [Field],
    },
    /// Text, two characters per register, over the registers of [`RegisterInfo::width`]
    /// ([`crate::width::Width::Text`]); decoded by [`crate::text`], never as a number.
    Text {
        /// Which byte of each register holds the earlier character.
        order: ByteOrder,
    },
}

impl Conversion {
    /// An unsigned word over its whole range, the commonest conversion: generated plan rows say
    /// `Conversion::WORD` for it.
    pub const WORD: Conversion = Conversion::Word {
        signed: false,
        range: Ranges::fixed(RawRange::word(false)),
    };

    /// What the value is to a front end, decided here for every kind: a front end (the value
    /// type of a generated register, the run-time codec, an export, the bridge) matches on the
    /// [`ValueShape`] and reads a number's scale through [`RegisterPlan::scale`], so a new kind
    /// of scale is a number everywhere once it has its arm here.
    pub const fn shape(&self) -> ValueShape {
        match *self {
            Conversion::Word { signed, .. } => ValueShape::Word { signed },
            Conversion::Decimal { .. }
            | Conversion::Relative { .. }
            | Conversion::Ratio { .. }
            | Conversion::Selected { .. } => ValueShape::Number,
            Conversion::Enum { values, .. } => ValueShape::Codes(values),
            Conversion::Bits { mask, fields } => ValueShape::Bits { mask, fields },
            Conversion::Text { order } => ValueShape::Text { order },
        }
    }

    /// Calls `each` with every setting the conversion reads: the selecting parameter of a
    /// selected scale ([`Dependency::Code`]) and the quantity a relative scale, or the case of
    /// a selected scale that `settings` choose, refers to ([`Dependency::Quantity`]; every
    /// case's while the selector's code is unknown), in that order.
    pub fn depends_on(&self, settings: &impl SettingsView, mut each: impl FnMut(Dependency)) {
        match self {
            Conversion::Relative { relative, .. } => each(Dependency::Quantity(relative.reference)),
            Conversion::Selected {
                selector, cases, ..
            } => {
                each(Dependency::Code(*selector));
                let code = settings.code(selector.slot);
                for case in cases.iter() {
                    if let (CaseScale::Relative(r), true) =
                        (&case.scale, code.is_none_or(|c| case.codes.contains(&c)))
                    {
                        each(Dependency::Quantity(r.reference));
                    }
                }
            }
            Conversion::Word { .. }
            | Conversion::Decimal { .. }
            | Conversion::Ratio { .. }
            | Conversion::Enum { .. }
            | Conversion::Bits { .. }
            | Conversion::Text { .. } => {}
        }
    }
}

/// What a register's value is to a front end, whatever its [`Conversion`]
/// ([`Conversion::shape`]): a plain word, a number in the register's unit (every kind of
/// scale), codes, bit fields, or text.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ValueShape {
    /// A plain word or pair, read as an integer.
    Word {
        /// Whether it is two's complement.
        signed: bool,
    },
    /// A number in the register's unit: its scale in force is [`RegisterPlan::scale`].
    Number,
    /// An enumeration: its listed codes.
    Codes(&'static [Label]),
    /// Bit fields.
    Bits {
        /// The bits of the fields (the others are reserved).
        mask: u16,
        /// The fields.
        fields: &'static [Field],
    },
    /// Text over the register's width ([`crate::width::Width::Text`]), decoded by
    /// [`crate::text`]: not a number.
    Text {
        /// Which byte of each register holds the earlier character.
        order: ByteOrder,
    },
}

/// A relative scale: `full_scale` raw counts are 100 % of the quantity in `reference`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relative {
    /// The raw count that is 100 % of the reference.
    pub full_scale: f64,
    /// The reference quantity (a quantity slot of the settings).
    pub reference: Setting,
}

/// One case of a selected scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// The selector codes that choose it.
    pub codes: &'static [u16],
    /// The scale of the case.
    pub scale: CaseScale,
}

/// The scale of one case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CaseScale {
    /// A decimal factor and the raw range.
    Decimal {
        /// The factor: engineering = raw × `scale`.
        scale: Decimal,
        /// The raw range.
        range: RawRange,
    },
    /// A scale relative to a reference quantity.
    Relative(Relative),
}

/// A raw range with overrides per variant: the first override whose variant the settings hold
/// applies, else `base`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranges {
    /// The range of every variant without an override.
    pub base: RawRange,
    /// The overrides: a variant option and its range.
    pub by_variant: &'static [(VariantOption, RawRange)],
}

impl Ranges {
    /// One range for every variant.
    pub const fn fixed(base: RawRange) -> Ranges {
        Ranges {
            base,
            by_variant: &[],
        }
    }

    /// The range in force with `settings`.
    pub fn select(&self, settings: &impl SettingsView) -> RawRange {
        self.by_variant
            .iter()
            .find(|(v, _)| settings.variant(v.axis) == v.option)
            .map_or(self.base, |(_, r)| *r)
    }
}

/// A listed code: enumeration value or value of a multi-bit field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Label {
    /// The code.
    pub code: u16,
    /// Its identifier in the map.
    pub id: &'static str,
    /// Its name as printed in the manual.
    pub name: &'static str,
}

/// A field of a bit-field register.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    /// The field's identifier in the map.
    pub id: &'static str,
    /// Its name as printed in the manual.
    pub name: &'static str,
    /// Its lowest bit.
    pub lsb: u8,
    /// Its number of bits.
    pub width: u8,
    /// Meanings of a multi-bit field's codes, when listed.
    pub values: &'static [Label],
    /// Where the manual prints it.
    pub source: &'static str,
}

impl Field {
    /// The field's bits in the word.
    pub const fn mask(&self) -> u16 {
        let ones = if self.width >= 16 {
            u16::MAX
        } else {
            (1u16 << self.width) - 1
        };
        ones << self.lsb
    }

    /// The field's value in `word`.
    pub const fn get(&self, word: u16) -> u16 {
        (word & self.mask()) >> self.lsb
    }

    /// `word` with the field set to `value`; `None` if `value` does not fit the field.
    pub const fn set(&self, word: u16, value: u16) -> Option<u16> {
        if value > self.mask() >> self.lsb {
            return None;
        }
        Some((word & !self.mask()) | (value << self.lsb))
    }
}

/// What a drive's settings tell a conversion. Generated `Settings` types implement it over
/// their named fields; the run-time interpreter over slots filled from the drive.
pub trait SettingsView {
    /// The code a selecting parameter holds, if known.
    fn code(&self, slot: u8) -> Option<u16>;
    /// A reference quantity in its engineering unit, if known.
    fn quantity(&self, slot: u8) -> Option<f64>;
    /// The option of variant axis `axis` (0, the base, unless set).
    fn variant(&self, axis: u8) -> u8;
}

/// Settings of a drive whose conversions depend on nothing.
impl SettingsView for () {
    fn code(&self, _: u8) -> Option<u16> {
        None
    }
    fn quantity(&self, _: u8) -> Option<f64> {
        None
    }
    fn variant(&self, _: u8) -> u8 {
        0
    }
}

impl Condition {
    /// Whether the condition holds.
    pub fn holds(&self, settings: &impl SettingsView, transport: TransportKind) -> bool {
        match self {
            Condition::Setting { selector, codes } => settings
                .code(selector.slot)
                .is_some_and(|c| codes.contains(&c)),
            Condition::Variant(v) => settings.variant(v.axis) == v.option,
            Condition::Transport(t) => t.contains(transport),
        }
    }
}

/// The scale of a quantity once the settings have chosen it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// A decimal factor, with the raw range.
    Decimal {
        /// The factor: engineering = raw × `scale`.
        scale: Decimal,
        /// The raw range.
        range: RawRange,
    },
    /// A share of a reference quantity.
    Relative {
        /// The raw count that is 100 % of the reference.
        full_scale: f64,
        /// The reference quantity's value in force.
        reference: f64,
        /// The reference's name, for messages.
        label: &'static str,
    },
    /// An exact ratio ([`Conversion::Ratio`]).
    Ratio {
        /// The exact scale: `counts` raw = `equals`.
        ratio: Ratio,
        /// The raw range.
        range: RawRange,
    },
}

impl Scale {
    /// Digits after the decimal point worth showing.
    pub fn decimals(&self) -> usize {
        match self {
            Scale::Decimal { scale, .. } => scale.exponent as usize,
            Scale::Relative { .. } => 2,
            Scale::Ratio { ratio, .. } => ratio.step().decimal_digits().unwrap_or(6) as usize,
        }
    }

    /// One raw count in the register's unit, as the nearest `f64` (0.01 Hz; 1/60 Hz for a
    /// ratio of 3600 = 60.0 Hz; the reference's value / `full_scale` for a relative scale):
    /// the factor a tool that scales words by multiplying uses.
    pub fn step(&self) -> f64 {
        match self {
            Scale::Decimal { scale, .. } => scale.decode(1),
            Scale::Relative {
                full_scale,
                reference,
                ..
            } => reference / full_scale,
            Scale::Ratio { ratio, .. } => ratio.decode(1),
        }
    }

    /// The exact value of the raw integer `int` where [`Scale::decimals`] digits do not carry
    /// it: a ratio's, kept as a fraction (`3599/60` Hz). `None` for a decimal scale, which its
    /// digits show exactly, and a relative one, whose reference is a float.
    pub fn exact(&self, int: i64) -> Option<Fraction> {
        match self {
            Scale::Ratio { ratio, .. } => Some(ratio.exact(int)),
            Scale::Decimal { .. } | Scale::Relative { .. } => None,
        }
    }
}

/// How many rows of `plans` are writable: the length of their [`write_rules`].
pub const fn writable_count(plans: &[RegisterPlan]) -> usize {
    let (mut i, mut n) = (0, 0);
    while i < plans.len() {
        if plans[i].info.access.writable() {
            n += 1;
        }
        i += 1;
    }
    n
}

/// The write rules of the writable rows of `plans`, in order: a profile's write table
/// ([`crate::profile::Profile::writes`]) derived from the drive's plan, evaluated at compile time
/// (`static WRITES: [WriteRule; writable_count(REGISTERS)] = write_rules(REGISTERS)`). `N` must
/// be [`writable_count`]; any other length is refused (a compile error in a constant).
pub const fn write_rules<const N: usize>(plans: &[RegisterPlan]) -> [WriteRule; N] {
    assert!(
        writable_count(plans) == N,
        "write_rules: N is not the number of writable rows"
    );
    let mut out = [WriteRule::rw("", 0, 0, 0); N];
    let (mut i, mut n) = (0, 0);
    while i < plans.len() {
        if plans[i].info.access.writable() {
            out[n] = plans[i].write_rule();
            n += 1;
        }
        i += 1;
    }
    out
}

impl RegisterPlan {
    /// A register on every transport, never broadcast, writable at any time, at its printed
    /// address only; `envelope` is the union of its raw ranges (see [`RegisterPlan::envelope`]).
    pub const fn new(
        info: RegisterInfo,
        unit: &'static str,
        conversion: Conversion,
        envelope: RawRange,
    ) -> RegisterPlan {
        RegisterPlan {
            info,
            unit,
            conversion,
            moves: &[],
            transports: Transports::ALL,
            broadcast: Broadcast::No,
            restriction: WriteRestriction::None,
            envelope,
            also_at: &[],
            repeat_needs_change: None,
            read_values: &[],
            read_param: None,
            limit: None,
            functions: Functions::ANY,
        }
    }

    /// A plain unsigned word without unit over its whole range ([`Conversion::WORD`], envelope
    /// `0 ..= 65535`), otherwise as [`RegisterPlan::new`]: the commonest row of a generated plan.
    pub const fn word(info: RegisterInfo) -> RegisterPlan {
        RegisterPlan::new(info, "", Conversion::WORD, RawRange::word(false))
    }

    /// The plan of a register that accepts only `functions` (its write rule too).
    pub const fn functions(self, functions: Functions) -> RegisterPlan {
        RegisterPlan { functions, ..self }
    }

    /// The plan of a register with an upper limit through another quantity.
    pub const fn limited(self, limit: RelativeLimit) -> RegisterPlan {
        RegisterPlan {
            limit: Some(limit),
            ..self
        }
    }

    /// The plan of a register that moves to other addresses (`also_at`: every target once).
    pub const fn moves(self, moves: &'static [Move], also_at: &'static [u16]) -> RegisterPlan {
        RegisterPlan {
            moves,
            also_at,
            ..self
        }
    }

    /// The plan of a register that exists only on `transports`.
    pub const fn on(self, transports: Transports) -> RegisterPlan {
        RegisterPlan { transports, ..self }
    }

    /// The plan of a register with broadcast use `broadcast`.
    pub const fn broadcast(self, broadcast: Broadcast) -> RegisterPlan {
        RegisterPlan { broadcast, ..self }
    }

    /// The plan of a register the drive accepts writes to only in some states.
    pub const fn restricted(self, restriction: WriteRestriction) -> RegisterPlan {
        RegisterPlan {
            restriction,
            ..self
        }
    }

    /// The plan of a register whose drive executes a value only when it differs from the
    /// previous write.
    pub const fn repeat_needs_change(self, rule: RepeatNeedsChange) -> RegisterPlan {
        RegisterPlan {
            repeat_needs_change: Some(rule),
            ..self
        }
    }

    /// The plan of a register whose words read mean `read_values`, while writes follow its
    /// conversion.
    pub const fn read_as(self, read_values: &'static [Label]) -> RegisterPlan {
        RegisterPlan {
            read_values,
            ..self
        }
    }

    /// The plan of a register whose reads return parameter `param` while writes set its own
    /// ([`RegisterPlan::read_param`]).
    pub const fn read_from(self, param: &'static str) -> RegisterPlan {
        RegisterPlan {
            read_param: Some(param),
            ..self
        }
    }

    /// The listed meaning of a word read from the register: by [`RegisterPlan::read_values`]
    /// when it has them, else by its conversion ([`RegisterPlan::label`]).
    pub fn read_label(&self, code: u16) -> Option<&'static Label> {
        if self.read_values.is_empty() {
            self.label(code)
        } else {
            self.read_values.iter().find(|v| v.code == code)
        }
    }

    /// The communication address with these settings on this transport (before the profile's
    /// per-transport offset): the first move whose condition holds, else the printed address.
    /// A setting not known holds no condition: for showing where a register usually is; what
    /// goes on the wire uses [`RegisterPlan::locate`], which refuses to guess.
    pub fn address_for(&self, settings: &impl SettingsView, transport: TransportKind) -> u16 {
        self.moves
            .iter()
            .find(|m| m.when.holds(settings, transport))
            .map_or(self.info.address, |m| m.address)
    }

    /// The communication address with these settings on this transport, refusing to guess:
    /// the first move whose condition holds, else the printed address, as
    /// [`RegisterPlan::address_for`] — but a move that depends on a setting whose code is not
    /// known (GPD 515 o2-09 not read) is an error, never passed over for the printed address
    /// (with o2-09 = 1 the printed address of the frequency reference is the operation command).
    /// A move listed before it that holds (an older firmware variant) still decides.
    pub fn locate(
        &self,
        settings: &impl SettingsView,
        transport: TransportKind,
    ) -> Result<u16, AddressUnknown> {
        for m in self.moves {
            if let Condition::Setting { selector, .. } = m.when
                && settings.code(selector.slot).is_none()
            {
                return Err(AddressUnknown {
                    register: self.info.id,
                    setting: selector.label,
                });
            }
            if m.when.holds(settings, transport) {
                return Ok(m.address);
            }
        }
        Ok(self.info.address)
    }

    /// Calls `each` with every setting this register's conversion and address read: the
    /// selecting parameters ([`Dependency::Code`]) and the quantities a relative scale refers to
    /// ([`Dependency::Quantity`]). For a selected scale only the case `settings` choose counts
    /// (every case while the selector's code is unknown). A setting may be reported twice.
    pub fn depends_on(&self, settings: &impl SettingsView, mut each: impl FnMut(Dependency)) {
        self.conversion.depends_on(settings, &mut each);
        for m in self.moves {
            if let Condition::Setting { selector, .. } = m.when {
                each(Dependency::Code(selector));
            }
        }
    }

    /// What the map allows when writing it, for the write gate.
    pub const fn write_rule(&self) -> WriteRule {
        WriteRule {
            register: self.info.id,
            access: self.info.access,
            broadcast: self.broadcast,
            transports: self.transports,
            address: self.info.address,
            also_at: self.also_at,
            raw: self.envelope,
            reserved: match self.conversion {
                Conversion::Bits { mask, .. } => !mask,
                _ => 0,
            },
            width: self.info.width,
            functions: self.functions,
            table: self.info.table,
        }
    }

    /// The integer a raw value read from the drive stands for (signed or not, one word or two).
    pub const fn int(&self, raw: u32) -> i64 {
        self.info.width.to_int(raw, self.signed())
    }

    /// The whole range of the register's word or pair: its limits where the manual prints none.
    pub const fn full_range(&self) -> RawRange {
        self.info.width.range(self.signed())
    }

    /// Whether the raw value is two's complement.
    pub const fn signed(&self) -> bool {
        match self.conversion {
            Conversion::Word { signed, .. }
            | Conversion::Decimal { signed, .. }
            | Conversion::Relative { signed, .. }
            | Conversion::Ratio { signed, .. }
            | Conversion::Selected { signed, .. } => signed,
            Conversion::Enum { .. } | Conversion::Bits { .. } | Conversion::Text { .. } => false,
        }
    }

    fn missing(&self, setting: Setting) -> ValueError {
        ValueError::MissingSetting {
            register: self.info.id,
            setting: setting.label,
        }
    }

    fn relative(&self, r: &Relative, settings: &impl SettingsView) -> Result<Scale, ValueError> {
        let reference = settings
            .quantity(r.reference.slot)
            .ok_or(self.missing(r.reference))?;
        Ok(Scale::Relative {
            full_scale: r.full_scale,
            reference,
            label: r.reference.label,
        })
    }

    /// The scale of a quantity in force with `settings`; `None` for words, codes and bits.
    pub fn scale(&self, settings: &impl SettingsView) -> Option<Result<Scale, ValueError>> {
        Some(match &self.conversion {
            Conversion::Decimal { scale, range, .. } => Ok(Scale::Decimal {
                scale: *scale,
                range: range.select(settings),
            }),
            Conversion::Relative { relative, .. } => self.relative(relative, settings),
            Conversion::Ratio { ratio, range, .. } => Ok(Scale::Ratio {
                ratio: *ratio,
                range: range.select(settings),
            }),
            Conversion::Selected {
                selector, cases, ..
            } => self.case(*selector, cases, settings),
            Conversion::Word { .. }
            | Conversion::Enum { .. }
            | Conversion::Bits { .. }
            | Conversion::Text { .. } => {
                return None;
            }
        })
    }

    fn case(
        &self,
        selector: Setting,
        cases: &[Case],
        settings: &impl SettingsView,
    ) -> Result<Scale, ValueError> {
        let code = settings.code(selector.slot).ok_or(self.missing(selector))?;
        let case = cases.iter().find(|c| c.codes.contains(&code)).ok_or(
            ValueError::UnsupportedSetting {
                register: self.info.id,
                setting: selector.label,
                code,
            },
        )?;
        match &case.scale {
            CaseScale::Decimal { scale, range } => Ok(Scale::Decimal {
                scale: *scale,
                range: *range,
            }),
            CaseScale::Relative(r) => self.relative(r, settings),
        }
    }

    /// The engineering value of a raw value (a word, or a pair joined) of a quantity register.
    pub fn decode_number(&self, raw: u32, settings: &impl SettingsView) -> Result<f64, ValueError> {
        if let Conversion::Text { .. } = self.conversion {
            return Err(ValueError::Text {
                register: self.info.id,
            });
        }
        let int = self.int(raw);
        match self.scale(settings) {
            Some(Ok(Scale::Decimal { scale, .. })) => Ok(scale.decode(int)),
            Some(Ok(Scale::Relative {
                full_scale,
                reference,
                ..
            })) => Ok(scale::decode_relative(int, full_scale, reference)),
            Some(Ok(Scale::Ratio { ratio, .. })) => Ok(ratio.decode(int)),
            Some(Err(e)) => Err(e),
            None => Ok(int as f64),
        }
    }

    /// The exact value of a raw value where the conversion is exact: a plain word, a decimal or
    /// a ratio scale (`Ok(None)` for a relative scale, whose reference is a float, and for
    /// codes and bits). [`RegisterPlan::decode_number`] gives the `f64` nearest to it.
    pub fn decode_exact(
        &self,
        raw: u32,
        settings: &impl SettingsView,
    ) -> Result<Option<Fraction>, ValueError> {
        let int = self.int(raw);
        Ok(match self.scale(settings) {
            Some(Ok(Scale::Decimal { scale, .. })) => Fraction::new(
                i128::from(int) * i128::from(scale.mantissa),
                10i128.pow(scale.exponent),
            ),
            Some(Ok(Scale::Ratio { ratio, .. })) => Some(ratio.exact(int)),
            Some(Ok(Scale::Relative { .. })) => None,
            Some(Err(e)) => return Err(e),
            None => match self.conversion {
                Conversion::Word { .. } => Some(Fraction::int(i128::from(int))),
                _ => None,
            },
        })
    }

    /// [`RegisterPlan::encode_number`] for an exact value (typed as `59.9` or `3599/60`): with a
    /// ratio scale the value is compared exactly with the counts, with no float involved; other
    /// conversions take its nearest `f64`.
    pub fn encode_exact(
        &self,
        value: Fraction,
        settings: &impl SettingsView,
    ) -> Result<u32, ValueError> {
        if let Some(Ok(Scale::Ratio { ratio, range })) = self.scale(settings) {
            self.check_limit(value.to_f64(), settings)?;
            let raw = ratio::encode_ratio_exact(self.info.id, self.unit, value, ratio, range)?;
            self.relative_max(settings)?;
            return Ok(self.info.width.from_int(raw));
        }
        self.encode_number(value.to_f64(), settings)
    }

    /// The quantity the register's limit through another quantity reads
    /// ([`RegisterPlan::limit`]): needed to write it, not to read it.
    pub fn limit_dependency(&self) -> Option<Dependency> {
        self.limit.map(|l| Dependency::Quantity(l.reference))
    }

    /// The upper limit in force through another quantity ([`RegisterPlan::limit`]), in the
    /// register's unit: `None` when the register has none; an error when the quantity is not
    /// in `settings` (a limit that cannot be checked refuses, it is never skipped).
    pub fn relative_max(&self, settings: &impl SettingsView) -> Result<Option<f64>, ValueError> {
        let Some(limit) = &self.limit else {
            return Ok(None);
        };
        let reference =
            settings
                .quantity(limit.reference.slot)
                .ok_or(ValueError::LimitNotKnown {
                    register: self.info.id,
                    setting: limit.reference.label,
                })?;
        // `percent / 100` first: exact for 100 % (and 50, 200, ...), so a value equal to the
        // reference is at the limit, not one rounding above it (59.983333333333334 × 100 / 100
        // is 59.98333333333333).
        Ok(Some(reference * (limit.percent / 100.0)))
    }

    /// Refuses `value` above the register's limit through another quantity, when that quantity
    /// is known (an unknown one is refused after the conversion, whose own errors come first).
    fn check_limit(&self, value: f64, settings: &impl SettingsView) -> Result<(), ValueError> {
        let (Some(limit), Ok(Some(max))) = (&self.limit, self.relative_max(settings)) else {
            return Ok(());
        };
        if value > max {
            return Err(ValueError::AboveLimit {
                register: self.info.id,
                value,
                max,
                unit: self.unit,
                percent: limit.percent,
                reference: limit.reference.label,
            });
        }
        Ok(())
    }

    /// The raw value (word, or pair) for an engineering value, checked against the range in
    /// force and the limit through another quantity ([`RegisterPlan::limit`]), sent as given:
    /// a value that is not a whole number of the register's steps is refused
    /// ([`ValueError::NotAStep`]; [`RegisterPlan::encode_number_with`] can round instead).
    pub fn encode_number(
        &self,
        value: f64,
        settings: &impl SettingsView,
    ) -> Result<u32, ValueError> {
        self.encode_number_with(value, settings, Rounding::Exact)
    }

    /// [`RegisterPlan::encode_number`] with a choice for values between two steps: every limit
    /// (range, limit through another quantity) is checked on the value given, then
    /// [`Rounding::Exact`] refuses it and [`Rounding::Nearest`] sends the nearest step.
    pub fn encode_number_with(
        &self,
        value: f64,
        settings: &impl SettingsView,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        if value.is_finite() {
            self.check_limit(value, settings)?;
        }
        let raw = self.convert(value, settings, rounding)?;
        // A limit that cannot be checked refuses the value; it is never skipped.
        self.relative_max(settings)?;
        Ok(raw)
    }

    fn convert(
        &self,
        value: f64,
        settings: &impl SettingsView,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        let (id, unit, words) = (self.info.id, self.unit, self.info.width);
        match self.scale(settings) {
            Some(Ok(Scale::Decimal { scale, range })) => {
                scale::encode_decimal_with(id, unit, value, scale, range, rounding)
                    .map(|i| words.from_int(i))
            }
            Some(Ok(Scale::Relative {
                full_scale,
                reference,
                label,
            })) => scale::encode_relative_with(
                id,
                label,
                unit,
                value,
                full_scale,
                reference,
                self.full_range(),
                rounding,
            )
            .map(|i| words.from_int(i)),
            Some(Ok(Scale::Ratio { ratio, range })) => {
                ratio::encode_ratio_with(id, unit, value, ratio, range, rounding)
                    .map(|i| words.from_int(i))
            }
            Some(Err(e)) => Err(e),
            None => {
                if !value.is_finite() {
                    return Err(ValueError::NotFinite {
                        register: id,
                        value,
                    });
                }
                match scale::round(value) {
                    Some(raw) if raw as f64 == value => self.encode_word(raw, settings),
                    Some(raw) if rounding == Rounding::Nearest => {
                        // The range on the value given: both whole numbers around it must be
                        // in range, so a value below the minimum is not rounded into it.
                        let floor = if (raw as f64) > value { raw - 1 } else { raw };
                        self.encode_word(floor, settings)?;
                        self.encode_word(floor + 1, settings)?;
                        self.encode_word(raw, settings)
                    }
                    _ => Err(ValueError::NotWhole {
                        register: id,
                        value,
                    }),
                }
            }
        }
    }

    /// The raw value (word, or pair) for a plain integer, checked against the range in force.
    pub fn encode_word(&self, raw: i64, settings: &impl SettingsView) -> Result<u32, ValueError> {
        let range = match &self.conversion {
            Conversion::Word { range, .. } => range.select(settings),
            Conversion::Enum { .. } => return self.encode_code(u16::try_from(raw).ok(), raw),
            Conversion::Text { .. } => {
                return Err(ValueError::Text {
                    register: self.info.id,
                });
            }
            Conversion::Bits { mask, .. } => {
                return match u16::try_from(raw) {
                    Ok(word) if word & !mask == 0 => Ok(u32::from(word)),
                    _ => Err(ValueError::OutOfRange {
                        register: self.info.id,
                        value: raw as f64,
                        min: 0.0,
                        max: f64::from(*mask),
                        unit: "(reserved bits set)",
                    }),
                };
            }
            Conversion::Decimal { .. }
            | Conversion::Relative { .. }
            | Conversion::Ratio { .. }
            | Conversion::Selected { .. } => return self.encode_number(raw as f64, settings),
        };
        scale::encode_int(self.info.id, self.unit, raw, range).map(|i| self.info.width.from_int(i))
    }

    fn encode_code(&self, code: Option<u16>, raw: i64) -> Result<u32, ValueError> {
        match code {
            Some(code) if self.code_allowed(code) => Ok(u32::from(code)),
            _ => Err(ValueError::UnknownCode {
                register: self.info.id,
                code: raw.clamp(0, i64::from(u16::MAX)) as u16,
            }),
        }
    }

    /// Whether an enumeration code may be written: listed, or inside the printed code range.
    pub fn code_allowed(&self, code: u16) -> bool {
        match &self.conversion {
            Conversion::Enum { values, unlisted } => {
                values.iter().any(|v| v.code == code)
                    || unlisted.is_some_and(|r| r.contains(i64::from(code)))
            }
            _ => true,
        }
    }

    /// The listed meaning of an enumeration code.
    pub fn label(&self, code: u16) -> Option<&'static Label> {
        match &self.conversion {
            Conversion::Enum { values, .. } => values.iter().find(|v| v.code == code),
            _ => None,
        }
    }

    /// The listed codes of an enumeration register (none for other kinds).
    pub const fn labels(&self) -> &'static [Label] {
        match self.conversion {
            Conversion::Enum { values, .. } => values,
            _ => &[],
        }
    }

    /// The listed codes of field `index` of a bit-field register (none for other kinds).
    pub const fn field_labels(&self, index: usize) -> &'static [Label] {
        match self.conversion {
            Conversion::Bits { fields, .. } if index < fields.len() => fields[index].values,
            _ => &[],
        }
    }

    /// A field of a bit-field register by id.
    pub fn field(&self, id: &str) -> Option<&'static Field> {
        match &self.conversion {
            Conversion::Bits { fields, .. } => fields.iter().find(|f| f.id == id),
            _ => None,
        }
    }
}

/// A drive's typed value of one register: `f64`, `u16`, `i16`, `u32`, `i32`, or a generated
/// enumeration or bit-field type. Conversions follow the register's [`RegisterPlan`]; the raw
/// value is the word, or a 32-bit pair's words joined in the map's order.
pub trait Value: Sized {
    /// The value of a raw value read from the drive.
    fn decode(
        raw: u32,
        plan: &RegisterPlan,
        settings: &impl SettingsView,
    ) -> Result<Self, ValueError>;
    /// The value of the words read from the drive (all [`crate::width::Width::count`] of
    /// them): a number's joined in the map's order ([`crate::width::Width::join`]), a text's
    /// decoded by [`crate::text`]. What the clients call.
    fn decode_words(
        words: &[u16],
        plan: &RegisterPlan,
        settings: &impl SettingsView,
    ) -> Result<Self, ValueError> {
        Self::decode(plan.info.width.join(words), plan, settings)
    }
    /// The raw value for the value, checked against the plan.
    fn encode(&self, plan: &RegisterPlan, settings: &impl SettingsView) -> Result<u32, ValueError>;
    /// [`Value::encode`] with a choice for a number between two steps of the register; codes,
    /// bit fields and integers have no such values, so only `f64` uses it.
    fn encode_with(
        &self,
        plan: &RegisterPlan,
        settings: &impl SettingsView,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        let _ = rounding;
        self.encode(plan, settings)
    }
}

impl Value for f64 {
    fn decode(
        raw: u32,
        plan: &RegisterPlan,
        settings: &impl SettingsView,
    ) -> Result<Self, ValueError> {
        plan.decode_number(raw, settings)
    }
    fn encode(&self, plan: &RegisterPlan, settings: &impl SettingsView) -> Result<u32, ValueError> {
        plan.encode_number(*self, settings)
    }
    fn encode_with(
        &self,
        plan: &RegisterPlan,
        settings: &impl SettingsView,
        rounding: Rounding,
    ) -> Result<u32, ValueError> {
        plan.encode_number_with(*self, settings, rounding)
    }
}

/// Plain integers: `u16`/`i16` for one word, `u32`/`i32` for a pair. Decoding takes the raw
/// bits at the type's width (the generator picks the type from the register's width and sign).
macro_rules! plain_value {
    ($($t:ty),*) => {$(
        impl Value for $t {
            fn decode(raw: u32, _: &RegisterPlan, _: &impl SettingsView) -> Result<Self, ValueError> {
                Ok(raw as $t)
            }
            fn encode(
                &self,
                plan: &RegisterPlan,
                settings: &impl SettingsView,
            ) -> Result<u32, ValueError> {
                plan.encode_word(i64::from(*self), settings)
            }
        }
    )*};
}
plain_value!(u16, i16, u32, i32);

/// A coil or discrete input: its raw value is 1 (on) or 0 (off); any other raw value read is
/// taken as on, as the Modbus bit it stands for.
impl Value for bool {
    fn decode(raw: u32, _: &RegisterPlan, _: &impl SettingsView) -> Result<Self, ValueError> {
        Ok(raw != 0)
    }
    fn encode(&self, plan: &RegisterPlan, settings: &impl SettingsView) -> Result<u32, ValueError> {
        plan.encode_word(i64::from(*self), settings)
    }
}

/// Enumeration and bit-field types: their word is their code (one register only).
impl<T: crate::register::Code> Value for T {
    fn decode(raw: u32, _: &RegisterPlan, _: &impl SettingsView) -> Result<Self, ValueError> {
        Ok(T::from_code(raw as u16))
    }
    fn encode(&self, plan: &RegisterPlan, _: &impl SettingsView) -> Result<u32, ValueError> {
        let code = self.code();
        plan.encode_code(
            Some(code).filter(|c| plan.code_allowed(*c)),
            i64::from(code),
        )
    }
}

/// Text read from a string register (`string:` in the map): `N` = 2 × its registers. Decoded
/// from all its words in the map's byte order, padding dropped; never a number, never written
/// (the map refuses a writable string; [`Value::encode`] refuses too).
impl<const N: usize> Value for crate::text::Text<N> {
    fn decode(_: u32, plan: &RegisterPlan, _: &impl SettingsView) -> Result<Self, ValueError> {
        Err(ValueError::Text {
            register: plan.info.id,
        })
    }
    fn decode_words(
        words: &[u16],
        plan: &RegisterPlan,
        _: &impl SettingsView,
    ) -> Result<Self, ValueError> {
        match plan.conversion {
            Conversion::Text { order } => Ok(crate::text::Text::decode(words, order)),
            _ => Err(ValueError::Text {
                register: plan.info.id,
            }),
        }
    }
    fn encode(&self, plan: &RegisterPlan, _: &impl SettingsView) -> Result<u32, ValueError> {
        Err(ValueError::Text {
            register: plan.info.id,
        })
    }
}
