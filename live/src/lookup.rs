//! Registers by the names a user types: id, parameter number as printed, or printed name,
//! case-insensitively, with the nearest names suggested when nothing matches.

use std::fmt;

use drivemap_codegen::ir::{Drive, Register};

/// No register has that name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NotFound {
    pub name: String,
    pub drive: String,
    /// Nearest ids (with parameter numbers), best first.
    pub suggestions: Vec<String>,
}

impl fmt::Display for NotFound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} has no register `{}`", self.drive, self.name)?;
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

/// Finds a register by id, parameter number or printed name (case and punctuation ignored).
/// Broadcast-only registers are found by id only.
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
        suggestions: scored
            .into_iter()
            .filter(|(d, _)| *d <= limit)
            .take(5)
            .map(|(_, s)| s)
            .collect(),
    })
}
