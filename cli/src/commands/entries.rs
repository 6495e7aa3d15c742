//! `drivemap read`/`write` of an entry of an indexed register (`indexed:` in the map: an index
//! written to one register selects what another shows) by the entry's id, parameter number or
//! printed name: `drivemap read --drive tarrow-tm44 acceleration_time`. The client writes the
//! index and reads or writes the value in one call (`drivemap_runtime::indexed`).

use std::process::ExitCode;

use drivemap_live::indexed::find_entry;
use drivemap_live::session::Session;
use drivemap_map::Map;
use drivemap_runtime::core::indexed::EntryRef;

use crate::error::Error;
use crate::live::Target;

/// The names that are entries of indexed registers and not registers, and the others.
pub(crate) fn split<'a>(drive: &Map, names: &'a [String]) -> (Vec<&'a String>, Vec<EntryRef>) {
    let mut registers = Vec::new();
    let mut entries = Vec::new();
    for n in names {
        match (
            drivemap_live::lookup::find(drive, n),
            find_entry(drive, n.trim()),
        ) {
            (Err(_), Some(e)) => entries.push(e),
            _ => registers.push(n),
        }
    }
    (registers, entries)
}

fn mixed() -> Error {
    Error::Refused(
        "name registers and entries of indexed registers in separate commands: an entry is reached through its index register".into(),
    )
}

fn what(e: EntryRef) -> String {
    format!(
        "entry {} of {} (index in {})",
        e.entry.index, e.pair.register, e.pair.index_register
    )
}

/// Reads `entries` (no register named with them) and prints one line each: id, value, unit and
/// the pair it is reached through. Exits 1 when any failed.
pub(crate) fn read(
    drive: &Map,
    target: &Target,
    registers: &[&String],
    entries: &[EntryRef],
) -> Result<ExitCode, Error> {
    if !registers.is_empty() {
        return Err(mixed());
    }
    let given = target.settings.resolve(drive)?;
    let mut session = Session::open(drive, &target.link, given.settings)?;
    let mut failed = false;
    for &e in entries {
        match session.read_entry(e) {
            Ok(v) => {
                let unit = if e.entry.unit.is_empty() {
                    String::new()
                } else {
                    format!(" {}", e.entry.unit)
                };
                outln!("{}  {v}{unit}  ({})", e.entry.id, what(e));
            }
            Err(err) => {
                failed = true;
                outln!("{}  failed: {err}  ({})", e.entry.id, what(e));
            }
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Writes `entries` (entry, value text in engineering units; no register named with them).
pub(crate) fn write(
    drive: &Map,
    target: &Target,
    registers: usize,
    entries: &[(EntryRef, String)],
) -> Result<ExitCode, Error> {
    if registers > 0 {
        return Err(mixed());
    }
    let mut values = Vec::new();
    for (e, text) in entries {
        let number = text.trim().trim_end_matches(e.entry.unit).trim();
        let v: f64 = number
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| {
                format!(
                    "`{}={text}`: not a number in {}; nothing written",
                    e.entry.id,
                    if e.entry.unit.is_empty() {
                        "its units"
                    } else {
                        e.entry.unit
                    }
                )
            })?;
        // Refused before connecting: a read-only entry or a value outside its range.
        if !e.entry.access.writable() {
            return Err(format!(
                "{} is read-only ({}); nothing written",
                e.entry.id,
                what(*e)
            )
            .into());
        }
        e.entry
            .encode(v)
            .map_err(|err| format!("{err}; nothing written"))?;
        values.push((*e, v));
    }
    let through = drivemap_live::draft::check_write(drive, target.draft_writes())?
        .map(|note| format!(" [{note}]"))
        .unwrap_or_default();
    let given = target.settings.resolve(drive)?;
    let mut session = Session::open_as(
        drive,
        drivemap_live::leak_profile(drive),
        &target.link,
        given.settings,
        target.draft_writes(),
    )?;
    for (e, v) in values {
        session
            .write_entry(e, v)
            .map_err(|err| format!("{}: {err} ({})", e.entry.id, what(e)))?;
        outln!("{} = {v}  ({}){through}", e.entry.id, what(e));
    }
    Ok(ExitCode::SUCCESS)
}
