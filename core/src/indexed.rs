//! Indexed access: a register whose value belongs to the entry selected by an index written to
//! another register ("write the parameter's index to register 44, read its value from 45").
//!
//! The map's `indexed:` on the value register is lowered once (`drivemap_map::lower`) into an
//! [`Indexed`]: the index register, the value register and the entries the manual lists, each
//! an [`Entry`] with its own scale, range, access and write rule. Clients read or write an entry
//! in one call (`Client::read_entry`, `Client::write_entry` in `drivemap-runtime`): they write
//! the index, then read or write the value, with no other request in between, and never
//! attribute a value to an entry the drive did not show it for.

use crate::register::{Access, Table};
use crate::rule::WriteRule;
use crate::scale::{self, Decimal, RawRange, Rounding, ValueError};

/// An index/value register pair and the entries reached through it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Indexed {
    /// The value register's id (the register the map writes `indexed:` on).
    pub register: &'static str,
    /// The value register's communication address.
    pub value_address: u16,
    /// The table both registers are in (holding: the index is written).
    pub table: Table,
    /// The index register's id.
    pub index_register: &'static str,
    /// The index register's communication address.
    pub index_address: u16,
    /// Whether the index register can be read back: clients then verify, with the value, that
    /// the drive still shows the entry they selected.
    pub index_readable: bool,
    /// The indices the index register accepts (its range in the map).
    pub index_range: RawRange,
    /// The entries the manual lists, by index.
    pub entries: &'static [Entry],
    /// Why the manual's list is missing or incomplete (`unknown:` in the map): entries not
    /// listed are then reached by raw index only.
    pub unknown: Option<&'static str>,
    /// `file:line` where the manual describes the pair.
    pub source: &'static str,
}

/// One entry of an indexed register: what its value means while its index is selected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    /// snake_case identifier, unique among the drive's registers and entries.
    pub id: &'static str,
    /// Name as printed.
    pub name: &'static str,
    /// The index written to the index register to select it.
    pub index: u16,
    /// Engineering unit (`""` for none).
    pub unit: &'static str,
    /// Whether its word is signed.
    pub signed: bool,
    /// engineering = raw × scale.
    pub scale: Decimal,
    /// Raw values it allows.
    pub range: RawRange,
    /// Access as the manual states it.
    pub access: Access,
    /// What the gate checks a write of its value against: `register` is the entry's id,
    /// `address` the value register's, `raw` the entry's range.
    pub rule: WriteRule,
    /// `file:line` of its row in the manual.
    pub source: &'static str,
}

/// An entry together with the pair it belongs to: what the generated code gives each listed
/// entry (a typed handle, like a register), and what clients take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EntryRef {
    /// The index/value pair.
    pub pair: &'static Indexed,
    /// The entry.
    pub entry: &'static Entry,
}

impl Indexed {
    /// The entry with id `id`.
    pub fn entry(&self, id: &str) -> Option<&'static Entry> {
        self.entries.iter().find(|e| e.id == id)
    }

    /// The entry selected by `index`, when the manual lists it.
    pub fn entry_at(&self, index: u16) -> Option<&'static Entry> {
        self.entries.iter().find(|e| e.index == index)
    }

    /// Whether the index register accepts `index`.
    pub fn index_allowed(&self, index: u16) -> bool {
        self.index_range.contains(i64::from(index))
    }

    /// Where the index register sits relative to the value register when the two are
    /// consecutive: `Some(true)` for the index just below the value (one read of two words
    /// returns both), `Some(false)` just above, `None` otherwise.
    pub fn index_below_value(&self) -> Option<bool> {
        if self.index_address.checked_add(1) == Some(self.value_address) {
            Some(true)
        } else if self.value_address.checked_add(1) == Some(self.index_address) {
            Some(false)
        } else {
            None
        }
    }
}

/// The entry `id` of any of `pairs`.
pub fn find(pairs: &'static [Indexed], id: &str) -> Option<EntryRef> {
    pairs
        .iter()
        .find_map(|pair| pair.entry(id).map(|entry| EntryRef { pair, entry }))
}

impl Entry {
    /// The engineering value of a word read while this entry was selected.
    pub fn decode(&self, word: u16) -> f64 {
        scale::decode_decimal(word, self.signed, self.scale)
    }

    /// The word for an engineering value, checked against the entry's range; a value between
    /// two steps is refused ([`ValueError::NotAStep`]), never rounded.
    pub fn encode(&self, value: f64) -> Result<u16, ValueError> {
        let raw = scale::encode_decimal_with(
            self.id,
            self.unit,
            value,
            self.scale,
            self.range,
            Rounding::Exact,
        )?;
        Ok(raw as u16)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rule::WriteRule;

    const ENTRIES: &[Entry] = &[Entry {
        id: "acceleration_time",
        name: "Acceleration time",
        index: 1,
        unit: "s",
        signed: false,
        scale: Decimal::new(1, 1),
        range: RawRange::new(1, 6000),
        access: Access::ReadWrite,
        rule: WriteRule::rw("acceleration_time", 45, 1, 6000),
        source: "m.txt:18",
    }];
    const PAIR: Indexed = Indexed {
        register: "parameter_value",
        value_address: 45,
        table: Table::Holding,
        index_register: "parameter_index",
        index_address: 44,
        index_readable: true,
        index_range: RawRange::new(1, 40),
        entries: ENTRIES,
        unknown: None,
        source: "m.txt:14",
    };

    #[test]
    fn an_entry_converts_with_its_own_scale_and_range() {
        let e = PAIR.entry("acceleration_time").unwrap();
        assert_eq!(e.encode(12.5), Ok(125));
        assert_eq!(e.decode(125), 12.5);
        assert!(matches!(e.encode(0.0), Err(ValueError::OutOfRange { .. })));
        assert!(matches!(e.encode(1.25), Err(ValueError::NotAStep { .. })));
        assert_eq!(PAIR.entry_at(1).map(|e| e.id), Some("acceleration_time"));
        assert_eq!(PAIR.entry_at(2), None);
        assert!(PAIR.index_allowed(40) && !PAIR.index_allowed(41) && !PAIR.index_allowed(0));
        assert_eq!(PAIR.index_below_value(), Some(true));
    }
}
