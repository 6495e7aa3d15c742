//! Which changes break applications built on the generated code, and why.
//!
//! A change is **breaking** when code compiled against the old map can stop compiling, or keeps
//! compiling but sends different words, reads values with a different meaning, or is refused
//! where it was accepted. Everything else — new registers, codes and capabilities, wider limits,
//! documentation and citations — is **compatible**. The rule is a function of the change kind
//! alone: the diff decides the direction (narrowed or widened) when it picks the kind.

use std::fmt;

/// How a change affects applications built on the generated code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// Code built on the old map may fail to compile or behave differently on the wire.
    Breaking,
    /// Existing code keeps compiling and behaving as before.
    Compatible,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Severity::Breaking => "breaking",
            Severity::Compatible => "compatible",
        })
    }
}

/// What changed between two maps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ChangeKind {
    /// A map that did not exist.
    DriveAdded,
    /// A map that no longer exists.
    DriveRemoved,
    /// Vendor, models, description or manuals.
    DriveMetaChanged,
    /// A new variant axis.
    VariantAxisAdded,
    /// A variant axis is gone.
    VariantAxisRemoved,
    /// A new option on an axis.
    VariantOptionAdded,
    /// An option is gone from an axis.
    VariantOptionRemoved,
    /// The first (base) option of an axis is another one.
    VariantBaseChanged,
    /// A transport the drive offers.
    TransportAdded,
    /// A transport the drive no longer offers.
    TransportRemoved,
    /// A function code the drive implements.
    FunctionCodeAdded,
    /// A function code the drive no longer implements.
    FunctionCodeRemoved,
    /// `max_read` or `max_write` raised.
    MaxRequestRaised,
    /// `max_read` or `max_write` lowered.
    MaxRequestLowered,
    /// More slave addresses accepted.
    SlaveRangeWidened,
    /// Fewer slave addresses accepted.
    SlaveRangeNarrowed,
    /// Broadcast accepts more functions or registers.
    BroadcastExtended,
    /// Broadcast accepts fewer functions or registers, or is gone.
    BroadcastRestricted,
    /// A drive-specific exception code.
    ExceptionAdded,
    /// A drive-specific exception code is gone.
    ExceptionRemoved,
    /// An exception's printed name or description.
    ExceptionReworded,
    /// A command (ENTER, ACCEPT, save).
    CommandAdded,
    /// A command is gone.
    CommandRemoved,
    /// A command writes other words or changes kind (persist / accept).
    CommandChanged,
    /// A command's printed name.
    CommandReworded,
    /// Per-transport address offsets.
    AddressingChanged,
    /// Frame gap, timeouts, response time.
    TimingChanged,
    /// Baud rates, parities, character format, EEPROM endurance.
    LineSettingsChanged,
    /// A register that did not exist.
    RegisterAdded,
    /// A register that no longer exists.
    RegisterRemoved,
    /// Same address and parameter number, another id.
    RegisterRenamed,
    /// Same id, another printed name.
    NameChanged,
    /// Same id, another parameter number.
    ParamChanged,
    /// Same id, another address.
    RegisterMoved,
    /// Addresses taken under a setting, variant or transport.
    AddressAlternativesChanged,
    /// Holding ↔ input table.
    TableChanged,
    /// Moved to another group of the manual.
    GroupChanged,
    /// Word, quantity, enumeration or bit fields: the value type changes.
    ValueKindChanged,
    /// Scale factor, reference or selection.
    ScaleChanged,
    /// A selector code that had no scale now has one.
    ScaleCaseAdded,
    /// Engineering unit.
    UnitChanged,
    /// Signed ↔ unsigned.
    SignednessChanged,
    /// One register ↔ a 32-bit pair, or the pair's word order.
    WidthChanged,
    /// A limit is stricter (higher minimum, lower maximum, a limit where there was none).
    RangeNarrowed,
    /// Limits are looser only.
    RangeWidened,
    /// Factory default.
    DefaultChanged,
    /// Read or write access lost.
    AccessNarrowed,
    /// Read or write access gained, none lost.
    AccessWidened,
    /// Writes accepted in fewer states (any time → stopped → PRG mode).
    WriteRestrictionTightened,
    /// Writes accepted in more states.
    WriteRestrictionRelaxed,
    /// `repeat_needs_change` added, removed, or another value written in between.
    RepeatNeedsChangeChanged,
    /// `function_codes` (the functions the register accepts) added, removed or changed.
    FunctionCodesChanged,
    /// `max_relative` (a limit through another quantity) added, removed or changed.
    RelativeLimitChanged,
    /// `read_values` (what a read means beside the write form) added, removed or changed.
    ReadMeaningChanged,
    /// `indexed:` (indexed access) added or removed, another index register, or an entry
    /// added, removed, re-indexed or converting otherwise.
    IndexedChanged,
    /// Available on fewer transports.
    TransportsNarrowed,
    /// Available on more transports.
    TransportsWidened,
    /// Moved into or out of the broadcast-only address space.
    BroadcastMembershipChanged,
    /// An enumeration code (register or multi-bit field).
    CodeAdded,
    /// An enumeration code is gone.
    CodeRemoved,
    /// Same code, another id.
    CodeRenamed,
    /// Same code and id, another printed meaning.
    CodeReworded,
    /// A bit field.
    FieldAdded,
    /// A bit field is gone.
    FieldRemoved,
    /// Same field id, other bits.
    FieldMoved,
    /// Same bits, another field id.
    FieldRenamed,
    /// Same field, another printed meaning.
    FieldReworded,
    /// A role the map did not give (`roles:`).
    RoleAdded,
    /// A role the map no longer gives.
    RoleRemoved,
    /// A role played by another register, field or quantity, or by other places.
    RoleRepointed,
    /// A role's codes (`on`, `off`), its `edge`, or the role it shares its place with
    /// (`shared_with`) changed.
    RoleCodesChanged,
    /// The `file:line` cited.
    CitationChanged,
    /// Notes, conflicts, unknowns, gaps, keypad display steps, removed-register reasons.
    DocumentationChanged,
}

impl ChangeKind {
    /// Every kind, in the order the classification table lists them.
    pub const ALL: &'static [ChangeKind] = &[
        ChangeKind::DriveAdded,
        ChangeKind::DriveRemoved,
        ChangeKind::DriveMetaChanged,
        ChangeKind::VariantAxisAdded,
        ChangeKind::VariantAxisRemoved,
        ChangeKind::VariantOptionAdded,
        ChangeKind::VariantOptionRemoved,
        ChangeKind::VariantBaseChanged,
        ChangeKind::TransportAdded,
        ChangeKind::TransportRemoved,
        ChangeKind::FunctionCodeAdded,
        ChangeKind::FunctionCodeRemoved,
        ChangeKind::MaxRequestRaised,
        ChangeKind::MaxRequestLowered,
        ChangeKind::SlaveRangeWidened,
        ChangeKind::SlaveRangeNarrowed,
        ChangeKind::BroadcastExtended,
        ChangeKind::BroadcastRestricted,
        ChangeKind::ExceptionAdded,
        ChangeKind::ExceptionRemoved,
        ChangeKind::ExceptionReworded,
        ChangeKind::CommandAdded,
        ChangeKind::CommandRemoved,
        ChangeKind::CommandChanged,
        ChangeKind::CommandReworded,
        ChangeKind::AddressingChanged,
        ChangeKind::TimingChanged,
        ChangeKind::LineSettingsChanged,
        ChangeKind::RegisterAdded,
        ChangeKind::RegisterRemoved,
        ChangeKind::RegisterRenamed,
        ChangeKind::NameChanged,
        ChangeKind::ParamChanged,
        ChangeKind::RegisterMoved,
        ChangeKind::AddressAlternativesChanged,
        ChangeKind::TableChanged,
        ChangeKind::GroupChanged,
        ChangeKind::ValueKindChanged,
        ChangeKind::ScaleChanged,
        ChangeKind::ScaleCaseAdded,
        ChangeKind::UnitChanged,
        ChangeKind::SignednessChanged,
        ChangeKind::WidthChanged,
        ChangeKind::RangeNarrowed,
        ChangeKind::RangeWidened,
        ChangeKind::DefaultChanged,
        ChangeKind::AccessNarrowed,
        ChangeKind::AccessWidened,
        ChangeKind::WriteRestrictionTightened,
        ChangeKind::WriteRestrictionRelaxed,
        ChangeKind::RepeatNeedsChangeChanged,
        ChangeKind::FunctionCodesChanged,
        ChangeKind::RelativeLimitChanged,
        ChangeKind::ReadMeaningChanged,
        ChangeKind::IndexedChanged,
        ChangeKind::TransportsNarrowed,
        ChangeKind::TransportsWidened,
        ChangeKind::BroadcastMembershipChanged,
        ChangeKind::CodeAdded,
        ChangeKind::CodeRemoved,
        ChangeKind::CodeRenamed,
        ChangeKind::CodeReworded,
        ChangeKind::FieldAdded,
        ChangeKind::FieldRemoved,
        ChangeKind::FieldMoved,
        ChangeKind::FieldRenamed,
        ChangeKind::FieldReworded,
        ChangeKind::RoleAdded,
        ChangeKind::RoleRemoved,
        ChangeKind::RoleRepointed,
        ChangeKind::RoleCodesChanged,
        ChangeKind::CitationChanged,
        ChangeKind::DocumentationChanged,
    ];

    /// A short label for output (`scale changed`).
    pub fn label(self) -> &'static str {
        use ChangeKind::*;
        match self {
            DriveAdded => "drive added",
            DriveRemoved => "drive removed",
            DriveMetaChanged => "drive description changed",
            VariantAxisAdded => "variant axis added",
            VariantAxisRemoved => "variant axis removed",
            VariantOptionAdded => "variant option added",
            VariantOptionRemoved => "variant option removed",
            VariantBaseChanged => "base variant changed",
            TransportAdded => "transport added",
            TransportRemoved => "transport removed",
            FunctionCodeAdded => "function code added",
            FunctionCodeRemoved => "function code removed",
            MaxRequestRaised => "request size raised",
            MaxRequestLowered => "request size lowered",
            SlaveRangeWidened => "slave addresses widened",
            SlaveRangeNarrowed => "slave addresses narrowed",
            BroadcastExtended => "broadcast extended",
            BroadcastRestricted => "broadcast restricted",
            ExceptionAdded => "exception added",
            ExceptionRemoved => "exception removed",
            ExceptionReworded => "exception reworded",
            CommandAdded => "command added",
            CommandRemoved => "command removed",
            CommandChanged => "command changed",
            CommandReworded => "command reworded",
            AddressingChanged => "address offsets changed",
            TimingChanged => "timing changed",
            LineSettingsChanged => "line settings changed",
            RegisterAdded => "register added",
            RegisterRemoved => "register removed",
            RegisterRenamed => "register renamed",
            NameChanged => "printed name changed",
            ParamChanged => "parameter number changed",
            RegisterMoved => "register moved",
            AddressAlternativesChanged => "alternative addresses changed",
            TableChanged => "Modbus table changed",
            GroupChanged => "group changed",
            ValueKindChanged => "value kind changed",
            ScaleChanged => "scale changed",
            ScaleCaseAdded => "scale case added",
            UnitChanged => "unit changed",
            SignednessChanged => "signedness changed",
            WidthChanged => "width or word order changed",
            RangeNarrowed => "range narrowed",
            RangeWidened => "range widened",
            DefaultChanged => "default changed",
            AccessNarrowed => "access narrowed",
            AccessWidened => "access widened",
            WriteRestrictionTightened => "write restriction tightened",
            WriteRestrictionRelaxed => "write restriction relaxed",
            RepeatNeedsChangeChanged => "repeat-needs-change rule changed",
            FunctionCodesChanged => "accepted function codes changed",
            RelativeLimitChanged => "limit through another quantity changed",
            ReadMeaningChanged => "read meaning changed",
            IndexedChanged => "indexed access changed",
            TransportsNarrowed => "transports narrowed",
            TransportsWidened => "transports widened",
            BroadcastMembershipChanged => "broadcast membership changed",
            CodeAdded => "code added",
            CodeRemoved => "code removed",
            CodeRenamed => "code renamed",
            CodeReworded => "code meaning reworded",
            FieldAdded => "field added",
            FieldRemoved => "field removed",
            FieldMoved => "field moved",
            FieldRenamed => "field renamed",
            FieldReworded => "field meaning reworded",
            RoleAdded => "role added",
            RoleRemoved => "role removed",
            RoleRepointed => "role re-pointed",
            RoleCodesChanged => "role codes or sharing changed",
            CitationChanged => "citation changed",
            DocumentationChanged => "documentation changed",
        }
    }
}

/// The reason of a [`ChangeKind::TableChanged`] between two tables as `describe::table` names
/// them (`holding`, `coil`), naming their read functions; `None` for holding ↔ input, whose
/// reason is [`classify`]'s, and for a side that is not a table.
pub(crate) fn table_reason(old: Option<&str>, new: Option<&str>) -> Option<&'static str> {
    macro_rules! reads {
        ($a:literal, $b:literal) => {
            concat!(
                "reads use another function code and table (",
                $a,
                " → ",
                $b,
                "); the generated type's value changes between a word and a bit"
            )
        };
    }
    Some(match (old?, new?) {
        ("holding", "coil") => reads!("03h holding registers", "01h coils"),
        ("holding", "discrete input") => reads!("03h holding registers", "02h discrete inputs"),
        ("input", "coil") => reads!("04h input registers", "01h coils"),
        ("input", "discrete input") => reads!("04h input registers", "02h discrete inputs"),
        ("coil", "holding") => reads!("01h coils", "03h holding registers"),
        ("coil", "input") => reads!("01h coils", "04h input registers"),
        ("discrete input", "holding") => reads!("02h discrete inputs", "03h holding registers"),
        ("discrete input", "input") => reads!("02h discrete inputs", "04h input registers"),
        ("coil", "discrete input") => {
            "reads use another function code and table (01h coils → 02h discrete inputs)"
        }
        ("discrete input", "coil") => {
            "reads use another function code and table (02h discrete inputs → 01h coils)"
        }
        _ => return None,
    })
}

/// The severity of a change kind and the reason, in terms of the generated code.
pub fn classify(kind: ChangeKind) -> (Severity, &'static str) {
    use ChangeKind::*;
    use Severity::{Breaking as B, Compatible as C};
    match kind {
        DriveAdded => (C, "a new module; nothing built on the old maps uses it"),
        DriveRemoved => (B, "the generated module disappears"),
        DriveMetaChanged => (C, "documentation only"),
        VariantAxisAdded => (
            C,
            "a new Settings field whose default is the base option, which keeps the old limits",
        ),
        VariantAxisRemoved => (B, "the Settings field and its enum disappear"),
        VariantOptionAdded => (C, "a new option; existing choices keep their limits"),
        VariantOptionRemoved => (B, "the option's enum variant disappears"),
        VariantBaseChanged => (
            B,
            "Settings::default() selects another option and top-level limits describe it",
        ),
        TransportAdded => (C, "a new way to reach the drive; existing links unchanged"),
        TransportRemoved => (B, "applications on that transport lose the drive"),
        FunctionCodeAdded => (C, "the client accepts more requests"),
        FunctionCodeRemoved => (B, "the client refuses requests that use it"),
        MaxRequestRaised => (C, "requests that fitted still fit"),
        MaxRequestLowered => (B, "multi-register requests that fitted are refused"),
        SlaveRangeWidened => (C, "addresses that were accepted still are"),
        SlaveRangeNarrowed => (B, "some slave addresses are refused"),
        BroadcastExtended => (C, "broadcasts that were accepted still are"),
        BroadcastRestricted => (B, "some broadcasts are refused"),
        ExceptionAdded => (C, "one more exception code is named"),
        ExceptionRemoved => (
            B,
            "the drive's meaning of the code is no longer known to the profile",
        ),
        ExceptionReworded => (C, "message text only"),
        CommandAdded => (C, "a new persist(slave, id) command"),
        CommandRemoved => (B, "persist(slave, id) with its id is refused"),
        CommandChanged => (
            B,
            "the same command writes other words or counts EEPROM writes differently",
        ),
        CommandReworded => (C, "message text only"),
        AddressingChanged => (B, "every PDU address on that transport moves"),
        TimingChanged => (C, "link timing only; no type, value or address changes"),
        LineSettingsChanged => (
            C,
            "documentation of the line; the application opens the port",
        ),
        RegisterAdded => (C, "a new register type; existing ones unchanged"),
        RegisterRemoved => (B, "the register type disappears"),
        RegisterRenamed => (B, "the generated type name changes"),
        NameChanged => (
            C,
            "rustdoc and messages only; the type name comes from the id",
        ),
        ParamChanged => (
            C,
            "the type keeps its name; RegisterInfo::PARAM and look-ups by parameter number change",
        ),
        RegisterMoved => (B, "the same type reads and writes another address"),
        AddressAlternativesChanged => (
            B,
            "the address used under some setting, variant or transport changes",
        ),
        TableChanged => (B, "reads use another function code (03h ↔ 04h)"),
        GroupChanged => (C, "grouping is documentation; the type is unchanged"),
        ValueKindChanged => (B, "the register's value type changes"),
        ScaleChanged => (
            B,
            "the same engineering value becomes another raw word (or needs other settings)",
        ),
        ScaleCaseAdded => (C, "a selector code that had no scale now converts"),
        UnitChanged => (B, "the f64 the application passes means something else"),
        SignednessChanged => (B, "raw words above 7FFFh decode to other values"),
        WidthChanged => (
            B,
            "the value takes another number of registers or its words swap: every read and write of it changes",
        ),
        RangeNarrowed => (B, "values that were accepted are refused before sending"),
        RangeWidened => (C, "values that were accepted still are"),
        DefaultChanged => (
            C,
            "documentation of the factory setting; encoding and limits unchanged",
        ),
        AccessNarrowed => (B, "Readable or Writable is no longer implemented"),
        AccessWidened => (C, "a new capability; existing calls unchanged"),
        WriteRestrictionTightened => (B, "writes the drive accepted may now be refused by it"),
        WriteRestrictionRelaxed => (C, "writes that were accepted still are"),
        RelativeLimitChanged => (
            B,
            "values that were written may now be refused, or need another quantity read first",
        ),
        FunctionCodesChanged => (
            B,
            "a write may go out with another function, be refused, or a read be planned apart",
        ),
        RepeatNeedsChangeChanged => (
            B,
            "a write sends another sequence of words (an intermediate value first, or no longer)",
        ),
        IndexedChanged => (
            B,
            "entries are reached through another index, convert otherwise, or appear or disappear",
        ),
        ReadMeaningChanged => (
            B,
            "reads decode to another type or other codes, and writes may take another type",
        ),
        TransportsNarrowed => (B, "the register is missing on a transport it had"),
        TransportsWidened => (C, "available on more transports"),
        BroadcastMembershipChanged => (B, "slave-0 rules and address space change"),
        CodeAdded => (
            C,
            "a new enum variant; the code decoded as Unknown(code) before",
        ),
        CodeRemoved => (B, "the enum variant disappears and the code is refused"),
        CodeRenamed => (B, "the enum variant name changes"),
        CodeReworded => (C, "rustdoc and name() text only"),
        FieldAdded => (
            C,
            "a new field; bits it covers were reserved (written as 0)",
        ),
        FieldRemoved => (
            B,
            "the field accessor disappears and its bits become reserved",
        ),
        FieldMoved => (B, "the same field reads and writes other bits"),
        FieldRenamed => (B, "the field accessor name changes"),
        FieldReworded => (C, "rustdoc text only"),
        RoleAdded => (
            C,
            "the drive API gains a role it refused with Refusal::NoRole; existing calls unchanged",
        ),
        RoleRemoved => (
            B,
            "the drive API refuses the role (Refusal::NoRole) where it acted, and the simulator drops it",
        ),
        RoleRepointed => (
            B,
            "the drive API reads or writes another register, field or quantity for the role",
        ),
        RoleCodesChanged => (
            B,
            "the drive API writes or expects other codes for the role, acts on its transition otherwise, or refuses (or allows) setting it apart from the role it shares a register with",
        ),
        CitationChanged => (C, "a new citation; documentation only"),
        DocumentationChanged => (C, "documentation only"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_the_issue_names_is_classified_as_it_says() {
        use ChangeKind::*;
        for k in [
            RegisterRemoved,
            RegisterMoved,
            RegisterRenamed,
            ScaleChanged,
            UnitChanged,
            AccessNarrowed,
            RangeNarrowed,
            CodeRemoved,
            FieldRemoved,
            SignednessChanged,
            WidthChanged,
            RoleRemoved,
            RoleRepointed,
            RoleCodesChanged,
        ] {
            assert_eq!(classify(k).0, Severity::Breaking, "{k:?}");
        }
        for k in [
            RegisterAdded,
            CodeAdded,
            RangeWidened,
            CitationChanged,
            DocumentationChanged,
            NameChanged,
            RoleAdded,
        ] {
            assert_eq!(classify(k).0, Severity::Compatible, "{k:?}");
        }
    }

    #[test]
    fn every_kind_is_listed_once_with_a_label_and_a_reason() {
        let mut seen = std::collections::HashSet::new();
        for &k in ChangeKind::ALL {
            assert!(seen.insert(k), "{k:?} listed twice");
            assert!(!k.label().is_empty());
            assert!(!classify(k).1.is_empty());
        }
        // Each direction pair splits into one breaking and one compatible kind.
        use ChangeKind::*;
        for (narrow, wide) in [
            (RangeNarrowed, RangeWidened),
            (AccessNarrowed, AccessWidened),
            (MaxRequestLowered, MaxRequestRaised),
            (SlaveRangeNarrowed, SlaveRangeWidened),
            (BroadcastRestricted, BroadcastExtended),
            (WriteRestrictionTightened, WriteRestrictionRelaxed),
            (TransportsNarrowed, TransportsWidened),
            (FunctionCodeRemoved, FunctionCodeAdded),
        ] {
            assert_eq!(classify(narrow).0, Severity::Breaking);
            assert_eq!(classify(wide).0, Severity::Compatible);
        }
    }
}
