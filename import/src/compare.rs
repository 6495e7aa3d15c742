//! Rows read from a manual set against the registers of an existing map: what `--merge`
//! proposes and reports, and the figures of `docs/import.md`.

use std::collections::BTreeMap;

use crate::row::Row;

/// A register of an existing map, as far as a manual row can show it.
#[derive(Debug, Clone, PartialEq)]
pub struct Known {
    /// The register's id.
    pub id: String,
    /// Its parameter number, as printed.
    pub param: Option<String>,
    /// Its address, as the manual prints it.
    pub address: u16,
    /// Its name, as printed.
    pub name: String,
    /// Its unit.
    pub unit: Option<String>,
    /// A decimal scale; `Err(kind)` for a scale a row cannot print as one number (relative,
    /// selected by another parameter).
    pub scale: Result<Option<f64>, &'static str>,
    /// Its lower limit, in engineering units.
    pub min: Option<f64>,
    /// Its upper limit, in engineering units.
    pub max: Option<f64>,
    /// `Err` for a default that depends on something (capacity, another setting).
    pub default: Result<Option<f64>, &'static str>,
    /// The manual file and line the register cites.
    pub source: Option<(String, usize)>,
}

/// One field where a row and a register disagree.
#[derive(Debug, Clone, PartialEq)]
pub struct Difference {
    /// The field (`name`, `unit`, `scale`, `min`, `max`, `default`).
    pub field: &'static str,
    /// What the map says.
    pub map: String,
    /// What the manual's row says.
    pub manual: String,
}

/// A row matched to a register (same address and parameter number), with its differences.
#[derive(Debug, Clone)]
pub struct Matched<'a> {
    /// The manual's row.
    pub row: &'a Row,
    /// The map's register.
    pub known: &'a Known,
    /// The fields where they disagree (none: every field equal).
    pub differences: Vec<Difference>,
}

/// Rows against a map's registers.
#[derive(Debug, Clone)]
pub struct Comparison<'a> {
    /// Rows matched to a register.
    pub matched: Vec<Matched<'a>>,
    /// Rows no register has (proposed by `--merge`).
    pub new_rows: Vec<&'a Row>,
    /// Registers citing the manual that no row matched.
    pub missed: Vec<&'a Known>,
}

fn key(param: Option<&str>, address: Option<u16>) -> (Option<String>, Option<u16>) {
    (param.map(str::to_ascii_uppercase), address)
}

/// Compares the proposed rows (reserved rows are not proposed) with the registers; `manual` is
/// the file name registers must cite to count as missed.
pub fn compare<'a>(rows: &'a [Row], known: &'a [Known], manual: &str) -> Comparison<'a> {
    let mut by_key: BTreeMap<(Option<String>, Option<u16>), Vec<&Known>> = BTreeMap::new();
    for k in known {
        by_key
            .entry(key(k.param.as_deref(), Some(k.address)))
            .or_default()
            .push(k);
    }
    let mut matched = Vec::new();
    let mut new_rows = Vec::new();
    let mut hit: std::collections::BTreeSet<&str> = Default::default();
    for row in rows.iter().filter(|r| !r.reserved && r.address.is_some()) {
        let candidates = by_key.get(&key(row.param.as_deref(), row.address));
        match candidates {
            Some(ks) => {
                // Several registers at one address and number (variants): the one citing this
                // line, else the first.
                let k = ks
                    .iter()
                    .find(|k| k.source.as_ref().is_some_and(|(_, l)| *l == row.line))
                    .unwrap_or(&ks[0]);
                hit.insert(&k.id);
                matched.push(Matched {
                    row,
                    known: k,
                    differences: differences(row, k),
                });
            }
            None => new_rows.push(row),
        }
    }
    let missed = known
        .iter()
        .filter(|k| !hit.contains(k.id.as_str()))
        .filter(|k| k.source.as_ref().is_some_and(|(f, _)| f == manual))
        .collect();
    Comparison {
        matched,
        new_rows,
        missed,
    }
}

/// A name as compared: case, blanks and punctuation aside (`Accel/Decel Time` = `accel / decel
/// time`).
pub fn name_key(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_alphanumeric())
        .flat_map(char::to_lowercase)
        .collect()
}

fn same(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
        _ => false,
    }
}

fn show(v: Option<f64>) -> String {
    v.map_or_else(|| "(none)".to_string(), |v| v.to_string())
}

fn differences(row: &Row, k: &Known) -> Vec<Difference> {
    let mut out = Vec::new();
    if name_key(&row.name) != name_key(&k.name) {
        out.push(Difference {
            field: "name",
            map: k.name.clone(),
            manual: row.name.clone(),
        });
    }
    if row.unit != k.unit {
        out.push(Difference {
            field: "unit",
            map: k.unit.clone().unwrap_or_else(|| "(none)".into()),
            manual: row.unit.clone().unwrap_or_else(|| "(none)".into()),
        });
    }
    match k.scale {
        Ok(s) if same(s, row.scale) => {}
        Ok(s) => out.push(Difference {
            field: "scale",
            map: show(s),
            manual: show(row.scale),
        }),
        Err(kind) => out.push(Difference {
            field: "scale",
            map: kind.to_string(),
            manual: show(row.scale),
        }),
    }
    for (field, m, r) in [("min", k.min, row.min), ("max", k.max, row.max)] {
        if !same(m, r) {
            out.push(Difference {
                field,
                map: show(m),
                manual: show(r),
            });
        }
    }
    match k.default {
        Ok(d) if same(d, row.default) => {}
        Ok(d) => out.push(Difference {
            field: "default",
            map: show(d),
            manual: show(row.default),
        }),
        Err(kind) => out.push(Difference {
            field: "default",
            map: kind.to_string(),
            manual: show(row.default),
        }),
    }
    out
}

/// The figures of `docs/import.md` for one manual against one or more maps' registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Figures {
    /// Registers of the maps citing the manual with an address (the rows to find).
    pub register_rows: usize,
    /// Rows proposed (reserved rows are reported, not proposed).
    pub proposed: usize,
    /// Proposed rows matching a register in address and parameter number.
    pub matched: usize,
    /// Of those, rows with name, unit, scale, range and default all equal.
    pub all_equal: usize,
    /// Proposed rows matching no register.
    pub unmatched: usize,
    /// Registers citing the manual no row matched.
    pub missed: usize,
}

impl Figures {
    /// The figures of a comparison whose registers citing the manual number `register_rows`.
    pub fn of(c: &Comparison<'_>, register_rows: usize) -> Figures {
        Figures {
            register_rows,
            proposed: c.matched.len() + c.new_rows.len(),
            matched: c.matched.len(),
            all_equal: c
                .matched
                .iter()
                .filter(|m| m.differences.is_empty())
                .count(),
            unmatched: c.new_rows.len(),
            missed: c.missed.len(),
        }
    }

    /// Registers found, in percent of the registers citing the manual.
    pub fn found_percent(&self) -> f64 {
        percent(self.register_rows - self.missed, self.register_rows)
    }

    /// Matched rows with every field right, in percent of the matched rows.
    pub fn all_equal_percent(&self) -> f64 {
        percent(self.all_equal, self.matched)
    }
}

fn percent(a: usize, b: usize) -> f64 {
    if b == 0 {
        0.0
    } else {
        100.0 * a as f64 / b as f64
    }
}
