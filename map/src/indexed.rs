//! Indexed access (`indexed:` on a register): the register's value belongs to the entry selected
//! by an index written to another register. The schema types, and their lowering into the
//! vocabulary's [`drivemap_core::indexed::Indexed`]. Checked by
//! `validate/indexed_valid.rs`; documented in `maps/README.md` ("Indexed access").

use drivemap_core::indexed::{Entry as EntryPlan, Indexed as IndexedPlan};
use drivemap_core::plan::RegisterPlan;
use drivemap_core::rule::{Broadcast, WriteRule};
use drivemap_core::scale::{Decimal, RawRange, raw_of};
use drivemap_core::width::Width;
use serde::{Deserialize, Serialize};

use crate::ir::{Drive, Register};
use crate::model::Access;

/// `indexed:` on the value register.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Indexed {
    /// The register the index is written to (id or parameter number).
    pub by: String,
    /// The entries the manual lists, each selected by its `index`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub entries: Vec<Entry>,
    /// Why the list is missing or incomplete (the manual prints no list, or leaves indices
    /// out); required when `entries` is empty.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// `file:line` where the manual describes the index/value pair.
    pub source: String,
}

/// One entry reached through the pair.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// The index that selects it.
    pub index: u16,
    /// snake_case identifier, unique among the map's registers and entries.
    pub id: String,
    /// Parameter number as printed, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param: Option<String>,
    /// Name as printed.
    pub name: String,
    /// The unit as printed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// Decimal factor: engineering = raw × scale (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// A signed word.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub signed: bool,
    /// Lower limit in engineering units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Upper limit in engineering units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Access as printed (default: the value register's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub access: Option<Access>,
    /// `file:line` of its row in the manual.
    pub source: String,
    /// The map's notes on it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl Entry {
    /// Its decimal factor (`None`: not a decimal).
    pub(crate) fn factor(&self) -> Option<Decimal> {
        Decimal::from_f64(self.scale.unwrap_or(1.0))
    }

    /// Its raw limits (missing limits are the word's own); `None` when a limit is not a whole
    /// number of its steps or the scale is not a decimal.
    pub(crate) fn raw_limits(&self) -> Option<(i128, i128)> {
        let factor = self.factor()?;
        let word = RawRange::word(self.signed);
        let min = match self.min {
            Some(m) => raw_of(m, factor)?,
            None => i128::from(word.min),
        };
        let max = match self.max {
            Some(m) => raw_of(m, factor)?,
            None => i128::from(word.max),
        };
        Some((min, max))
    }

    /// Its access: as written, else the value register's.
    pub(crate) fn access_under(&self, register: &Register) -> Access {
        self.access.unwrap_or(register.access)
    }
}

fn leak<T>(v: Vec<T>) -> &'static [T] {
    Box::leak(v.into_boxed_slice())
}

fn text(s: &str) -> &'static str {
    Box::leak(s.to_owned().into_boxed_str())
}

/// Lowers every `indexed:` of a validated drive, in map order; `registers` is the lowered table.
/// Pairs whose index register does not resolve and entries whose scale or limits do not convert
/// are left out: validation has reported them.
pub(crate) fn lower(drive: &Drive, registers: &'static [RegisterPlan]) -> &'static [IndexedPlan] {
    let mut out = Vec::new();
    for r in &drive.registers {
        let Some(ix) = &r.def.indexed else { continue };
        let Some(index) = drive.find(&ix.by) else {
            continue;
        };
        let (Some(value_plan), Some(index_plan)) = (
            registers.iter().find(|p| p.info.id == r.id()),
            registers.iter().find(|p| p.info.id == index.id()),
        ) else {
            continue;
        };
        let mut entries = Vec::new();
        for e in &ix.entries {
            let (Some(factor), Some((min, max))) = (e.factor(), e.raw_limits()) else {
                continue;
            };
            let (Ok(min), Ok(max)) = (i64::try_from(min), i64::try_from(max)) else {
                continue;
            };
            let id = text(&e.id);
            let access = e.access_under(r);
            let range = RawRange::new(min, max);
            entries.push(EntryPlan {
                id,
                name: text(&e.name),
                index: e.index,
                unit: text(e.unit.as_deref().unwrap_or("")),
                signed: e.signed,
                scale: factor,
                range,
                access,
                rule: WriteRule {
                    register: id,
                    access,
                    broadcast: Broadcast::No,
                    transports: value_plan.transports,
                    address: value_plan.info.address,
                    also_at: &[],
                    raw: range,
                    reserved: 0,
                    width: Width::Word,
                    // Written to the value register: its functions.
                    functions: value_plan.functions,
                    table: value_plan.info.table,
                },
                source: text(&e.source),
            });
        }
        out.push(IndexedPlan {
            register: value_plan.info.id,
            value_address: value_plan.info.address,
            table: value_plan.info.table,
            index_register: index_plan.info.id,
            index_address: index_plan.info.address,
            index_readable: index_plan.info.access.readable(),
            index_range: index_plan.envelope,
            entries: leak(entries),
            unknown: ix.unknown.as_deref().map(text),
            source: text(&ix.source),
        });
    }
    leak(out)
}

/// The export of every index/value pair (`drivemap export`'s `indexed`): per pair the value
/// and index registers (ids, addresses), whether the index is read back, the index range, the
/// citation, the `unknown` reason and the entries, each with its engineering and raw limits.
pub(crate) fn export(drive: &Drive) -> serde_json::Value {
    use serde_json::json;
    let plan = drive.plan();
    let pairs: Vec<serde_json::Value> = drive
        .registers
        .iter()
        .filter_map(|r| Some((r, r.def.indexed.as_ref()?)))
        .map(|(r, ix)| {
            let lowered = plan.indexed.iter().find(|p| p.register == r.id());
            let entries: Vec<serde_json::Value> = ix
                .entries
                .iter()
                .map(|e| {
                    let raw = e.raw_limits();
                    json!({
                        "index": e.index,
                        "id": e.id,
                        "param": e.param,
                        "name": e.name,
                        "unit": e.unit,
                        "scale": e.scale.unwrap_or(1.0),
                        "signed": e.signed,
                        "min": e.min,
                        "max": e.max,
                        "raw_min": raw.map(|x| x.0 as i64),
                        "raw_max": raw.map(|x| x.1 as i64),
                        "access": match e.access_under(r) {
                            Access::Read => "r",
                            Access::Write => "w",
                            Access::ReadWrite => "rw",
                        },
                        "source": e.source,
                        "notes": e.notes,
                    })
                })
                .collect();
            json!({
                "register": r.id(),
                "value_address": r.def.address,
                "index_register": lowered.map_or(ix.by.as_str(), |p| p.index_register),
                "index_address": lowered.map(|p| p.index_address),
                "index_readable": lowered.map(|p| p.index_readable),
                "index_min": lowered.map(|p| p.index_range.min),
                "index_max": lowered.map(|p| p.index_range.max),
                "source": ix.source,
                "unknown": ix.unknown,
                "entries": entries,
            })
        })
        .collect();
    serde_json::Value::Array(pairs)
}
