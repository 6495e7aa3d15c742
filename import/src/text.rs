//! The words of a manual's row: numbers as printed, units, ranges, addresses.
//!
//! Written from what drive manuals print, not from any one manual: hex addresses with a suffix
//! (`0101h`, `032BH`), a prefix (`0x0300`, `0h0300`) or none (decimal `40001`, `1102`); ranges as
//! `0.0~400.0`, `0.00 to 655.35`, `1 – 60`, `-10.0 - 10.0`, `±100 %`; a unit column that is a
//! resolution (`0.01 Hz`, `0.1s`, `1%`) or a bare unit (`Hz`, `sec`).

use std::sync::LazyLock;

use regex::Regex;

/// A number as printed: its value and how many decimals it shows (`0.00` → 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Num {
    /// The value.
    pub value: f64,
    /// How many decimals are printed.
    pub decimals: u32,
}

impl Num {
    /// Parses `12`, `-10.0`, `+5`, `655.35`, `.5`; nothing else (no exponent, no hex).
    pub fn parse(s: &str) -> Option<Num> {
        let s = s.trim();
        let body = s.strip_prefix(['+', '-', '−']).unwrap_or(s);
        if body.is_empty() || !body.chars().all(|c| c.is_ascii_digit() || c == '.') {
            return None;
        }
        if body.matches('.').count() > 1 || body == "." || body.ends_with('.') {
            return None;
        }
        let decimals = body.split_once('.').map_or(0, |(_, f)| f.len() as u32);
        let negative = s.starts_with(['-', '−']);
        let value: f64 = body.parse().ok()?;
        Some(Num {
            value: if negative { -value } else { value },
            decimals,
        })
    }
}

/// Units as manuals print them, with the spelling a map uses. Longer spellings first, so that a
/// unit glued to the next word is read whole (`secs`, not `s` + `ecs`).
const UNITS: &[(&str, &str)] = &[
    ("seconds", "s"),
    ("second", "s"),
    ("secs", "s"),
    ("sec.", "s"),
    ("sec", "s"),
    ("msec.", "ms"),
    ("msec", "ms"),
    ("ms", "ms"),
    ("minutes", "min"),
    ("min.", "min"),
    ("min", "min"),
    ("hours", "h"),
    ("hrs", "h"),
    ("kHz", "kHz"),
    ("Hz", "Hz"),
    ("hz", "Hz"),
    ("VAC", "V"),
    ("VDC", "V"),
    ("Vac", "V"),
    ("Vdc", "V"),
    ("kVA", "kVA"),
    ("kW", "kW"),
    ("mA", "mA"),
    ("mH", "mH"),
    ("mV", "mV"),
    ("rpm", "rpm"),
    ("r/min", "rpm"),
    ("ohms", "Ω"),
    ("ohm", "Ω"),
    ("Ω", "Ω"),
    ("°C", "°C"),
    ("℃", "°C"),
    ("%", "%"),
    ("V", "V"),
    ("A", "A"),
    ("W", "W"),
    ("s", "s"),
    ("h", "h"),
];

/// The unit spelled at the start of `s` (after blanks), with the rest of `s`. A unit must end
/// at a word boundary: `Hz0.0` is `Hz` then `0.0`, `Heat` is no unit.
pub fn unit_prefix(s: &str) -> Option<(&'static str, &str)> {
    let t = s.trim_start();
    for (printed, unit) in UNITS {
        if let Some(rest) = t.strip_prefix(printed) {
            let next = rest.chars().next();
            let boundary = match next {
                None => true,
                Some(c) => !c.is_alphabetic() || printed.ends_with('.') || *printed == "%",
            };
            if boundary {
                return Some((unit, rest));
            }
        }
    }
    None
}

/// A whole cell that is a unit (`Hz`, `sec`, `%`).
pub fn unit_cell(s: &str) -> Option<&'static str> {
    match unit_prefix(s) {
        Some((u, rest)) if rest.trim().is_empty() => Some(u),
        _ => None,
    }
}

/// A unit column giving a resolution: `0.01Hz`, `0.1 s`, `1%`, `0.00 1Ω` (a blank inside the
/// number, as OCR leaves it), `0.01` (no unit). Returns the step and the unit.
pub fn resolution_cell(s: &str) -> Option<(Num, Option<&'static str>)> {
    static RE: LazyLock<Regex> =
        LazyLock::new(|| Regex::new(r"^(\d+(?:\.[\d ]*\d)?)\s*(.*)$").expect("pattern"));
    let c = RE.captures(s.trim())?;
    let digits: String = c[1].chars().filter(|c| *c != ' ').collect();
    let n = Num::parse(&digits)?;
    if n.value <= 0.0 {
        return None;
    }
    // A resolution is 1, or 1 in some decimal place (0.1, 0.01, 0.001, 10, 100).
    let mantissa = n.value / 10f64.powi(n.value.log10().floor() as i32);
    if (mantissa - 1.0).abs() > 1e-9 {
        return None;
    }
    let rest = c[2].trim();
    if rest.is_empty() {
        return Some((n, None));
    }
    Some((n, Some(unit_cell(rest)?)))
}

/// A range as printed, with the units printed after either end.
#[derive(Debug, Clone, PartialEq)]
pub struct Range {
    /// The lower end.
    pub min: Num,
    /// The upper end.
    pub max: Num,
    /// The unit printed after either end.
    pub unit: Option<&'static str>,
    /// Byte offsets of the range in the text it was found in.
    pub start: usize,
    /// Where the range ends in the text (byte offset).
    pub end: usize,
}

static NUMBER: &str = r"[-+−]?(?:\d+(?:\.\d+)?|\.\d+)";

/// The first range in `s`: `a~b`, `a ~ b`, `a to b`, `a - b`, `a – b`, `a..b`, each end
/// optionally followed by a unit; or `±a`. A hex range (`0 to Eh`) is not a decimal range.
pub fn find_range(s: &str) -> Option<Range> {
    static RE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(&format!(
            r"(?:^|[^\d.])(?P<a>{NUMBER})\s*(?P<ua>[^\d\s~.\-–—]{{0,7}}?)\s*(?:~|～|\bto\b|–|—|-|\.\.)\s*(?P<b>{NUMBER})(?P<ub>\s*[^\d\s]{{0,7}})?"
        ))
        .expect("pattern")
    });
    static PM: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"±\s*(?P<a>\d+(?:\.\d+)?)(?P<ua>\s*[^\d\s]{0,7})?").expect("pattern")
    });
    let mut best: Option<Range> = None;
    for c in RE.captures_iter(s) {
        let a = Num::parse(&c["a"]);
        let b = Num::parse(&c["b"]);
        let (Some(min), Some(max)) = (a, b) else {
            continue;
        };
        if min.value > max.value {
            continue;
        }
        let ua = c.name("ua").map(|m| m.as_str().trim()).unwrap_or("");
        let unit_a = if ua.is_empty() { None } else { unit_cell(ua) };
        if !ua.is_empty() && unit_a.is_none() {
            continue;
        }
        let ub = c
            .name("ub")
            .and_then(|m| unit_prefix(m.as_str()))
            .map(|(u, _)| u);
        if let (Some(x), Some(y)) = (unit_a, ub)
            && x != y
        {
            continue;
        }
        // A hex end (`0 to Eh`) is not read as decimal: the char after b must not be hex+h.
        let after = &s[c.name("b").map_or(s.len(), |m| m.end())..];
        if after.starts_with(|c: char| c.is_ascii_hexdigit()) && after.contains(['h', 'H']) {
            let tail: String = after
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric())
                .collect();
            if tail.ends_with(['h', 'H']) && tail.len() <= 4 {
                continue;
            }
        }
        let start = c.name("a").map_or(0, |m| m.start());
        let end = c.name("ub").filter(|_| ub.is_some()).map_or_else(
            || c.name("b").map_or(0, |m| m.end()),
            |m| {
                let text = m.as_str();
                let trimmed = text.trim_start();
                let lead = text.len() - trimmed.len();
                let unit_len =
                    unit_prefix(trimmed).map_or(0, |(_, rest)| trimmed.len() - rest.len());
                m.start() + lead + unit_len
            },
        );
        best = Some(Range {
            min,
            max,
            unit: unit_a.or(ub),
            start,
            end,
        });
        break;
    }
    if let Some(c) = PM.captures(s) {
        let m = c.get(0).expect("whole match");
        if best.as_ref().is_none_or(|r| m.start() < r.start) {
            let a = Num::parse(&c["a"])?;
            let unit = c
                .name("ua")
                .and_then(|u| unit_prefix(u.as_str()))
                .map(|(u, _)| u);
            return Some(Range {
                min: Num {
                    value: -a.value,
                    decimals: a.decimals,
                },
                max: a,
                unit,
                start: m.start(),
                end: m.end(),
            });
        }
    }
    // Bands joined by `or` or a comma (`0.00 - 9.99 or 100.0 - 400.0Hz`) are one range, from
    // the first band's minimum to the last band's maximum.
    if let Some(r) = best.as_mut() {
        loop {
            let after = &s[r.end..];
            let trimmed = after.trim_start();
            let Some(rest) = trimmed
                .strip_prefix("or ")
                .or_else(|| trimmed.strip_prefix(','))
            else {
                break;
            };
            let offset = s.len() - rest.len();
            match find_range(rest) {
                Some(next)
                    if rest[..next.start].trim().is_empty() && next.min.value >= r.max.value =>
                {
                    r.max = next.max;
                    r.min.decimals = r.min.decimals.max(next.min.decimals);
                    r.unit = r.unit.or(next.unit);
                    r.end = offset + next.end;
                }
                _ => break,
            }
        }
    }
    best
}

/// An address as printed, read as a number: `0101h`, `032BH`, `0x0300`, `0h0300`.
pub fn hex_address(tok: &str) -> Option<u16> {
    let t = tok.trim();
    let digits = if let Some(d) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        d
    } else if let Some(d) = t.strip_prefix("0h").filter(|d| d.len() == 4) {
        d
    } else if let Some(d) = t.strip_suffix(['h', 'H']) {
        // `Eh` or `01h` is a code (a function, an exception), not an address: an address
        // printed with a suffix shows at least three digits (`1A0h`, `0101h`).
        if d.len() < 3 {
            return None;
        }
        d
    } else {
        return None;
    };
    if digits.is_empty() || digits.len() > 4 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return None;
    }
    u16::from_str_radix(digits, 16).ok()
}

/// Splits a line into cells: tabs, `|` rules and runs of two or more blanks separate cells.
pub fn cells(line: &str) -> Vec<&str> {
    static RE: LazyLock<Regex> =
        LazyLock::new(|| Regex::new(r"\t+| {2,}|\s\|\s|^\|\s*|\s*\|$").expect("pattern"));
    RE.split(line)
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_their_decimals() {
        assert_eq!(Num::parse("0.00").map(|n| n.decimals), Some(2));
        assert_eq!(Num::parse("-10.5").map(|n| n.value), Some(-10.5));
        assert_eq!(Num::parse("1.2.3"), None);
        assert_eq!(Num::parse("12a"), None);
    }

    #[test]
    fn ranges_in_many_notations() {
        let r = find_range("0.0~400.0Hz").unwrap();
        assert_eq!((r.min.value, r.max.value, r.unit), (0.0, 400.0, Some("Hz")));
        let r = find_range("Droop 0.00 to 655.35 sec").unwrap();
        assert_eq!(
            (r.max.value, r.max.decimals, r.unit),
            (655.35, 2, Some("s"))
        );
        let r = find_range("1 – 60min").unwrap();
        assert_eq!((r.min.value, r.max.value, r.unit), (1.0, 60.0, Some("min")));
        let r = find_range("±100 %").unwrap();
        assert_eq!(
            (r.min.value, r.max.value, r.unit),
            (-100.0, 100.0, Some("%"))
        );
        let r = find_range("-10.0 - 10.0 V").unwrap();
        assert_eq!((r.min.value, r.max.value), (-10.0, 10.0));
        assert!(find_range("0 to Eh").is_none());
        let r = find_range("0.00 - 9.99hz or 100.0 - 400.0Hz").unwrap();
        assert_eq!(
            (r.min.value, r.max.value, r.unit, r.min.decimals),
            (0.0, 400.0, Some("Hz"), 2)
        );
        assert!(find_range("Stop").is_none());
    }

    #[test]
    fn resolutions_and_units() {
        assert_eq!(
            resolution_cell("0.01Hz").map(|(n, u)| (n.value, u)),
            Some((0.01, Some("Hz")))
        );
        assert_eq!(
            resolution_cell("0.00 1Ω").map(|(n, u)| (n.value, u)),
            Some((0.001, Some("Ω")))
        );
        assert_eq!(
            resolution_cell("1%").map(|(n, u)| (n.value, u)),
            Some((1.0, Some("%")))
        );
        assert_eq!(resolution_cell("5 Hz"), None);
        assert_eq!(unit_prefix("Hz0.0"), Some(("Hz", "0.0")));
        assert_eq!(unit_prefix("Heat"), None);
    }

    #[test]
    fn addresses() {
        assert_eq!(hex_address("032BH"), Some(0x032B));
        assert_eq!(hex_address("0x0300"), Some(0x0300));
        assert_eq!(hex_address("0h03E7"), Some(0x03E7));
        assert_eq!(hex_address("Eh"), None);
        assert_eq!(hex_address("01H"), None);
        assert_eq!(hex_address("0101"), None);
    }
}
