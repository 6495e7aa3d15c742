//! No two registers at one address in the same address space (holding/input table, broadcast or
//! not) on a shared transport.

use std::collections::HashMap;

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register};
use crate::model::ModbusTable;

fn shares_transport(a: &Register, b: &Register) -> bool {
    match (&a.transports, &b.transports) {
        (Some(x), Some(y)) => x.iter().any(|t| y.contains(t)),
        _ => true,
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let mut by_key: HashMap<(bool, ModbusTable, u16), Vec<&Register>> = HashMap::new();
    for r in &drive.registers {
        let slot = by_key
            .entry((r.broadcast, r.table, r.def.address))
            .or_default();
        if let Some(first) = slot.iter().find(|f| shares_transport(f, r)) {
            let at = drive.locate(&first.path);
            out.push(drive.error(
                &r.key_path("address"),
                Some(r.id()),
                format!(
                    "address {} is already used by `{}` (line {}); two registers cannot share an address in one space — choose one reading and record the other in `conflicts`",
                    crate::facts::manual_address(drive, r.def.address),
                    first.id(),
                    at.line
                ),
            ));
        }
        slot.push(r);
    }
}
