//! Semantic diff of two maps: compares the validated IR of the old and the new map and lists
//! every change with its kind, both sides and the citation of each side. [`classify`] says
//! which kinds break applications built on the generated code; [`render`] prints the result
//! for a terminal or as Markdown; [`git`] fetches the old maps from a revision.

pub mod classify;
pub mod git;
pub mod render;
#[cfg(test)]
mod tests;

use std::collections::{BTreeMap, BTreeSet};

use drivemap_codegen::ir::{Drive, Register, ValueKind};
use drivemap_codegen::model::{
    Access, DefaultValue, EnumValue, Field, Scale, TransportName, WriteRestriction,
};
use drivemap_codegen::validate::field_span;
use serde::Serialize;

pub use classify::{ChangeKind, Severity, classify};

use crate::describe;

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
const HEAD: u32 = 0;
/// Order of map-level documentation: after all registers.
const TAIL: u32 = u32::MAX;

struct Collector {
    changes: Vec<Change>,
}

/// A side of a change: its text and citation.
type Side = (Option<String>, Option<String>);

impl Collector {
    #[allow(clippy::too_many_arguments)]
    fn push(
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
            order,
        });
    }
}

fn same<T: Serialize>(a: &T, b: &T) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
}

fn json<T: Serialize>(a: &T) -> String {
    serde_json::to_string(a).unwrap_or_default()
}

/// A drive that exists only on one side.
pub fn added(new: &Drive) -> DriveDiff {
    let mut c = Collector {
        changes: Vec::new(),
    };
    c.push(
        ChangeKind::DriveAdded,
        &new.meta.id,
        "",
        (None, None),
        (
            Some(format!("{} registers", new.registers.len())),
            new.protocol.source.clone(),
        ),
        HEAD,
    );
    DriveDiff {
        drive: new.meta.id.clone(),
        changes: c.changes,
    }
}

/// A drive that exists only on the old side.
pub fn removed(old: &Drive) -> DriveDiff {
    let mut c = Collector {
        changes: Vec::new(),
    };
    c.push(
        ChangeKind::DriveRemoved,
        &old.meta.id,
        "",
        (
            Some(format!("{} registers", old.registers.len())),
            old.protocol.source.clone(),
        ),
        (None, None),
        HEAD,
    );
    DriveDiff {
        drive: old.meta.id.clone(),
        changes: c.changes,
    }
}

/// Compares two versions of a drive's map.
pub fn compare(old: &Drive, new: &Drive) -> DriveDiff {
    let mut c = Collector {
        changes: Vec::new(),
    };
    meta(&mut c, old, new);
    variants(&mut c, old, new);
    protocol(&mut c, old, new);
    registers(&mut c, old, new);
    map_documentation(&mut c, old, new);
    c.changes.sort_by_key(|ch| ch.order);
    DriveDiff {
        drive: new.meta.id.clone(),
        changes: c.changes,
    }
}

fn meta(c: &mut Collector, old: &Drive, new: &Drive) {
    let (a, b) = (&old.meta, &new.meta);
    let id = &b.id;
    let mut parts = Vec::new();
    if a.id != b.id {
        parts.push("id");
    }
    if a.extends != b.extends {
        parts.push("extends");
    }
    if a.vendor != b.vendor {
        parts.push("vendor");
    }
    if a.models != b.models {
        parts.push("models");
    }
    if a.description != b.description {
        parts.push("description");
    }
    if !same(&a.manuals, &b.manuals) {
        parts.push("manuals");
    }
    if !parts.is_empty() {
        let text = |m: &drivemap_codegen::model::DriveMeta| {
            format!(
                "{} {} ({} manual(s))",
                m.vendor,
                m.models.join(" / "),
                m.manuals.len()
            )
        };
        c.push(
            ChangeKind::DriveMetaChanged,
            id,
            &parts.join(", "),
            (Some(text(a)), None),
            (Some(text(b)), None),
            HEAD,
        );
    }
}

fn variants(c: &mut Collector, old: &Drive, new: &Drive) {
    let subject = "variants";
    for a in &old.variants {
        let Some(b) = new.variants.iter().find(|b| b.id == a.id) else {
            let opts: Vec<&str> = a.options.iter().map(|o| o.id.as_str()).collect();
            c.push(
                ChangeKind::VariantAxisRemoved,
                subject,
                &a.id,
                (
                    Some(opts.join(", ")),
                    a.options.first().and_then(|o| o.source.clone()),
                ),
                (None, None),
                HEAD,
            );
            continue;
        };
        for o in &a.options {
            if !b.options.iter().any(|p| p.id == o.id) {
                c.push(
                    ChangeKind::VariantOptionRemoved,
                    subject,
                    &format!("{} option {}", a.id, o.id),
                    (Some(o.name.clone()), o.source.clone()),
                    (None, None),
                    HEAD,
                );
            }
        }
        for o in &b.options {
            if !a.options.iter().any(|p| p.id == o.id) {
                c.push(
                    ChangeKind::VariantOptionAdded,
                    subject,
                    &format!("{} option {}", b.id, o.id),
                    (None, None),
                    (Some(o.name.clone()), o.source.clone()),
                    HEAD,
                );
            }
        }
        if let (Some(x), Some(y)) = (a.options.first(), b.options.first()) {
            if x.id != y.id {
                c.push(
                    ChangeKind::VariantBaseChanged,
                    subject,
                    &a.id,
                    (Some(x.id.clone()), x.source.clone()),
                    (Some(y.id.clone()), y.source.clone()),
                    HEAD,
                );
            }
        }
    }
    for b in &new.variants {
        if !old.variants.iter().any(|a| a.id == b.id) {
            let opts: Vec<&str> = b.options.iter().map(|o| o.id.as_str()).collect();
            c.push(
                ChangeKind::VariantAxisAdded,
                subject,
                &b.id,
                (None, None),
                (
                    Some(opts.join(", ")),
                    b.options.first().and_then(|o| o.source.clone()),
                ),
                HEAD,
            );
        }
    }
}

fn list<T: ToString>(items: impl IntoIterator<Item = T>) -> String {
    items
        .into_iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

fn functions(f: &[u8]) -> String {
    list(f.iter().map(|f| describe::function(*f)))
}

fn protocol(c: &mut Collector, old: &Drive, new: &Drive) {
    let (a, b) = (&old.protocol, &new.protocol);
    let s = "protocol";
    let src = (a.source.clone(), b.source.clone());

    let ta: BTreeSet<TransportName> = a.transports.iter().copied().collect();
    let tb: BTreeSet<TransportName> = b.transports.iter().copied().collect();
    for t in ta.difference(&tb) {
        c.push(
            ChangeKind::TransportRemoved,
            s,
            "transports",
            (Some(describe::transport(*t).into()), src.0.clone()),
            (None, src.1.clone()),
            HEAD,
        );
    }
    for t in tb.difference(&ta) {
        c.push(
            ChangeKind::TransportAdded,
            s,
            "transports",
            (None, src.0.clone()),
            (Some(describe::transport(*t).into()), src.1.clone()),
            HEAD,
        );
    }

    let fa: BTreeSet<u8> = a.function_codes.iter().copied().collect();
    let fb: BTreeSet<u8> = b.function_codes.iter().copied().collect();
    let removed: Vec<u8> = fa.difference(&fb).copied().collect();
    let added: Vec<u8> = fb.difference(&fa).copied().collect();
    if !removed.is_empty() {
        c.push(
            ChangeKind::FunctionCodeRemoved,
            s,
            &format!("function codes: {}", functions(&removed)),
            (Some(functions(&a.function_codes)), src.0.clone()),
            (Some(functions(&b.function_codes)), src.1.clone()),
            HEAD,
        );
    }
    if !added.is_empty() {
        c.push(
            ChangeKind::FunctionCodeAdded,
            s,
            &format!("function codes: {}", functions(&added)),
            (Some(functions(&a.function_codes)), src.0.clone()),
            (Some(functions(&b.function_codes)), src.1.clone()),
            HEAD,
        );
    }

    for (what, x, y) in [
        ("max_read", a.max_read, b.max_read),
        ("max_write", a.max_write, b.max_write),
    ] {
        if x != y {
            let kind = if y < x {
                ChangeKind::MaxRequestLowered
            } else {
                ChangeKind::MaxRequestRaised
            };
            c.push(
                kind,
                s,
                what,
                (Some(x.to_string()), src.0.clone()),
                (Some(y.to_string()), src.1.clone()),
                HEAD,
            );
        }
    }

    let (sa, sb) = (&a.slave_address, &b.slave_address);
    if sa.min != sb.min || sa.max != sb.max {
        let kind = if sb.min > sa.min || sb.max < sa.max {
            ChangeKind::SlaveRangeNarrowed
        } else {
            ChangeKind::SlaveRangeWidened
        };
        c.push(
            kind,
            s,
            "slave address",
            (
                Some(format!("{} ..= {}", sa.min, sa.max)),
                sa.source.clone(),
            ),
            (
                Some(format!("{} ..= {}", sb.min, sb.max)),
                sb.source.clone(),
            ),
            HEAD,
        );
    } else if sa.default != sb.default || sa.param != sb.param {
        c.push(
            ChangeKind::DocumentationChanged,
            s,
            "slave address default or parameter",
            (Some(json(sa)), sa.source.clone()),
            (Some(json(sb)), sb.source.clone()),
            HEAD,
        );
    } else if sa.source != sb.source {
        c.push(
            ChangeKind::CitationChanged,
            s,
            "slave address",
            (None, sa.source.clone()),
            (None, sb.source.clone()),
            HEAD,
        );
    }

    broadcast(c, old, new);
    exceptions(c, a, b);
    commands(c, a, b);

    let offsets = |p: &drivemap_codegen::model::Protocol| {
        p.addressing
            .as_ref()
            .map(|x| (x.rtu_offset, x.tcp_offset))
            .unwrap_or((0, 0))
    };
    let asrc =
        |p: &drivemap_codegen::model::Protocol| p.addressing.as_ref().map(|x| x.source.clone());
    let text = |(r, t): (i32, i32)| format!("RTU {r:+}, TCP {t:+}");
    if offsets(a) != offsets(b) {
        c.push(
            ChangeKind::AddressingChanged,
            s,
            "address offsets",
            (Some(text(offsets(a))), asrc(a)),
            (Some(text(offsets(b))), asrc(b)),
            HEAD,
        );
    } else if !same(&a.addressing, &b.addressing) {
        c.push(
            ChangeKind::DocumentationChanged,
            s,
            "addressing description",
            (None, asrc(a)),
            (None, asrc(b)),
            HEAD,
        );
    }

    if !same(&a.timing, &b.timing) {
        let src = |p: &drivemap_codegen::model::Protocol| {
            p.timing.as_ref().and_then(|t| t.source.clone())
        };
        c.push(
            ChangeKind::TimingChanged,
            s,
            "timing",
            (a.timing.as_ref().map(json), src(a)),
            (b.timing.as_ref().map(json), src(b)),
            HEAD,
        );
    }
    if !same(&a.serial, &b.serial) {
        let src =
            |p: &drivemap_codegen::model::Protocol| p.serial.as_ref().map(|t| t.source.clone());
        c.push(
            ChangeKind::LineSettingsChanged,
            s,
            "serial line",
            (a.serial.as_ref().map(json), src(a)),
            (b.serial.as_ref().map(json), src(b)),
            HEAD,
        );
    }
    if !same(&a.eeprom, &b.eeprom) {
        let src =
            |p: &drivemap_codegen::model::Protocol| p.eeprom.as_ref().map(|t| t.source.clone());
        let text = |p: &drivemap_codegen::model::Protocol| {
            p.eeprom.as_ref().map(|e| format!("{} writes", e.endurance))
        };
        c.push(
            ChangeKind::LineSettingsChanged,
            s,
            "EEPROM endurance",
            (text(a), src(a)),
            (text(b), src(b)),
            HEAD,
        );
    }
    if a.notes != b.notes {
        c.push(
            ChangeKind::DocumentationChanged,
            s,
            "notes",
            (Some(format!("{} note(s)", a.notes.len())), src.0.clone()),
            (Some(format!("{} note(s)", b.notes.len())), src.1.clone()),
            HEAD,
        );
    }
    if a.source != b.source {
        c.push(
            ChangeKind::CitationChanged,
            s,
            "",
            (None, src.0),
            (None, src.1),
            HEAD,
        );
    }
}

fn broadcast(c: &mut Collector, old: &Drive, new: &Drive) {
    let (a, b) = (&old.protocol.broadcast, &new.protocol.broadcast);
    if same(a, b) {
        return;
    }
    let set = |d: &Drive| -> (BTreeSet<u8>, BTreeSet<String>) {
        match &d.protocol.broadcast {
            None => (BTreeSet::new(), BTreeSet::new()),
            Some(x) => (
                x.functions.iter().copied().collect(),
                x.registers.iter().cloned().collect(),
            ),
        }
    };
    let text = |x: &Option<drivemap_codegen::model::Broadcast>| {
        x.as_ref().map(|x| {
            let mut t = functions(&x.functions);
            if !x.registers.is_empty() {
                t += &format!(" to {}", x.registers.join(", "));
            }
            t
        })
    };
    let src = |x: &Option<drivemap_codegen::model::Broadcast>| x.as_ref().map(|x| x.source.clone());
    let (fa, ra) = set(old);
    let (fb, rb) = set(new);
    // An empty register list means "any writable register".
    let registers_lost = match (ra.is_empty(), rb.is_empty()) {
        (true, true) => false,
        (true, false) => a.is_some(),
        (false, true) => false,
        (false, false) => !ra.is_subset(&rb),
    };
    let lost = (a.is_some() && b.is_none()) || !fa.is_subset(&fb) || registers_lost;
    let gained = (a.is_none() && b.is_some())
        || !fb.is_subset(&fa)
        || (!ra.is_empty() && (rb.is_empty() || !rb.is_subset(&ra)));
    let kind = if lost {
        ChangeKind::BroadcastRestricted
    } else if gained {
        ChangeKind::BroadcastExtended
    } else {
        ChangeKind::CitationChanged
    };
    c.push(
        kind,
        "protocol",
        "broadcast",
        (text(a), src(a)),
        (text(b), src(b)),
        HEAD,
    );
}

fn exceptions(
    c: &mut Collector,
    a: &drivemap_codegen::model::Protocol,
    b: &drivemap_codegen::model::Protocol,
) {
    let s = "protocol";
    for x in &a.exceptions {
        let what = format!("exception {}", describe::function(x.code));
        match b.exceptions.iter().find(|y| y.code == x.code) {
            None => c.push(
                ChangeKind::ExceptionRemoved,
                s,
                &what,
                (Some(x.name.clone()), Some(x.source.clone())),
                (None, None),
                HEAD,
            ),
            Some(y) if x.name != y.name || x.description != y.description => c.push(
                ChangeKind::ExceptionReworded,
                s,
                &what,
                (Some(x.name.clone()), Some(x.source.clone())),
                (Some(y.name.clone()), Some(y.source.clone())),
                HEAD,
            ),
            Some(y) if x.source != y.source => c.push(
                ChangeKind::CitationChanged,
                s,
                &what,
                (None, Some(x.source.clone())),
                (None, Some(y.source.clone())),
                HEAD,
            ),
            Some(_) => {}
        }
    }
    for y in &b.exceptions {
        if !a.exceptions.iter().any(|x| x.code == y.code) {
            c.push(
                ChangeKind::ExceptionAdded,
                s,
                &format!("exception {}", describe::function(y.code)),
                (None, None),
                (Some(y.name.clone()), Some(y.source.clone())),
                HEAD,
            );
        }
    }
}

fn commands(
    c: &mut Collector,
    a: &drivemap_codegen::model::Protocol,
    b: &drivemap_codegen::model::Protocol,
) {
    let s = "protocol";
    let text = |x: &drivemap_codegen::model::Command| {
        let writes: Vec<String> = x
            .writes
            .iter()
            .map(|w| format!("{} ← {:04X}h", describe::address(w.address), w.value))
            .collect();
        format!("{} ({:?})", writes.join(", "), x.kind).to_lowercase()
    };
    for x in &a.commands {
        let what = format!("command {}", x.id);
        match b.commands.iter().find(|y| y.id == x.id) {
            None => c.push(
                ChangeKind::CommandRemoved,
                s,
                &what,
                (Some(text(x)), Some(x.source.clone())),
                (None, None),
                HEAD,
            ),
            Some(y) if !same(&x.writes, &y.writes) || x.kind != y.kind => c.push(
                ChangeKind::CommandChanged,
                s,
                &what,
                (Some(text(x)), Some(x.source.clone())),
                (Some(text(y)), Some(y.source.clone())),
                HEAD,
            ),
            Some(y) if x.name != y.name => c.push(
                ChangeKind::CommandReworded,
                s,
                &what,
                (Some(x.name.clone()), Some(x.source.clone())),
                (Some(y.name.clone()), Some(y.source.clone())),
                HEAD,
            ),
            Some(y) if x.source != y.source => c.push(
                ChangeKind::CitationChanged,
                s,
                &what,
                (None, Some(x.source.clone())),
                (None, Some(y.source.clone())),
                HEAD,
            ),
            Some(_) => {}
        }
    }
    for y in &b.commands {
        if !a.commands.iter().any(|x| x.id == y.id) {
            c.push(
                ChangeKind::CommandAdded,
                s,
                &format!("command {}", y.id),
                (None, None),
                (Some(text(y)), Some(y.source.clone())),
                HEAD,
            );
        }
    }
}

fn registers(c: &mut Collector, old: &Drive, new: &Drive) {
    let mut pairs: Vec<(&Register, &Register)> = Vec::new();
    let mut old_left: Vec<&Register> = Vec::new();
    for r in &old.registers {
        match new.registers.iter().find(|n| n.def.id == r.def.id) {
            Some(n) => pairs.push((r, n)),
            None => old_left.push(r),
        }
    }
    let mut new_left: Vec<&Register> = new
        .registers
        .iter()
        .filter(|n| !old.registers.iter().any(|r| r.def.id == n.def.id))
        .collect();
    // Renamed: same address and parameter number (and table), another id.
    let mut removed = Vec::new();
    for r in old_left {
        let hit = new_left.iter().position(|n| {
            n.def.address == r.def.address
                && n.def.param == r.def.param
                && n.table == r.table
                && n.broadcast == r.broadcast
        });
        match hit {
            Some(i) => {
                let n = new_left.remove(i);
                c.push(
                    ChangeKind::RegisterRenamed,
                    &describe::register(n),
                    "",
                    (Some(r.def.id.clone()), r.def.source.clone()),
                    (Some(n.def.id.clone()), n.def.source.clone()),
                    u32::from(n.def.address) + 1,
                );
                pairs.push((r, n));
            }
            None => removed.push(r),
        }
    }
    for r in removed {
        c.push(
            ChangeKind::RegisterRemoved,
            &describe::register(r),
            "",
            (Some(summary(old, r)), r.def.source.clone()),
            (None, None),
            u32::from(r.def.address) + 1,
        );
    }
    for n in new_left {
        c.push(
            ChangeKind::RegisterAdded,
            &describe::register(n),
            "",
            (None, None),
            (Some(summary(new, n)), n.def.source.clone()),
            u32::from(n.def.address) + 1,
        );
    }
    for (r, n) in pairs {
        register(c, old, r, new, n);
    }
}

/// A one-line description of a register.
fn summary(drive: &Drive, r: &Register) -> String {
    let mut s = format!(
        "{} {} at {}, {}",
        r.def.name,
        describe::kind(r),
        describe::address(r.def.address),
        describe::access(r.access)
    );
    if let Some(u) = &r.def.unit {
        s += &format!(", {u}");
    }
    if let Some(sc) = &r.def.scale {
        s += &format!(", scale {}", describe::scale(drive, sc));
    }
    let range = describe::range(r.def.min, r.def.max, r.def.unit.as_deref().unwrap_or(""));
    if !range.is_empty() {
        s += &format!(", {range}");
    }
    s
}

fn same_kind(a: &Register, b: &Register) -> bool {
    matches!(
        (a.kind(), b.kind()),
        (ValueKind::Word, ValueKind::Word)
            | (
                ValueKind::Quantity(_) | ValueKind::UnitQuantity,
                ValueKind::Quantity(_) | ValueKind::UnitQuantity
            )
            | (ValueKind::Enum(_), ValueKind::Enum(_))
            | (ValueKind::Bits(_), ValueKind::Bits(_))
    )
}

fn can(a: Access) -> (bool, bool) {
    match a {
        Access::Read => (true, false),
        Access::Write => (false, true),
        Access::ReadWrite => (true, true),
    }
}

fn strictness(w: WriteRestriction) -> u8 {
    match w {
        WriteRestriction::None => 0,
        WriteRestriction::Stopped => 1,
        WriteRestriction::PrgMode => 2,
    }
}

fn register(c: &mut Collector, old: &Drive, r: &Register, new: &Drive, n: &Register) {
    let subject = describe::register(n);
    let order = u32::from(n.def.address) + 1;
    let (a, b) = (&r.def, &n.def);
    let src = (a.source.clone(), b.source.clone());
    let push = |c: &mut Collector, kind, what: &str, x: Option<String>, y: Option<String>| {
        c.push(
            kind,
            &subject,
            what,
            (x, src.0.clone()),
            (y, src.1.clone()),
            order,
        );
    };

    if a.address != b.address {
        push(
            c,
            ChangeKind::RegisterMoved,
            "",
            Some(describe::address(a.address)),
            Some(describe::address(b.address)),
        );
    }
    if !same(&a.address_alternatives, &b.address_alternatives) {
        let text = |d: &drivemap_codegen::model::Register| {
            let alts: Vec<String> = d
                .address_alternatives
                .iter()
                .map(|x| {
                    format!(
                        "{} if {}",
                        describe::address(x.address),
                        describe::condition(&x.when)
                    )
                })
                .collect();
            if alts.is_empty() {
                "none".to_owned()
            } else {
                alts.join("; ")
            }
        };
        let addresses = |d: &drivemap_codegen::model::Register| {
            d.address_alternatives
                .iter()
                .map(|x| json(&(x.address, &x.when)))
                .collect::<Vec<_>>()
        };
        if addresses(a) == addresses(b) {
            push(
                c,
                ChangeKind::CitationChanged,
                "alternative addresses",
                None,
                None,
            );
        } else {
            push(
                c,
                ChangeKind::AddressAlternativesChanged,
                "alternative addresses",
                Some(text(a)),
                Some(text(b)),
            );
        }
    }
    if a.name != b.name {
        push(
            c,
            ChangeKind::NameChanged,
            "",
            Some(a.name.clone()),
            Some(b.name.clone()),
        );
    }
    if a.param != b.param {
        push(
            c,
            ChangeKind::ParamChanged,
            "",
            a.param.clone(),
            b.param.clone(),
        );
    }
    if r.table != n.table {
        push(
            c,
            ChangeKind::TableChanged,
            "table",
            Some(describe::table(r.table).into()),
            Some(describe::table(n.table).into()),
        );
    }
    let (ga, gb) = (&old.group_of(r).id, &new.group_of(n).id);
    if ga != gb {
        push(
            c,
            ChangeKind::GroupChanged,
            "group",
            Some(ga.clone()),
            Some(gb.clone()),
        );
    }
    if r.broadcast != n.broadcast {
        let t = |x: bool| if x { "broadcast only" } else { "addressed" }.to_owned();
        push(
            c,
            ChangeKind::BroadcastMembershipChanged,
            "broadcast",
            Some(t(r.broadcast)),
            Some(t(n.broadcast)),
        );
    }
    if r.access != n.access {
        let ((ra, wa), (rb, wb)) = (can(r.access), can(n.access));
        let kind = if (ra && !rb) || (wa && !wb) {
            ChangeKind::AccessNarrowed
        } else {
            ChangeKind::AccessWidened
        };
        push(
            c,
            kind,
            "access",
            Some(describe::access(r.access).into()),
            Some(describe::access(n.access).into()),
        );
    }
    if r.write_restriction != n.write_restriction {
        let kind = if strictness(n.write_restriction) > strictness(r.write_restriction)
            || (r.write_restriction != WriteRestriction::None
                && n.write_restriction != WriteRestriction::None)
        {
            ChangeKind::WriteRestrictionTightened
        } else {
            ChangeKind::WriteRestrictionRelaxed
        };
        push(
            c,
            kind,
            "write restriction",
            Some(describe::write_restriction(r.write_restriction).into()),
            Some(describe::write_restriction(n.write_restriction).into()),
        );
    }
    if r.transports != n.transports {
        let all = [TransportName::Rtu, TransportName::Tcp];
        let set = |t: &Option<Vec<TransportName>>| -> BTreeSet<TransportName> {
            t.clone()
                .unwrap_or_else(|| all.to_vec())
                .into_iter()
                .collect()
        };
        let (sa, sb) = (set(&r.transports), set(&n.transports));
        if sa != sb {
            let kind = if sa.is_subset(&sb) {
                ChangeKind::TransportsWidened
            } else {
                ChangeKind::TransportsNarrowed
            };
            push(
                c,
                kind,
                "transports",
                Some(describe::transports(r.transports.as_deref())),
                Some(describe::transports(n.transports.as_deref())),
            );
        }
    }
    if a.signed != b.signed {
        let t = |s: bool| if s { "signed" } else { "unsigned" }.to_owned();
        push(
            c,
            ChangeKind::SignednessChanged,
            "signedness",
            Some(t(a.signed)),
            Some(t(b.signed)),
        );
    }
    if !same_kind(r, n) {
        push(
            c,
            ChangeKind::ValueKindChanged,
            "value kind",
            Some(summary(old, r)),
            Some(summary(new, n)),
        );
    } else {
        if a.unit != b.unit {
            push(
                c,
                ChangeKind::UnitChanged,
                "unit",
                Some(a.unit.clone().unwrap_or_else(|| "none".into())),
                Some(b.unit.clone().unwrap_or_else(|| "none".into())),
            );
        }
        scale(c, old, r, new, n, &subject, order);
        match (r.kind(), n.kind()) {
            (ValueKind::Enum(x), ValueKind::Enum(y)) => {
                enum_codes(c, &subject, "", x, y, src.clone(), order)
            }
            (ValueKind::Bits(x), ValueKind::Bits(y)) => {
                fields(c, &subject, x, y, src.clone(), order)
            }
            _ => {}
        }
    }
    ranges(c, r, n, &subject, order);
    defaults(c, r, n, &subject, order);
    documentation(c, r, n, &subject, order);
    if a.source != b.source {
        c.push(
            ChangeKind::CitationChanged,
            &subject,
            "",
            (None, src.0.clone()),
            (None, src.1.clone()),
            order,
        );
    }
}

/// Scale per selector code; `None` as key for a fixed scale.
type Cases<'a> = BTreeMap<Option<u16>, (&'a Scale, Option<f64>, Option<f64>, Option<String>)>;

fn cases<'a>(r: &'a Register) -> Option<(Option<&'a str>, Cases<'a>)> {
    let d = &r.def;
    match &d.scale {
        None => None,
        Some(Scale::Selected(sel)) => {
            let mut m = Cases::new();
            for case in &sel.cases {
                for code in &case.when {
                    m.insert(
                        Some(*code),
                        (&case.scale, case.min, case.max, case.source.clone()),
                    );
                }
            }
            Some((Some(sel.selected_by.as_str()), m))
        }
        Some(s) => {
            let mut m = Cases::new();
            m.insert(None, (s, d.min, d.max, d.source.clone()));
            Some((None, m))
        }
    }
}

fn scale(
    c: &mut Collector,
    old: &Drive,
    r: &Register,
    new: &Drive,
    n: &Register,
    subject: &str,
    order: u32,
) {
    let (a, b) = (&r.def.scale, &n.def.scale);
    if same(a, b) {
        return;
    }
    let src = (r.def.source.clone(), n.def.source.clone());
    let text = |d: &Drive, s: &Option<Scale>| match s {
        None => "none".to_owned(),
        Some(s) => describe::scale(d, s),
    };
    let whole = |c: &mut Collector| {
        c.push(
            ChangeKind::ScaleChanged,
            subject,
            "scale",
            (Some(text(old, a)), src.0.clone()),
            (Some(text(new, b)), src.1.clone()),
            order,
        )
    };
    let (Some((sa, ca)), Some((sb, cb))) = (cases(r), cases(n)) else {
        whole(c);
        return;
    };
    if sa.is_none() || sa != sb {
        whole(c);
        return;
    }
    // Both selected by the same parameter: compare code by code.
    let selector = sa.unwrap_or_default();
    for (code, (x, _, _, xs)) in &ca {
        let what = format!(
            "scale when {selector} = {}",
            code.map(|c| c.to_string()).unwrap_or_default()
        );
        match cb.get(code) {
            None => c.push(
                ChangeKind::ScaleChanged,
                subject,
                &what,
                (Some(describe::scale(old, x)), xs.clone().or(src.0.clone())),
                (Some("none".into()), src.1.clone()),
                order,
            ),
            Some((y, _, _, ys)) if !same(*x, *y) => c.push(
                ChangeKind::ScaleChanged,
                subject,
                &what,
                (Some(describe::scale(old, x)), xs.clone().or(src.0.clone())),
                (Some(describe::scale(new, y)), ys.clone().or(src.1.clone())),
                order,
            ),
            Some((_, _, _, ys)) if xs != ys => c.push(
                ChangeKind::CitationChanged,
                subject,
                &what,
                (None, xs.clone()),
                (None, ys.clone()),
                order,
            ),
            Some(_) => {}
        }
    }
    for (code, (y, _, _, ys)) in &cb {
        if !ca.contains_key(code) {
            c.push(
                ChangeKind::ScaleCaseAdded,
                subject,
                &format!(
                    "scale when {selector} = {}",
                    code.map(|c| c.to_string()).unwrap_or_default()
                ),
                (None, src.0.clone()),
                (Some(describe::scale(new, y)), ys.clone().or(src.1.clone())),
                order,
            );
        }
    }
}

/// Whether going from `a` to `b` refuses something `a` accepted, and whether it accepts
/// something new. `None` limits are unbounded.
fn range_change(a: (Option<f64>, Option<f64>), b: (Option<f64>, Option<f64>)) -> (bool, bool) {
    let lo = |x: Option<f64>| x.unwrap_or(f64::NEG_INFINITY);
    let hi = |x: Option<f64>| x.unwrap_or(f64::INFINITY);
    let narrowed = lo(b.0) > lo(a.0) || hi(b.1) < hi(a.1);
    let widened = lo(b.0) < lo(a.0) || hi(b.1) > hi(a.1);
    (narrowed, widened)
}

#[allow(clippy::too_many_arguments)]
fn range_push(
    c: &mut Collector,
    subject: &str,
    what: &str,
    unit: (&str, &str),
    a: (Option<f64>, Option<f64>),
    b: (Option<f64>, Option<f64>),
    src: (Option<String>, Option<String>),
    order: u32,
) {
    let (narrowed, widened) = range_change(a, b);
    if !narrowed && !widened {
        return;
    }
    let kind = if narrowed {
        ChangeKind::RangeNarrowed
    } else {
        ChangeKind::RangeWidened
    };
    let text = |(min, max): (Option<f64>, Option<f64>), unit: &str| {
        let t = describe::range(min, max, unit);
        if t.is_empty() { "unbounded".into() } else { t }
    };
    c.push(
        kind,
        subject,
        what,
        (Some(text(a, unit.0)), src.0),
        (Some(text(b, unit.1)), src.1),
        order,
    );
}

fn ranges(c: &mut Collector, r: &Register, n: &Register, subject: &str, order: u32) {
    let (a, b) = (&r.def, &n.def);
    let unit = (
        a.unit.as_deref().unwrap_or(""),
        b.unit.as_deref().unwrap_or(""),
    );
    let src = (a.source.clone(), b.source.clone());
    range_push(
        c,
        subject,
        "range",
        unit,
        (a.min, a.max),
        (b.min, b.max),
        src.clone(),
        order,
    );
    let options: BTreeSet<&String> = a.by_variant.keys().chain(b.by_variant.keys()).collect();
    for option in options {
        let (oa, ob) = (a.by_variant.get(option), b.by_variant.get(option));
        let overrides = |o: Option<&drivemap_codegen::model::VariantOverride>| {
            o.map(|o| (o.min, o.max)).unwrap_or((None, None))
        };
        let ((mina, maxa), (minb, maxb)) = (overrides(oa), overrides(ob));
        // Bounds neither side overrides follow the base, reported above.
        let (ea, eb) = (r.limits_for(option), n.limits_for(option));
        let min_differs = (mina.is_some() || minb.is_some()) && ea.0 != eb.0;
        let max_differs = (maxa.is_some() || maxb.is_some()) && ea.1 != eb.1;
        if !(min_differs || max_differs) {
            continue;
        }
        // The old side, with the bounds that follow the base taken from the new side.
        let pick = |e: (Option<f64>, Option<f64>), base: (Option<f64>, Option<f64>)| {
            (
                if min_differs { e.0 } else { base.0 },
                if max_differs { e.1 } else { base.1 },
            )
        };
        let osrc = (
            oa.and_then(|o| o.source.clone()).or(src.0.clone()),
            ob.and_then(|o| o.source.clone()).or(src.1.clone()),
        );
        range_push(
            c,
            subject,
            &format!("range ({option})"),
            unit,
            pick(ea, eb),
            eb,
            osrc,
            order,
        );
    }
    if let (Some((Some(sa), ca)), Some((Some(sb), cb))) = (cases(r), cases(n)) {
        if sa == sb {
            for (code, (_, mina, maxa, xs)) in &ca {
                if let Some((_, minb, maxb, ys)) = cb.get(code) {
                    range_push(
                        c,
                        subject,
                        &format!(
                            "range when {sa} = {}",
                            code.map(|c| c.to_string()).unwrap_or_default()
                        ),
                        unit,
                        (*mina, *maxa),
                        (*minb, *maxb),
                        (xs.clone().or(src.0.clone()), ys.clone().or(src.1.clone())),
                        order,
                    );
                }
            }
        }
    }
}

fn default_text(d: &Option<DefaultValue>) -> String {
    d.as_ref()
        .map(describe::default)
        .unwrap_or_else(|| "none".into())
}

fn defaults(c: &mut Collector, r: &Register, n: &Register, subject: &str, order: u32) {
    let (a, b) = (&r.def, &n.def);
    let src = (a.source.clone(), b.source.clone());
    if !same(&a.default, &b.default) {
        c.push(
            ChangeKind::DefaultChanged,
            subject,
            "default",
            (Some(default_text(&a.default)), src.0.clone()),
            (Some(default_text(&b.default)), src.1.clone()),
            order,
        );
    }
    let options: BTreeSet<&String> = a.by_variant.keys().chain(b.by_variant.keys()).collect();
    for option in options {
        let (oa, ob) = (a.by_variant.get(option), b.by_variant.get(option));
        let (da, db) = (
            oa.and_then(|o| o.default.clone()),
            ob.and_then(|o| o.default.clone()),
        );
        if !same(&da, &db) {
            c.push(
                ChangeKind::DefaultChanged,
                subject,
                &format!("default ({option})"),
                (
                    Some(default_text(&da)),
                    oa.and_then(|o| o.source.clone()).or(src.0.clone()),
                ),
                (
                    Some(default_text(&db)),
                    ob.and_then(|o| o.source.clone()).or(src.1.clone()),
                ),
                order,
            );
        }
    }
}

fn documentation(c: &mut Collector, r: &Register, n: &Register, subject: &str, order: u32) {
    let (a, b) = (&r.def, &n.def);
    let src = (a.source.clone(), b.source.clone());
    let mut parts = Vec::new();
    if a.notes != b.notes {
        parts.push("notes");
    }
    if !same(&a.conflicts, &b.conflicts) {
        parts.push("conflicts");
    }
    if !same(&a.unknown, &b.unknown) {
        parts.push("unknowns");
    }
    if !same(&a.display_steps, &b.display_steps) {
        parts.push("display steps");
    }
    let variant_docs = |d: &drivemap_codegen::model::Register| {
        d.by_variant
            .iter()
            .map(|(k, o)| (k.clone(), json(&o.unknown)))
            .collect::<Vec<_>>()
    };
    if variant_docs(a) != variant_docs(b) {
        parts.push("variant unknowns");
    }
    if !parts.is_empty() {
        c.push(
            ChangeKind::DocumentationChanged,
            subject,
            &parts.join(", "),
            (None, src.0),
            (None, src.1),
            order,
        );
    }
}

fn code_text(v: &EnumValue) -> String {
    format!("{} `{}`: {}", v.value, v.id, v.name)
}

fn enum_codes(
    c: &mut Collector,
    subject: &str,
    prefix: &str,
    a: &[EnumValue],
    b: &[EnumValue],
    src: (Option<String>, Option<String>),
    order: u32,
) {
    for x in a {
        let what = format!("{prefix}code {}", x.value);
        let xs = x.source.clone().or(src.0.clone());
        match b.iter().find(|y| y.value == x.value) {
            None => c.push(
                ChangeKind::CodeRemoved,
                subject,
                &what,
                (Some(code_text(x)), xs),
                (None, src.1.clone()),
                order,
            ),
            Some(y) => {
                let ys = y.source.clone().or(src.1.clone());
                if x.id != y.id {
                    c.push(
                        ChangeKind::CodeRenamed,
                        subject,
                        &what,
                        (Some(code_text(x)), xs),
                        (Some(code_text(y)), ys),
                        order,
                    );
                } else if x.name != y.name {
                    c.push(
                        ChangeKind::CodeReworded,
                        subject,
                        &what,
                        (Some(code_text(x)), xs),
                        (Some(code_text(y)), ys),
                        order,
                    );
                } else if x.source != y.source {
                    c.push(
                        ChangeKind::CitationChanged,
                        subject,
                        &what,
                        (None, xs),
                        (None, ys),
                        order,
                    );
                }
            }
        }
    }
    for y in b {
        if !a.iter().any(|x| x.value == y.value) {
            c.push(
                ChangeKind::CodeAdded,
                subject,
                &format!("{prefix}code {}", y.value),
                (None, src.0.clone()),
                (Some(code_text(y)), y.source.clone().or(src.1.clone())),
                order,
            );
        }
    }
}

fn field_text(f: &Field) -> String {
    format!("`{}` at {}: {}", f.id, describe::bits(f), f.name)
}

fn fields(
    c: &mut Collector,
    subject: &str,
    a: &[Field],
    b: &[Field],
    src: (Option<String>, Option<String>),
    order: u32,
) {
    let mut pairs: Vec<(&Field, &Field)> = Vec::new();
    let mut old_left: Vec<&Field> = Vec::new();
    for x in a {
        match b.iter().find(|y| y.id == x.id) {
            Some(y) => pairs.push((x, y)),
            None => old_left.push(x),
        }
    }
    let mut new_left: Vec<&Field> = b
        .iter()
        .filter(|y| !a.iter().any(|x| x.id == y.id))
        .collect();
    for x in old_left {
        let xs = x.source.clone().or(src.0.clone());
        match new_left.iter().position(|y| field_span(y) == field_span(x)) {
            Some(i) => {
                let y = new_left.remove(i);
                c.push(
                    ChangeKind::FieldRenamed,
                    subject,
                    &format!("field at {}", describe::bits(y)),
                    (Some(field_text(x)), xs),
                    (Some(field_text(y)), y.source.clone().or(src.1.clone())),
                    order,
                );
                pairs.push((x, y));
            }
            None => c.push(
                ChangeKind::FieldRemoved,
                subject,
                &format!("field {}", x.id),
                (Some(field_text(x)), xs),
                (None, src.1.clone()),
                order,
            ),
        }
    }
    for y in new_left {
        c.push(
            ChangeKind::FieldAdded,
            subject,
            &format!("field {}", y.id),
            (None, src.0.clone()),
            (Some(field_text(y)), y.source.clone().or(src.1.clone())),
            order,
        );
    }
    for (x, y) in pairs {
        let fs = (
            x.source.clone().or(src.0.clone()),
            y.source.clone().or(src.1.clone()),
        );
        let what = format!("field {}", y.id);
        if field_span(x) != field_span(y) {
            c.push(
                ChangeKind::FieldMoved,
                subject,
                &what,
                (Some(describe::bits(x)), fs.0.clone()),
                (Some(describe::bits(y)), fs.1.clone()),
                order,
            );
        }
        if x.name != y.name {
            c.push(
                ChangeKind::FieldReworded,
                subject,
                &what,
                (Some(x.name.clone()), fs.0.clone()),
                (Some(y.name.clone()), fs.1.clone()),
                order,
            );
        }
        enum_codes(
            c,
            subject,
            &format!("field {} ", y.id),
            &x.values,
            &y.values,
            fs.clone(),
            order,
        );
        if x.notes != y.notes {
            c.push(
                ChangeKind::DocumentationChanged,
                subject,
                &format!("field {} notes", y.id),
                (None, fs.0.clone()),
                (None, fs.1.clone()),
                order,
            );
        }
        if x.source != y.source {
            c.push(
                ChangeKind::CitationChanged,
                subject,
                &what,
                (None, x.source.clone()),
                (None, y.source.clone()),
                order,
            );
        }
    }
}

fn map_documentation(c: &mut Collector, old: &Drive, new: &Drive) {
    let id = &new.meta.id;
    let count = |n: usize, what: &str| Some(format!("{n} {what}"));
    let counts = |a: usize, b: usize, what: &str| {
        if a == b {
            (None, None)
        } else {
            (count(a, what), count(b, what))
        }
    };
    if !same(&old.conflicts, &new.conflicts) {
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "map conflicts",
            (
                counts(old.conflicts.len(), new.conflicts.len(), "conflict(s)").0,
                None,
            ),
            (
                counts(old.conflicts.len(), new.conflicts.len(), "conflict(s)").1,
                None,
            ),
            TAIL,
        );
    }
    if !same(&old.gaps, &new.gaps) {
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "gaps",
            (counts(old.gaps.len(), new.gaps.len(), "gap(s)").0, None),
            (counts(old.gaps.len(), new.gaps.len(), "gap(s)").1, None),
            TAIL,
        );
    }
    if !same(&old.removed, &new.removed) {
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "removed-register reasons",
            (
                counts(old.removed.len(), new.removed.len(), "entry(ies)").0,
                None,
            ),
            (
                counts(old.removed.len(), new.removed.len(), "entry(ies)").1,
                None,
            ),
            TAIL,
        );
    }
    let group_docs = |d: &Drive| {
        d.groups
            .iter()
            .map(|g| {
                (
                    g.id.clone(),
                    g.name.clone(),
                    g.table.clone(),
                    g.notes.clone(),
                )
            })
            .collect::<Vec<_>>()
    };
    if group_docs(old) != group_docs(new) {
        c.push(
            ChangeKind::DocumentationChanged,
            id,
            "groups",
            (
                counts(old.groups.len(), new.groups.len(), "group(s)").0,
                None,
            ),
            (
                counts(old.groups.len(), new.groups.len(), "group(s)").1,
                None,
            ),
            TAIL,
        );
    }
}
