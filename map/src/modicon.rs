//! Modicon references (`40001`, `400001`, `30002`, `00001`, `10001`): the PLC numbering many
//! manuals print beside a register's own number. The first digit names the table (0 coils, 1
//! discrete inputs, 3 input registers, 4 holding registers), the rest counts from 1, so `40001`
//! is PDU address 0. A map records the reference a manual prints with `reference:` on the
//! register; `drivemap check` holds it to the register's address, its table and
//! `protocol.addressing`.

use drivemap_core::register::Table;

/// A Modicon reference read from its printed digits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Modicon {
    /// The table its first digit names.
    pub table: Table,
    /// The PDU address (the number after the table digit, minus 1).
    pub pdu: u16,
}

impl Modicon {
    /// Reads `text` as a Modicon reference: digits only, five (`40024`: table digit, number
    /// 1 to 9999) or six (`400024`: number 1 to 65536), the first 0, 1, 3 or 4.
    pub fn parse(text: &str) -> Option<Modicon> {
        let t = text.trim();
        if !(5..=6).contains(&t.len()) || !t.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let table = table_of_digit(t.as_bytes()[0])?;
        let number: u32 = t[1..].parse().ok()?;
        let pdu = u16::try_from(number.checked_sub(1)?).ok()?;
        Some(Modicon { table, pdu })
    }

    /// The five-digit reference (six when the number passes 9999) of PDU address `pdu` in
    /// `table`: `40024` for holding register PDU 23.
    pub fn text(table: Table, pdu: u16) -> String {
        let n = u32::from(pdu) + 1;
        if n <= 9999 {
            format!("{}{n:04}", digit(table))
        } else {
            format!("{}{n:05}", digit(table))
        }
    }
}

/// The table digit of a reference (`4` for holding registers).
pub fn digit(table: Table) -> char {
    match table {
        Table::Coil => '0',
        Table::DiscreteInput => '1',
        Table::Input => '3',
        Table::Holding => '4',
    }
}

fn table_of_digit(d: u8) -> Option<Table> {
    match d {
        b'0' => Some(Table::Coil),
        b'1' => Some(Table::DiscreteInput),
        b'3' => Some(Table::Input),
        b'4' => Some(Table::Holding),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_five_and_six_digits_and_names_the_table() {
        let m = |t| Modicon::parse(t);
        assert_eq!(
            m("40024"),
            Some(Modicon {
                table: Table::Holding,
                pdu: 23
            })
        );
        assert_eq!(m("400024"), m("40024"));
        assert_eq!(m("30002").map(|r| r.table), Some(Table::Input));
        assert_eq!(m("00001").map(|r| (r.table, r.pdu)), Some((Table::Coil, 0)));
        assert_eq!(m("10001").map(|r| r.table), Some(Table::DiscreteInput));
        assert_eq!(m("465536").map(|r| r.pdu), Some(65535));
        for bad in ["40000", "465537", "20001", "4001", "4000001", "4x001", ""] {
            assert_eq!(m(bad), None, "{bad}");
        }
        assert_eq!(Modicon::text(Table::Holding, 23), "40024");
        assert_eq!(Modicon::text(Table::Input, 9999), "310000");
        assert_eq!(Modicon::text(Table::Coil, 0), "00001");
    }
}
