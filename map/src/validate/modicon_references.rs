//! A register's printed Modicon reference (`reference: 40024`) agrees with the map: its digits
//! are a reference, its table digit is the register's table, and its number is the register's
//! address with the map's `protocol.addressing` offset (on at least one side the register is
//! read on, since a manual prints one column).

use crate::describe;
use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::{AddressFormat, TransportName};
use crate::modicon::Modicon;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let (rtu, tcp) = drive.address_offsets();
    for r in &drive.registers {
        let Some(text) = r.def.reference.as_deref() else {
            continue;
        };
        let path = r.key_path("reference");
        let mut err = |message: String| out.push(drive.error(&path, Some(r.id()), message));
        let Some(reference) = Modicon::parse(text) else {
            err(format!(
                "`reference: {text}` is not a Modicon reference: write the digits as printed, five (`40001`: the table digit 0 coil, 1 discrete input, 3 input register or 4 holding register, then the number from 0001) or six (`400001`); a coil's `00001` keeps its zeros"
            ));
            continue;
        };
        let own = |address: u16| match drive.address_format {
            AddressFormat::Decimal => format!("register {address}"),
            AddressFormat::Hex => format!("address {}", describe::address(address)),
        };
        if reference.table != r.table {
            err(format!(
                "`reference: {text}` names {} {} (its first digit {}), but `{}` at {} is {} {}; its reference would be {}",
                article(reference.table.item()),
                reference.table.item(),
                crate::modicon::digit(reference.table),
                r.id(),
                own(r.def.address),
                article(r.table.item()),
                r.table.item(),
                expected(r.table, r.def.address, rtu)
                    .unwrap_or_else(|| "below the first".to_owned()),
            ));
            continue;
        }
        // The sides the register is read on: its own transports, else the map's.
        let listed = r
            .transports
            .as_deref()
            .unwrap_or(&drive.protocol.transports);
        let mut sides: Vec<(&str, i32)> = Vec::new();
        if listed.iter().any(|t| t.is_serial()) || listed.is_empty() {
            sides.push(("the serial side", rtu));
        }
        if listed.contains(&TransportName::Tcp) {
            sides.push(("Modbus TCP", tcp));
        }
        let pdu = |offset: i32| u16::try_from(i32::from(r.def.address) + offset).ok();
        if sides.iter().any(|(_, o)| pdu(*o) == Some(reference.pdu)) {
            continue;
        }
        let readings: Vec<String> = sides
            .iter()
            .map(|(side, o)| match pdu(*o) {
                Some(p) => format!(
                    "PDU address {} on {side} (offset {o}), reference {}",
                    describe::address(p),
                    Modicon::text(r.table, p)
                ),
                None => format!("no PDU address on {side} (offset {o})"),
            })
            .collect();
        let address_of_reference = i32::from(reference.pdu) - sides[0].1;
        err(format!(
            "`reference: {text}` is PDU address {}, which the map's addressing makes {}, but `{}` is {} ({}); fix `address`, the reference or `protocol.addressing`",
            describe::address(reference.pdu),
            u16::try_from(address_of_reference)
                .map_or_else(|_| "no address of the map".to_owned(), own),
            r.id(),
            own(r.def.address),
            readings.join("; "),
        ));
    }
}

fn article(item: &str) -> &'static str {
    if item.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    }
}

/// The reference of `address` in `table` with `offset`, if it has one.
fn expected(table: drivemap_core::register::Table, address: u16, offset: i32) -> Option<String> {
    let pdu = u16::try_from(i32::from(address) + offset).ok()?;
    Some(Modicon::text(table, pdu))
}
