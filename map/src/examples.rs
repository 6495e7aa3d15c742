//! Example frames a manual prints (`examples:` in a map): the bytes of a request or response as
//! printed, where the manual prints them, and what they say.
//!
//! The front end reads and checks their form (`validate::examples_valid`): bytes in hex, a
//! citation of one line or a line range, an `answers` naming an earlier request. What the bytes
//! mean is verified against the Modbus codec and the map by `drivemap_live::examples`, which the
//! `drivemap check` command runs (this crate has no codec: it depends on `drivemap-core` only).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::diagnostic::Loc;
use crate::model::TransportName;

/// One example frame as the manual prints it.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Example {
    /// A name for the example, unique in the map (`read_request`).
    pub id: String,
    /// The framing of the bytes: `rtu` (address, PDU, CRC low byte first) or `tcp` (MBAP header
    /// and PDU).
    pub transport: TransportName,
    /// `request` (master to drive) or `response` (drive to master).
    pub direction: Direction,
    /// The bytes as printed, in hex, separated by spaces (`"02 03 00 20 00 04 45 F0"`); a byte
    /// may carry the manual's `h`/`H` suffix or `0x` prefix (`"02h 03h"`). Written on one line.
    pub bytes: String,
    /// Where the manual prints the frame: `file:line`, or `file:first-last` for a frame printed
    /// over several lines.
    pub source: String,
    /// A response: the id of the request example it answers (an earlier example).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub answers: Option<String>,
    /// What the manual says the frame does, where it says it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub says: Option<Says>,
    /// The drive's state the manual assumes for the frame, where a conversion or an address
    /// depends on it: a register (by id or parameter number) or an external quantity, and its
    /// value in engineering units (`settings: {o2-09: 1}`). Examples are otherwise read at the
    /// map's defaults.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub settings: BTreeMap<String, f64>,
    /// The topic of the `conflicts:` entry recording that the printed bytes contradict the
    /// codec or the map (a CRC that does not check, a value the map refuses). `check` then
    /// reports its findings as known instead of errors, and refuses the mark on an example that
    /// verifies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conflict: Option<String>,
    /// Remarks.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl Example {
    /// The example in one line, as `doc` and `diff` show it: transport, direction, the bytes,
    /// what it answers and what it says.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} {} `{}`",
            self.transport,
            self.direction.as_str(),
            self.bytes.trim()
        );
        if let Some(a) = &self.answers {
            s.push_str(&format!(", answers `{a}`"));
        }
        if let Some(says) = &self.says {
            let said = says.text();
            if !said.is_empty() {
                s.push_str(": ");
                s.push_str(&said);
            }
        }
        if !self.settings.is_empty() {
            let set: Vec<String> = self
                .settings
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect();
            s.push_str(&format!(" (with {})", set.join(", ")));
        }
        if let Some(c) = &self.conflict {
            s.push_str(&format!(
                " (contradicts the codec or the map: conflict \"{c}\")"
            ));
        }
        for n in &self.notes {
            s.push_str(&format!(" ({n})"));
        }
        s
    }
}

impl Says {
    /// What the manual says, in words (`read of `frequency_reference``, `exception 21h`).
    pub fn text(&self) -> String {
        let mut parts = Vec::new();
        if let Some(r) = &self.read {
            parts.push(format!("read from `{r}`"));
        }
        if let Some(w) = &self.write {
            parts.push(format!("write to `{w}`"));
        }
        if !self.values.is_empty() {
            let v: Vec<String> = self.values.iter().map(|v| v.to_string()).collect();
            parts.push(format!("values {}", v.join(", ")));
        }
        if let Some(e) = self.exception {
            parts.push(format!("exception {e:02X}h"));
        }
        parts.join(", ")
    }
}

/// The direction of a frame on the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// From the master to the drive.
    Request,
    /// From the drive to the master.
    Response,
}

impl Direction {
    /// `request` or `response`, as the map writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            Direction::Request => "request",
            Direction::Response => "response",
        }
    }
}

/// What the manual says an example does. At most one of `read`, `write`, `exception`.
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Says {
    /// A read (request) or its answer (response) starting at this register (by id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub read: Option<String>,
    /// A write (06h/10h request, or its echo) starting at this register (by id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub write: Option<String>,
    /// The value of each register the frame carries, in order, in engineering units as the map
    /// converts them (a code for an enumeration, the word for bit fields): a write's values, or
    /// the values a read response returns.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<f64>,
    /// An exception response with this code (hex, as printed: `0x21`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exception: Option<u8>,
}

/// One byte of an example's `bytes` text: its value and its character offset in the text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Byte {
    /// The byte.
    pub value: u8,
    /// Where its text starts in the `bytes` text, in characters.
    pub offset: usize,
}

/// Reads `bytes` text into bytes with their offsets; the error is the offset of the first word
/// that is not a byte in hex, and what is wrong with it.
pub fn parse_bytes(text: &str) -> Result<Vec<Byte>, (usize, String)> {
    let mut out = Vec::new();
    let mut offset = 0;
    for word in text.split_inclusive(|c: char| c.is_whitespace() || c == ',') {
        let here = offset;
        offset += word.len();
        let token = word.trim_end_matches(|c: char| c.is_whitespace() || c == ',');
        if token.is_empty() {
            continue;
        }
        let digits = token
            .strip_prefix("0x")
            .or_else(|| token.strip_prefix("0X"))
            .or_else(|| token.strip_suffix(['h', 'H']))
            .unwrap_or(token);
        if digits.len() != 2 || !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err((
                here,
                format!("`{token}` is not a byte in hex (two hex digits: `0B`, `0Bh` or `0x0B`)"),
            ));
        }
        let value = u8::from_str_radix(digits, 16).map_err(|e| (here, e.to_string()))?;
        out.push(Byte {
            value,
            offset: here,
        });
    }
    if out.is_empty() {
        return Err((0, "no bytes".to_owned()));
    }
    Ok(out)
}

/// Splits an example's citation: `file:line` or `file:first-last` into (file, first, last).
pub(crate) fn parse_range_citation(s: &str) -> Option<(&str, usize, usize)> {
    let (file, lines) = s.rsplit_once(':')?;
    let (first, last) = match lines.split_once('-') {
        Some((a, b)) => (a.trim().parse().ok()?, b.trim().parse().ok()?),
        None => {
            let n: usize = lines.trim().parse().ok()?;
            (n, n)
        }
    };
    (!file.is_empty() && first > 0 && first <= last).then_some((file, first, last))
}

/// Where the character at `offset` of a one-line scalar written at `at` lies: the scalar's
/// column, moved past an opening quote when the file shows one there.
pub(crate) fn locate_offset(at: &Loc, offset: usize) -> Loc {
    let quoted = std::fs::read_to_string(&*at.file)
        .ok()
        .and_then(|text| {
            text.lines()
                .nth(at.line.checked_sub(1)?)
                .and_then(|l| l.chars().nth(at.col.checked_sub(1)?))
        })
        .is_some_and(|c| c == '"' || c == '\'');
    Loc::new(
        at.file.clone(),
        at.line,
        at.col + offset + usize::from(quoted),
    )
}

/// Renders bytes as `02 03 00 20`.
pub fn hex_text(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_read_in_every_printed_notation_with_their_offsets() {
        let b = parse_bytes("02 03h 0x20, 0BH").unwrap();
        let v: Vec<(u8, usize)> = b.iter().map(|b| (b.value, b.offset)).collect();
        assert_eq!(v, [(2, 0), (3, 3), (0x20, 7), (0x0B, 13)]);
        assert_eq!(parse_bytes("02 3 04").unwrap_err().0, 3);
        assert_eq!(parse_bytes("02 0G").unwrap_err().0, 3);
        assert!(parse_bytes("  ").is_err());
    }

    #[test]
    fn citations_of_one_line_or_a_range() {
        assert_eq!(parse_range_citation("a.txt:12"), Some(("a.txt", 12, 12)));
        assert_eq!(parse_range_citation("a.txt:12-19"), Some(("a.txt", 12, 19)));
        assert_eq!(parse_range_citation("a.txt:19-12"), None);
        assert_eq!(parse_range_citation("a.txt:0"), None);
        assert_eq!(parse_range_citation("a.txt"), None);
    }
}
