//! The typed part of a register's facts ([`RegisterFacts::data`](super::RegisterFacts::data)):
//! the numbers, codes and citations beside the worded rows, for a printer that writes values
//! rather than words (the JSON export, `drivemap-export/1`, is a mapping of it).
//!
//! What the lowered plan decides is taken from the plan: access, table, width, write
//! restriction, the codes of an enumeration and the bits of fields, the raw value a repeated
//! write is separated by. What the plan holds only as raw counts is taken as the map writes
//! it, in engineering units: scales, limits and defaults; with the citations and the map's
//! own records (notes, conflicts, unknowns, alternative addresses, display steps).
//!
//! [`ScaleData`] is where the map's side of a kind of scale is decided, once: `scale_of` is
//! the one match on the map's `scale:` forms, and every printer reads the typed scale's
//! methods rather than matching on its kind — its wording ([`ScaleData::describe`], the facts
//! view's row), the export's columns, the step of a number input ([`ScaleData::step`]), its
//! cases, the one factor a manual's row can show ([`ScaleData::factor`]) and how validation
//! checks the limits a map gives with it. A new kind of scale is a variant here and an arm in
//! each of these matches (the compiler names them), and no other file of this crate but the
//! model and lowering.

use serde_json::{Value, json};

use drivemap_core::plan::{Conversion, Field, Label};
use drivemap_core::ratio::Fraction;
use drivemap_core::register::{Access, Table, WriteRestriction};
use drivemap_core::rule::Transports;
use drivemap_core::width::Width;

use super::{FactKey, InputBounds};
use crate::describe;
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
    /// A string's registers, byte order, example and citation (`string:`); `None` for a
    /// number, codes or bits.
    pub string: Option<crate::model::StringText>,
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

/// A scale in engineering units, as the map writes it: see the [module](self) for what is
/// decided on it.
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
        /// Who selects it as documentation words it, after "selected by": `n152`, or
        /// `field unit (bits 0-3) of C6-01` for a field.
        selector_prose: String,
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
        /// The register's name as printed (`Max output frequency`), when a register has it.
        title: Option<String>,
    },
    /// A quantity the application supplies.
    External {
        /// The quantity's name.
        external: String,
        /// Its unit.
        unit: String,
        /// What it is (the motor's rated current).
        description: String,
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
            string: d.string.clone(),
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
        ValueKind::Enum(_) | ValueKind::Bits(_) | ValueKind::Text(_) => ScaleData::None,
    }
}

/// The typed form of a scale the map writes: the one match on the map's `scale:` forms.
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
            selector_prose: describe::setting(drive, &sel.selected_by),
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

/// A register or external quantity the map refers to (`relative_to`).
pub(crate) fn quantity(drive: &Drive, reference: &Reference) -> Quantity {
    match reference {
        Reference::Register(name) => {
            let target = drive.find(name);
            Quantity::Register {
                name: name.clone(),
                shown: target
                    .map(|r| r.def.param.clone().unwrap_or_else(|| r.def.id.clone()))
                    .unwrap_or_else(|| name.clone()),
                title: target.map(|r| r.def.name.clone()),
            }
        }
        Reference::External(q) => Quantity::External {
            external: q.external.clone(),
            unit: q.unit.clone(),
            description: q.description.clone(),
        },
    }
}

impl Quantity {
    /// How documentation words it: `Cn-02 (Max output frequency)`, or an external quantity's
    /// description and unit (`Motor rated current (A, external)`).
    pub fn describe(&self) -> String {
        match self {
            Quantity::Register {
                shown,
                title: Some(title),
                ..
            } => format!("{shown} ({title})"),
            Quantity::Register { name, .. } => name.clone(),
            Quantity::External {
                unit, description, ..
            } => format!("{description} ({unit}, external)"),
        }
    }

    /// The export's form: a register as shown (`"Cn-02"`), an external quantity as
    /// `{"external", "unit"}`.
    pub(crate) fn shown_json(&self) -> Value {
        match self {
            Quantity::Register { shown, .. } => json!(shown),
            Quantity::External { external, unit, .. } => {
                json!({"external": external, "unit": unit})
            }
        }
    }
}

/// How validation checks the `min`, `max` and `default` a map gives a register with a scale
/// ([`ScaleData::limits`]): a rule per kind of scale, decided with the kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Limits<'a> {
    /// Each a whole number of increments of the factor (a positive decimal) inside the word.
    Increments(f64),
    /// None in engineering units: the value is a share of another quantity, known only at run
    /// time, and no default is one; the raw count of 100 % (`full_scale`) must be positive.
    Share {
        /// The raw count that is 100 %.
        full_scale: f64,
    },
    /// Checked by the kind's own pass (a ratio's: `validate::ratio_scales`).
    OwnPass,
    /// Given in each case of a selected scale, by its own rule (a case cannot select again).
    Cases(&'a [CaseData]),
}

impl ScaleData {
    /// The scale in engineering units, as `doc`, the rustdoc and the diff word it: `0.01 Hz`
    /// (per count), `30000 = 100 % of Cn-02 (…)`, `3600 = 60 Hz (1/60 (≈0.016667) Hz per
    /// count, exact)`, or a selected scale with its cases (`selected by C6-01: 0 → 0.01 Hz;
    /// 1 → 0.1 Hz`); empty for none.
    pub fn describe(&self, unit: &str) -> String {
        match self {
            ScaleData::None => String::new(),
            ScaleData::Factor(f) => format!("{} {unit}", describe::num(*f))
                .trim_end()
                .to_owned(),
            ScaleData::Relative {
                reference,
                full_scale,
            } => format!(
                "{} = 100 % of {}",
                describe::num(*full_scale),
                reference.describe()
            ),
            ScaleData::Ratio { counts, equals, .. } => describe::ratio(
                &crate::model::RatioScale {
                    counts: *counts,
                    equals: *equals,
                },
                unit,
            ),
            ScaleData::Selected {
                selector_prose,
                cases,
                ..
            } => {
                let cases: Vec<String> = cases
                    .iter()
                    .map(|c| format!("{} → {}", describe::codes(&c.when), c.scale.describe(unit)))
                    .collect();
                format!("selected by {selector_prose}: {}", cases.join("; "))
            }
        }
    }

    /// The row of the facts view it gives: a fixed scale worded ([`FactKey::Scale`]), or who
    /// selects it ([`FactKey::SelectedBy`]: `selected by C6-01`; the cases are rows of their
    /// own); none for codes and bits.
    pub(crate) fn row(&self, unit: &str) -> Option<(FactKey, String)> {
        match self {
            ScaleData::None => None,
            ScaleData::Selected { selector_prose, .. } => {
                Some((FactKey::SelectedBy, format!("selected by {selector_prose}")))
            }
            ScaleData::Factor(_) | ScaleData::Relative { .. } | ScaleData::Ratio { .. } => {
                Some((FactKey::Scale, self.describe(unit)))
            }
        }
    }

    /// The finest step of the value in engineering units: the factor; one count of a ratio
    /// (`equals / counts`, the `f64` nearest to it: 1/60 Hz for 3600 = 60.0 Hz);
    /// [`InputBounds::RELATIVE_STEP`] for a share of another quantity, whose size depends on
    /// that quantity at run time; the finest of a selected scale's cases (infinite without
    /// cases); 1 for none.
    pub fn step(&self) -> f64 {
        match self {
            ScaleData::None => 1.0,
            ScaleData::Factor(f) => *f,
            ScaleData::Relative { .. } => InputBounds::RELATIVE_STEP,
            ScaleData::Ratio { counts, equals, .. } => equals / f64::from(*counts),
            ScaleData::Selected { cases, .. } => cases
                .iter()
                .map(|c| c.scale.step())
                .fold(f64::INFINITY, f64::min),
        }
    }

    /// The cases of a selected scale, in the map's order; none for any other.
    pub fn cases(&self) -> &[CaseData] {
        match self {
            ScaleData::Selected { cases, .. } => cases,
            ScaleData::None
            | ScaleData::Factor(_)
            | ScaleData::Relative { .. }
            | ScaleData::Ratio { .. } => &[],
        }
    }

    /// The scale as the one factor a manual's table row prints (what `drivemap import`
    /// compares): `Ok(None)` for none, `Ok(Some(factor))` for a fixed factor, else `Err`
    /// naming the kind of scale a row cannot show as one number (`a relative scale`).
    pub fn factor(&self) -> Result<Option<f64>, &'static str> {
        match self {
            ScaleData::None => Ok(None),
            ScaleData::Factor(f) => Ok(Some(*f)),
            ScaleData::Relative { .. } => Err("a relative scale"),
            ScaleData::Ratio { .. } => Err("a ratio scale"),
            ScaleData::Selected { .. } => Err("a scale selected by another parameter"),
        }
    }

    /// How validation checks the limits a map gives with it; `None` for codes and bits,
    /// which have rules of their own.
    pub(crate) fn limits(&self) -> Option<Limits<'_>> {
        Some(match self {
            ScaleData::None => return None,
            ScaleData::Factor(f) => Limits::Increments(*f),
            ScaleData::Relative { full_scale, .. } => Limits::Share {
                full_scale: *full_scale,
            },
            ScaleData::Ratio { .. } => Limits::OwnPass,
            ScaleData::Selected { cases, .. } => Limits::Cases(cases),
        })
    }

    /// The export's scale columns (`drivemap-export/1`): `scale` (a fixed factor, or a
    /// ratio's `{"counts", "equals", "step"}`), `scale_selected_by`, `scale_relative_to`
    /// (`{"reference", "full_scale"}`) and `scale_cases`, each null where it does not apply.
    pub(crate) fn export_columns(&self) -> [Value; 4] {
        match self {
            ScaleData::None => [Value::Null, Value::Null, Value::Null, Value::Null],
            ScaleData::Factor(x) => [json!(x), Value::Null, Value::Null, Value::Null],
            ScaleData::Relative {
                reference,
                full_scale,
            } => [
                Value::Null,
                Value::Null,
                json!({"reference": reference.shown_json(), "full_scale": full_scale}),
                Value::Null,
            ],
            ScaleData::Ratio {
                counts,
                equals,
                step,
            } => [
                ratio_json(*counts, *equals, *step),
                Value::Null,
                Value::Null,
                Value::Null,
            ],
            ScaleData::Selected {
                selector, cases, ..
            } => {
                let cases = cases
                    .iter()
                    .map(|c| json!({"when": c.when, "scale": c.scale.case_json(), "min": c.min, "max": c.max}))
                    .collect::<Vec<_>>();
                [Value::Null, json!(selector), Value::Null, json!(cases)]
            }
        }
    }

    /// A case's scale in the export: a factor, `{"relative_to", "full_scale"}`, a ratio; null
    /// for a selection (refused by validation) and none.
    fn case_json(&self) -> Value {
        match self {
            ScaleData::Factor(f) => json!(f),
            ScaleData::Relative {
                reference,
                full_scale,
            } => json!({"relative_to": reference.shown_json(), "full_scale": full_scale}),
            ScaleData::Ratio {
                counts,
                equals,
                step,
            } => ratio_json(*counts, *equals, *step),
            ScaleData::Selected { .. } | ScaleData::None => Value::Null,
        }
    }
}

/// A ratio scale in the export: `{"counts": 3600, "equals": 60.0, "step": "1/60"}` (the exact
/// value of one count as a fraction or a finite decimal).
fn ratio_json(counts: u32, equals: f64, step: Option<Fraction>) -> Value {
    let step = step.map(|s| {
        if s.is_decimal() {
            s.to_string()
        } else {
            format!("{}/{}", s.num, s.den)
        }
    });
    json!({"counts": counts, "equals": equals, "step": step})
}
