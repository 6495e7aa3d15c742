//! Contradictions, gaps, unknowns and removals are recorded completely: a contradiction has at
//! least two cited readings, the reading chosen and the reason; the others say why.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::Conflict;
use crate::source::Path;

fn conflict(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    c: &Conflict,
    path: Path,
    register: Option<&str>,
) {
    if c.readings.len() < 2 {
        out.push(drive.error(
            &path.key("readings"),
            register,
            format!(
                "conflict `{}` needs at least two readings, each with its citation",
                c.topic
            ),
        ));
    }
    for (field, text) in [
        ("topic", &c.topic),
        ("chosen", &c.chosen),
        ("reason", &c.reason),
    ] {
        if text.trim().is_empty() {
            out.push(drive.error(
                &path.key(field),
                register,
                format!("conflict needs a non-empty `{field}`"),
            ));
        }
    }
    for (i, r) in c.readings.iter().enumerate() {
        if r.says.trim().is_empty() {
            out.push(drive.error(
                &path.key("readings").index(i).key("says"),
                register,
                "say what this reading says",
            ));
        }
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for (i, c) in drive.conflicts.iter().enumerate() {
        conflict(drive, out, c, Path::root().key("conflicts").index(i), None);
    }
    for (i, g) in drive.gaps.iter().enumerate() {
        let gp = Path::root().key("gaps").index(i);
        if let Some([lo, hi]) = g.addresses
            && lo > hi
        {
            out.push(drive.error(
                &gp.key("addresses"),
                None,
                format!(
                    "gap {}..{} runs backwards",
                    crate::facts::manual_address(drive, lo),
                    crate::facts::manual_address(drive, hi)
                ),
            ));
        }
        if g.description.trim().is_empty() {
            out.push(drive.error(&gp.key("description"), None, "say what is missing"));
        }
    }
    for (i, r) in drive.removed.iter().enumerate() {
        if r.reason.trim().is_empty() {
            out.push(drive.error(
                &Path::root().key("removed").index(i).key("reason"),
                Some(&r.id),
                "say why the register is removed",
            ));
        }
    }
    for r in &drive.registers {
        for (i, c) in r.def.conflicts.iter().enumerate() {
            conflict(
                drive,
                out,
                c,
                r.key_path("conflicts").index(i),
                Some(r.id()),
            );
        }
        for (i, u) in r.def.unknown.iter().enumerate() {
            if u.reason.trim().is_empty() {
                out.push(drive.error(
                    &r.key_path("unknown").index(i).key("reason"),
                    Some(r.id()),
                    "say why it is unknown",
                ));
            }
        }
    }
}
