//! Parameter tables addressed by a formula the manual prints in prose: `the register is 10 x
//! the parameter number`, `128 + parameter number`, `(parameter number - 1) * 2 + 529`,
//! `group x 256 + index`. A row that prints a parameter number and no address gets the
//! address the formula gives, with a note citing the formula's line; nothing is computed
//! without a formula the manual prints.

use std::sync::LazyLock;

use regex::Regex;

/// An address formula read from the manual.
#[derive(Debug, Clone, PartialEq)]
pub struct Formula {
    /// Added to the result. A Modicon base (`40000`, `400000`) makes the result a reference,
    /// and the register is the reference less `40001` / `400001` (40001 is register 0).
    pub base: i64,
    /// Multiplies the parameter number (or the group).
    pub mul: i64,
    /// Subtracted from the parameter number before multiplying (`(parameter number - 1)`).
    pub minus: i64,
    /// `group x mul + index` rather than `number x mul`.
    pub group: bool,
    /// The 1-based line of the formula.
    pub line: usize,
    /// The formula as printed.
    pub text: String,
}

const NUMBER: &str = r"param(?:eter)?\s*(?:number|no\.?|code)";

/// The first address formula of the manual, if it prints one.
pub fn find(lines: &[&str]) -> Option<Formula> {
    static GROUP: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"(?i)(?:(\d+)\s*\+\s*)?(?:(?:parameter\s+)?group(?:\s+number)?\s*[x×*]\s*(\d+)|(\d+)\s*[x×*]\s*(?:parameter\s+)?group(?:\s+number)?)\s*\+\s*(?:parameter\s+)?(?:index|number)")
            .expect("pattern")
    });
    static TIMES: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(&format!(
            r"(?i)(?:(\d+)\s*\+\s*)?(?:\(\s*(?:the\s+)?{NUMBER}\s*(?:-\s*(\d+))?\s*\)|(?:the\s+)?{NUMBER})\s*[x×*]\s*(\d+)(?:\s*\+\s*(\d+))?"
        ))
        .expect("pattern")
    });
    static TIMES_BEFORE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(&format!(
            r"(?i)(?:(\d+)\s*\+\s*)?(\d+)\s*[x×*]\s*(?:the\s+)?{NUMBER}(?:\s*\+\s*(\d+))?"
        ))
        .expect("pattern")
    });
    static PLUS: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(&format!(r"(?i)\b(\d+)\s*\+\s*(?:the\s+)?{NUMBER}")).expect("pattern")
    });
    let n = |m: Option<regex::Match<'_>>| m.and_then(|m| m.as_str().parse::<i64>().ok());
    for (i, line) in lines.iter().enumerate() {
        let make = |base: i64, mul: i64, minus: i64, group: bool, m: regex::Match<'_>| Formula {
            base,
            mul,
            minus,
            group,
            line: i + 1,
            text: m.as_str().to_string(),
        };
        if let Some(c) = GROUP.captures(line) {
            let mul = n(c.get(2)).or(n(c.get(3)))?;
            return Some(make(n(c.get(1)).unwrap_or(0), mul, 0, true, c.get(0)?));
        }
        if let Some(c) = TIMES.captures(line) {
            let base = n(c.get(1)).unwrap_or(0) + n(c.get(4)).unwrap_or(0);
            return Some(make(
                base,
                n(c.get(3))?,
                n(c.get(2)).unwrap_or(0),
                false,
                c.get(0)?,
            ));
        }
        if let Some(c) = TIMES_BEFORE.captures(line) {
            let base = n(c.get(1)).unwrap_or(0) + n(c.get(3)).unwrap_or(0);
            return Some(make(base, n(c.get(2))?, 0, false, c.get(0)?));
        }
        if let Some(c) = PLUS.captures(line) {
            return Some(make(n(c.get(1))?, 1, 0, false, c.get(0)?));
        }
    }
    None
}

impl Formula {
    /// The address of a parameter number as printed (`3-41`, `P0940`, `22.80`), when the
    /// formula gives one that fits a register.
    pub fn address(&self, param: &str) -> Option<u16> {
        // A reference: register = reference - (40000 + 1), as for every Modicon number.
        let base = match self.base {
            40000 | 400000 => -1,
            40001 | 400001 => 0,
            b => b,
        };
        let value = if self.group {
            let (g, i) = param
                .trim_start_matches(|c: char| c.is_ascii_alphabetic())
                .split_once(['.', '-', '_'])?;
            let g: i64 = g.parse().ok()?;
            let i: i64 = i.parse().ok()?;
            base + g * self.mul + i
        } else {
            let digits: String = param.chars().filter(char::is_ascii_digit).collect();
            if digits.is_empty() || digits.len() > 6 {
                return None;
            }
            let number: i64 = digits.parse().ok()?;
            base + (number - self.minus) * self.mul
        };
        u16::try_from(value).ok()
    }

    /// Whether the base is a Modicon prefix (the formula gives a 4xxxx reference).
    pub fn modicon(&self) -> bool {
        matches!(self.base, 40000 | 40001 | 400000 | 400001)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formulas_as_manuals_print_them() {
        let f = find(&["The register is 10 x the parameter number."]).unwrap();
        assert_eq!(f.address("3-41"), Some(3410));
        let f = find(&["Register number = (parameter number - 1) * 2 + 529"]).unwrap();
        assert_eq!(f.address("0940"), Some(2407));
        let f = find(&["address = 128 + parameter number"]).unwrap();
        assert_eq!(f.address("P012"), Some(140));
        let f = find(&["use 400000 + 256 * parameter group + parameter index"]).unwrap();
        // 400000 + 256 x 22 + 80 = 405712, the Modicon reference of register 5711.
        assert_eq!(f.address("22.80"), Some(5711));
        assert!(f.modicon());
        assert_eq!(find(&["The drive has 12 parameters."]), None);
    }
}
