//! A register is one kind of value: bit fields, an enumeration, a scaled quantity or a plain word.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        let d = &r.def;
        let rid = Some(r.id());
        let kinds = [
            !d.fields.is_empty(),
            !d.values.is_empty(),
            d.scale.is_some(),
        ];
        if kinds.iter().filter(|k| **k).count() > 1 {
            out.push(drive.error(
                &r.path,
                rid,
                "a register is one of: bit fields (`fields`), an enumeration (`values`) or a scaled quantity (`scale`); it has more than one",
            ));
        }
        if (!d.fields.is_empty() || !d.values.is_empty()) && d.unit.is_some() {
            out.push(drive.error(
                &r.key_path("unit"),
                rid,
                "bit fields and enumerations carry no unit; put a unit only on a quantity",
            ));
        }
        if !d.fields.is_empty() && d.signed {
            out.push(drive.error(
                &r.key_path("signed"),
                rid,
                "a bit-field register cannot be signed",
            ));
        }
    }
}
