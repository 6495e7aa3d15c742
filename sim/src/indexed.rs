//! Indexed access served as the drive does (`indexed:` in the map, lowered to
//! [`drivemap_map::MapPlan::indexed`]): the value register shows, and accepts, the
//! value of the entry whose index the index register holds. Used by the map-driven
//! [`crate::Simulator`] and by the bare [`crate::SimulatedSlave`].

use std::collections::BTreeMap;

use drivemap_runtime::core::indexed::Indexed;

/// The entries' values behind every index/value pair of a drive.
#[derive(Debug, Clone, Default)]
pub struct IndexedBank {
    pairs: Vec<(&'static Indexed, BTreeMap<u16, u16>)>,
}

/// What a write to a value register would do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriteCheck {
    /// Not a value register: the caller's own rules apply.
    NotIndexed,
    /// The selected entry takes the word.
    Accepted,
    /// The selected entry is read-only.
    ReadOnly,
    /// The word is outside the selected entry's range.
    OutOfRange,
}

impl IndexedBank {
    /// Every pair of `pairs`, each listed entry powered on at the value of its range nearest 0
    /// (the map gives entries no default).
    pub fn new(pairs: &'static [Indexed]) -> IndexedBank {
        IndexedBank {
            pairs: pairs
                .iter()
                .map(|p| {
                    let values = p
                        .entries
                        .iter()
                        .map(|e| (e.index, e.range.min.max(0).min(e.range.max) as u16))
                        .collect();
                    (p, values)
                })
                .collect(),
        }
    }

    /// Whether the drive has any pair.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    fn pair(&self, value_address: u16) -> Option<&(&'static Indexed, BTreeMap<u16, u16>)> {
        self.pairs
            .iter()
            .find(|(p, _)| p.value_address == value_address)
    }

    /// The word the value register at `address` shows, given `word(a)`, the holding word at `a`
    /// (the index register's); `None` when `address` holds no value register. An index the map
    /// does not list shows what was last written for it, else 0.
    pub fn shown(&self, address: u16, word: impl Fn(u16) -> u16) -> Option<u16> {
        let (p, values) = self.pair(address)?;
        Some(values.get(&word(p.index_address)).copied().unwrap_or(0))
    }

    /// Whether the entry selected now accepts `value` at `address`.
    pub fn check(&self, address: u16, value: u16, word: impl Fn(u16) -> u16) -> WriteCheck {
        let Some((p, _)) = self.pair(address) else {
            return WriteCheck::NotIndexed;
        };
        match p.entry_at(word(p.index_address)) {
            None => WriteCheck::Accepted,
            Some(e) if !e.access.writable() => WriteCheck::ReadOnly,
            Some(e)
                if !e.range.contains(if e.signed {
                    i64::from(value as i16)
                } else {
                    i64::from(value)
                }) =>
            {
                WriteCheck::OutOfRange
            }
            Some(_) => WriteCheck::Accepted,
        }
    }

    /// Stores `value` written to the value register at `address` as the selected entry's;
    /// false when `address` holds no value register.
    pub fn store(&mut self, address: u16, value: u16, word: impl Fn(u16) -> u16) -> bool {
        let Some((p, values)) = self
            .pairs
            .iter_mut()
            .find(|(p, _)| p.value_address == address)
        else {
            return false;
        };
        values.insert(word(p.index_address), value);
        true
    }

    /// The value held for entry `index` of the pair whose value register is `register`.
    pub fn value(&self, register: &str, index: u16) -> Option<u16> {
        let (_, values) = self.pairs.iter().find(|(p, _)| p.register == register)?;
        values.get(&index).copied()
    }

    /// Sets the value held for entry `index` of the pair whose value register is `register`
    /// (as the keypad would); false when there is no such pair.
    pub fn set(&mut self, register: &str, index: u16, value: u16) -> bool {
        match self.pairs.iter_mut().find(|(p, _)| p.register == register) {
            Some((_, values)) => {
                values.insert(index, value);
                true
            }
            None => false,
        }
    }
}
