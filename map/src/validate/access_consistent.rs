//! Access agrees with the rest: write restrictions only on writable registers, input registers
//! and discrete inputs read-only, broadcast registers write-only, and the drive has the function
//! codes the access needs (03h/04h/01h/02h to read its table, 06h or 10h to write a register,
//! 05h or 0Fh to write a coil).

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::{Access, ModbusTable, WriteRestriction};

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let fc = &drive.protocol.function_codes.codes;
    for r in &drive.registers {
        let rid = Some(r.id());
        if !r.writable()
            && r.write_restriction != WriteRestriction::None
            && r.def.write_restriction.is_some()
        {
            out.push(drive.error(
                &r.key_path("write_restriction"),
                rid,
                "a read-only register has no write restriction",
            ));
        }
        if r.table == ModbusTable::Input && r.writable() {
            out.push(drive.error(
                &r.key_path("access"),
                rid,
                "input registers (04h) are read-only",
            ));
        }
        if r.table == ModbusTable::DiscreteInput && r.writable() {
            out.push(drive.error(
                &r.key_path("access"),
                rid,
                "discrete inputs (02h) are read-only",
            ));
        }
        if r.broadcast && r.access != Access::Write {
            out.push(drive.error(
                &r.key_path("access"),
                rid,
                "broadcast registers are write-only (`access: w`)",
            ));
        }
        if r.readable() && !r.broadcast {
            let needed = r.table.read_function();
            if !fc.contains(&needed) {
                out.push(drive.error(
                    &r.path,
                    rid,
                    format!(
                        "readable {}, but the protocol lacks function {needed:02X}h",
                        r.table.item()
                    ),
                ));
            }
        }
        if r.table == ModbusTable::Coil {
            if r.writable() && !fc.contains(&0x05) && !fc.contains(&0x0F) {
                out.push(drive.error(
                    &r.path,
                    rid,
                    "writable coil, but the protocol has neither 05h nor 0Fh",
                ));
            }
            continue;
        }
        if r.writable() && !fc.contains(&0x06) && !fc.contains(&0x10) {
            out.push(drive.error(
                &r.path,
                rid,
                "writable register, but the protocol has neither 06h nor 10h",
            ));
        }
    }
}
