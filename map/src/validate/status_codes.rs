//! Status roles that read codes of the same bits (a multi-bit status field, or the codes of a
//! whole status register) must be able to hold together as the drive reports them. A status
//! role holds while the bits show one of its `on` codes; its `off`, where given, is the code the
//! bits show whenever it does not hold. So with two roles `a` and `b` on the same bits:
//! - while `b` holds and `a` does not, the bits show a code of `b` that must be `a`'s `off`:
//!   refused where a code of `b` is neither among `a`'s `on` codes nor `a`'s `off`;
//! - while neither holds, the bits show `a`'s `off` and `b`'s `off`: refused where they differ.
//!
//! (An MX2-style status register, 2 stop, 3 run, 5 trip, with `running: {on: 3, off: 2}` and
//! `fault: {on: 5, off: 2}`, would have to show 2 while running; the simulated drive then
//! reported "stopped" at 30 Hz.)

use drivemap_core::roles::{RoleKind, Target};

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::source::Path;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    // A drive that does not lower is reported by the lowering, the last pass.
    let Ok(plan) = drive.try_plan() else {
        return;
    };
    let places: Vec<_> = plan
        .roles
        .places
        .iter()
        .filter(|p| p.role.kind() == RoleKind::Status)
        .filter_map(|p| match p.target {
            Target::Field(f) => Some((p.role, f)),
            _ => None,
        })
        .collect();
    for (i, &(ra, a)) in places.iter().enumerate() {
        for &(rb, b) in &places[i + 1..] {
            if a.row != b.row || a.lsb != b.lsb || a.width != b.width || ra == rb {
                continue;
            }
            let register = plan.registers[usize::from(a.row)].info.id;
            let mut why = None;
            for (x, rx, y, ry) in [(a, ra, b, rb), (b, rb, a, ra)] {
                if let Some(off) = x.off
                    && let Some(&c) = y.on.iter().find(|c| !x.on.contains(c) && **c != off)
                {
                    why = Some(format!(
                        "while `{}` holds ({c}) and `{}` does not, `{}` would have to show {c} and `{}`'s `off` {off} at once",
                        ry.id(),
                        rx.id(),
                        register,
                        rx.id()
                    ));
                    break;
                }
            }
            if why.is_none()
                && let (Some(x), Some(y)) = (a.off, b.off)
                && x != y
            {
                why = Some(format!(
                    "while neither holds, `{register}` would have to show `{}`'s `off` {x} and `{}`'s `off` {y} at once",
                    ra.id(),
                    rb.id()
                ));
            }
            if let Some(why) = why {
                out.push(drive.error(
                    &Path::root().key("roles").key(rb.id()),
                    Some(register),
                    format!(
                        "status roles `{}` and `{}` read codes of the same bits of `{register}` that cannot hold together: {why}; give `off` only where the bits show that code whenever the role does not hold (maps/README.md, \"Codes as states\")",
                        ra.id(),
                        rb.id()
                    ),
                ));
            }
        }
    }
}
