//! Parameter number schemes, learnt from the manual itself.
//!
//! Manuals number parameters in many ways (`n001`, `Sn-01`, `C1-01`, `CM.01`, `P0.01`,
//! `F1-05`). None is built in: a token shaped like a parameter number (letters, digits and at most
//! one separator) that starts a row is a candidate, and a *shape* (letters → `A`, digits → `9`:
//! `Sn-01` → `AA-99`) becomes a scheme when several different numbers of that shape start
//! lines of the manual. Prose that happens to start with `RS-485` or `CRC-16` does not make a
//! scheme: one such line is not a table.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::LazyLock;

use regex::Regex;

use crate::text::hex_address;

/// How many different numbers of one shape must start lines before the shape is a scheme.
pub const MIN_SCHEME_ROWS: usize = 4;

/// The shape of a parameter number: each letter `A` (either case: `b1-01` and `C1-01` are one
/// scheme), each digit `9`.
pub fn shape(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_digit() {
                '9'
            } else if c.is_alphabetic() {
                'A'
            } else {
                c
            }
        })
        .collect()
}

/// A token at the start of `s` that could be a parameter number, with the rest of `s`.
/// `b6-03Dwell` gives `b6-03` (a number glued to the name that follows it, as OCR leaves
/// tables), `n001` gives `n001`, `Sn-01` gives `Sn-01`.
pub fn param_prefix(s: &str) -> Option<(&str, &str)> {
    static RE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"^(?:[A-Za-z]{1,4}\d{0,2}[-._]\d{1,4}|[A-Za-z]{1,3}\d{1,4})").expect("pattern")
    });
    let m = RE.find(s)?;
    let token = m.as_str();
    let rest = &s[m.end()..];
    // The number must end at a word boundary, or be glued to a capitalised word.
    let mut chars = rest.chars();
    match chars.next() {
        None => {}
        Some(c) if !c.is_alphanumeric() => {}
        // Glued to the capital letter of the name (`b6-03Dwell`, `C2-01S-curve`, `U1-07DC Bus`).
        Some(c) if c.is_uppercase() => {}
        _ => return None,
    }
    if !token.chars().any(|c| c.is_ascii_alphabetic()) || hex_address(token).is_some() {
        return None;
    }
    Some((token, rest))
}

/// A hex address glued to what follows (`19Ehb6-03`, `300hE1-01`): the address and the rest.
pub fn glued_address(s: &str) -> Option<(u16, &str, &str)> {
    static RE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"^(?:0x[0-9A-Fa-f]{1,4}|0h[0-9A-Fa-f]{4}|[0-9A-F]{1,4}[hH])").expect("pattern")
    });
    let m = RE.find(s)?;
    let printed = m.as_str();
    let address = hex_address(printed).or_else(|| {
        let d = printed.strip_suffix(['h', 'H'])?;
        (d.len() >= 3)
            .then(|| u16::from_str_radix(d, 16).ok())
            .flatten()
    })?;
    Some((address, printed, &s[m.end()..]))
}

/// The schemes of a manual: shapes of parameter numbers that start (or follow an address at the
/// start of) at least [`MIN_SCHEME_ROWS`] lines with different numbers.
pub fn learn(lines: &[&str]) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in lines {
        let t = line.trim_start();
        let after_address = glued_address(t)
            .map(|(_, _, rest)| rest.trim_start())
            .or_else(|| {
                let first = t.split_whitespace().next()?;
                // After an address: marked hex, or a decimal register number.
                (hex_address(first).is_some()
                    || (first.len() <= 5 && first.chars().all(|c| c.is_ascii_digit())))
                .then(|| t[first.len()..].trim_start())
            });
        for candidate in [Some(t), after_address].into_iter().flatten() {
            if let Some((token, rest)) = param_prefix(candidate) {
                // A row names something after its number: prose such as `n003 = 1` does not count.
                let rest = rest.trim_start();
                if rest.starts_with(|c: char| c.is_alphanumeric() || c == '(') {
                    seen.entry(shape(token))
                        .or_default()
                        .insert(token.to_string());
                }
            }
        }
    }
    seen.into_iter()
        .filter(|(_, numbers)| numbers.len() >= MIN_SCHEME_ROWS)
        .map(|(shape, _)| shape)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_at_the_start_of_a_row() {
        assert_eq!(
            param_prefix("b6-03Dwell Time"),
            Some(("b6-03", "Dwell Time"))
        );
        assert_eq!(
            param_prefix("Sn-01\tInverter"),
            Some(("Sn-01", "\tInverter"))
        );
        assert_eq!(param_prefix("n001 0101h"), Some(("n001", " 0101h")));
        assert_eq!(param_prefix("CM.01 Int485"), Some(("CM.01", " Int485")));
        assert_eq!(param_prefix("Stop"), None);
        assert_eq!(param_prefix("0101h"), None);
    }

    #[test]
    fn glued_addresses() {
        assert_eq!(
            glued_address("19Ehb6-03Dwell").map(|(a, _, r)| (a, r)),
            Some((0x19E, "b6-03Dwell"))
        );
        assert_eq!(glued_address("0x0300 Out").map(|(a, _, _)| a), Some(0x300));
        assert_eq!(glued_address("Fh Custom"), None);
    }

    #[test]
    fn a_scheme_needs_several_rows() {
        let lines = [
            "Sn-01 Capacity",
            "Sn-02 Curve",
            "Sn-03 Modes",
            "RS-485 wiring",
            "Sn-04 Source",
        ];
        let schemes = learn(&lines);
        assert!(schemes.contains("AA-99"));
        assert!(!schemes.contains("AA-999"));
    }
}
