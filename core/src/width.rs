//! How many registers a value occupies, and in which order its words travel.
//!
//! Most drive registers hold one 16-bit word. Drives of other vendors keep energy counters,
//! running hours and 32-bit frequencies or positions in two consecutive registers; the manual says
//! whether the high or the low word comes first (at the lower address). Such a pair is one value:
//! it is read in one request (the planner never splits it) and written in one 10h request.

use crate::scale::RawRange;

/// The registers one value occupies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Width {
    /// One 16-bit register.
    Word,
    /// Two consecutive registers holding one 32-bit value.
    Pair(WordOrder),
    /// This many consecutive registers (1 or more) holding text, two characters each
    /// ([`crate::text`]): read whole in one request, never joined into a number. Its
    /// integer view ([`Width::join`], [`Width::range`]) is its first word's, which nothing
    /// decodes: a text is decoded from all its words by [`crate::text::decode`].
    Text(u8),
}

/// Which half of a 32-bit value sits at the lower address (a map's `pair.order`:
/// `high_first`, `low_first`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum WordOrder {
    /// The high word first (at the register's address), the low word at the next address.
    HighFirst,
    /// The low word first, the high word at the next address.
    LowFirst,
}

impl Width {
    /// The most registers one value takes: one read request's (Modbus 03h/04h read at most
    /// 125). A map's string is bounded by its `max_read`, below this.
    pub const MAX_WORDS: usize = 125;

    /// The number of registers.
    pub const fn count(self) -> u16 {
        match self {
            Width::Word => 1,
            Width::Pair(_) => 2,
            Width::Text(n) => n as u16,
        }
    }

    /// The number of bits of the value.
    pub const fn bits(self) -> u32 {
        16 * self.count() as u32
    }

    /// The whole range of the value, signed (two's complement) or unsigned.
    pub const fn range(self, signed: bool) -> RawRange {
        match (self, signed) {
            (Width::Word | Width::Text(_), _) => RawRange::word(signed),
            (Width::Pair(_), true) => RawRange::new(i32::MIN as i64, i32::MAX as i64),
            (Width::Pair(_), false) => RawRange::new(0, u32::MAX as i64),
        }
    }

    /// The integer a raw value stands for, signed or unsigned at this width.
    pub const fn to_int(self, raw: u32, signed: bool) -> i64 {
        match (self, signed) {
            (Width::Word | Width::Text(_), true) => raw as u16 as i16 as i64,
            (Width::Word | Width::Text(_), false) => raw as u16 as i64,
            (Width::Pair(_), true) => raw as i32 as i64,
            (Width::Pair(_), false) => raw as i64,
        }
    }

    /// The raw value of an integer already checked against a range of this width.
    pub const fn from_int(self, int: i64) -> u32 {
        match self {
            Width::Word | Width::Text(_) => int as u16 as u32,
            Width::Pair(_) => int as u32,
        }
    }

    /// The value held by the first [`Width::count`] words of `words` (missing words read as 0).
    pub fn join(self, words: &[u16]) -> u32 {
        let word = |i: usize| u32::from(words.get(i).copied().unwrap_or(0));
        match self {
            Width::Word | Width::Text(_) => word(0),
            Width::Pair(WordOrder::HighFirst) => (word(0) << 16) | word(1),
            Width::Pair(WordOrder::LowFirst) => (word(1) << 16) | word(0),
        }
    }

    /// The words of `raw` in wire order; only the first [`Width::count`] are meaningful.
    pub const fn split(self, raw: u32) -> [u16; 2] {
        let (high, low) = ((raw >> 16) as u16, raw as u16);
        match self {
            Width::Word | Width::Text(_) => [low, 0],
            Width::Pair(WordOrder::HighFirst) => [high, low],
            Width::Pair(WordOrder::LowFirst) => [low, high],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_join_and_split_in_their_order() {
        let high = Width::Pair(WordOrder::HighFirst);
        let low = Width::Pair(WordOrder::LowFirst);
        assert_eq!(high.join(&[0x0001, 0x86A0]), 100_000);
        assert_eq!(low.join(&[0x86A0, 0x0001]), 100_000);
        assert_eq!(high.split(100_000), [0x0001, 0x86A0]);
        assert_eq!(low.split(100_000), [0x86A0, 0x0001]);
        assert_eq!(Width::Word.join(&[0xFFFB]), 0xFFFB);
        assert_eq!(Width::Word.to_int(0xFFFB, true), -5);
        assert_eq!(high.to_int(0xFFFF_FFFB, true), -5);
        assert_eq!(high.to_int(0xFFFF_FFFB, false), 0xFFFF_FFFB);
        assert_eq!(high.from_int(-5), 0xFFFF_FFFB);
        assert_eq!(Width::Word.from_int(-5), 0xFFFB);
        for raw in [0u32, 1, 0x8000_0000, 0xFFFF_FFFF, 0x1234_5678] {
            for w in [high, low] {
                assert_eq!(w.join(&w.split(raw)), raw);
            }
        }
    }
}
