//! `function_codes` (on a register or its group): the Modbus functions the register accepts
//! where the manual restricts them below the drive's list. The list is a non-empty set of
//! register functions (03h, 04h, 06h, 10h) the drive implements (`protocol.function_codes`);
//! `refused_with` is 01h (illegal function) or 02h (illegal data address). The list must let the
//! register be used as the map describes it: a readable register accepts the read function of
//! its table (03h for a holding register, 04h for an input register), a writable register a
//! write function (06h or 10h), and a writable 32-bit pair 10h (it is only written whole, both
//! words in one request). A coil's list names among 01h, 05h and 0Fh (read, write one, write
//! several: a writable coil lists 05h or 0Fh), a discrete input's 02h.

use std::collections::HashSet;

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::ModbusTable;

/// The register functions a `function_codes` list may name.
const REGISTER_FUNCTIONS: [u8; 4] = [0x03, 0x04, 0x06, 0x10];
/// The functions a coil's list may name.
const COIL_FUNCTIONS: [u8; 3] = [0x01, 0x05, 0x0F];
/// The function a discrete input's list may name.
const DISCRETE_INPUT_FUNCTIONS: [u8; 1] = [0x02];

/// The functions a list of a register of `table` may name, and how an error names them.
fn allowed(table: ModbusTable) -> (&'static [u8], &'static str) {
    match table {
        ModbusTable::Holding | ModbusTable::Input => (
            &REGISTER_FUNCTIONS,
            "which is not a register function: a register's list names 03h, 04h, 06h or 10h",
        ),
        ModbusTable::Coil => (
            &COIL_FUNCTIONS,
            "which is not a coil function: a coil's list names 01h, 05h or 0Fh",
        ),
        ModbusTable::DiscreteInput => (
            &DISCRETE_INPUT_FUNCTIONS,
            "which is not a discrete-input function: a discrete input's list names 02h",
        ),
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let implemented = &drive.protocol.function_codes.codes;
    let mut seen = HashSet::new();
    for r in &drive.registers {
        let Some((f, path)) = &r.function_codes else {
            continue;
        };
        let rid = Some(r.id());
        // The list itself: once per place it is written (a group's list serves many registers).
        if seen.insert(path.clone()) {
            if f.codes.is_empty() {
                out.push(drive.error(
                    &path.key("codes"),
                    rid,
                    "`function_codes.codes` is empty: list the functions the manual says the register accepts",
                ));
            }
            for (i, &code) in f.codes.iter().enumerate() {
                let at = path.key("codes").index(i);
                if f.codes[..i].contains(&code) {
                    out.push(drive.error(
                        &at,
                        rid,
                        format!("`function_codes` lists {code:02X}h twice"),
                    ));
                } else if !allowed(r.table).0.contains(&code) {
                    out.push(drive.error(
                        &at,
                        rid,
                        format!("`function_codes` lists {code:02X}h, {}", allowed(r.table).1),
                    ));
                } else if !implemented.contains(&code) {
                    let list: Vec<String> =
                        implemented.iter().map(|c| format!("{c:02X}h")).collect();
                    out.push(drive.error(
                        &at,
                        rid,
                        format!(
                            "`function_codes` lists {code:02X}h, which the drive does not implement (`protocol.function_codes`: {}): a register accepts a subset of the drive's functions",
                            list.join(", ")
                        ),
                    ));
                }
            }
            if let Some(code) = f.refused_with
                && !matches!(code, 0x01 | 0x02)
            {
                out.push(drive.error(
                    &path.key("refused_with"),
                    rid,
                    format!(
                        "`function_codes.refused_with: {code:#04x}`: a drive refuses a function on a register with exception 01h (illegal function) or 02h (illegal data address)"
                    ),
                ));
            }
        }
        if f.codes.is_empty() {
            continue;
        }
        // The list against what the map says the register is.
        let read = r.table.read_function();
        let what = match r.table {
            ModbusTable::Holding => "a holding register",
            ModbusTable::Input => "an input register",
            ModbusTable::Coil => "a coil",
            ModbusTable::DiscreteInput => "a discrete input",
        };
        if r.readable() && !r.broadcast && !f.codes.contains(&read) {
            out.push(drive.error(
                &path.key("codes"),
                rid,
                format!(
                    "`{}` is readable and {what}, read with {read:02X}h, but `function_codes` does not list {read:02X}h: list it, or correct `access` or `modbus_table`",
                    r.id()
                ),
            ));
        }
        if r.table == ModbusTable::Coil {
            if r.writable() && !f.codes.iter().any(|c| matches!(c, 0x05 | 0x0F)) {
                out.push(drive.error(
                    &path.key("codes"),
                    rid,
                    format!(
                        "`{}` is a writable coil, but `function_codes` lists no coil write function (05h or 0Fh): list the one the manual allows, or correct `access`",
                        r.id()
                    ),
                ));
            }
            continue;
        }
        if r.writable() {
            if r.def.pair.is_some() && !f.codes.contains(&0x10) {
                out.push(drive.error(
                    &path.key("codes"),
                    rid,
                    format!(
                        "`{}` is a writable 32-bit pair, written whole with 10h, but `function_codes` does not list 10h",
                        r.id()
                    ),
                ));
            } else if !f.codes.iter().any(|c| matches!(c, 0x06 | 0x10)) {
                out.push(drive.error(
                    &path.key("codes"),
                    rid,
                    format!(
                        "`{}` is writable, but `function_codes` lists no write function (06h or 10h): list the one the manual allows, or correct `access`",
                        r.id()
                    ),
                ));
            }
        }
    }
}
