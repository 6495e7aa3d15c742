//! `read_values` (what a word read means when a write means something else): the register is
//! read and written (`rw`), and its own description is the write side, a plain word (no
//! `values`, `fields`, `scale` or `unit`), so reads decode to the read enumeration and writes
//! take the word. Ids and codes are checked with the other values (`identifiers_*`).

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, ValueKind};
use crate::model::Access;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        if r.def.read_values.is_empty() {
            continue;
        }
        let rid = Some(r.id());
        let path = r.key_path("read_values");
        if r.access != Access::ReadWrite {
            out.push(drive.error(
                &path,
                rid,
                "`read_values` needs a register that is read and written (`access: rw`): they say what a read means beside what a write means; on a register that is only read, give `values`",
            ));
        }
        if !matches!(r.kind(), ValueKind::Word) {
            out.push(drive.error(
                &path,
                rid,
                "`read_values` goes beside a plain word (the write side, with `min`/`max`); this register also has `values`, `fields`, `scale` or `unit`",
            ));
        }
        if r.def.signed {
            out.push(drive.error(
                &r.key_path("signed"),
                rid,
                "a register with `read_values` reads codes, so it cannot be signed",
            ));
        }
    }
}
