//! `read_param` (a register read from one parameter and written to another, Siemens BICO:
//! read r0055 bit 8, write P2200): the register is a holding register read and written
//! (`access: rw`), `param` names the parameter a write sets and differs from `read_param`, and
//! no setting is read from it (a selector, a reference or an index register would be read as a
//! parameter that is not the one written).

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::{Access, ModbusTable};

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let settings = super::settings_read(drive);
    for r in &drive.registers {
        let Some(read) = &r.def.read_param else {
            continue;
        };
        let rid = Some(r.id());
        let path = r.key_path("read_param");
        if read.trim().is_empty() {
            out.push(drive.error(
                &path,
                rid,
                "`read_param` is empty: write the parameter a read returns, as printed (`r0055.8`)",
            ));
        }
        if r.access != Access::ReadWrite || r.table != ModbusTable::Holding {
            out.push(drive.error(
                &path,
                rid,
                "`read_param` needs a holding register that is read and written (`access: rw`): it names what a read returns beside the parameter a write sets (`param`)",
            ));
        }
        match &r.def.param {
            None => out.push(drive.error(
                &path,
                rid,
                "`read_param` needs `param`, the parameter a write sets (`param: P2200`, `read_param: r0055.8`)",
            )),
            Some(p) if p.eq_ignore_ascii_case(read) => out.push(drive.error(
                &path,
                rid,
                format!("`read_param` is `param` ({p}): leave `read_param` out when a read returns the parameter written"),
            )),
            Some(_) => {}
        }
        if settings.contains(&r.id()) {
            out.push(drive.error(
                &path,
                rid,
                "a register read from another parameter than the one written cannot select a scale or be a reference: a read returns `read_param`, not the setting",
            ));
        }
    }
}
