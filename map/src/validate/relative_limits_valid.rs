//! `max_relative` (a limit through another register or quantity): on a number register (a
//! unit or a scale) that can be written; `percent` finite and above 0; `relative_to` a readable
//! one-word register with a fixed scale, or an external quantity, in the register's own unit
//! (a frequency bounded by a frequency), and not the register itself. Its `source` is checked
//! with the other citations.

use crate::diagnostic::Diagnostic;
use crate::hints::closest;
use crate::ir::{Drive, ValueKind};
use crate::model::{Reference, Scale};

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        let Some(limit) = &r.def.max_relative else {
            continue;
        };
        let path = r.key_path("max_relative");
        let rid = Some(r.id());
        let unit = r.def.unit.as_deref().unwrap_or("");
        if !matches!(r.kind(), ValueKind::Quantity(_) | ValueKind::UnitQuantity) || unit.is_empty()
        {
            out.push(drive.error(
                &path,
                rid,
                format!(
                    "`max_relative` on `{}`, which is not a quantity with a unit: a limit through another quantity bounds a value in that quantity's unit",
                    r.id()
                ),
            ));
            continue;
        }
        if !r.writable() {
            out.push(drive.error(
                &path,
                rid,
                format!(
                    "`max_relative` on the read-only register `{}`: the limit bounds what is written",
                    r.id()
                ),
            ));
        }
        if !(limit.percent.is_finite() && limit.percent > 0.0) {
            out.push(drive.error(
                &path.key("percent"),
                rid,
                format!(
                    "`max_relative.percent: {}` must be a number above 0 (percent of the reference)",
                    limit.percent
                ),
            ));
        }
        let rp = path.key("relative_to");
        match &limit.relative_to {
            Reference::External(q) => {
                if q.unit != unit {
                    out.push(drive.error(
                        &rp.key("unit"),
                        rid,
                        format!(
                            "`max_relative.relative_to` is the external quantity `{}` in {}, but `{}` is in {unit}: a limit must be in the register's unit",
                            q.external,
                            q.unit,
                            r.id()
                        ),
                    ));
                }
            }
            Reference::Register(name) => {
                let Some(target) = drive.find(name) else {
                    let candidates = drive
                        .registers
                        .iter()
                        .flat_map(|x| std::iter::once(x.id()).chain(x.def.param.as_deref()));
                    let hint = closest(name, candidates)
                        .map(|c| format!(" (did you mean `{c}`?)"))
                        .unwrap_or_default();
                    out.push(drive.error(
                        &rp,
                        rid,
                        format!(
                            "`max_relative.relative_to: {name}` names no register of this map (by id or parameter number){hint}"
                        ),
                    ));
                    continue;
                };
                if target.def.id == r.def.id {
                    out.push(drive.error(
                        &rp,
                        rid,
                        format!(
                            "`max_relative.relative_to: {name}` is `{}` itself: a limit must come from another register",
                            r.id()
                        ),
                    ));
                    continue;
                }
                let fixed = matches!(
                    target.kind(),
                    ValueKind::Quantity(Scale::Factor(_) | Scale::Ratio(_))
                        | ValueKind::UnitQuantity
                );
                if !fixed || !target.readable() || target.def.pair.is_some() || target.broadcast {
                    out.push(drive.error(
                        &rp,
                        rid,
                        format!(
                            "`max_relative.relative_to: {name}` must be a readable one-word register with a fixed scale (it is read before the write)"
                        ),
                    ));
                    continue;
                }
                let theirs = target.def.unit.as_deref().unwrap_or("");
                if theirs != unit {
                    out.push(drive.error(
                        &rp,
                        rid,
                        format!(
                            "`max_relative.relative_to: {name}` is in {theirs}, but `{}` is in {unit}: a limit must be in the register's unit",
                            r.id()
                        ),
                    ));
                }
            }
        }
    }
}
