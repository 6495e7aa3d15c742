//! `function_codes` (on a register or its group): the Modbus functions the register accepts
//! where the manual restricts them below the drive's list. The list is a non-empty set of
//! register functions (03h, 04h, 06h, 10h) the drive implements (`protocol.function_codes`);
//! `refused_with` is 01h (illegal function) or 02h (illegal data address). The list must let the
//! register be used as the map describes it: a readable register accepts the read function of
//! its table (03h for a holding register, 04h for an input register), a writable register a
//! write function (06h or 10h), and a writable 32-bit pair 10h (it is only written whole, both
//! words in one request).

use std::collections::HashSet;

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::ModbusTable;

/// The register functions a `function_codes` list may name.
const REGISTER_FUNCTIONS: [u8; 4] = [0x03, 0x04, 0x06, 0x10];

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
                } else if !REGISTER_FUNCTIONS.contains(&code) {
                    out.push(drive.error(
                        &at,
                        rid,
                        format!(
                            "`function_codes` lists {code:02X}h, which is not a register function: a register's list names 03h, 04h, 06h or 10h"
                        ),
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
        let (read, table) = match r.table {
            ModbusTable::Holding => (0x03, "holding"),
            ModbusTable::Input => (0x04, "input"),
        };
        if r.readable() && !r.broadcast && !f.codes.contains(&read) {
            out.push(drive.error(
                &path.key("codes"),
                rid,
                format!(
                    "`{}` is readable and a {table} register, read with {read:02X}h, but `function_codes` does not list {read:02X}h: list it, or correct `access` or `modbus_table`",
                    r.id()
                ),
            ));
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
