//! Semantic diff of two maps (`drivemap diff`): compares the old and the new map and lists
//! every change with its kind, both sides and the citation of each side. What the lowering pass
//! decides about a register (access, table, transports, write restriction) is compared on the
//! two [`drivemap_core::plan::RegisterPlan`]s; what the manual prints (scales, limits, defaults, codes,
//! fields, citations) on the map as it writes it ([`Map::written`], the facts view). Both sides are written in the library's one wording
//! ([`drivemap_map::describe`]), the wording of the rustdoc and of `drivemap doc`.
//!
//! [`classify()`] says which kinds break applications built on the generated code;
//! [`render`] prints the result for a terminal, as Markdown or as GitHub annotations. The
//! comparisons themselves are in `protocol` (metadata, variants), `profile` (the protocol
//! profile, row by row on the protocol facts) and `registers`. Fetching the old maps from a
//! git revision is the command line's (`cli/src/git.rs`).

mod classify;
mod indexed;
mod locate;
mod profile;
mod protocol;
mod registers;
pub mod render;
mod roles;
#[cfg(test)]
mod tests;

use drivemap_map::Map;
use drivemap_map::describe;
use drivemap_map::facts::WrittenMap;
use serde::Serialize;

pub use classify::{ChangeKind, Severity, classify};

/// One change between the old and the new map.
#[derive(Debug, Clone, PartialEq)]
pub struct Change {
    /// What kind of change; decides the severity.
    pub kind: ChangeKind,
    /// What changed: a register (`accel_time_1 (Bn-01)`), `protocol`, `variants`, the drive.
    pub subject: String,
    /// Which part of it (`code 3`, `range (v440)`, `function codes`); empty for the whole.
    pub what: String,
    /// The old side, as text; `None` when it did not exist.
    pub old: Option<String>,
    /// The new side, as text; `None` when it no longer exists.
    pub new: Option<String>,
    /// Citation of the old side.
    pub old_source: Option<String>,
    /// Citation of the new side.
    pub new_source: Option<String>,
    /// Where the change is in the new map (a variant map's inherited register is in its base's
    /// file), for annotations; `None` when the new map does not have it.
    pub at: Option<drivemap_map::Loc>,
    /// Address, for ordering register changes as the manual lists them.
    order: u32,
}

impl Change {
    /// Breaking or compatible.
    pub fn severity(&self) -> Severity {
        classify(self.kind).0
    }

    /// Why it is classified so.
    pub fn reason(&self) -> &'static str {
        if self.kind == ChangeKind::TableChanged
            && let Some(reason) = classify::table_reason(self.old.as_deref(), self.new.as_deref())
        {
            return reason;
        }
        classify(self.kind).1
    }
}

/// The changes of one drive.
#[derive(Debug, Clone)]
pub struct DriveDiff {
    /// Drive id (the new map's, or the old one's when removed).
    pub drive: String,
    /// Changes in order: drive and protocol, then registers by address, then map documentation.
    pub changes: Vec<Change>,
}

impl DriveDiff {
    /// Number of breaking changes.
    pub fn breaking(&self) -> usize {
        self.changes
            .iter()
            .filter(|c| c.severity() == Severity::Breaking)
            .count()
    }

    /// Number of compatible changes.
    pub fn compatible(&self) -> usize {
        self.changes.len() - self.breaking()
    }
}

/// Order of changes that do not concern a register: before all registers.
pub(crate) const HEAD: u32 = 0;
/// Order of map-level documentation: after all registers.
pub(crate) const TAIL: u32 = u32::MAX;

pub(crate) struct Collector {
    pub(crate) changes: Vec<Change>,
}

/// A side of a change: its text and citation.
pub(crate) type Side = (Option<String>, Option<String>);

impl Collector {
    pub(crate) fn push(
        &mut self,
        kind: ChangeKind,
        subject: &str,
        what: &str,
        old: Side,
        new: Side,
        order: u32,
    ) {
        self.changes.push(Change {
            kind,
            subject: subject.to_owned(),
            what: what.to_owned(),
            old: old.0,
            new: new.0,
            old_source: old.1,
            new_source: new.1,
            at: None,
            order,
        });
    }
}

pub(crate) fn same<T: Serialize>(a: &T, b: &T) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
}

pub(crate) fn json<T: Serialize>(a: &T) -> String {
    serde_json::to_string(a).unwrap_or_default()
}

/// A drive that exists only on one side.
pub fn added(new: &Map) -> DriveDiff {
    let mut c = Collector {
        changes: Vec::new(),
    };
    c.push(
        ChangeKind::DriveAdded,
        new.id(),
        "",
        (None, None),
        (
            Some(format!("{} registers", new.registers().len())),
            new.protocol().source.clone(),
        ),
        HEAD,
    );
    for ch in &mut c.changes {
        ch.at = Some(new.locate("drive"));
    }
    DriveDiff {
        drive: new.id().to_owned(),
        changes: c.changes,
    }
}

/// A drive that exists only on the old side.
pub fn removed(old: &Map) -> DriveDiff {
    let mut c = Collector {
        changes: Vec::new(),
    };
    c.push(
        ChangeKind::DriveRemoved,
        old.id(),
        "",
        (
            Some(format!("{} registers", old.registers().len())),
            old.protocol().source.clone(),
        ),
        (None, None),
        HEAD,
    );
    DriveDiff {
        drive: old.id().to_owned(),
        changes: c.changes,
    }
}

/// Compares two versions of a drive's map.
///
/// Every part of a map is compared. The parts are named here field by field, with no `..`, as
/// are the keys of each register in the function that compares them: the map front end names
/// every part and key of the schema in [`WrittenMap`] and
/// [`WrittenRegister`](drivemap_map::facts::WrittenRegister), so a part or key added to the
/// schema fails to compile until the diff compares it (or says here why it is not a part).
pub fn compare(old: &Map, new: &Map) -> DriveDiff {
    let mut c = Collector {
        changes: Vec::new(),
    };
    let WrittenMap {
        meta: _,           // protocol::meta
        address_format: _, // map_documentation
        variants: _,       // protocol::variants
        protocol: _,       // profile::protocol, on the protocol facts
        groups: _,         // map_documentation (registers carry the group defaults)
        registers: _,      // registers::registers
        conflicts: _,      // map_documentation, entry by entry
        gaps: _,           // map_documentation, entry by entry
        removed: _,        // map_documentation, entry by entry
        roles: _,          // roles::roles
        profile: _,        // roles::command_profile
        draft: _,          // map_documentation
        examples: _,       // map_documentation, example by example
    } = new.written();
    protocol::meta(&mut c, old, new);
    protocol::variants(&mut c, old, new);
    profile::protocol(&mut c, old, new);
    roles::roles(&mut c, old, new);
    roles::command_profile(&mut c, old, new);
    registers::registers(&mut c, old, new);
    map_documentation(&mut c, old, new);
    c.changes.sort_by_key(|ch| ch.order);
    for ch in &mut c.changes {
        ch.at = locate::at(ch, old, new);
    }
    DriveDiff {
        drive: new.id().to_owned(),
        changes: c.changes,
    }
}

/// Map documentation kept as a list of entries (conflicts, gaps, removed registers): each entry
/// by its key (the n-th of a repeated key with the n-th), added, removed or changed, with its
/// text and citation on each side.
// The two lists and how to read an entry of them (key, text, citation): each call site
// names its three readers in place; a struct of closures would only be unpacked here.
#[allow(clippy::too_many_arguments)]
fn keyed<T: Serialize>(
    c: &mut Collector,
    id: &str,
    label: &str,
    a: &[T],
    b: &[T],
    key: impl Fn(&T) -> String,
    text: impl Fn(&T) -> String,
    source: impl Fn(&T) -> Option<String>,
) {
    let keys = |list: &[T]| {
        let mut seen: Vec<String> = Vec::new();
        list.iter()
            .map(|x| {
                let k = key(x);
                let n = seen.iter().filter(|s| **s == k).count();
                seen.push(k.clone());
                if n == 0 {
                    k
                } else {
                    format!("{k} ({})", n + 1)
                }
            })
            .collect::<Vec<_>>()
    };
    let (ka, kb) = (keys(a), keys(b));
    for (x, k) in a.iter().zip(&ka) {
        match kb.iter().position(|j| j == k) {
            None => c.push(
                ChangeKind::DocumentationChanged,
                id,
                &format!("{label} {k} removed"),
                (Some(text(x)), source(x)),
                (None, None),
                TAIL,
            ),
            Some(j) if !same(x, &b[j]) => c.push(
                ChangeKind::DocumentationChanged,
                id,
                &format!("{label} {k}"),
                (Some(text(x)), source(x)),
                (Some(text(&b[j])), source(&b[j])),
                TAIL,
            ),
            Some(_) => {}
        }
    }
    for (y, k) in b.iter().zip(&kb) {
        if !ka.contains(k) {
            c.push(
                ChangeKind::DocumentationChanged,
                id,
                &format!("{label} {k} added"),
                (None, None),
                (Some(text(y)), source(y)),
                TAIL,
            );
        }
    }
}

fn map_documentation(c: &mut Collector, old: &Map, new: &Map) {
    let id = new.id();
    let count = |n: usize, what: &str| Some(format!("{n} {what}"));
    let counts = |a: usize, b: usize, what: &str| {
        if a == b {
            (None, None)
        } else {
            (count(a, what), count(b, what))
        }
    };
    // Conflicts, gaps and removed-register entries one by one, with their citations.
    keyed(
        c,
        id,
        "conflict",
        old.conflicts(),
        new.conflicts(),
        |x| format!("\"{}\"", x.topic),
        |x| format!("chosen: {}", x.chosen),
        |x| x.readings.first().map(|r| r.source.clone()),
    );
    keyed(
        c,
        id,
        "gap",
        old.gaps(),
        new.gaps(),
        // In the new map's notation (`4 – 9` in a decimal-numbered map), the same for both
        // sides: the text is also the key the gaps are matched by.
        |x| match (x.addresses, &x.params) {
            (Some([a, b]), _) => describe::address_span_as(new.address_format(), a, b),
            (None, Some(p)) => p.clone(),
            (None, None) => x.description.clone(),
        },
        |x| x.description.clone(),
        |x| Some(x.source.clone()),
    );
    keyed(
        c,
        id,
        "removed register",
        old.removed(),
        new.removed(),
        |x| format!("`{}`", x.id),
        |x| x.reason.clone(),
        |x| Some(x.source.clone()),
    );
    keyed(
        c,
        id,
        "example frame",
        old.examples(),
        new.examples(),
        |x| format!("`{}`", x.id),
        |x| x.summary(),
        |x| Some(x.source.clone()),
    );
    if old.draft() != new.draft() {
        let text = |d: Option<&drivemap_map::facts::Draft>| {
            Some(match d {
                None => "not a draft".to_string(),
                Some(d) => format!(
                    "a draft by {} ({} item(s) to confirm)",
                    d.by,
                    d.to_confirm.len()
                ),
            })
        };
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "draft mark",
            (text(old.draft()), None),
            (text(new.draft()), None),
            TAIL,
        );
    }
    if old.address_format() != new.address_format() {
        let text = |f: drivemap_map::facts::AddressFormat| Some(format!("{f:?}").to_lowercase());
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "address format",
            (text(old.address_format()), None),
            (text(new.address_format()), None),
            TAIL,
        );
    }
    let group_docs = |d: &Map| {
        d.groups()
            .iter()
            .map(|g| {
                // Access, table, write restriction, transports and repeat rules of a group are
                // its registers' defaults, and its broadcast flag their membership: compared on
                // each register (an empty group's flag here).
                let drivemap_map::facts::Group {
                    id,
                    name,
                    table,
                    source,
                    broadcast,
                    notes,
                    path: _,
                } = g;
                let empty = !d.registers().any(|r| std::ptr::eq(r.group(), g));
                json(&(id, name, table, source, *broadcast && empty, notes))
            })
            .collect::<Vec<_>>()
    };
    if group_docs(old) != group_docs(new) {
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "groups",
            (
                counts(old.groups().len(), new.groups().len(), "group(s)").0,
                None,
            ),
            (
                counts(old.groups().len(), new.groups().len(), "group(s)").1,
                None,
            ),
            TAIL,
        );
    }
}
