//! Registers by the names a user types: id, parameter number as printed, printed name
//! (case-insensitively), or the address in the manual's notation (`2101H`, `2101h`, `0x2101`; the
//! register number as printed, `45`, when the manual numbers registers in decimal), with the
//! nearest names suggested when nothing matches.

use std::fmt;

use drivemap_map::ir::{Drive, Register};

/// No register has that name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NotFound {
    pub name: String,
    pub drive: String,
    /// Nearest ids (with parameter numbers), best first.
    pub suggestions: Vec<String>,
    /// When the name is an address inside one of the map's gaps (a reserved or illegible
    /// range): the gap as the map describes it, with its citation (boxed: the error stays
    /// small where it is carried).
    pub gap: Option<Box<str>>,
}

impl fmt::Display for NotFound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(gap) = &self.gap {
            return write!(
                f,
                "{} has no register at `{}`: it is in a gap of the map, where nothing is mapped ({gap})",
                self.drive,
                crate::codec::shorten(&self.name)
            );
        }
        write!(
            f,
            "{} has no register `{}`",
            self.drive,
            crate::codec::shorten(&self.name)
        )?;
        if !self.suggestions.is_empty() {
            write!(f, "; did you mean {}?", self.suggestions.join(", "))?;
        }
        Ok(())
    }
}

impl std::error::Error for NotFound {}

fn norm(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// Levenshtein distance, for suggestions.
pub fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let cost = usize::from(ca != *cb);
            cur[j + 1] = (prev[j] + cost).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The address a name writes in a manual's notation: hex with a marker (`2101H`, `2101h`,
/// `0x2101`), or bare decimal digits when `decimal` (a manual numbering registers in decimal).
fn address_in(name: &str, decimal: bool) -> Option<u16> {
    let t = name.trim();
    let hex = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .or_else(|| t.strip_suffix(['h', 'H']));
    match hex {
        Some(h) if !h.is_empty() && h.len() <= 4 && h.bytes().all(|b| b.is_ascii_hexdigit()) => {
            u16::from_str_radix(h, 16).ok()
        }
        Some(_) => None,
        None if decimal
            && !t.is_empty()
            && t.len() <= 5
            && t.bytes().all(|b| b.is_ascii_digit()) =>
        {
            t.parse().ok()
        }
        None => None,
    }
}

/// The register at `address` (its own address, an alternative, or the second word of a pair),
/// among those found by name.
fn at_address(drive: &Drive, address: u16) -> Option<&Register> {
    let normal = drive.registers.iter().filter(|r| !r.broadcast);
    normal
        .clone()
        .find(|r| r.def.address == address)
        .or_else(|| {
            normal.clone().find(|r| {
                r.def
                    .address_alternatives
                    .iter()
                    .any(|a| a.address == address)
                    || (r.def.pair.is_some() && r.def.address.checked_add(1) == Some(address))
            })
        })
}

/// How the manual prints a register's address: `2101H`, or its number in a decimal manual.
fn printed_address(drive: &Drive, r: &Register) -> String {
    match drive.address_format {
        drivemap_map::model::AddressFormat::Decimal => r.def.address.to_string(),
        drivemap_map::model::AddressFormat::Hex => format!("{:04X}H", r.def.address),
    }
}

/// Finds a register by id, parameter number, printed name (case and punctuation ignored), or
/// address in the manual's notation. Broadcast-only registers are found by id only.
pub fn find<'a>(drive: &'a Drive, name: &str) -> Result<&'a Register, NotFound> {
    if let Some(r) = drive.registers.iter().find(|r| r.def.id == name) {
        return Ok(r);
    }
    let key = norm(name);
    let normal = drive.registers.iter().filter(|r| !r.broadcast);
    let hit = normal
        .clone()
        .find(|r| norm(&r.def.id) == key || r.def.param.as_deref().is_some_and(|p| norm(p) == key))
        .or_else(|| normal.clone().find(|r| norm(&r.def.name) == key));
    if let Some(r) = hit {
        return Ok(r);
    }
    let decimal = drive.address_format == drivemap_map::model::AddressFormat::Decimal;
    if let Some(r) = address_in(name, decimal).and_then(|a| at_address(drive, a)) {
        return Ok(r);
    }
    // An address the map records as a gap (reserved, illegible): said so, not suggested away.
    let gap = address_in(name, decimal).and_then(|a| {
        drive.gaps.iter().find_map(|g| {
            let [lo, hi] = g.addresses?;
            (lo..=hi).contains(&a).then(|| {
                // The map's text, on one line, at most 120 characters.
                let mut d: String = g
                    .description
                    .chars()
                    .map(|c| if c.is_control() { ' ' } else { c })
                    .collect();
                if let Some((i, _)) = d.char_indices().nth(120) {
                    d.truncate(i);
                    d.push_str("...");
                }
                format!("{d}; {}", g.source).into_boxed_str()
            })
        })
    });
    if gap.is_some() {
        return Err(NotFound {
            name: name.to_owned(),
            drive: drive.meta.id.clone(),
            suggestions: Vec::new(),
            gap,
        });
    }
    // Digits alone in a manual that prints hex: the register they would be as hex, suggested.
    let as_hex = (!decimal)
        .then(|| address_in(&format!("{}H", name.trim()), false))
        .flatten()
        .and_then(|a| at_address(drive, a))
        .map(|r| format!("{} ({})", printed_address(drive, r), r.def.id));
    let mut scored: Vec<(usize, String)> = drive
        .registers
        .iter()
        .map(|r| {
            let mut d = distance(&key, &norm(&r.def.id));
            if let Some(p) = &r.def.param {
                d = d.min(distance(&key, &norm(p)));
            }
            if !key.is_empty() && norm(&r.def.id).contains(&key) {
                d = d.min(1);
            }
            let shown = match &r.def.param {
                Some(p) => format!("{} ({p})", r.def.id),
                None => r.def.id.clone(),
            };
            (d, shown)
        })
        .collect();
    scored.sort();
    let limit = (key.len() / 2).max(3);
    Err(NotFound {
        name: name.to_owned(),
        drive: drive.meta.id.clone(),
        gap: None,
        suggestions: as_hex
            .into_iter()
            .chain(
                scored
                    .into_iter()
                    .filter(|(d, _)| *d <= limit)
                    .take(5)
                    .map(|(_, s)| s),
            )
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture(path: &str) -> Drive {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/fixtures")
            .join(path);
        drivemap_map::read_map(&p, &Default::default()).expect("fixture map")
    }

    fn id<'a>(drive: &'a Drive, name: &str) -> Result<&'a str, NotFound> {
        find(drive, name).map(|r| r.def.id.as_str())
    }

    #[test]
    fn a_register_is_found_by_the_manuals_hex_address() {
        let acme = fixture("acme-vf1/acme-vf1.yaml");
        for name in ["2101H", "2101h", "0x2101", "0X2101", " 2101H "] {
            assert_eq!(id(&acme, name), Ok("output_frequency"), "{name}");
        }
        // The second word of a 32-bit pair names the pair.
        assert_eq!(id(&acme, "2201H"), Ok("energy_counter"));
        assert_eq!(id(&acme, "0x2200"), Ok("energy_counter"));
        // Digits alone in a hex manual are not an address, but the register they would be is
        // suggested first.
        let e = id(&acme, "2101").unwrap_err().to_string();
        assert!(
            e.starts_with("acme-vf1 has no register `2101`; did you mean 2101H (output_frequency)"),
            "{e}"
        );
        // An address no register has: not found, no guess from it.
        let e = id(&acme, "0x7777").unwrap_err();
        assert_eq!((e.name.as_str(), e.drive.as_str()), ("0x7777", "acme-vf1"));
        let e = e.to_string();
        assert!(e.starts_with("acme-vf1 has no register `0x7777`"), "{e}");
    }

    #[test]
    fn a_decimal_manuals_register_is_found_by_its_number() {
        let z3 = fixture("zenith-z3/zenith-z3.yaml");
        assert_eq!(id(&z3, "45"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "P-01"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "p01"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "10"), Ok("output_frequency"));
        // The hex notations stay hex: 2DH is register 45.
        assert_eq!(id(&z3, "2DH"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "0x2D"), Ok("acceleration_time"));
        let e = id(&z3, "49").unwrap_err().to_string();
        assert!(e.starts_with("zenith-z3 has no register `49`"), "{e}");
        let e = id(&z3, "P-05").unwrap_err();
        assert!(!e.suggestions.is_empty(), "{e}");
        assert!(e.to_string().contains("did you mean"), "{e}");
    }
}
