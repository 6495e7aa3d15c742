//! Indexed access (`indexed:` on a value register) compared: a change to what an entry means
//! (added, removed, another index, scale, unit, sign, limits, access, name, the index register,
//! the `unknown` reason) is an "indexed access changed"; a change of citations or notes only is
//! a "citation changed".

use drivemap_map::facts::{Indexed, IndexedEntry};

use super::classify::ChangeKind;

/// One line per entry: what it means, without its citation or notes.
fn entry(e: &IndexedEntry) -> String {
    let mut s = format!("{} {} ({})", e.index, e.id, e.name);
    if let Some(p) = &e.param {
        s += &format!(" {p}");
    }
    s += &format!(" ×{}", e.scale.unwrap_or(1.0));
    if let Some(u) = &e.unit {
        s += &format!(" {u}");
    }
    if e.signed {
        s += " signed";
    }
    let limit = |l: Option<f64>| l.map_or("-".to_owned(), |v| v.to_string());
    s += &format!(" {}..={}", limit(e.min), limit(e.max));
    if let Some(a) = e.access {
        s += &format!(" {a:?}");
    }
    s
}

/// What the pair means, as text: the index register, its entries and the `unknown` reason.
fn meaning(ix: &Indexed) -> String {
    let mut parts = vec![format!("index in {}", ix.by)];
    parts.extend(ix.entries.iter().map(entry));
    if let Some(u) = &ix.unknown {
        parts.push(format!("not listed: {u}"));
    }
    parts.join("; ")
}

fn citations(ix: &Indexed) -> Vec<(&str, &[String])> {
    std::iter::once((ix.source.as_str(), &[][..]))
        .chain(ix.entries.iter().map(|e| (e.source.as_str(), &e.notes[..])))
        .collect()
}

/// The change between two `indexed:` of one register, if any: its kind and both sides' text.
pub(super) fn change(
    a: Option<&Indexed>,
    b: Option<&Indexed>,
) -> Option<(ChangeKind, Option<String>, Option<String>)> {
    let text = |x: Option<&Indexed>| Some(x.map_or_else(|| "none".to_owned(), meaning));
    match (a, b) {
        (None, None) => None,
        (Some(x), Some(y)) if x == y => None,
        (Some(x), Some(y)) if meaning(x) == meaning(y) && citations(x) != citations(y) => {
            Some((ChangeKind::CitationChanged, None, None))
        }
        _ => Some((ChangeKind::IndexedChanged, text(a), text(b))),
    }
}
