//! No protocol number without a source or an `unknown`: every protocol fact (registers per
//! request, slave-address range, serial settings, exception list, timing) is either given —
//! with the manual line that prints it — or marked `unknown: "<why>"` when the manual prints
//! none (`maps/README.md`, "Facts the manual does not print").
//!
//! `check` refuses what cannot be read one way: a fact that is neither given nor `unknown`,
//! an `unknown` with an empty reason, or an `unknown` with figures beside it (which would the
//! tools use?). [`warnings`] reports, without refusing, a number given with no citation of its
//! own or of its block (a plain `max_read: 16`): such maps load, as they always did, but
//! `drivemap check` names each number to cite or to mark not printed.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::{Interval, Limit};
use crate::source::Path;

fn empty(why: &Option<String>) -> bool {
    why.as_ref().is_some_and(|w| w.trim().is_empty())
}

fn limit(drive: &Drive, out: &mut Vec<Diagnostic>, l: &Limit, key: &str) {
    let at = Path::root().key("protocol").key(key);
    if l.value.is_none() && l.unknown.is_none() {
        out.push(drive.error(
            &at,
            None,
            format!(
                "`{key}` needs its number (`value`) or why the manual prints none (`unknown: <why>`)"
            ),
        ));
    }
}

fn interval(drive: &Drive, out: &mut Vec<Diagnostic>, i: &Interval, at: Path) {
    if empty(&i.unknown) {
        out.push(drive.error(
            &at.key("unknown"),
            None,
            "an interval marked unknown needs its reason: why the manual prints none",
        ));
    }
    if i.unknown.is_some() && (i.ms.is_some() || i.bits.is_some() || i.chars.is_some()) {
        out.push(drive.error(
            &at,
            None,
            "an interval the manual does not print (`unknown`) gives no `ms`, `bits` or `chars`",
        ));
    }
}

/// The bit limits: stated by a map that has the tables they are about (coils or discrete
/// inputs to read, writable coils with 0Fh to write), each given or `unknown` like any limit;
/// refused on a map without such registers, where they would say nothing.
fn bit_limits(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    let pp = Path::root().key("protocol");
    let first = |pred: &dyn Fn(&crate::ir::Register) -> bool| {
        drive.registers.iter().find(|r| pred(r)).map(|r| r.id())
    };
    let read = first(&|r| r.table.is_bits() && r.readable());
    let write = if p.function_codes.codes.contains(&0x0F) {
        first(&|r| r.table == crate::model::ModbusTable::Coil && r.writable())
    } else {
        None
    };
    for (key, limit, needed, why, what) in [
        (
            "max_read_bits",
            &p.max_read_bits,
            read,
            "is a readable coil or discrete input",
            "the coils or discrete inputs one 01h/02h request may read",
        ),
        (
            "max_write_bits",
            &p.max_write_bits,
            write,
            "is a writable coil and the drive has 0Fh",
            "the coils one 0Fh request may write",
        ),
    ] {
        match (limit, needed) {
            (Some(l), _) => self::limit(drive, out, l, key),
            (None, Some(id)) => out.push(drive.error(
                &pp,
                Some(id),
                format!(
                    "`{id}` {why}: state `protocol.{key}`, {what}, with its citation (`{{value: N, source: \"file:line\"}}`) or why the manual prints none (`{{unknown: \"<why>\"}}`)"
                ),
            )),
            (None, None) => {}
        }
    }
}

/// Refuses a fact neither given nor `unknown`, an empty reason, or figures beside `unknown`.
pub(crate) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    let pp = Path::root().key("protocol");
    limit(drive, out, &p.max_read, "max_read");
    limit(drive, out, &p.max_write, "max_write");
    bit_limits(drive, out);

    let s = &p.slave_address;
    let sp = pp.key("slave_address");
    match &s.unknown {
        Some(why) => {
            if why.trim().is_empty() {
                out.push(drive.error(
                    &sp.key("unknown"),
                    None,
                    "a slave-address range marked unknown needs its reason: why the manual prints none",
                ));
            }
            for (key, given) in [("min", s.min.is_some()), ("max", s.max.is_some())] {
                if given {
                    out.push(drive.error(
                        &sp.key(key),
                        None,
                        format!(
                            "a slave-address range the manual does not print (`unknown`) gives no `{key}`: the tools use 1-247"
                        ),
                    ));
                }
            }
        }
        None if s.min.is_none() || s.max.is_none() => out.push(drive.error(
            &sp,
            None,
            "give the slave-address range (`min` and `max`) or why the manual prints none (`unknown: <why>`)",
        )),
        None => {}
    }

    let e = &p.exceptions;
    if empty(&e.unknown) {
        out.push(drive.error(
            &pp.key("exceptions").key("unknown"),
            None,
            "an exception list marked unknown needs its reason: why the manual prints none",
        ));
    }

    if let Some(ser) = &p.serial {
        let at = pp.key("serial");
        match &ser.unknown {
            Some(why) => {
                if why.trim().is_empty() {
                    out.push(drive.error(
                        &at.key("unknown"),
                        None,
                        "serial settings marked unknown need their reason: why the manual prints none",
                    ));
                }
                let given = [
                    ("baud_rates", !ser.baud_rates.is_empty()),
                    ("default_baud", ser.default_baud.is_some()),
                    ("parities", !ser.parities.is_empty()),
                    ("default_parity", ser.default_parity.is_some()),
                    ("char_bits", ser.char_bits.is_some()),
                    ("formats", ser.formats.is_some()),
                ];
                for (key, _) in given.iter().filter(|(_, g)| *g) {
                    out.push(drive.error(
                        &at.key(key),
                        None,
                        format!(
                            "serial settings the manual does not print (`unknown`) give no `{key}`; drop `unknown` to give them"
                        ),
                    ));
                }
            }
            None => {
                for (key, missing) in [
                    ("baud_rates", ser.baud_rates.is_empty()),
                    ("parities", ser.parities.is_empty()),
                    ("source", ser.source.trim().is_empty()),
                ] {
                    if missing {
                        out.push(drive.error(
                            &at,
                            None,
                            format!(
                                "serial settings need `{key}`, or `unknown: <why>` when the manual prints none"
                            ),
                        ));
                    }
                }
            }
        }
    }

    if let Some(t) = &p.timing {
        let tp = pp.key("timing");
        if empty(&t.unknown) {
            out.push(drive.error(
                &tp.key("unknown"),
                None,
                "timing marked unknown needs its reason: why the manual prints none",
            ));
        }
        let figures = [
            ("frame_gap_chars", t.frame_gap_chars_given.is_some()),
            ("frame_gap", t.frame_gap.is_some()),
            ("inter_char_timeout", t.inter_char_timeout.is_some()),
            ("response_time", t.response_time.is_some()),
            ("request_gap", t.request_gap.is_some()),
        ];
        if t.unknown.is_some() {
            for (key, _) in figures.iter().filter(|(_, g)| *g) {
                out.push(drive.error(
                    &tp.key(key),
                    None,
                    format!(
                        "timing the manual does not print (`timing: {{unknown}}`) gives no `{key}`; mark one figure `{{unknown: <why>}}` instead to give others"
                    ),
                ));
            }
        }
        if t.frame_gap.as_ref().is_some_and(|g| g.unknown.is_some())
            && t.frame_gap_chars_given.is_some()
        {
            out.push(drive.error(
                &tp.key("frame_gap_chars"),
                None,
                "`frame_gap` is marked not printed (`unknown`), so no `frame_gap_chars` is given: the tools use 3.5 characters, the Modbus RTU rule",
            ));
        }
        for (key, i) in t.figures() {
            if let Some(i) = i {
                interval(drive, out, i, tp.key(key));
            }
        }
    }
}

/// Numbers given without a citation of their own or of their block (`timing.source` covers
/// the timing figures): each is reported, to be cited or marked `unknown`. A warning, not an
/// error, so that maps written before the rule still load.
pub(crate) fn warnings(drive: &Drive) -> Vec<Diagnostic> {
    let p = &drive.protocol;
    let pp = Path::root().key("protocol");
    let mut out = Vec::new();
    let bits = [
        ("max_read_bits", p.max_read_bits.as_ref()),
        ("max_write_bits", p.max_write_bits.as_ref()),
    ];
    let limits = [
        ("max_read", Some(&p.max_read)),
        ("max_write", Some(&p.max_write)),
    ];
    for (key, l) in limits.into_iter().chain(bits) {
        let Some(l) = l else { continue };
        if let (Some(v), false) = (l.value, l.stated()) {
            out.push(drive.error(
                &pp.key(key),
                None,
                format!(
                    "{key} {v} has no source: cite the manual line that prints it (`{{value: {v}, source: \"file:line\"}}`) or say why it prints none (`{{unknown: \"<why>\"}}`; the tools then use the Modbus limit)"
                ),
            ));
        }
    }
    let s = &p.slave_address;
    if s.unknown.is_none() && s.source.is_none() && s.indirect.is_none() {
        out.push(drive.error(
            &pp.key("slave_address"),
            None,
            "the slave-address range has no source: cite the manual line that prints it, or say why it prints none (`slave_address: {unknown: \"<why>\"}`)",
        ));
    }
    if let Some(t) = &p.timing
        && t.source.is_none()
    {
        let tp = pp.key("timing");
        if t.frame_gap_chars_given.is_some() {
            out.push(drive.error(
                &tp.key("frame_gap_chars"),
                None,
                "frame_gap_chars has no source (timing has none): cite the line, or mark `frame_gap: {unknown: \"<why>\"}` and drop the number",
            ));
        }
        for (key, i) in t.figures() {
            if let Some(i) = i
                && i.unknown.is_none()
                && i.source.is_none()
                && i.indirect.is_none()
            {
                out.push(drive.error(
                    &tp.key(key),
                    None,
                    format!(
                        "timing `{key}` has no source: cite the line, or say why the manual prints none (`{{unknown: \"<why>\"}}`)"
                    ),
                ));
            }
        }
    }
    out
}
