//! Text in consecutive registers: model names, serial numbers and firmware versions, two
//! characters per register.
//!
//! A map's `string: {registers: N, byte_order: high_first}` says a register holds `N` registers
//! of text starting at its address ([`crate::width::Width::Text`]); the manual says which byte of
//! each register holds the first character ([`ByteOrder`]). Drives pad the text with NUL or
//! spaces; [`decode`] drops the padding at the end. The text comes from the wire and is not
//! trusted: [`Text`]'s `Display` escapes every byte that is not printable ASCII, so a log line or
//! a table cell shows what was read without a control character reaching the terminal.
//!
//! No allocation: a text is held in a fixed buffer of `N` bytes ([`Text`]), `N` = 2 × registers.

use core::fmt;

/// Which byte of each register holds the earlier character (a map's `string.byte_order`:
/// `high_first`, `low_first`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum ByteOrder {
    /// The high byte holds the first character of the pair (the usual order: "AB" is 4142h).
    HighFirst,
    /// The low byte holds the first character ("AB" is 4241h).
    LowFirst,
}

impl ByteOrder {
    /// The two characters of one register, in text order.
    pub const fn bytes(self, word: u16) -> [u8; 2] {
        let [hi, lo] = word.to_be_bytes();
        match self {
            ByteOrder::HighFirst => [hi, lo],
            ByteOrder::LowFirst => [lo, hi],
        }
    }

    /// The register holding two characters given in text order.
    pub const fn word(self, pair: [u8; 2]) -> u16 {
        match self {
            ByteOrder::HighFirst => u16::from_be_bytes(pair),
            ByteOrder::LowFirst => u16::from_le_bytes(pair),
        }
    }

    /// `high_first` / `low_first`, as a map writes it.
    pub const fn name(self) -> &'static str {
        match self {
            ByteOrder::HighFirst => "high_first",
            ByteOrder::LowFirst => "low_first",
        }
    }
}

/// Whether a byte is shown as itself: printable ASCII, space included (20h-7Eh).
pub const fn printable(byte: u8) -> bool {
    matches!(byte, 0x20..=0x7E)
}

/// Writes the characters of `words` into `out` in text order and returns how many of them are
/// text: trailing NUL (00h) and space (20h) bytes are padding and dropped. Bytes past the
/// end of `out` are ignored; `out` past `2 × words.len()` is left as it is. Any words decode.
pub fn decode(words: &[u16], order: ByteOrder, out: &mut [u8]) -> usize {
    let mut n = 0;
    for (&word, slot) in words.iter().zip(out.chunks_mut(2)) {
        let pair = order.bytes(word);
        slot.copy_from_slice(&pair[..slot.len()]);
        n += slot.len();
    }
    let mut len = n;
    while len > 0 && matches!(out[len - 1], 0x00 | b' ') {
        len -= 1;
    }
    len
}

/// A text that does not fit its registers, or that holds a byte that is not printable ASCII.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum TextError {
    /// Longer than the registers hold.
    #[error("{len} characters do not fit in {registers} registers (at most {})", 2 * *registers as usize)]
    TooLong {
        /// The characters given.
        len: usize,
        /// The registers of the text.
        registers: u16,
    },
    /// A byte that is not printable ASCII (20h-7Eh).
    #[error("character {index} (byte {byte:02X}h) is not printable ASCII (20h-7Eh)")]
    NotPrintable {
        /// Its place in the text, from 0.
        index: usize,
        /// The byte.
        byte: u8,
    },
}

/// The registers holding `text` in `order`, padded with NUL: fills all of `words`. Only
/// printable ASCII that fits is accepted.
pub fn encode(text: &[u8], order: ByteOrder, words: &mut [u16]) -> Result<(), TextError> {
    let registers = u16::try_from(words.len()).unwrap_or(u16::MAX);
    if text.len() > 2 * words.len() {
        return Err(TextError::TooLong {
            len: text.len(),
            registers,
        });
    }
    if let Some((index, &byte)) = text.iter().enumerate().find(|(_, b)| !printable(**b)) {
        return Err(TextError::NotPrintable { index, byte });
    }
    for (i, word) in words.iter_mut().enumerate() {
        let at = |k: usize| text.get(2 * i + k).copied().unwrap_or(0);
        *word = order.word([at(0), at(1)]);
    }
    Ok(())
}

/// A text read from `N / 2` registers, without padding, in a fixed buffer: the value of a
/// generated string register (`Text<16>` for eight registers). Shown (`Display`) with every
/// byte that is not printable ASCII escaped (`\xNN`; `\\` and `\"` for a backslash and a quote), so the text
/// of an unknown drive cannot put control characters into a log or a terminal.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Text<const N: usize> {
    bytes: [u8; N],
    len: usize,
}

impl<const N: usize> Text<N> {
    /// Decodes the registers read (`words`, at most `N / 2` used) in `order`.
    pub fn decode(words: &[u16], order: ByteOrder) -> Text<N> {
        let mut bytes = [0; N];
        let len = decode(words, order, &mut bytes);
        Text { bytes, len }
    }

    /// The bytes of the text, padding dropped, as read (not escaped).
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    /// The text when every byte is printable ASCII, `None` otherwise (show it with `Display`).
    pub fn as_str(&self) -> Option<&str> {
        let bytes = self.as_bytes();
        if bytes.iter().all(|&b| printable(b)) {
            core::str::from_utf8(bytes).ok()
        } else {
            None
        }
    }

    /// Whether the registers held only padding.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl<const N: usize> Default for Text<N> {
    fn default() -> Self {
        Text {
            bytes: [0; N],
            len: 0,
        }
    }
}

/// Writes `bytes` with every byte that is not printable ASCII escaped as `\xNN`, a
/// backslash as `\\` and a quote as `\"`: the one way text from a drive is shown.
pub fn write_escaped(f: &mut impl fmt::Write, bytes: &[u8]) -> fmt::Result {
    for &b in bytes {
        match b {
            b'\\' => f.write_str("\\\\")?,
            b'"' => f.write_str("\\\"")?,
            b if printable(b) => f.write_char(char::from(b))?,
            b => write!(f, "\\x{b:02X}")?,
        }
    }
    Ok(())
}

impl<const N: usize> fmt::Display for Text<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_escaped(f, self.as_bytes())
    }
}

impl<const N: usize> fmt::Debug for Text<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Text(\"")?;
        write_escaped(f, self.as_bytes())?;
        f.write_str("\")")
    }
}
