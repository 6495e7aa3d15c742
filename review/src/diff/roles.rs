//! Differences of roles: which register, field or external quantity plays each standard part
//! of a drive, with which codes. Roles decide what the drive API (`VariableFrequencyDrive`)
//! reads and writes, so they are classified like registers: a role removed, re-pointed or given
//! other codes is breaking, one added is compatible; a citation or note is documentation.
//!
//! A place is compared by what it means, resolved as the lowering resolves it (`lower.rs`,
//! `role_target`): the register (by id, or the same address and parameter number when the
//! register was renamed), the field's bits, the codes as numbers (`on: run` and `on: 1` are the
//! same code), the default codes of a 1-bit field, `edge` (edge, level or not printed; the
//! reason of a not-printed one is documentation), a number field's `signed` and `scale`,
//! `shared_with`. A place written otherwise with the
//! same meaning (a register by parameter number instead of id, a code by id instead of number)
//! is reported as documentation.

use std::collections::BTreeSet;

use drivemap_map::describe;
use drivemap_map::facts::field_span;
use drivemap_map::facts::{CodeRef, Codes, RolePlace};
use drivemap_map::{Map, RegisterRef};

use super::{ChangeKind, Collector, HEAD};

/// What a role place resolves to.
#[derive(Debug, Clone, PartialEq)]
enum Target {
    Register {
        id: String,
        address: u16,
        /// Parameter number, table and broadcast membership: with the address, what identifies
        /// a register that was renamed.
        param: (Option<String>, bool, bool),
    },
    Field {
        register: String,
        address: u16,
        param: (Option<String>, bool, bool),
        field: String,
        span: Option<(u8, u8)>,
    },
    External(String),
    /// A place the manual does not print (`unknown: <why>`, no register).
    NotPrinted,
    /// Names something the map does not have (validation refuses it; kept for completeness).
    Unresolved(String),
}

impl Target {
    /// The same register (or field of it, or quantity) on both sides: by id, or by address and
    /// parameter number (a renamed register), and for a field by id or bits.
    fn same(&self, other: &Target) -> bool {
        type Key<'a> = (&'a str, u16, &'a (Option<String>, bool, bool));
        let same_register = |a: Key<'_>, b: Key<'_>| a.0 == b.0 || (a.1 == b.1 && a.2 == b.2);
        match (self, other) {
            (
                Target::Register { id, address, param },
                Target::Register {
                    id: i2,
                    address: a2,
                    param: p2,
                },
            ) => same_register((id, *address, param), (i2, *a2, p2)),
            (
                Target::Field {
                    register,
                    address,
                    param,
                    field,
                    span,
                },
                Target::Field {
                    register: r2,
                    address: a2,
                    param: p2,
                    field: f2,
                    span: s2,
                },
            ) => {
                same_register((register, *address, param), (r2, *a2, p2))
                    && span == s2
                    && (field == f2 || span.is_some())
            }
            (Target::External(a), Target::External(b)) => a == b,
            (Target::NotPrinted, Target::NotPrinted) => true,
            (Target::Unresolved(a), Target::Unresolved(b)) => a == b,
            _ => false,
        }
    }

    /// The target as a change names it, its address in the map's notation (`format`).
    fn text(&self, format: drivemap_map::facts::AddressFormat) -> String {
        match self {
            Target::Register { id, address, .. } => {
                format!("{id} ({})", describe::address_as(format, *address))
            }
            Target::Field {
                register,
                address,
                field,
                span,
                ..
            } => {
                let bits = span
                    .map(|(lsb, w)| describe::bit_span(lsb, w))
                    .unwrap_or_else(|| "no bits".into());
                format!(
                    "field `{field}` ({bits}) of {register} ({})",
                    describe::address_as(format, *address)
                )
            }
            Target::External(name) => format!("external quantity `{name}`"),
            Target::NotPrinted => "not printed".to_owned(),
            Target::Unresolved(name) => format!("`{name}` (not in the map)"),
        }
    }
}

/// A place's meaning: where, and the codes (field places only).
#[derive(Debug, Clone, PartialEq)]
struct Meaning {
    target: Target,
    /// The links the place holds on (`None`: every transport of the map).
    transports: Option<Vec<drivemap_map::facts::TransportName>>,
    on: Vec<Option<u16>>,
    off: Option<u16>,
    /// How the drive acts on a command: "level", "edge" or "not printed".
    edge: &'static str,
    /// A number role on a field: signed, and one count in the role's unit.
    number: Option<(bool, f64)>,
    /// The role it shares its register or bits with, as the map says.
    shared_with: Option<String>,
    /// How the map prints addresses (for the text only; not a change of the role).
    address_format: drivemap_map::facts::AddressFormat,
}

impl Meaning {
    fn of(drive: &Map, id: &str, p: &RolePlace) -> Meaning {
        // Every key of a place is read here or below: a new key fails to compile until the diff
        // compares it.
        let RolePlace {
            register,
            field,
            external,
            on,
            off,
            edge,
            signed,
            scale,
            shared_with,
            transports,
            unknown,
            source: _,
            indirect: _,
            notes: _,
        } = p;
        let key = |r: RegisterRef| {
            (
                r.param().map(str::to_owned),
                r.plan().info.table == drivemap_core::register::Table::Input,
                r.broadcast_only(),
            )
        };
        let target = match (register, external) {
            (_, Some(name)) => Target::External(name.clone()),
            (Some(name), None) => match drive.register(name) {
                None => Target::Unresolved(name.clone()),
                Some(r) => match field {
                    None => Target::Register {
                        id: r.id().to_owned(),
                        address: r.address(),
                        param: key(r),
                    },
                    Some(fid) => {
                        let f = r.fields().iter().find(|f| f.id == *fid);
                        Target::Field {
                            register: r.id().to_owned(),
                            address: r.address(),
                            param: key(r),
                            field: fid.clone(),
                            span: f.and_then(field_span),
                        }
                    }
                },
            },
            (None, None) if unknown.is_some() => Target::NotPrinted,
            (None, None) => Target::Unresolved(String::new()),
        };
        // Codes by id: the field's values, or the register's own (a source role's `on: rs485`).
        let values: Vec<(String, u16)> =
            match (register.as_deref().and_then(|n| drive.register(n)), field) {
                (Some(r), Some(fid)) => r
                    .fields()
                    .iter()
                    .find(|f| f.id == *fid)
                    .map(|f| f.values.iter().map(|v| (v.id.clone(), v.value)).collect())
                    .unwrap_or_default(),
                (Some(r), None) => r.values().iter().map(|v| (v.id.clone(), v.value)).collect(),
                _ => Vec::new(),
            };
        let code = |c: &CodeRef| match c {
            CodeRef::Number(n) => Some(*n),
            CodeRef::Id(id) => values.iter().find(|(v, _)| v == id).map(|(_, n)| *n),
        };
        let width = match &target {
            Target::Field { span, .. } => span.map(|(_, w)| w),
            _ => None,
        };
        // A number role on a field (a fault code in a byte) has no codes: its sign and scale.
        let number = field.is_some()
            && drivemap_core::roles::Role::from_id(id).is_some_and(|r| {
                matches!(
                    r.kind(),
                    drivemap_core::roles::RoleKind::Setpoint
                        | drivemap_core::roles::RoleKind::Monitor
                )
            });
        let (on, off) = if matches!(target, Target::Field { .. }) && !number {
            let on: Vec<Option<u16>> = match on {
                Some(codes) => codes.list().into_iter().map(code).collect(),
                None => vec![Some(1)],
            };
            let off = match off {
                Some(c) => code(c),
                None if width == Some(1) => Some(if on == [Some(0)] { 1 } else { 0 }),
                None => None,
            };
            (on, off)
        } else {
            // A register or external place has no codes (validation refuses them there); what
            // is written is compared as written.
            (
                on.as_ref()
                    .map(|c| c.list().into_iter().map(code).collect())
                    .unwrap_or_default(),
                off.as_ref().and_then(code),
            )
        };
        let transports = transports.as_ref().map(|t| {
            let mut t = t.clone();
            t.sort();
            t.dedup();
            t
        });
        Meaning {
            target,
            transports,
            on,
            off,
            edge: match edge {
                drivemap_map::facts::EdgeSpec::Known(false) => "level",
                drivemap_map::facts::EdgeSpec::Known(true) => "edge",
                drivemap_map::facts::EdgeSpec::Unknown(_) => "not printed",
            },
            number: number.then(|| (*signed, scale.unwrap_or(1.0))),
            shared_with: shared_with.clone(),
            address_format: drive.address_format(),
        }
    }

    fn codes_text(&self) -> String {
        let shared = self
            .shared_with
            .as_ref()
            .map(|r| format!("shared with `{r}`"));
        if let Some((signed, scale)) = self.number {
            let mut s = format!(
                "{}, {scale} per count",
                if signed { "signed" } else { "unsigned" }
            );
            if let Some(shared) = shared {
                s += &format!(", {shared}");
            }
            return s;
        }
        if self.on.is_empty() && self.off.is_none() && self.edge == "level" {
            return shared.unwrap_or_default();
        }
        let on: Vec<String> = self
            .on
            .iter()
            .map(|c| c.map_or("?".into(), |c| c.to_string()))
            .collect();
        let mut s = format!("on {}", on.join(" or "));
        if let Some(off) = self.off {
            s += &format!(", off {off}");
        }
        match self.edge {
            "edge" => s += ", on the transition",
            "not printed" => s += ", edge or level not printed",
            _ => {}
        }
        if let Some(shared) = shared {
            s += &format!(", {shared}");
        }
        s
    }

    fn text(&self) -> String {
        let codes = self.codes_text();
        let mut s = self.target.text(self.address_format);
        if !codes.is_empty() {
            s = format!("{s}, {codes}");
        }
        if let Some(t) = &self.transports {
            let t: Vec<String> = t.iter().map(|t| t.to_string()).collect();
            s = format!("{s}, on {}", t.join(" and "));
        }
        s
    }
}

fn places_text(drive: &Map, id: &str, places: &[RolePlace]) -> String {
    places
        .iter()
        .map(|p| Meaning::of(drive, id, p).text())
        .collect::<Vec<_>>()
        .join("; ")
}

fn first_source(places: &[RolePlace]) -> Option<String> {
    places.iter().find_map(|p| p.source.clone())
}

/// How a place is written, apart from its citation and notes.
type Spelling<'a> = (
    Option<&'a str>,
    Option<&'a str>,
    Option<&'a str>,
    Option<&'a Codes>,
    Option<&'a str>,
);

fn spelling(p: &RolePlace) -> Spelling<'_> {
    (
        p.register.as_deref(),
        p.field.as_deref(),
        p.external.as_deref(),
        p.on.as_ref(),
        p.unknown.as_deref(),
    )
}

pub(super) fn roles(c: &mut Collector, old: &Map, new: &Map) {
    let subject = "roles";
    let ids: BTreeSet<&String> = old.roles().keys().chain(new.roles().keys()).collect();
    for id in ids {
        let empty = Vec::new();
        let a = old.roles().get(id).unwrap_or(&empty);
        let b = new.roles().get(id).unwrap_or(&empty);
        match (a.is_empty(), b.is_empty()) {
            (true, true) => continue,
            (false, true) => {
                c.push(
                    ChangeKind::RoleRemoved,
                    subject,
                    id,
                    (Some(places_text(old, id, a)), first_source(a)),
                    (None, None),
                    HEAD,
                );
                continue;
            }
            (true, false) => {
                c.push(
                    ChangeKind::RoleAdded,
                    subject,
                    id,
                    (None, None),
                    (Some(places_text(new, id, b)), first_source(b)),
                    HEAD,
                );
                continue;
            }
            (false, false) => {}
        }
        let ma: Vec<Meaning> = a.iter().map(|p| Meaning::of(old, id, p)).collect();
        let mb: Vec<Meaning> = b.iter().map(|p| Meaning::of(new, id, p)).collect();
        let repointed = ma.len() != mb.len()
            || ma
                .iter()
                .zip(&mb)
                .any(|(x, y)| !x.target.same(&y.target) || x.transports != y.transports);
        if repointed {
            c.push(
                ChangeKind::RoleRepointed,
                subject,
                id,
                (Some(places_text(old, id, a)), first_source(a)),
                (Some(places_text(new, id, b)), first_source(b)),
                HEAD,
            );
            continue;
        }
        for (i, ((x, y), (p, q))) in ma.iter().zip(&mb).zip(a.iter().zip(b)).enumerate() {
            let what = if a.len() == 1 {
                id.clone()
            } else {
                format!("{id} place {}", i + 1)
            };
            let sides = |m: &Meaning, s: &RolePlace| (Some(m.text()), s.source.clone());
            if (&x.on, x.off, x.edge, x.number, &x.shared_with)
                != (&y.on, y.off, y.edge, y.number, &y.shared_with)
            {
                c.push(
                    ChangeKind::RoleCodesChanged,
                    subject,
                    &what,
                    sides(x, p),
                    sides(y, q),
                    HEAD,
                );
                continue;
            }
            // Same meaning: how it is written, its notes, its citation.
            let mut parts = Vec::new();
            if spelling(p) != spelling(q)
                || p.off != q.off
                || p.edge != q.edge
                || x.target != y.target
            {
                parts.push("written otherwise");
            }
            if p.notes != q.notes {
                parts.push("notes");
            }
            if p.indirect != q.indirect {
                parts.push("indirect citation");
            }
            if !parts.is_empty() {
                c.push(
                    ChangeKind::DocumentationChanged,
                    subject,
                    &format!("{what}: {}", parts.join(", ")),
                    sides(x, p),
                    sides(y, q),
                    HEAD,
                );
            }
            if p.source != q.source {
                c.push(
                    ChangeKind::CitationChanged,
                    subject,
                    &what,
                    (None, p.source.clone()),
                    (None, q.source.clone()),
                    HEAD,
                );
            }
        }
    }
}

/// Differences of the command profile (`profile:`), compared as resolved (the standard it
/// names merged under the map's entries): a profile added is compatible; one removed, or a
/// control or status register, a state's mask or value, a transition's word, kept bits, edge,
/// states or time limit, a path or the power-on state changed, is breaking (the drive trait
/// walks them); a citation is documentation.
pub(super) fn command_profile(c: &mut Collector, old: &Map, new: &Map) {
    use drivemap_map::facts::{PathSpec, StateSpec, TransitionSpec};
    let subject = "profile";
    let text = |d: &Map| {
        d.profile().map(|p| {
            let r = p.resolved();
            format!(
                "{} (control {}, status {})",
                r.standard.as_deref().unwrap_or("own"),
                r.control.as_deref().unwrap_or("?"),
                r.status.as_deref().unwrap_or("?")
            )
        })
    };
    let (a, b) = match (old.profile(), new.profile()) {
        (None, None) => return,
        (Some(a), None) => {
            c.push(
                ChangeKind::RoleRemoved,
                subject,
                "profile",
                (text(old), a.source.clone()),
                (None, None),
                HEAD,
            );
            return;
        }
        (None, Some(b)) => {
            c.push(
                ChangeKind::RoleAdded,
                subject,
                "profile",
                (None, None),
                (text(new), b.source.clone()),
                HEAD,
            );
            return;
        }
        (Some(a), Some(b)) => (a.resolved(), b.resolved()),
    };
    let mut entry = |what: String,
                     x: Option<String>,
                     y: Option<String>,
                     sx: Option<String>,
                     sy: Option<String>| {
        if x != y {
            let kind = if x.is_none() {
                ChangeKind::RoleAdded
            } else {
                ChangeKind::RoleCodesChanged
            };
            c.push(kind, subject, &what, (x, sx), (y, sy), HEAD);
        } else if sx != sy {
            c.push(
                ChangeKind::DocumentationChanged,
                subject,
                &what,
                (None, sx),
                (None, sy),
                HEAD,
            );
        }
    };
    entry(
        "profile".into(),
        Some(format!(
            "{} control {} status {} power-on {}",
            a.standard.as_deref().unwrap_or("own"),
            a.control.as_deref().unwrap_or("?"),
            a.status.as_deref().unwrap_or("?"),
            a.power_on.as_ref().map_or("?", |s| s.state.as_str())
        )),
        Some(format!(
            "{} control {} status {} power-on {}",
            b.standard.as_deref().unwrap_or("own"),
            b.control.as_deref().unwrap_or("?"),
            b.status.as_deref().unwrap_or("?"),
            b.power_on.as_ref().map_or("?", |s| s.state.as_str())
        )),
        a.source.clone(),
        b.source.clone(),
    );
    let state = |s: &StateSpec| {
        format!(
            "mask {:#06X} value {:#06X}",
            s.mask.map_or(0, |w| w.0),
            s.value.map_or(0, |w| w.0)
        )
    };
    let ids: BTreeSet<&String> = a.states.keys().chain(b.states.keys()).collect();
    for id in ids {
        let (x, y) = (a.states.get(id), b.states.get(id));
        entry(
            format!("state {id}"),
            x.map(state),
            y.map(state),
            x.and_then(|s| s.source.clone()),
            y.and_then(|s| s.source.clone()),
        );
    }
    let transition = |t: &TransitionSpec| {
        format!(
            "word {:#06X} keep {:#06X} edge {:#06X} from {} to {} within {} ms",
            t.word.map_or(0, |w| w.0),
            t.keep.map_or(0, |w| w.0),
            t.edge.map_or(0, |w| w.0),
            t.from.as_deref().unwrap_or_default().join(", "),
            t.to.as_deref().unwrap_or("?"),
            t.limit_ms.unwrap_or(0)
        )
    };
    let ids: BTreeSet<&String> = a.transitions.keys().chain(b.transitions.keys()).collect();
    for id in ids {
        let (x, y) = (a.transitions.get(id), b.transitions.get(id));
        entry(
            format!("transition {id}"),
            x.map(transition),
            y.map(transition),
            x.and_then(|t| t.source.clone()),
            y.and_then(|t| t.source.clone()),
        );
    }
    let path = |p: &PathSpec| format!("via {} to {}", p.via.join(", "), p.to.join(", "));
    let ids: BTreeSet<&String> = a.paths.keys().chain(b.paths.keys()).collect();
    for id in ids {
        entry(
            format!("path {id}"),
            a.paths.get(id).map(path),
            b.paths.get(id).map(path),
            None,
            None,
        );
    }
}
