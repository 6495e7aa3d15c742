//! The typed part of a register's facts ([`RegisterFacts::data`](super::RegisterFacts::data)):
//! the numbers, codes and citations beside the worded rows, for a printer that writes values
//! rather than words (the JSON export, `drivemap-export/1`, is a mapping of it).
//!
//! What the lowered plan decides is taken from the plan: access, table, width, write
//! restriction, the codes of an enumeration and the bits of fields, the raw value a repeated
//! write is separated by. What the plan holds only as raw counts is taken as the map writes
//! it, in engineering units: scales, limits and defaults; with the citations and the map's
//! own records (notes, conflicts, unknowns, alternative addresses, display steps).

use drivemap_core::plan::{Conversion, Field, Label};
use drivemap_core::ratio::Fraction;
use drivemap_core::register::{Access, Table, WriteRestriction};
use drivemap_core::rule::Transports;
use drivemap_core::width::Width;

use crate::ir::{Drive, Register, ValueKind};
use crate::model::{
    AddressAlternative, Conflict, DefaultValue, DisplayStep, Reference, Scale, TransportName,
    Unknown,
};

/// A register's facts as values: see the [module](self).
#[derive(Debug, Clone, PartialEq)]
pub struct RegisterData {
    /// Access from the plan.
    pub access: Access,
    /// The Modbus table from the plan.
    pub table: Table,
    /// One register, or a 32-bit pair and its word order, from the plan.
    pub width: Width,
    /// Where the manual states a pair's word order, when not on the register's row.
    pub word_order_source: Option<String>,
    /// Only reachable as a broadcast (slave 0) write.
    pub broadcast: bool,
    /// When the drive accepts a write, from the plan.
    pub write_restriction: WriteRestriction,
    /// The transports the map lists for it (`None`: every transport of the drive).
    pub transports: Option<Vec<TransportName>>,
    /// The transports it exists on, from the plan.
    pub exists_on: Transports,
    /// The unit as the manual prints it.
    pub unit: Option<String>,
    /// A signed word or pair.
    pub signed: bool,
    /// The scale in engineering units.
    pub scale: ScaleData,
    /// The base variant's lower limit in engineering units.
    pub min: Option<f64>,
    /// The base variant's upper limit in engineering units.
    pub max: Option<f64>,
    /// The base variant's default, or what it depends on.
    pub default: Option<DefaultValue>,
    /// What each variant option gives, in the map's order of options (sorted by id).
    pub by_variant: Vec<VariantData>,
    /// Bit fields, from the plan.
    pub fields: &'static [Field],
    /// Enumeration codes, from the plan (empty for any other kind of value).
    pub values: &'static [Label],
    /// What a read means when it differs from a write, from the plan.
    pub read_values: &'static [Label],
    /// A drive that executes a written value only when it changed.
    pub repeat_needs_change: Option<RepeatData>,
    /// The functions it accepts, where the map restricts them.
    pub function_codes: Option<FunctionsData>,
    /// An upper limit through another quantity.
    pub max_relative: Option<LimitData>,
    /// The id of its group.
    pub group: String,
    /// Addresses it moves to under a condition, cited.
    pub address_alternatives: Vec<AddressAlternative>,
    /// How the keypad shows finer values.
    pub display_steps: Vec<DisplayStep>,
    /// Conflicts between readings of the manual about it.
    pub conflicts: Vec<Conflict>,
    /// What the manual leaves unknown about it.
    pub unknown: Vec<Unknown>,
}

/// A scale in engineering units, as the map writes it.
#[derive(Debug, Clone, PartialEq)]
pub enum ScaleData {
    /// None: an enumeration or bit fields.
    None,
    /// Engineering value = raw × factor; 1 for a plain word or a unit without a scale.
    Factor(f64),
    /// `full_scale` raw = 100 % of `reference`.
    Relative {
        /// The quantity 100 % refers to.
        reference: Quantity,
        /// The raw value that is 100 %.
        full_scale: f64,
    },
    /// `counts` raw = `equals` exactly; `step` is one count's exact value (`None` when the
    /// ratio is not one the core can hold).
    Ratio {
        /// Raw counts.
        counts: u32,
        /// What `counts` equal in engineering units.
        equals: f64,
        /// One count's exact value.
        step: Option<Fraction>,
    },
    /// Chosen by a setting, named as a user names it (`n152`, `C6-01.unit`).
    Selected {
        /// Who selects the scale, as a user names it.
        selector: String,
        /// The cases, in the map's order.
        cases: Vec<CaseData>,
    },
}

/// One case of a selected scale.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseData {
    /// The selector's codes that choose it.
    pub when: Vec<u16>,
    /// The case's scale.
    pub scale: ScaleData,
    /// The case's lower limit.
    pub min: Option<f64>,
    /// The case's upper limit.
    pub max: Option<f64>,
}

/// A quantity a scale or a limit is relative to.
#[derive(Debug, Clone, PartialEq)]
pub enum Quantity {
    /// A register of the drive: as the map names it, and as a user does (its parameter
    /// number when printed, else its id; the map's name when no register has it).
    Register {
        /// The register as the map names it.
        name: String,
        /// The register as a user names it.
        shown: String,
    },
    /// A quantity the application supplies.
    External {
        /// The quantity's name.
        external: String,
        /// Its unit.
        unit: String,
    },
}

/// What one variant option gives: its limits (the base's where it gives none) and default.
#[derive(Debug, Clone, PartialEq)]
pub struct VariantData {
    /// The variant option's id.
    pub option: String,
    /// Its lower limit (the base's where it gives none).
    pub min: Option<f64>,
    /// Its upper limit (the base's where it gives none).
    pub max: Option<f64>,
    /// Its default, when it overrides the base's.
    pub default: Option<DefaultValue>,
}

/// A drive that executes a written value only when it changed: the value written between
/// (as the map writes it, and raw from the plan) and the citation.
#[derive(Debug, Clone, PartialEq)]
pub struct RepeatData {
    /// The value written in between, in engineering units.
    pub between: f64,
    /// The same value as the raw word, from the plan.
    pub between_raw: Option<u32>,
    /// The rule's citation.
    pub source: String,
}

/// The functions a register accepts, the exception another is answered with, the citation.
#[derive(Debug, Clone, PartialEq)]
pub struct FunctionsData {
    /// The function codes accepted.
    pub codes: Vec<u8>,
    /// The exception code another function is answered with.
    pub refused_with: u8,
    /// The statement's citation.
    pub source: String,
}

/// An upper limit through another quantity: at most `percent` % of it.
#[derive(Debug, Clone, PartialEq)]
pub struct LimitData {
    /// The quantity the limit is relative to.
    pub relative_to: Quantity,
    /// The limit in percent of it.
    pub percent: f64,
    /// The limit's citation.
    pub source: String,
}

impl RegisterData {
    /// The typed facts of a register of `drive`.
    pub(crate) fn of(drive: &Drive, r: &Register) -> RegisterData {
        let d = &r.def;
        let plan = drive.register_plan(r);
        let (values, fields): (&'static [Label], &'static [Field]) = match plan.conversion {
            Conversion::Enum { values, .. } => (values, &[]),
            Conversion::Bits { fields, .. } => (&[], fields),
            _ => (&[], &[]),
        };
        RegisterData {
            access: plan.info.access,
            table: plan.info.table,
            width: plan.info.width,
            word_order_source: d.pair.as_ref().and_then(|p| p.source.clone()),
            broadcast: r.broadcast,
            write_restriction: plan.restriction,
            transports: r.transports.clone(),
            exists_on: plan.transports,
            unit: d.unit.clone(),
            signed: d.signed,
            scale: scale_data(drive, r),
            min: d.min,
            max: d.max,
            default: d.default.clone(),
            by_variant: d
                .by_variant
                .iter()
                .map(|(k, o)| {
                    let (min, max) = r.limits_for(k);
                    VariantData {
                        option: k.clone(),
                        min,
                        max,
                        default: o.default.clone(),
                    }
                })
                .collect(),
            fields,
            values,
            read_values: plan.read_values,
            repeat_needs_change: r.repeat_needs_change.as_ref().map(|(rule, _)| RepeatData {
                between: rule.between,
                between_raw: plan.repeat_needs_change.map(|x| x.between),
                source: rule.source.clone(),
            }),
            function_codes: r.function_codes.as_ref().map(|(f, _)| FunctionsData {
                codes: f.codes.clone(),
                refused_with: f.refusal(),
                source: f.source.clone(),
            }),
            max_relative: d.max_relative.as_ref().map(|l| LimitData {
                relative_to: quantity(drive, &l.relative_to),
                percent: l.percent,
                source: l.source.clone(),
            }),
            group: drive.group_of(r).id.clone(),
            address_alternatives: d.address_alternatives.clone(),
            display_steps: d.display_steps.clone(),
            conflicts: d.conflicts.clone(),
            unknown: d.unknown.clone(),
        }
    }
}

/// The scale of a register by the kind of its value: a plain word or a unit without a scale
/// is factor 1; codes and bits have none.
fn scale_data(drive: &Drive, r: &Register) -> ScaleData {
    match r.kind() {
        ValueKind::Quantity(scale) => scale_of(drive, scale),
        ValueKind::Word | ValueKind::UnitQuantity => ScaleData::Factor(1.0),
        ValueKind::Enum(_) | ValueKind::Bits(_) => ScaleData::None,
    }
}

pub(crate) fn scale_of(drive: &Drive, scale: &Scale) -> ScaleData {
    match scale {
        Scale::Factor(f) => ScaleData::Factor(*f),
        Scale::Relative(rel) => ScaleData::Relative {
            reference: quantity(drive, &rel.relative_to),
            full_scale: rel.full_scale,
        },
        Scale::Ratio(rs) => ScaleData::Ratio {
            counts: rs.counts,
            equals: rs.equals,
            step: crate::ratio::ratio_of(rs).map(|r| r.step()),
        },
        Scale::Selected(sel) => ScaleData::Selected {
            selector: drive
                .selector(&sel.selected_by)
                .map_or_else(|| sel.selected_by.clone(), |s| s.label()),
            cases: sel
                .cases
                .iter()
                .map(|c| CaseData {
                    when: c.when.clone(),
                    scale: scale_of(drive, &c.scale),
                    min: c.min,
                    max: c.max,
                })
                .collect(),
        },
    }
}

fn quantity(drive: &Drive, reference: &Reference) -> Quantity {
    match reference {
        Reference::Register(name) => Quantity::Register {
            name: name.clone(),
            shown: drive
                .find(name)
                .map(|r| r.def.param.clone().unwrap_or_else(|| r.def.id.clone()))
                .unwrap_or_else(|| name.clone()),
        },
        Reference::External(q) => Quantity::External {
            external: q.external.clone(),
            unit: q.unit.clone(),
        },
    }
}
