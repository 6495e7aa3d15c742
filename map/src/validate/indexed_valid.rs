//! `indexed:` (indexed access, [`crate::indexed`]): the register it is written on is a value
//! register (one plain holding word whose meaning is each entry's), `by` names another
//! writable holding register (the index register), every entry's index is one the index register
//! accepts, no index and no entry id is listed twice (nor an entry id taken by a register), each
//! entry's scale, limits and access convert and fit the value register, and every citation is
//! checked like a register's (by `citations_present`, which reads every citation place).

use std::collections::HashMap;

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register, ValueKind};
use crate::model::{Access, ModbusTable};
use crate::source::Path;

use super::identifiers_valid::is_identifier;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let mut ids: HashMap<String, Path> = HashMap::new();
    for r in &drive.registers {
        let Some(ix) = &r.def.indexed else { continue };
        let rid = Some(r.id());
        let path = r.key_path("indexed");
        value_register(drive, r, &path, out);
        if ix.entries.is_empty() && ix.unknown.is_none() {
            out.push(drive.error(
                &path,
                rid,
                "`indexed:` lists no entries and gives no `unknown:` reason: list the entries the manual prints, or say why it prints none",
            ));
        }
        let index = index_register(drive, r, &ix.by, &path.key("by"), out);
        let mut indices: HashMap<u16, Path> = HashMap::new();
        for (i, e) in ix.entries.iter().enumerate() {
            let p = path.key("entries").index(i);
            let mut refusals = Vec::new();
            if !is_identifier(&e.id) {
                refusals.push(("id", format!("entry id `{}` is not snake_case (a-z, 0-9, single underscores, starting with a letter)", e.id)));
            }
            if let Some(first) = indices.get(&e.index) {
                let line = drive.locate(first).line;
                refusals.push(("index", format!("duplicate entry index {} (first at line {line}): one index selects one entry", e.index)));
            } else {
                indices.insert(e.index, p.key("index"));
            }
            if let Some(first) = ids.get(&e.id) {
                let line = drive.locate(first).line;
                refusals.push((
                    "id",
                    format!("duplicate entry id `{}` (first at line {line})", e.id),
                ));
            } else if let Some(other) = drive.registers.iter().find(|x| x.id() == e.id) {
                let (address, line) = (
                    crate::facts::manual_address(drive, other.def.address),
                    drive.locate(&other.path).line,
                );
                refusals.push(("id", format!("entry id `{}` is the id of register {address} (line {line}): entries and registers are looked up by the same names", e.id)));
            } else {
                ids.insert(e.id.clone(), p.key("id"));
            }
            if let Some((lo, hi)) = index
                && !(lo..=hi).contains(&i128::from(e.index))
            {
                refusals.push(("index", format!("entry index {} is outside the range of the index register `{}` ({lo}..={hi}): the drive refuses it", e.index, ix.by)));
            }
            refusals.extend(entry_values(r, e));
            // One diagnostic a refusal, at the entry's key it names (`""`: the entry itself).
            for (key, why) in refusals {
                let at = if key.is_empty() {
                    p.clone()
                } else {
                    p.key(key)
                };
                out.push(drive.error(&at, rid, why));
            }
        }
    }
}

/// The register `indexed:` is written on: one plain word of the holding table, its meaning
/// given by the entries.
fn value_register(drive: &Drive, r: &Register, path: &Path, out: &mut Vec<Diagnostic>) {
    let rid = Some(r.id());
    let why = if r.table != ModbusTable::Holding {
        Some("it is an input register, and an index selects through a written holding register")
    } else if r.def.pair.is_some() {
        Some("it is a 32-bit pair; entries are one word each")
    } else if !matches!(r.kind(), ValueKind::Word) {
        Some("it has its own scale, unit, codes or fields, while its meaning is each entry's")
    } else if r.def.min.is_some() || r.def.max.is_some() {
        Some("it has its own limits, while each entry has its own")
    } else {
        None
    };
    if let Some(why) = why {
        out.push(drive.error(
            path,
            rid,
            format!(
                "`indexed:` on `{}`, which is not a value register: {why}",
                r.id()
            ),
        ));
    }
}

/// The index register `by` names; its raw range when it resolves to a valid index register.
fn index_register(
    drive: &Drive,
    value: &Register,
    by: &str,
    path: &Path,
    out: &mut Vec<Diagnostic>,
) -> Option<(i128, i128)> {
    let rid = Some(value.id());
    let Some(index) = drive.find(by) else {
        out.push(drive.error(
            path,
            rid,
            format!("`by: {by}` names no register of this map (the index register)"),
        ));
        return None;
    };
    let why = if std::ptr::eq(index, value) {
        Some("it is the value register itself")
    } else if !index.writable() {
        Some("it is read-only, and the index is written")
    } else if index.table != ModbusTable::Holding || index.def.pair.is_some() {
        Some("it is not one holding word")
    } else if index.def.indexed.is_some() {
        Some("it is itself an indexed value register")
    } else {
        None
    };
    if let Some(why) = why {
        out.push(drive.error(
            path,
            rid,
            format!("`by: {by}` cannot be the index register: {why}"),
        ));
        return None;
    }
    let factor = index.factor()?;
    let limits = index.raw_limits(factor, index.def.min, index.def.max)?;
    Some((
        i128::from(limits.min.max(0)),
        i128::from(limits.max.min(i64::from(u16::MAX))),
    ))
}

/// What an entry's own values break: `(key, why)`, the key of the entry it names (`""` for
/// the entry itself). A scale that is no factor stops there (its limits cannot be converted).
fn entry_values(r: &Register, e: &crate::indexed::Entry) -> Vec<(&'static str, String)> {
    if e.scale.is_some_and(|s| !s.is_finite() || s <= 0.0) || e.factor().is_none() {
        let why = "an entry's scale is a positive decimal factor (0.1, 0.01, 1)";
        return vec![("scale", why.to_owned())];
    }
    let mut refusals = Vec::new();
    let sign = if e.signed { "signed" } else { "unsigned" };
    let word = if e.signed {
        i128::from(i16::MIN)..=i128::from(i16::MAX)
    } else {
        0..=i128::from(u16::MAX)
    };
    match e.raw_limits() {
        None => refusals.push((
            "",
            format!(
                "entry `{}`: its limits are not whole numbers of its steps ({})",
                e.id,
                e.scale.unwrap_or(1.0)
            ),
        )),
        Some((lo, hi)) if !word.contains(&lo) || !word.contains(&hi) => {
            refusals.push((
                "",
                format!("entry `{}`: its limits do not fit one {sign} word", e.id),
            ));
        }
        Some((lo, hi)) if lo > hi => {
            refusals.push(("min", format!("entry `{}`: min is above max", e.id)))
        }
        Some(_) => {}
    }
    let access = e.access_under(r);
    let (reads, writes) = (
        matches!(access, Access::Read | Access::ReadWrite),
        matches!(access, Access::Write | Access::ReadWrite),
    );
    if (reads && !r.readable()) || (writes && !r.writable()) {
        let (theirs, its) = (access_text(access), access_text(r.access));
        refusals.push((
            "access",
            format!(
                "entry `{}` is {theirs}, but the value register `{}` is {its}",
                e.id,
                r.id()
            ),
        ));
    }
    refusals
}

fn access_text(a: Access) -> &'static str {
    match a {
        Access::Read => "read-only",
        Access::Write => "write-only",
        Access::ReadWrite => "read/write",
    }
}
