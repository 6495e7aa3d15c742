//! The facts view: what a map says about each register, decided once from the lowered plan and
//! the map's citations, as rows of `(label, value, citation)` that every printer reads as a
//! table (after chiptool's IR, which its printers read instead of the SVD).
//!
//! Values are worded by [`describe`] (a scale as `0.01 Hz`, a range as `0 ..= 400 Hz`), so a
//! printer only chooses which rows it shows and how it frames them: the rustdoc of generated
//! items (`drivemap-codegen`'s `generate/docs.rs`) reads [`RegisterFacts`] alone. The view is
//! [`serde::Serialize`], so a tool can take it as JSON ([`Map::facts`](crate::Map::facts)
//! gives a drive's, [`RegisterRef::facts`](crate::RegisterRef::facts) a register's).
//!
//! The protocol has its part ([`Map::protocol_facts`](crate::Map::protocol_facts),
//! [`ProtocolFacts`]): one [`ProtocolRow`] per fact, which `drivemap doc` prints and
//! `drivemap diff` compares key by key.
//!
//! Beside the worded view, the map's own records keep the types the map writes them in: who
//! the drive is, its protocol, groups, variants, roles, command profile and example frames, a
//! register's scale, limits, codes and fields with their citations, and every place that
//! cites a manual. [`WrittenMap`] and [`WrittenRegister`] name every key of a map and of a
//! register in them, for a tool that compares two maps (`drivemap diff`).
//!
//! A new kind of scale adds one [`ConversionKind`] in the vocabulary crate and its typed form
//! in [`data::ScaleData`], which words it (`scale_row`, this module, reads it): every printer
//! that reads the view shows it (`tests/tests/cross_crate/scale_kinds.rs`).

use serde::Serialize;

use drivemap_core::kind::ConversionKind;

pub mod data;

use crate::describe;
use crate::ir::{Drive, Register, ValueKind};

mod input;
mod protocol;
mod written;
/// Every place of a map that cites a manual ([`Map::citation_places`](crate::Map::citation_places)),
/// and the citations outside the registers' rows with what their lines must show
/// ([`Map::other_citations`](crate::Map::other_citations)).
pub use crate::citations::{CitationPlace, PlaceKind, Reason as CitationReason};
/// The map's own records, as it writes them: who the drive is, its protocol, groups, variants,
/// conflicts, gaps, removed registers, roles, the command profile, the example frames, and a
/// register's scale, limits, defaults, codes, fields, alternative addresses and unknowns.
pub use crate::command_profile::{
    PathSpec, PowerOnSpec, ProfileSpec, StateSpec, TransitionSpec, Word as ProfileWord,
};
pub use crate::examples::{Byte, Direction, Example, Says, hex_text, parse_bytes};
pub use crate::indexed::{Entry as IndexedEntry, Indexed};
pub use crate::ir::{Group, SerialDefaults};
pub use crate::model::{
    AddressAlternative, AddressFormat, Addressing, Broadcast, CodeRef, Codes, Command,
    CommandWrite, Condition, Conflict, DefaultValue, Dependency, DependentDefault, DisplayStep,
    Draft, DriveMeta, EdgeSpec, EdgeUnknown, Eeprom, EnumValue, ExceptionCode, Exceptions,
    ExternalQuantity, Field as BitField, FunctionCodes, Gap, Interval, Limit, Manual, Pair, Parity,
    Protocol, RatioScale, Reading, Reference, RegisterFunctions, RelativeLimit, RelativeScale,
    Removed, RepeatNeedsChange, RolePlace, Scale, ScaleCase, SelectedScale, Serial,
    SerialFormatCase, SerialFormats, SlaveAddress, StringText, Timing, TransportName, Unknown,
    UnknownItem, VariantAxis, VariantOption, VariantOverride,
};
pub use crate::others::{Other as OtherCitation, Rule as CitationRule};
pub use crate::stated::Unprinted;
/// Citations and bit fields as written: `file:line`, `<manual id>:p<page>`, a field's span.
pub use crate::validate::{field_span, parse_citation, parse_page_citation};
pub use data::RegisterData;
pub use input::InputBounds;
pub use protocol::{
    CommandFacts, ExceptionFacts, Figure, NotPrinted, ProtocolData, ProtocolFacts, ProtocolKey,
    ProtocolRow,
};
pub(crate) use protocol::{manual_address, protocol};
pub use written::{WrittenMap, WrittenRegister};

/// What a row of a register's facts says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FactKey {
    /// Where the register is: `0200h`, or a pair's span `0200h – 0201h`.
    Address,
    /// The Modicon reference the manual prints beside the register (`reference:`), as printed:
    /// `40024`. Only where the map records one.
    Reference,
    /// A 32-bit pair's width and word order (`32-bit pair, high word first`), cited.
    Width,
    /// Access from the plan: `read/write`.
    Access,
    /// Broadcast only (slave 0).
    Broadcast,
    /// The unit as the manual prints it.
    Unit,
    /// A fixed scale in engineering units: `0.01 Hz`, `30000 = 100 % of …`.
    Scale,
    /// Who selects the scale: `selected by C6-01` (the cases are [`RegisterFacts::cases`]).
    SelectedBy,
    /// The base variant's range: `0 ..= 400 Hz`.
    Range,
    /// The base variant's default: `5`, `depends on capacity`.
    Default,
    /// A limit through another quantity: `at most 100 % of n011 (file:line)`.
    RelativeLimit,
    /// When writes are accepted (shown when restricted).
    WriteRestriction,
    /// A drive that executes a written value only when it changed.
    RepeatNeedsChange,
    /// The functions the register accepts, where the map restricts them (`function_codes`).
    FunctionCodes,
    /// What a read means when it differs from a write: `0 Unlock, 1 Lock`.
    ReadValues,
    /// The parameter a read returns when it is not the one a write sets: `r0055.8 (writes
    /// set P2200)`.
    ReadParam,
    /// An alternative address (`0201h`), cited; its condition in [`Fact::when`].
    AlternativeAddress,
    /// How the keypad shows a finer value.
    DisplaySteps,
}

impl FactKey {
    /// The row's label as printers write it before the value (`scale 0.01 Hz`).
    pub const fn label(self) -> &'static str {
        match self {
            FactKey::Address => "address",
            FactKey::Reference => "Modicon reference",
            FactKey::Width => "width",
            FactKey::Access => "access",
            FactKey::Broadcast => "broadcast",
            FactKey::Unit => "unit",
            FactKey::Scale | FactKey::SelectedBy => "scale",
            FactKey::Range => "range",
            FactKey::Default => "default",
            FactKey::RelativeLimit => "limit",
            FactKey::WriteRestriction => "write restriction",
            FactKey::RepeatNeedsChange => "repeat needs change",
            FactKey::FunctionCodes => "function codes",
            FactKey::ReadValues => "read meaning",
            FactKey::ReadParam => "read from",
            FactKey::AlternativeAddress => "alternative address",
            FactKey::DisplaySteps => "display steps",
        }
    }
}

/// One row: what it says, its value in [`describe`]'s wording, and the manual line it rests on
/// when the map cites one for it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fact {
    /// What the row says.
    pub key: FactKey,
    /// The row's label as printers write it ([`FactKey::label`]).
    pub label: &'static str,
    /// The value in [`describe`]'s wording.
    pub value: String,
    /// The condition under which the row applies (an alternative address's `o2-09 is 1`).
    pub when: Option<String>,
    /// The manual line the row rests on, when the map cites one for it.
    pub citation: Option<String>,
}

impl Fact {
    fn new(key: FactKey, value: impl Into<String>, citation: Option<&str>) -> Fact {
        Fact {
            key,
            label: key.label(),
            value: value.into(),
            when: None,
            citation: citation.map(str::to_owned),
        }
    }
}

/// One case of a selected scale: the selector's codes, the scale and range they choose.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseFacts {
    /// The selector's codes that choose the case (`0`, `1, 2`).
    pub codes: String,
    /// The case's scale, worded.
    pub scale: String,
    /// The case's range, worded.
    pub range: String,
    /// The case's citation.
    pub citation: Option<String>,
}

/// What one variant option changes: its name, its range (the base's where it gives none) and
/// default when it overrides them, and what it leaves unknown.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VariantFacts {
    /// The variant option's id.
    pub option: String,
    /// The option's name as the map gives it.
    pub name: String,
    /// Its range, when it overrides the base's.
    pub range: Option<String>,
    /// Its default, when it overrides the base's.
    pub default: Option<String>,
    /// What it leaves unknown.
    pub unknowns: Vec<UnknownFacts>,
}

/// A conflict between readings of the manual and the one chosen.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConflictFacts {
    /// What the readings disagree on.
    pub topic: String,
    /// The citation of each reading.
    pub citations: Vec<String>,
    /// The reading the map follows.
    pub chosen: String,
    /// Why.
    pub reason: String,
}

/// An item the manual leaves unknown: the item (`range`) and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnknownFacts {
    /// The item left unknown (`range`, `default`).
    pub what: &'static str,
    /// Why the manual leaves it unknown.
    pub reason: String,
}

/// Everything the printers say about one register.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegisterFacts {
    /// The register's row in the drive plan.
    pub row: usize,
    /// The register id.
    pub id: String,
    /// The parameter number as printed (with `read_param`, the one a write sets).
    pub param: Option<String>,
    /// The parameter a read returns, when it is not `param` (Siemens BICO).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read_param: Option<String>,
    /// The name as printed.
    pub name: String,
    /// The communication address as the manual prints it.
    pub address: u16,
    /// The kind of conversion the plan decided.
    #[serde(serialize_with = "kind_name")]
    pub kind: ConversionKind,
    /// The rows, in the order printers show them.
    pub rows: Vec<Fact>,
    /// Who selects the scale, as a user names it (`C6-01`), for a selected scale.
    pub selector: Option<String>,
    /// The cases of a selected scale (none for any other).
    pub cases: Vec<CaseFacts>,
    /// What each variant option overrides.
    pub variants: Vec<VariantFacts>,
    /// The register's notes.
    pub notes: Vec<String>,
    /// Conflicts between readings of the manual about it.
    pub conflicts: Vec<ConflictFacts>,
    /// What the manual leaves unknown about it.
    pub unknowns: Vec<UnknownFacts>,
    /// The register's own citation.
    pub source: Option<String>,
    /// The same facts as values (numbers, codes, citations) for printers that write values:
    /// the JSON export reads them. Not part of this view's JSON (`export --format facts`),
    /// which is the worded rows; the export is their JSON.
    #[serde(skip)]
    pub data: data::RegisterData,
}

impl RegisterFacts {
    /// The first row with `key`.
    pub fn get(&self, key: FactKey) -> Option<&Fact> {
        self.rows.iter().find(|f| f.key == key)
    }

    /// Every row with `key`, in the map's order.
    pub fn all(&self, key: FactKey) -> impl Iterator<Item = &Fact> {
        self.rows.iter().filter(move |f| f.key == key)
    }
}

/// The facts of one drive: its registers in the map's order, then its protocol.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DriveFacts {
    /// The drive id.
    pub drive: String,
    /// Every register's facts, in the map's order.
    pub registers: Vec<RegisterFacts>,
    /// The protocol's facts.
    pub protocol: ProtocolFacts,
}

/// The facts of every register of a drive.
pub(crate) fn facts(drive: &Drive) -> DriveFacts {
    DriveFacts {
        drive: drive.meta.id.clone(),
        registers: drive.registers.iter().map(|r| register(drive, r)).collect(),
        protocol: protocol(drive),
    }
}

/// The scale row of a register, by the kind of its value: a fixed scale (a unit without a
/// scale is factor 1), or who selects it ([`data::ScaleData`] decides which); none for words,
/// codes and bits.
pub(crate) fn scale_row(drive: &Drive, r: &Register) -> Option<Fact> {
    let unit = r.def.unit.as_deref().unwrap_or("");
    let scale = match r.kind() {
        ValueKind::Quantity(scale) => data::scale_of(drive, scale),
        ValueKind::UnitQuantity => data::ScaleData::Factor(1.0),
        ValueKind::Word | ValueKind::Enum(_) | ValueKind::Bits(_) | ValueKind::Text(_) => {
            return None;
        }
    };
    let (key, value) = scale.row(unit)?;
    Some(Fact::new(key, value, None))
}

/// The rows of a register, in the order printers show them: one entry per key, absent where
/// the map says nothing of it.
fn rows(drive: &Drive, r: &Register) -> Vec<Fact> {
    use FactKey as K;
    let d = &r.def;
    let plan = drive.register_plan(r);
    let unit = d.unit.as_deref().unwrap_or("");
    let range = describe::range(d.min, d.max, unit);
    // In the notation the map gives its addresses: `0200h`, or `45 (002Dh)` in a map that
    // numbers its registers in decimal; a pair's or a string's span from its first to its last
    // word.
    let address = match (r.width().count(), drive.address_format) {
        (1, _) => manual_address(drive, d.address),
        (n, AddressFormat::Hex) => describe::address_span(d.address, d.address.wrapping_add(n - 1)),
        (n, AddressFormat::Decimal) => format!(
            "{} – {} ({})",
            d.address,
            d.address.wrapping_add(n - 1),
            describe::address_span(d.address, d.address.wrapping_add(n - 1))
        ),
    };
    let restricted = plan.restriction != drivemap_core::register::WriteRestriction::None;
    let table = [
        Some(Fact::new(K::Address, address, None)),
        (d.reference.as_deref()).map(|t| Fact::new(K::Reference, t, None)),
        (d.pair.as_ref())
            .map(|p| Fact::new(K::Width, describe::width(r.width()), p.source.as_deref()))
            .or_else(|| {
                let t = d.string.as_ref()?;
                let text = describe::text(t.registers, t.byte_order, t.example.as_deref());
                Some(Fact::new(K::Width, text, t.source.as_deref()))
            }),
        Some(Fact::new(
            K::Access,
            describe::access(plan.info.access),
            None,
        )),
        (d.read_param.as_ref()).map(|p| {
            let text = match &d.param {
                Some(w) => format!("{p} (writes set {w}; a write does not show in a read)"),
                None => p.clone(),
            };
            Fact::new(K::ReadParam, text, None)
        }),
        (r.broadcast).then(|| Fact::new(K::Broadcast, "broadcast only (slave 0)", None)),
        (d.unit.clone()).map(|u| Fact::new(K::Unit, u, None)),
        scale_row(drive, r),
        (!range.is_empty()).then(|| Fact::new(K::Range, range, None)),
        (d.default.as_ref()).map(|v| Fact::new(K::Default, describe::default(v), None)),
        (d.max_relative.as_ref()).map(|l| {
            let text = describe::relative_limit(drive, l);
            Fact::new(K::RelativeLimit, text, Some(&l.source))
        }),
        restricted.then(|| {
            let text = describe::write_restriction(plan.restriction);
            Fact::new(K::WriteRestriction, text, None)
        }),
        (r.repeat_needs_change.as_ref()).map(|(rule, _)| {
            let text = describe::repeat_needs_change(rule);
            Fact::new(K::RepeatNeedsChange, text, Some(&rule.source))
        }),
        (r.function_codes.as_ref()).map(|(f, _)| {
            Fact::new(
                K::FunctionCodes,
                describe::function_codes(f),
                Some(&f.source),
            )
        }),
        (!d.read_values.is_empty())
            .then(|| Fact::new(K::ReadValues, describe::read_values(&d.read_values), None)),
    ];
    let alternatives = d.address_alternatives.iter().map(|alt| Fact {
        when: Some(describe::condition(&alt.when)),
        ..Fact::new(
            K::AlternativeAddress,
            manual_address(drive, alt.address),
            Some(&alt.source),
        )
    });
    let steps = (!d.display_steps.is_empty()).then(|| {
        Fact::new(
            K::DisplaySteps,
            describe::display_steps(&d.display_steps),
            None,
        )
    });
    table
        .into_iter()
        .flatten()
        .chain(alternatives)
        .chain(steps)
        .collect()
}

/// The cases of a selected scale; none for any other.
fn cases(drive: &Drive, r: &Register) -> Vec<CaseFacts> {
    let unit = r.def.unit.as_deref().unwrap_or("");
    let Some(Scale::Selected(sel)) = &r.def.scale else {
        return Vec::new();
    };
    sel.cases
        .iter()
        .map(|c| CaseFacts {
            codes: describe::codes(&c.when),
            scale: describe::scale(drive, &c.scale, unit),
            range: describe::range(c.min, c.max, unit),
            citation: c.source.clone(),
        })
        .collect()
}

/// What each variant option overrides.
fn variants(drive: &Drive, r: &Register) -> Vec<VariantFacts> {
    let unit = r.def.unit.as_deref().unwrap_or("");
    r.def
        .by_variant
        .iter()
        .map(|(k, o)| {
            let (min, max) = r.limits_for(k);
            VariantFacts {
                option: k.clone(),
                name: drive
                    .variant_option(k)
                    .map(|(_, o)| o.name.clone())
                    .unwrap_or_else(|| k.clone()),
                range: (o.min.is_some() || o.max.is_some())
                    .then(|| describe::range(min, max, unit)),
                default: o.default.as_ref().map(describe::default),
                unknowns: o.unknown.iter().map(unknown).collect(),
            }
        })
        .collect()
}

/// The facts of one register of `drive` (a register of another map is a caller's mistake and
/// panics, as `Drive::register_plan` does).
pub(crate) fn register(drive: &Drive, r: &Register) -> RegisterFacts {
    let d = &r.def;
    RegisterFacts {
        row: drive.plan().order[r.index()],
        id: d.id.clone(),
        param: d.param.clone(),
        read_param: d.read_param.clone(),
        name: d.name.clone(),
        address: d.address,
        kind: ConversionKind::of(&drive.register_plan(r).conversion),
        rows: rows(drive, r),
        selector: match &d.scale {
            Some(Scale::Selected(sel)) => Some(describe::setting(drive, &sel.selected_by)),
            _ => None,
        },
        cases: cases(drive, r),
        variants: variants(drive, r),
        notes: d.notes.clone(),
        conflicts: d
            .conflicts
            .iter()
            .map(|c| ConflictFacts {
                topic: c.topic.clone(),
                citations: c.readings.iter().map(|r| r.source.clone()).collect(),
                chosen: c.chosen.clone(),
                reason: c.reason.clone(),
            })
            .collect(),
        unknowns: d.unknown.iter().map(unknown).collect(),
        source: d.source.clone(),
        data: data::RegisterData::of(drive, r),
    }
}

fn unknown(u: &crate::model::Unknown) -> UnknownFacts {
    UnknownFacts {
        what: describe::unknown_item(u.what),
        reason: u.reason.clone(),
    }
}

fn kind_name<S: serde::Serializer>(k: &ConversionKind, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(k.name())
}
