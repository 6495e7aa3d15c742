//! The JSON export (`drivemap-export/1`) that other tools and review checks consume.
//!
//! Registers are the facts view's ([`crate::facts`]): each register's object is a mapping of
//! its [`RegisterData`](crate::facts::data::RegisterData) and identity, with no second walk of
//! the map's registers. They are listed by address (broadcast registers after the others). `min`, `max` and
//! `default` are engineering values of the base variant; `scale` is null where it depends on a
//! setting (`scale_selected_by` names the parameter, or `<parameter>.<field>` for a field of it)
//! or on another quantity (`scale_relative_to`). `drive.manuals` lists the names citations use;
//! `drive.manual_details` gives each manual's `file` or `id`, `title`, `document` and `url`.
//! `words` is 1, or 2 for a 32-bit value in two registers, whose `word_order` (`high_first` or
//! `low_first`) says which word sits at `address`; `min`/`max` are then limits of the 32-bit
//! value. Keys beyond the documented shape carry the rest of the map. `protocol.limits` (when
//! cited or not printed) gives `function_codes`, `max_read` and `max_write` with `source` and
//! `not_printed`; a broadcast whose rules are not printed has `broadcast.not_printed` and
//! `broadcast.text`; `serial.formats` (`selected_by`, `source`, `cases`: `when`, `data_bits`,
//! `parity`, `stop_bits`, `format` such as `8E1`, `source`) replaces `serial.stop_bits` when the
//! map lists the formats a parameter selects. `examples` (when the map has any) lists the manual's example frames: the
//! map's keys (`id`, `transport`, `direction`, `bytes` as printed, `source`, `answers`, `says`,
//! `conflict`, `notes`), `frame` (the bytes as numbers) and `text` (the line `doc` prints).

use serde_json::{Value, json};

use crate::facts::data::{Quantity, ScaleData};
use crate::facts::{self, RegisterFacts};
use crate::ir::Drive;
use crate::model::{self, DefaultValue};

pub const FORMAT: &str = "drivemap-export/1";

/// Codes and their meanings: `[{"value": 0, "id": "stop", "name": "Stop"}]`.
fn labels(list: &[drivemap_core::plan::Label]) -> Value {
    Value::Array(
        list.iter()
            .map(|v| json!({"value": v.code, "id": v.id, "name": v.name}))
            .collect(),
    )
}

/// A register by its shown name (`"Cn-02"`), or an external quantity.
fn shown(q: &Quantity) -> Value {
    match q {
        Quantity::Register { shown, .. } => json!(shown),
        Quantity::External { external, unit } => json!({"external": external, "unit": unit}),
    }
}

/// A case's scale: a factor, `{"relative_to", "full_scale"}`, a ratio; null for a selection.
fn scale_json(scale: &ScaleData) -> Value {
    match scale {
        ScaleData::Factor(f) => json!(f),
        ScaleData::Relative {
            reference,
            full_scale,
        } => json!({"relative_to": shown(reference), "full_scale": full_scale}),
        ScaleData::Ratio { .. } => ratio_json(scale),
        ScaleData::Selected { .. } | ScaleData::None => Value::Null,
    }
}

/// A ratio scale: `{"counts": 3600, "equals": 60.0, "step": "1/60"}` (the exact value of one
/// count as a fraction or a finite decimal).
fn ratio_json(scale: &ScaleData) -> Value {
    let ScaleData::Ratio {
        counts,
        equals,
        step,
    } = scale
    else {
        return Value::Null;
    };
    let step = step.map(|s| {
        if s.is_decimal() {
            s.to_string()
        } else {
            format!("{}/{}", s.num, s.den)
        }
    });
    json!({"counts": counts, "equals": equals, "step": step})
}

fn default_json(d: &Option<DefaultValue>) -> (Value, Value) {
    match d {
        Some(DefaultValue::Value(v)) => (json!(v), Value::Null),
        Some(DefaultValue::Depends(dep)) => (
            Value::Null,
            serde_json::to_value(dep.depends_on).unwrap_or(Value::Null),
        ),
        None => (Value::Null, Value::Null),
    }
}

/// The export's object of one register: a mapping of its facts' data.
fn register(f: &RegisterFacts) -> Value {
    let d = &f.data;
    // (scale, scale_selected_by, scale_relative_to, scale_cases)
    let (scale, selected_by, relative_to, cases) = match &d.scale {
        ScaleData::Factor(x) => (json!(x), Value::Null, Value::Null, Value::Null),
        ScaleData::Relative {
            reference,
            full_scale,
        } => (
            Value::Null,
            Value::Null,
            json!({"reference": shown(reference), "full_scale": full_scale}),
            Value::Null,
        ),
        ScaleData::Ratio { .. } => (ratio_json(&d.scale), Value::Null, Value::Null, Value::Null),
        ScaleData::Selected { selector, cases } => {
            let cases = cases
                .iter()
                .map(|c| json!({"when": c.when, "scale": scale_json(&c.scale), "min": c.min, "max": c.max}))
                .collect::<Vec<_>>();
            (Value::Null, json!(selector), Value::Null, json!(cases))
        }
        ScaleData::None => (Value::Null, Value::Null, Value::Null, Value::Null),
    };
    let fields: Vec<Value> = d
        .fields
        .iter()
        .map(|x| json!({"id": x.id, "name": x.name, "lsb": x.lsb, "width": x.width, "values": labels(x.values)}))
        .collect();
    let (default, depends_on) = default_json(&d.default);
    let by_variant: serde_json::Map<String, Value> = d
        .by_variant
        .iter()
        .map(|v| {
            let (dv, dep) = default_json(&v.default);
            (
                v.option.clone(),
                json!({"min": v.min, "max": v.max, "default": dv, "default_depends_on": dep}),
            )
        })
        .collect();
    let word_order = match d.width {
        drivemap_core::width::Width::Word => None,
        drivemap_core::width::Width::Pair(order) => Some(order),
    };
    json!({
        "id": f.id,
        "param": f.param,
        "name": f.name,
        "address": f.address,
        "access": d.access,
        "unit": d.unit,
        "scale": scale,
        "scale_selected_by": selected_by,
        "scale_cases": cases,
        "scale_relative_to": relative_to,
        "signed": d.signed,
        "words": d.width.count(),
        "word_order": word_order,
        "word_order_source": d.word_order_source,
        "min": if selected_by.is_null() { json!(d.min) } else { Value::Null },
        "max": if selected_by.is_null() { json!(d.max) } else { Value::Null },
        "default": default,
        "default_depends_on": depends_on,
        "by_variant": by_variant,
        "fields": fields,
        "values": labels(d.values),
        "read_values": labels(d.read_values),
        "repeat_needs_change": d.repeat_needs_change.as_ref().map(|x| json!({
            "between": x.between,
            "between_raw": x.between_raw,
            "source": x.source,
        })),
        "function_codes": d.function_codes.as_ref().map(|x| json!({
            "codes": x.codes,
            "refused_with": x.refused_with,
            "source": x.source,
        })),
        "max_relative": d.max_relative.as_ref().map(|l| json!({
            // As the map names it (`n011`), not as shown.
            "relative_to": match &l.relative_to {
                Quantity::Register { name, .. } => json!(name),
                q @ Quantity::External { .. } => shown(q),
            },
            "percent": l.percent,
            "source": l.source,
        })),
        "source": f.source,
        "group": d.group,
        "table": table_name(d.table),
        "broadcast": d.broadcast,
        "write_restriction": serde_json::to_value(d.write_restriction).unwrap_or(Value::Null),
        "transports": d.transports,
        "address_alternatives": d.address_alternatives,
        "display_steps": d.display_steps,
        "notes": f.notes,
        "conflicts": d.conflicts,
        "unknown": d.unknown,
    })
}

fn table_name(t: drivemap_core::register::Table) -> &'static str {
    match t {
        drivemap_core::register::Table::Holding => "holding",
        drivemap_core::register::Table::Input => "input",
    }
}

/// The export of one drive.
/// A per-request limit: its working value (the Modbus one when the map gives none), its
/// citation and, when the manual prints none, the reason.
fn limit_json(l: &model::Limit, working: u16) -> Value {
    json!({"value": working, "source": l.source, "not_printed": l.unknown})
}

/// An example frame: the map's keys (`bytes` as printed), the bytes as numbers (`frame`,
/// empty when the text is not hex bytes) and the line `doc` shows (`text`).
fn example_json(e: &crate::examples::Example) -> Value {
    let mut v = json!(e);
    v["frame"] = json!(
        crate::examples::parse_bytes(&e.bytes)
            .map(|b| b.iter().map(|b| b.value).collect::<Vec<u8>>())
            .unwrap_or_default()
    );
    v["text"] = json!(e.summary());
    v
}

pub fn export(drive: &Drive) -> Value {
    let p = &drive.protocol;
    let mut regs = facts::facts(drive).registers;
    regs.sort_by_key(|f| (f.data.broadcast, f.address));
    let mut out = json!({
        "format": FORMAT,
        "drive": {
            "id": drive.meta.id,
            "vendor": drive.meta.vendor,
            "models": drive.meta.models,
            // Names as citations give them (a text manual's file, a paged manual's id).
            "manuals": drive.meta.manuals.iter().map(|m| m.name()).collect::<Vec<_>>(),
            // Each manual in full: `file` or `id`, `title`, and `document`/`url` when given.
            "manual_details": drive.meta.manuals,
            "extends": drive.meta.extends,
            // How the manual numbers registers; `address` values are numbers either way.
            "address_format": drive.address_format,
        },
        "variants": drive.variants,
        "protocol": {
            "transports": p.transports,
            // The working list; `limits.function_codes` (when cited or not printed) says more.
            "function_codes": p.function_codes.codes,
            // The working numbers; `limits` (when one is cited or not printed) says more.
            "max_read": p.max_read(),
            "max_write": p.max_write(),

            "slave_address": p.slave_address,
            "broadcast": p.broadcast,
            "exceptions": p.exceptions,
            "commands": p.commands,
            "eeprom": p.eeprom,
            "addressing": p.addressing,
            "timing": p.timing,
            "serial": p.serial,
        },
        "groups": drive.groups.iter().map(|g| json!({"id": g.id, "name": g.name, "table": g.table, "source": g.source, "broadcast": g.broadcast})).collect::<Vec<_>>(),
        "registers": regs.iter().map(register).collect::<Vec<_>>(),
        "conflicts": drive.conflicts,
        "gaps": drive.gaps,
        "removed": drive.removed,
        "roles": drive.roles,
    });
    if !drive.examples.is_empty() {
        out["examples"] = json!(drive.examples.iter().map(example_json).collect::<Vec<_>>());
    }
    // What the protocol's working figures rest on, when a map says more than the number:
    // a citation, or "not printed" with the reason.
    let mut limits = serde_json::Map::new();
    let fc = &p.function_codes;
    if fc.stated() {
        limits.insert(
            "function_codes".into(),
            json!({"codes": fc.codes, "source": fc.source, "not_printed": fc.unknown}),
        );
    }
    let stated = |l: &model::Limit| l.source.is_some() || l.unknown.is_some();
    if stated(&p.max_read) || stated(&p.max_write) {
        limits.insert("max_read".into(), limit_json(&p.max_read, p.max_read()));
        limits.insert("max_write".into(), limit_json(&p.max_write, p.max_write()));
    }
    // A broadcast whose rules are not printed: says so in the words of `doc`, with the reason.
    if let Some(b) = &p.broadcast
        && let Some(why) = &b.unknown
    {
        out["protocol"]["broadcast"] = json!({
            "functions": b.functions,
            "registers": b.registers,
            "source": b.source,
            "not_printed": why.trim(),
            "text": format!("{} ({})", crate::describe::broadcast_not_printed(why), b.source),
        });
    }
    // Serial formats chosen by a parameter: each case with its data bits and its notation
    // (`8E1`); the line's single `stop_bits` does not apply then.
    if let Some(s) = &p.serial
        && let Some(f) = &s.formats
    {
        let cases: Vec<Value> = f
            .cases
            .iter()
            .zip(drive.serial_format_list())
            .map(|(c, x)| {
                json!({
                    "when": c.when,
                    "data_bits": x.data_bits,
                    "parity": c.parity,
                    "stop_bits": c.stop_bits,
                    "format": x.to_string(),
                    "source": c.source,
                })
            })
            .collect();
        let serial = &mut out["protocol"]["serial"];
        if let Some(m) = serial.as_object_mut() {
            m.remove("stop_bits");
        }
        serial["formats"] = json!({
            "selected_by": f.selected_by,
            "source": f.source,
            "cases": cases,
        });
    }
    if !limits.is_empty() {
        out["protocol"]["limits"] = Value::Object(limits);
    }
    // The working frame gap, given or the Modbus 3.5 characters, is always written.
    // (First, where the model's serialization always had it.)
    if let Some(t) = &p.timing
        && let Some(given) = out["protocol"]["timing"].as_object()
    {
        let mut timing = serde_json::Map::new();
        timing.insert("frame_gap_chars".into(), json!(t.frame_gap_chars()));
        for (k, v) in given {
            if k != "frame_gap_chars" {
                timing.insert(k.clone(), v.clone());
            }
        }
        out["protocol"]["timing"] = Value::Object(timing);
    }
    not_printed(p, &mut out["protocol"]);
    // Index/value register pairs and their entries (an empty list when none).
    out["indexed"] = crate::indexed::export(drive);
    out
}

/// The facts the manual does not print, written explicitly: `protocol.not_printed` maps each
/// fact's key (`slave_address`, `timing.frame_gap`) to `{why, source, used}` — `used` is what
/// the tools take in its place. The working figures stay where they always were (the slave
/// range as `min`/`max`, `timing.frame_gap_chars`), so a reader of the numbers alone keeps
/// working; each object marked not printed carries `not_printed: <why>` in place of the map's
/// `unknown`.
fn not_printed(p: &model::Protocol, out: &mut Value) {
    let list = crate::stated::unprinted(p);
    if list.is_empty() {
        return;
    }
    let (lo, hi) = p.slave_address.range();
    out["slave_address"]["min"] = json!(lo);
    out["slave_address"]["max"] = json!(hi);
    let mut facts = serde_json::Map::new();
    for u in list {
        facts.insert(
            u.fact.key().into(),
            json!({"why": u.why, "source": u.source, "used": u.fact.fallback()}),
        );
        // The object itself says so, in export's words (`not_printed`, as `limits` does).
        let mut at = &mut *out;
        for k in u.fact.key().split('.') {
            at = &mut at[k];
        }
        if let Some(o) = at.as_object_mut()
            && o.remove("unknown").is_some()
        {
            o.insert("not_printed".into(), json!(u.why));
        }
    }
    out["not_printed"] = Value::Object(facts);
}
