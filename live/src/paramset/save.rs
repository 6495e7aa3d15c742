//! Saving: every setting read with the read planner, decoded by the map.

use std::collections::BTreeMap;

use drivemap_map::RegisterRef;

use super::file::{FORMAT, ParameterSet, SavedSetting, UnreadSetting};
use super::{fingerprint, settings_of};
use crate::codec::{self, Value};
use crate::session::{ReadError, Session, SessionError};

/// A saved set, and what saving cost.
#[derive(Debug, Clone)]
pub struct SaveReport {
    /// The set.
    pub set: ParameterSet,
    /// Requests sent.
    pub requests: u32,
    /// Values read that the map's conversion does not give back exactly (restoring them would
    /// be refused or change them), one line each.
    pub warnings: Vec<String>,
}

/// The raw values of `regs` on the drive: first those whose address is known, in planned
/// requests; what they hold of the settings that select scales and addresses is taken in
/// (so a setting whose address moves with one is read where it is), then the rest. Returns
/// each register's raw value or why there is none, and the requests sent.
pub(crate) fn read_all(
    session: &mut Session<'_>,
    regs: &[RegisterRef<'_>],
) -> Result<(Vec<Result<u32, ReadError>>, u32), SessionError> {
    read_all_with(session, regs, false, &mut |_, _| {})
}

/// [`read_all`], planned group by group of the map when `by_group` (for a progress display:
/// `progress(read, total)` after each group; the planner does not bridge one group's area
/// to another's anyway, so this costs no request where groups lie apart).
pub(crate) fn read_all_with(
    session: &mut Session<'_>,
    regs: &[RegisterRef<'_>],
    by_group: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Vec<Result<u32, ReadError>>, u32), SessionError> {
    let drive = session.drive;
    let mut results: Vec<Option<Result<u32, ReadError>>> = vec![None; regs.len()];
    let mut requests = 0;
    for pass in 0..2 {
        let wanted: Vec<usize> = (0..regs.len())
            .filter(|&i| results[i].is_none())
            .filter(|&i| pass == 1 || session.address(regs[i]).is_ok())
            .collect();
        let chunks: Vec<&[usize]> = if by_group {
            wanted
                .chunk_by(|&a, &b| std::ptr::eq(regs[a].group(), regs[b].group()))
                .collect()
        } else if wanted.is_empty() {
            Vec::new()
        } else {
            vec![&wanted[..]]
        };
        for chunk in chunks {
            let these: Vec<RegisterRef<'_>> = chunk.iter().map(|&i| regs[i]).collect();
            let mut plan = session.plan(&these)?;
            let (words, sent) = session.poll_counted(&mut plan);
            requests += sent;
            for (&i, w) in chunk.iter().zip(words) {
                if let Ok(raw) = &w {
                    // Selectors and references are one-word registers.
                    session
                        .settings
                        .absorb(drive, regs[i].address(), *raw as u16);
                }
                results[i] = Some(w);
            }
            progress(results.iter().filter(|r| r.is_some()).count(), regs.len());
        }
    }
    Ok((
        results
            .into_iter()
            .map(|r| r.unwrap_or(Err(ReadError::NotRead)))
            .collect(),
        requests,
    ))
}

/// A decoded value as a set holds it: the number in the register's unit, a code's number and
/// id, a word.
pub(crate) fn value_text(value: &Value) -> (String, Option<String>) {
    match value {
        Value::Word(w) => (w.to_string(), None),
        Value::Quantity {
            exact: Some(exact), ..
        } => {
            let text = exact.to_string();
            // A fraction without a finite decimal: `3599/60 (≈59.983333)` keeps `3599/60`.
            let text = text.split(" (").next().unwrap_or(&text).to_owned();
            (text, None)
        }
        Value::Quantity {
            value, decimals, ..
        } => (format!("{value:.decimals$}"), None),
        Value::Code { code, id, .. } => (code.to_string(), id.clone()),
        Value::Bits { raw, .. } => (raw.to_string(), None),
        Value::Bit(on) => (u8::from(*on).to_string(), None),
        // Strings are read-only, so never settings; escaped should one be shown.
        Value::Text(_) => (value.text().unwrap_or_default(), None),
    }
}

/// Reads every setting of the session's map ([`settings_of`]) with the read planner and
/// returns the set, stamped `saved` (an RFC 3339 time the caller gives). Settings the link
/// cannot read, or the drive refuses, are listed in [`ParameterSet::unread`] with why.
pub fn save(session: &mut Session<'_>, saved: &str) -> Result<SaveReport, SessionError> {
    save_with(session, saved, &mut |_, _| {})
}

/// [`save`], telling `progress(read, total)` the settings read so far after each group of the
/// map (each group's settings planned on their own).
pub fn save_with(
    session: &mut Session<'_>,
    saved: &str,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<SaveReport, SessionError> {
    let drive = session.drive;
    let regs = settings_of(drive);
    let (words, requests) = read_all_with(session, &regs, true, progress)?;
    let mut settings = Vec::new();
    let mut unread = Vec::new();
    let mut warnings = Vec::new();
    for (r, w) in regs.iter().zip(words) {
        let param = r.param().map(str::to_owned);
        let decoded = w.map_err(|e| e.to_string()).and_then(|raw| {
            session
                .decode(*r, raw)
                .map(|v| (raw, v))
                .map_err(|e| e.to_string())
        });
        match decoded {
            Ok((raw, value)) => {
                let (text, code) = value_text(&value);
                match codec::parse_value(drive, *r, &text, &session.settings) {
                    Ok(back) if back == raw => {}
                    Ok(back) => warnings.push(format!(
                        "{}: the drive holds {}, which the map writes as {}",
                        r.label(),
                        session.raw_text(*r, raw),
                        session.raw_text(*r, back)
                    )),
                    Err(e) => warnings.push(format!(
                        "{}: the drive holds {text} ({}), which restoring would refuse: {e}",
                        r.label(),
                        session.raw_text(*r, raw)
                    )),
                }
                settings.push(SavedSetting {
                    id: r.id().to_owned(),
                    param,
                    value: text,
                    code,
                });
            }
            Err(reason) => unread.push(UnreadSetting {
                id: r.id().to_owned(),
                param,
                reason,
            }),
        }
    }
    let variant: BTreeMap<String, String> = drive
        .variants()
        .iter()
        .filter_map(|a| {
            session
                .settings
                .variant(drive, &a.id)
                .map(|o| (a.id.clone(), o.to_owned()))
        })
        .collect();
    Ok(SaveReport {
        set: ParameterSet {
            format: FORMAT.to_owned(),
            drive: drive.id().to_owned(),
            variant,
            fingerprint: fingerprint(drive),
            slave: session.slave,
            saved: saved.to_owned(),
            settings,
            unread,
        },
        requests,
        warnings,
    })
}
