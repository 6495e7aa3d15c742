//! The protocol's timing is one the runtime can keep: a positive frame gap (in milliseconds as
//! `frame_gap`, in characters as `frame_gap_chars`), and each interval given in some unit and
//! not negative.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::{Interval, Timing};
use crate::source::Path;

/// One rule of the timing: reads `protocol.timing` (found at `timing`) and appends its findings.
type Rule = fn(&Drive, &Timing, &Path, &mut Vec<Diagnostic>);

/// The rules, in the order their findings are reported.
const RULES: &[Rule] = &[frame_gap_chars, frame_gap, intervals];

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let Some(t) = &drive.protocol.timing else {
        return;
    };
    let tp = Path::root().key("protocol").key("timing");
    for rule in RULES {
        rule(drive, t, &tp, out);
    }
}

/// The frame gap in characters (given, or the default) is positive.
fn frame_gap_chars(drive: &Drive, t: &Timing, tp: &Path, out: &mut Vec<Diagnostic>) {
    if t.frame_gap_chars().is_nan() || t.frame_gap_chars() <= 0.0 {
        out.push(drive.error(
            &tp.key("frame_gap_chars"),
            None,
            "the frame gap must be positive",
        ));
    }
}

/// `frame_gap` is in milliseconds only, finite and positive.
fn frame_gap(drive: &Drive, t: &Timing, tp: &Path, out: &mut Vec<Diagnostic>) {
    let Some(g) = &t.frame_gap else {
        return;
    };
    if g.unknown.is_some() {
        return;
    }
    // Only milliseconds: a gap in characters is `frame_gap_chars`, and the two are not
    // contradictory (the larger at the line's baud rate is kept).
    let gp = tp.key("frame_gap");
    let other = g.bits.is_some() || g.chars.is_some();
    match g.ms {
        None if other => {}
        None => out.push(drive.error(
            &gp,
            None,
            "give the frame gap in `ms` (a gap in characters is `frame_gap_chars`)",
        )),
        Some(ms) if !ms.is_finite() || ms <= 0.0 => out.push(drive.error(
            &gp.key("ms"),
            None,
            "the frame gap in ms must be finite and positive",
        )),
        Some(_) => {}
    }
    if other {
        out.push(drive.error(
            &gp,
            None,
            "`frame_gap` takes `ms` only; write a gap in characters as `frame_gap_chars`",
        ));
    }
}

/// The inter-character timeout, response time and request gap.
fn intervals(drive: &Drive, t: &Timing, tp: &Path, out: &mut Vec<Diagnostic>) {
    for (key, i) in [
        ("inter_char_timeout", &t.inter_char_timeout),
        ("response_time", &t.response_time),
        ("request_gap", &t.request_gap),
    ] {
        if let Some(i) = i {
            interval(drive, out, i, tp.key(key));
        }
    }
}

fn interval(drive: &Drive, out: &mut Vec<Diagnostic>, i: &Interval, path: Path) {
    if i.unknown.is_some() {
        // Not printed: `protocol_stated` checks that no figure stands beside the reason.
        return;
    }
    if i.ms.is_none() && i.bits.is_none() && i.chars.is_none() {
        out.push(drive.error(&path, None, "give `ms`, `bits` or `chars` (several add up)"));
    }
    if i.ms.is_some_and(|v| v.is_nan() || v < 0.0) || i.chars.is_some_and(|v| v.is_nan() || v < 0.0)
    {
        out.push(drive.error(&path, None, "an interval cannot be negative"));
    }
}
