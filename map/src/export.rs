//! The JSON export (`drivemap-export/1`) that other tools and review checks consume.
//!
//! Registers and protocol are the facts view's ([`crate::facts`]): each register's object is a
//! mapping of its [`RegisterData`](crate::facts::data::RegisterData) and identity, the
//! `protocol` object of the protocol rows' figures and entries and
//! [`ProtocolData`](crate::facts::ProtocolData), with no second walk of the map's registers or
//! protocol. Registers are listed by address (broadcast registers after the others). `min`, `max` and
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

use crate::facts::data::Quantity;
use drivemap_core::stated::ProtocolFact;

use crate::facts::{self, FactKey, Figure, ProtocolFacts, ProtocolKey, ProtocolRow, RegisterFacts};
use crate::ir::Drive;
use crate::model::DefaultValue;

/// The format name and version written in every export (`format`).
pub const FORMAT: &str = "drivemap-export/1";

/// Codes and their meanings: `[{"value": 0, "id": "stop", "name": "Stop"}]`.
fn labels(list: &[drivemap_core::plan::Label]) -> Value {
    Value::Array(
        list.iter()
            .map(|v| json!({"value": v.code, "id": v.id, "name": v.name}))
            .collect(),
    )
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
    let [scale, selected_by, relative_to, cases] = d.scale.export_columns();
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
        drivemap_core::width::Width::Word | drivemap_core::width::Width::Text(_) => None,
        drivemap_core::width::Width::Pair(order) => Some(order),
    };
    let mut out = json!({
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
                q @ Quantity::External { .. } => q.shown_json(),
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
    });
    // Only a string has the key, so the export of a map without strings is as it was.
    if let (Some(t), Some(obj)) = (&d.string, out.as_object_mut()) {
        obj.insert(
            "string".into(),
            json!({
                "registers": t.registers,
                "byte_order": t.byte_order.name(),
                "example": t.example,
                "source": t.source,
            }),
        );
    }
    // The Modicon reference the manual prints beside the register, after its address, only
    // where the map records one (`reference:`).
    if let (Some(reference), Value::Object(o)) = (f.get(FactKey::Reference), &mut out) {
        o.shift_insert(4, "reference".to_owned(), json!(reference.value));
    }
    // Only on a register read from another parameter than the one written (BICO), after
    // `param`: every other register's export is as before.
    if let (Some(p), Some(o)) = (&f.read_param, out.as_object_mut()) {
        let mut with = serde_json::Map::with_capacity(o.len() + 1);
        for (k, v) in std::mem::take(o) {
            let after_param = k == "param";
            with.insert(k, v);
            if after_param {
                with.insert("read_param".to_owned(), json!(p));
            }
        }
        *o = with;
    }
    out
}

fn table_name(t: drivemap_core::register::Table) -> &'static str {
    match t {
        drivemap_core::register::Table::Holding => "holding",
        drivemap_core::register::Table::Input => "input",
        drivemap_core::register::Table::Coil => "coil",
        drivemap_core::register::Table::DiscreteInput => "discrete_input",
    }
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

/// The export of one drive.
pub(crate) fn export(drive: &Drive) -> Value {
    let view = facts::facts(drive);
    let mut regs: Vec<&RegisterFacts> = view.registers.iter().collect();
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
        "protocol": protocol(&view.protocol),
        "groups": drive.groups.iter().map(|g| json!({"id": g.id, "name": g.name, "table": g.table, "source": g.source, "broadcast": g.broadcast})).collect::<Vec<_>>(),
        "registers": regs.into_iter().map(register).collect::<Vec<_>>(),
        "conflicts": drive.conflicts,
        "gaps": drive.gaps,
        "removed": drive.removed,
        "roles": drive.roles,
    });
    if !drive.examples.is_empty() {
        out["examples"] = json!(drive.examples.iter().map(example_json).collect::<Vec<_>>());
    }
    // The command profile as written (`profile:`), where the map gives one.
    if let Some(p) = &drive.profile {
        out["profile"] = json!(p);
    }
    // Index/value register pairs and their entries (an empty list when none).
    out["indexed"] = crate::indexed::export(drive);
    out
}

/// A row's entry (the map's object as written), null when the row is absent.
fn entry(view: &ProtocolFacts, key: ProtocolKey) -> Value {
    view.get(key).map_or(Value::Null, |r| r.entry.clone())
}

/// A row's working count (registers per read or write), null when absent.
fn count(view: &ProtocolFacts, key: ProtocolKey) -> Value {
    match view.get(key).map(|r| &r.figure) {
        Some(Figure::Count(n)) => json!(n),
        _ => Value::Null,
    }
}

/// The working list of function codes.
fn codes(view: &ProtocolFacts) -> Value {
    match view.get(ProtocolKey::FunctionCodes).map(|r| &r.figure) {
        Some(Figure::Codes(codes)) => json!(codes),
        _ => json!([]),
    }
}

/// The `protocol` object: a mapping of the protocol facts' figures and entries.
fn protocol(view: &ProtocolFacts) -> Value {
    let mut out = json!({
        "transports": entry(view, ProtocolKey::Transports),
        // The working list; `limits.function_codes` (when cited or not printed) says more.
        "function_codes": codes(view),
        // The working numbers; `limits` (when one is cited or not printed) says more.
        "max_read": count(view, ProtocolKey::MaxRead),
        "max_write": count(view, ProtocolKey::MaxWrite),

        "slave_address": entry(view, ProtocolKey::SlaveAddress),
        "broadcast": entry(view, ProtocolKey::Broadcast),
        "exceptions": view.data.exceptions,
        "commands": view.commands.iter().map(|c| c.entry.clone()).collect::<Vec<_>>(),
        "eeprom": entry(view, ProtocolKey::Eeprom),
        "addressing": entry(view, ProtocolKey::Addressing),
        "timing": entry(view, ProtocolKey::Timing),
        "serial": entry(view, ProtocolKey::Serial),
    });
    // Coils and discrete inputs per request: only in a map that states them (one with coils).
    for (name, key) in [
        ("max_read_bits", ProtocolKey::MaxReadBits),
        ("max_write_bits", ProtocolKey::MaxWriteBits),
    ] {
        if view.get(key).is_some() {
            out[name] = count(view, key);
        }
    }
    if let Some(b) = broadcast_not_printed(view) {
        out["broadcast"] = b;
    }
    serial_formats(view, &mut out["serial"]);
    let limits = limits(view);
    if !limits.is_empty() {
        out["limits"] = Value::Object(limits);
    }
    frame_gap_first(view, &mut out["timing"]);
    not_printed(view, &mut out);
    out
}

/// What the protocol's working figures rest on, when a map says more than the number: a
/// citation, or "not printed" with the reason.
fn limits(view: &ProtocolFacts) -> serde_json::Map<String, Value> {
    let stated = |r: &&ProtocolRow| r.citation.is_some() || r.not_printed.is_some();
    let why = |r: &ProtocolRow| r.not_printed.as_ref().map(|n| n.why.clone());
    let mut limits = serde_json::Map::new();
    if let Some(fc) = view.get(ProtocolKey::FunctionCodes).filter(stated) {
        limits.insert(
            "function_codes".into(),
            json!({"codes": codes(view), "source": fc.citation, "not_printed": why(fc)}),
        );
    }
    let (read, write) = (
        view.get(ProtocolKey::MaxRead),
        view.get(ProtocolKey::MaxWrite),
    );
    if let (Some(read), Some(write)) = (read, write)
        && (stated(&read) || stated(&write))
    {
        // A per-request limit: its working value (the Modbus one when the map gives none),
        // its citation and, when the manual prints none, the reason.
        for (name, l) in [("max_read", read), ("max_write", write)] {
            limits.insert(
                name.into(),
                json!({"value": count(view, l.key), "source": l.citation, "not_printed": why(l)}),
            );
        }
    }
    for (name, key) in [
        ("max_read_bits", ProtocolKey::MaxReadBits),
        ("max_write_bits", ProtocolKey::MaxWriteBits),
    ] {
        if let Some(l) = view.get(key).filter(stated) {
            limits.insert(
                name.into(),
                json!({"value": count(view, key), "source": l.citation, "not_printed": why(l)}),
            );
        }
    }
    limits
}

/// A broadcast whose rules are not printed: says so in the words of `doc`, with the reason.
fn broadcast_not_printed(view: &ProtocolFacts) -> Option<Value> {
    let b = view.get(ProtocolKey::Broadcast)?;
    let np = b.not_printed.as_ref()?;
    let Figure::Broadcast {
        functions,
        registers,
    } = &b.figure
    else {
        return None;
    };
    let source = b.citation.as_deref().unwrap_or_default();
    Some(json!({
        "functions": functions,
        "registers": registers,
        "source": source,
        "not_printed": np.why.trim(),
        "text": format!("{} ({source})", crate::describe::broadcast_not_printed(&np.why)),
    }))
}

/// Serial formats chosen by a parameter: each case with its data bits and its notation
/// (`8E1`); the line's single `stop_bits` does not apply then.
fn serial_formats(view: &ProtocolFacts, serial: &mut Value) {
    let Some(f) = serial["formats"].as_object().cloned() else {
        return;
    };
    let cases: Vec<Value> = (f["cases"].as_array().into_iter().flatten())
        .zip(&view.data.serial_formats)
        .map(|(c, x)| {
            json!({
                "when": c["when"],
                "data_bits": x.data_bits,
                "parity": c["parity"],
                "stop_bits": c["stop_bits"],
                "format": x.to_string(),
                "source": c["source"],
            })
        })
        .collect();
    if let Some(m) = serial.as_object_mut() {
        m.remove("stop_bits");
    }
    serial["formats"] = json!({
        "selected_by": f["selected_by"],
        "source": f["source"],
        "cases": cases,
    });
}

/// The working frame gap, given or the Modbus 3.5 characters, is always written (first, where
/// the model's serialization always had it).
fn frame_gap_first(view: &ProtocolFacts, timing: &mut Value) {
    let (Some(chars), Some(given)) = (view.data.frame_gap_chars, timing.as_object()) else {
        return;
    };
    let mut out = serde_json::Map::new();
    out.insert("frame_gap_chars".into(), json!(chars));
    for (k, v) in given {
        if k != "frame_gap_chars" {
            out.insert(k.clone(), v.clone());
        }
    }
    *timing = Value::Object(out);
}

/// The facts the manual does not print, written explicitly: `protocol.not_printed` maps each
/// fact's key (`slave_address`, `timing.frame_gap`) to `{why, source, used}` — `used` is what
/// the tools take in its place. The working figures stay where they always were (the slave
/// range as `min`/`max`, `timing.frame_gap_chars`), so a reader of the numbers alone keeps
/// working; each object marked not printed carries `not_printed: <why>` in place of the map's
/// `unknown`.
fn not_printed(view: &ProtocolFacts, out: &mut Value) {
    // The rows marked not printed, in the vocabulary's order of facts.
    let mut list: Vec<(ProtocolFact, &ProtocolRow, &str)> = view
        .rows
        .iter()
        .filter_map(|r| Some((r.key.fact()?, r, r.not_printed.as_ref()?.why.trim())))
        .collect();
    if list.is_empty() {
        return;
    }
    list.sort_by_key(|(fact, ..)| ProtocolFact::ALL.iter().position(|f| f == fact));
    if let Some(Figure::Range { min, max }) = view.get(ProtocolKey::SlaveAddress).map(|r| &r.figure)
    {
        out["slave_address"]["min"] = json!(min);
        out["slave_address"]["max"] = json!(max);
    }
    let mut facts = serde_json::Map::new();
    for (fact, row, why) in list {
        facts.insert(
            fact.key().into(),
            json!({"why": why, "source": row.citation, "used": fact.fallback()}),
        );
        // The object itself says so, in export's words (`not_printed`, as `limits` does).
        let mut at = &mut *out;
        for k in fact.key().split('.') {
            at = &mut at[k];
        }
        if let Some(o) = at.as_object_mut()
            && o.remove("unknown").is_some()
        {
            o.insert("not_printed".into(), json!(why));
        }
    }
    out["not_printed"] = Value::Object(facts);
}
