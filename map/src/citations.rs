//! Every place of a map that carries a `source:` citation, listed once.
//!
//! [`citation_places`] walks the expanded map (`Drive`) and returns one [`CitationPlace`] per
//! `source` key: where it is written (for `file:line:col`), the citation as written, the register
//! it belongs to, what kind of place it is, and whether a citation is required there. The
//! citation checks read this list instead of walking the model themselves: the form check
//! (`validate::citations_present`), the review by content ([`crate::others`] and
//! `drivemap_review::review`) and the coverage of a manual's rows. A new `source` key of the
//! schema is added here once; `map/tests/map/citation_places.rs` fails while a `source` key written
//! in a map or fixture has no place in the list.
//!
//! Order: the protocol (in the order of `maps/README.md`), variant options, groups, roles, gaps,
//! removed registers, the map's conflicts, then each register (its row, its `values`, its
//! `read_values`, each field with its values, then the rest of its keys), then the example
//! frames. Review prints its findings in this order.

use crate::ir::Drive;
use crate::model;
use crate::source::{Path, Seg};

/// What a citation place is the citation of. Indices are into the list the key is written in
/// (`exceptions[i]`, the register's `fields[i]`), registers are named by
/// [`CitationPlace::register`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlaceKind<'a> {
    /// `protocol.source`: the protocol as a whole.
    Protocol,
    /// `protocol.slave_address.source`.
    SlaveAddress,
    /// `protocol.broadcast.source`.
    Broadcast,
    /// `protocol.exceptions[i].source`.
    Exception(usize),
    /// `protocol.exceptions.source` where the manual prints no list (`{unknown, source}`).
    ExceptionsUnknown,
    /// `protocol.commands[i].source`.
    Command(usize),
    /// `protocol.eeprom.source`.
    Eeprom,
    /// `protocol.addressing.source`.
    Addressing,
    /// `protocol.timing.source`.
    Timing,
    /// `protocol.timing.<key>.source` (`frame_gap`, `inter_char_timeout`, `response_time`,
    /// `request_gap`).
    TimingInterval(&'static str),
    /// `protocol.serial.source`.
    Serial,
    /// `protocol.serial.formats.source`.
    SerialFormats,
    /// `protocol.serial.formats.cases[i].source`.
    SerialFormatCase(usize),
    /// `protocol.function_codes.source`.
    FunctionCodes,
    /// `protocol.<key>.source` (`max_read`, `max_write`).
    Limit(&'static str),
    /// `variants[axis].options[option].source`.
    VariantOption {
        /// The axis's place in `variants`.
        axis: usize,
        /// The option's place in its axis's `options`.
        option: usize,
    },
    /// `groups[i].source`.
    Group(usize),
    /// `roles.<role>[i].source`.
    Role {
        /// The role's id.
        role: &'a str,
        /// The place's index in the role's list.
        index: usize,
    },
    /// `gaps[i].source`.
    Gap(usize),
    /// `removed[i].source`.
    Removed(usize),
    /// A reading of a conflict: `conflicts[c].readings[r].source` of the map, or of the
    /// register's `conflicts` when [`CitationPlace::register`] is set.
    ConflictReading {
        /// The conflict's index in its list.
        conflict: usize,
        /// The reading's index in the conflict's `readings`.
        reading: usize,
    },
    /// A register's row (`source` of the register; required).
    Register,
    /// The register's `values[i]`.
    Value(usize),
    /// The register's `read_values[i]`.
    ReadValue(usize),
    /// The register's `fields[i]`.
    Field(usize),
    /// The register's `fields[field].values[value]`.
    FieldValue {
        /// The field's index in the register's `fields`.
        field: usize,
        /// The value's index in the field's `values`.
        value: usize,
    },
    /// The register's `pair`.
    Pair,
    /// The register's `string` (its byte order and example).
    Text,
    /// The register's `repeat_needs_change` (or its group's).
    RepeatNeedsChange,
    /// The register's `function_codes` (or its group's).
    RegisterFunctions,
    /// The register's `max_relative`.
    RelativeLimit,
    /// The register's `by_variant.<option>`.
    ByVariant(&'a str),
    /// The register's `address_alternatives[i]`.
    AddressAlternative(usize),
    /// The register's `scale.cases[i]` (a scale selected by another register).
    ScaleCase(usize),
    /// The register's `indexed` (indexed access).
    Indexed,
    /// The register's `indexed.entries[i]`.
    IndexedEntry(usize),
    /// `examples[i].source`: a line or a line range (`file:first-last`).
    Example(usize),
    /// `profile.source` (the drive uses the profile: `part` "profile"),
    /// `profile.power_on_source` ("power on"), `profile.states.<id>.source` ("state") or
    /// `profile.transitions.<id>.source` ("transition").
    Profile {
        /// `profile`, `power on`, `state` or `transition`.
        part: &'static str,
        /// The state's or transition's id; the power-on state's id; `profile` for the
        /// profile's own.
        id: &'a str,
    },
}

impl PlaceKind<'_> {
    /// A short name of the kind (`register`, `field value`, `timing interval`), for tests and
    /// messages.
    pub fn name(&self) -> &'static str {
        match self {
            PlaceKind::Protocol => "protocol",
            PlaceKind::SlaveAddress => "slave address",
            PlaceKind::Broadcast => "broadcast",
            PlaceKind::Exception(_) => "exception",
            PlaceKind::ExceptionsUnknown => "exceptions unknown",
            PlaceKind::Command(_) => "command",
            PlaceKind::Eeprom => "eeprom",
            PlaceKind::Addressing => "addressing",
            PlaceKind::Timing => "timing",
            PlaceKind::TimingInterval(_) => "timing interval",
            PlaceKind::Serial => "serial",
            PlaceKind::SerialFormats => "serial formats",
            PlaceKind::SerialFormatCase(_) => "serial format case",
            PlaceKind::FunctionCodes => "function codes",
            PlaceKind::Limit(_) => "limit",
            PlaceKind::VariantOption { .. } => "variant option",
            PlaceKind::Group(_) => "group",
            PlaceKind::Role { .. } => "role",
            PlaceKind::Gap(_) => "gap",
            PlaceKind::Removed(_) => "removed",
            PlaceKind::ConflictReading { .. } => "conflict reading",
            PlaceKind::Register => "register",
            PlaceKind::Value(_) => "value",
            PlaceKind::ReadValue(_) => "read value",
            PlaceKind::Field(_) => "field",
            PlaceKind::FieldValue { .. } => "field value",
            PlaceKind::Pair => "pair",
            PlaceKind::Text => "string",
            PlaceKind::RepeatNeedsChange => "repeat needs change",
            PlaceKind::RegisterFunctions => "register function codes",
            PlaceKind::RelativeLimit => "relative limit",
            PlaceKind::ByVariant(_) => "by variant",
            PlaceKind::AddressAlternative(_) => "address alternative",
            PlaceKind::ScaleCase(_) => "scale case",
            PlaceKind::Indexed => "indexed",
            PlaceKind::IndexedEntry(_) => "indexed entry",
            PlaceKind::Example(_) => "example",
            PlaceKind::Profile { .. } => "profile",
        }
    }

    /// Every kind's [`name`](Self::name), in the order of the enum.
    pub const NAMES: &'static [&'static str] = &[
        "protocol",
        "slave address",
        "broadcast",
        "exception",
        "exceptions unknown",
        "command",
        "eeprom",
        "addressing",
        "timing",
        "timing interval",
        "serial",
        "serial formats",
        "serial format case",
        "function codes",
        "limit",
        "variant option",
        "group",
        "role",
        "gap",
        "removed",
        "conflict reading",
        "register",
        "value",
        "read value",
        "field",
        "field value",
        "pair",
        "string",
        "repeat needs change",
        "register function codes",
        "relative limit",
        "by variant",
        "address alternative",
        "scale case",
        "indexed",
        "indexed entry",
        "example",
        "profile",
    ];
}

/// Why a citation may not show the item itself, as the place can say it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reason<'a> {
    /// The place has no such key.
    None,
    /// The place has an `indirect:` key (a reason, which needs a citation to qualify); `None`
    /// when it is left out.
    Indirect(Option<&'a str>),
    /// A list or limit the manual does not print (`unknown:`), cited where its working value
    /// comes from: indirect by nature.
    Unknown(Option<&'a str>),
}

impl<'a> Reason<'a> {
    /// The reason, whichever key gives it.
    pub fn text(&self) -> Option<&'a str> {
        match self {
            Reason::None => None,
            Reason::Indirect(r) | Reason::Unknown(r) => *r,
        }
    }
}

/// One place of a map that carries (or, for a register's row, must carry) a `source:` citation.
#[derive(Debug, Clone, PartialEq)]
pub struct CitationPlace<'a> {
    /// What the place is the citation of.
    pub kind: PlaceKind<'a>,
    /// Where the `source` key is (or belongs, when it is missing).
    pub path: Path,
    /// The citation as written; `None` where it is left out.
    pub source: Option<&'a str>,
    /// The register it belongs to (an index into `Map::registers`), if any.
    pub register: Option<usize>,
    /// The register diagnostics about the citation name: the register's id, the `register` a
    /// role place names as written, a `removed` entry's id.
    pub register_name: Option<&'a str>,
    /// Whether a citation is required here (a register's row).
    pub required: bool,
    /// What the place says about the citation being indirect.
    pub reason: Reason<'a>,
}

impl CitationPlace<'_> {
    /// The item the `source` key belongs to (the path without its last key).
    pub fn item_path(&self) -> Path {
        if matches!(self.path.last(), Some(Seg::Key(k)) if k == "source") {
            self.path.parent()
        } else {
            self.path.clone()
        }
    }
}

/// Collects places in order.
struct Walk<'a> {
    out: Vec<CitationPlace<'a>>,
}

impl<'a> Walk<'a> {
    /// A place outside the registers.
    fn at(&mut self, kind: PlaceKind<'a>, item: Path, source: Option<&'a str>, reason: Reason<'a>) {
        self.out.push(CitationPlace {
            kind,
            path: item.key("source"),
            source,
            register: None,
            register_name: None,
            required: false,
            reason,
        });
    }
}

fn indirect(r: &Option<String>) -> Reason<'_> {
    Reason::Indirect(r.as_deref())
}

/// Every citation place of the map, in the order described in the module documentation.
pub(crate) fn citation_places(drive: &Drive) -> Vec<CitationPlace<'_>> {
    let mut w = Walk { out: Vec::new() };
    protocol(drive, &mut w);
    let root = Path::root();
    for (ai, axis) in drive.variants.iter().enumerate() {
        for (oi, o) in axis.options.iter().enumerate() {
            w.at(
                PlaceKind::VariantOption {
                    axis: ai,
                    option: oi,
                },
                root.key("variants").index(ai).key("options").index(oi),
                o.source.as_deref(),
                Reason::None,
            );
        }
    }
    for (gi, g) in drive.groups.iter().enumerate() {
        w.at(
            PlaceKind::Group(gi),
            g.path.clone(),
            g.source.as_deref(),
            Reason::None,
        );
    }
    for (id, places) in &drive.roles {
        for (i, p) in places.iter().enumerate() {
            w.at(
                PlaceKind::Role { role: id, index: i },
                root.key("roles").key(id).index(i),
                p.source.as_deref(),
                indirect(&p.indirect),
            );
            if let Some(last) = w.out.last_mut() {
                last.register_name = p.register.as_deref();
            }
        }
    }
    if let Some(profile) = &drive.profile {
        let at = root.key("profile");
        w.at(
            PlaceKind::Profile {
                part: "profile",
                id: "profile",
            },
            at.clone(),
            profile.source.as_deref(),
            Reason::None,
        );
        if let Some(p) = &profile.power_on {
            w.at(
                PlaceKind::Profile {
                    part: "power on",
                    id: &p.state,
                },
                at.key("power_on"),
                p.source.as_deref(),
                Reason::None,
            );
        }
        for (id, s) in &profile.states {
            w.at(
                PlaceKind::Profile { part: "state", id },
                at.key("states").key(id),
                s.source.as_deref(),
                Reason::None,
            );
        }
        for (id, t) in &profile.transitions {
            w.at(
                PlaceKind::Profile {
                    part: "transition",
                    id,
                },
                at.key("transitions").key(id),
                t.source.as_deref(),
                Reason::None,
            );
        }
    }
    for (i, g) in drive.gaps.iter().enumerate() {
        w.at(
            PlaceKind::Gap(i),
            root.key("gaps").index(i),
            Some(&g.source),
            indirect(&g.indirect),
        );
    }
    for (i, r) in drive.removed.iter().enumerate() {
        w.at(
            PlaceKind::Removed(i),
            root.key("removed").index(i),
            Some(&r.source),
            Reason::None,
        );
        if let Some(last) = w.out.last_mut() {
            last.register_name = Some(&r.id);
        }
    }
    conflicts(&mut w, &drive.conflicts, root.key("conflicts"), None);
    for ri in 0..drive.registers.len() {
        register(drive, ri, &mut w);
    }
    for (i, e) in drive.examples.iter().enumerate() {
        w.at(
            PlaceKind::Example(i),
            root.key("examples").index(i),
            Some(&e.source),
            Reason::None,
        );
    }
    w.out
}

fn protocol<'a>(drive: &'a Drive, w: &mut Walk<'a>) {
    let at = Path::root().key("protocol");
    let model::Protocol {
        transports: _,
        function_codes: _,
        max_read: _,
        max_write: _,
        max_read_bits: _,
        max_write_bits: _,
        slave_address,
        broadcast,
        exceptions,
        commands,
        eeprom,
        addressing,
        timing: _,
        serial: _,
        source,
        indirect: reason,
        notes: _,
    } = &drive.protocol;
    w.at(
        PlaceKind::Protocol,
        at.clone(),
        source.as_deref(),
        indirect(reason),
    );
    w.at(
        PlaceKind::SlaveAddress,
        at.key("slave_address"),
        slave_address.source.as_deref(),
        indirect(&slave_address.indirect),
    );
    if let Some(b) = broadcast {
        w.at(
            PlaceKind::Broadcast,
            at.key("broadcast"),
            Some(&b.source),
            indirect(&b.indirect),
        );
    }
    for (i, e) in exceptions.list.iter().enumerate() {
        w.at(
            PlaceKind::Exception(i),
            at.key("exceptions").index(i),
            Some(&e.source),
            indirect(&e.indirect),
        );
    }
    if exceptions.source.is_some() || exceptions.indirect.is_some() {
        w.at(
            PlaceKind::ExceptionsUnknown,
            at.key("exceptions"),
            exceptions.source.as_deref(),
            indirect(&exceptions.indirect),
        );
    }
    for (i, c) in commands.iter().enumerate() {
        w.at(
            PlaceKind::Command(i),
            at.key("commands").index(i),
            Some(&c.source),
            indirect(&c.indirect),
        );
    }
    if let Some(e) = eeprom {
        w.at(
            PlaceKind::Eeprom,
            at.key("eeprom"),
            Some(&e.source),
            indirect(&e.indirect),
        );
    }
    if let Some(a) = addressing {
        w.at(
            PlaceKind::Addressing,
            at.key("addressing"),
            Some(&a.source),
            indirect(&a.indirect),
        );
    }
    protocol_figures(drive, w);
}

/// The protocol's timing, serial line and limits (continues [`protocol`]).
fn protocol_figures<'a>(drive: &'a Drive, w: &mut Walk<'a>) {
    let at = Path::root().key("protocol");
    let model::Protocol {
        function_codes,
        max_read,
        max_write,
        max_read_bits,
        max_write_bits,
        timing,
        serial,
        ..
    } = &drive.protocol;
    if let Some(t) = timing {
        let tp = at.key("timing");
        w.at(
            PlaceKind::Timing,
            tp.clone(),
            t.source.as_deref(),
            indirect(&t.indirect),
        );
        for (key, i) in t.figures() {
            if let Some(i) = i {
                w.at(
                    PlaceKind::TimingInterval(key),
                    tp.key(key),
                    i.source.as_deref(),
                    indirect(&i.indirect),
                );
            }
        }
    }
    if let Some(s) = serial {
        let sp = at.key("serial");
        w.at(
            PlaceKind::Serial,
            sp.clone(),
            Some(&s.source),
            indirect(&s.indirect),
        );
        if let Some(f) = &s.formats {
            let fp = sp.key("formats");
            w.at(
                PlaceKind::SerialFormats,
                fp.clone(),
                Some(&f.source),
                indirect(&f.indirect),
            );
            for (i, c) in f.cases.iter().enumerate() {
                w.at(
                    PlaceKind::SerialFormatCase(i),
                    fp.key("cases").index(i),
                    c.source.as_deref(),
                    indirect(&c.indirect),
                );
            }
        }
    }
    w.at(
        PlaceKind::FunctionCodes,
        at.key("function_codes"),
        function_codes.source.as_deref(),
        Reason::Unknown(function_codes.unknown.as_deref()),
    );
    let bits = [
        ("max_read_bits", max_read_bits.as_ref()),
        ("max_write_bits", max_write_bits.as_ref()),
    ];
    let limits = [("max_read", Some(max_read)), ("max_write", Some(max_write))];
    for (key, l) in limits.into_iter().chain(bits) {
        let Some(l) = l else { continue };
        w.at(
            PlaceKind::Limit(key),
            at.key(key),
            l.source.as_deref(),
            Reason::Unknown(l.unknown.as_deref()),
        );
    }
}

fn conflicts<'a>(
    w: &mut Walk<'a>,
    list: &'a [model::Conflict],
    base: Path,
    register: Option<(usize, &'a str)>,
) {
    for (ci, c) in list.iter().enumerate() {
        for (ri, reading) in c.readings.iter().enumerate() {
            w.out.push(CitationPlace {
                kind: PlaceKind::ConflictReading {
                    conflict: ci,
                    reading: ri,
                },
                path: base.index(ci).key("readings").index(ri).key("source"),
                source: Some(&reading.source),
                register: register.map(|(i, _)| i),
                register_name: register.map(|(_, id)| id),
                required: false,
                reason: indirect(&reading.indirect),
            });
        }
    }
}

fn register<'a>(drive: &'a Drive, ri: usize, w: &mut Walk<'a>) {
    let r = &drive.registers[ri];
    let d = &r.def;
    let id: &'a str = &d.id;
    let mut at = |kind: PlaceKind<'a>, item: Path, source: Option<&'a str>, reason: Reason<'a>| {
        w.out.push(CitationPlace {
            kind,
            path: item.key("source"),
            source,
            register: Some(ri),
            register_name: Some(id),
            required: kind == PlaceKind::Register,
            reason,
        });
    };
    at(
        PlaceKind::Register,
        r.path.clone(),
        d.source.as_deref(),
        indirect(&d.indirect),
    );
    for (vi, v) in d.values.iter().enumerate() {
        at(
            PlaceKind::Value(vi),
            r.key_path("values").index(vi),
            v.source.as_deref(),
            indirect(&v.indirect),
        );
    }
    for (vi, v) in d.read_values.iter().enumerate() {
        at(
            PlaceKind::ReadValue(vi),
            r.key_path("read_values").index(vi),
            v.source.as_deref(),
            indirect(&v.indirect),
        );
    }
    for (fi, f) in d.fields.iter().enumerate() {
        let fp = r.key_path("fields").index(fi);
        at(
            PlaceKind::Field(fi),
            fp.clone(),
            f.source.as_deref(),
            indirect(&f.indirect),
        );
        for (vi, v) in f.values.iter().enumerate() {
            at(
                PlaceKind::FieldValue {
                    field: fi,
                    value: vi,
                },
                fp.key("values").index(vi),
                v.source.as_deref(),
                indirect(&v.indirect),
            );
        }
    }
    register_keys(drive, ri, w);
}

/// A register's other cited keys (continues [`register`]): pair, string, rules, limits, variants,
/// alternatives, scale cases, indexed entries, conflicts.
fn register_keys<'a>(drive: &'a Drive, ri: usize, w: &mut Walk<'a>) {
    let r = &drive.registers[ri];
    let d = &r.def;
    let id: &'a str = &d.id;
    let mut at = |kind: PlaceKind<'a>, item: Path, source: Option<&'a str>, reason: Reason<'a>| {
        w.out.push(CitationPlace {
            kind,
            path: item.key("source"),
            source,
            register: Some(ri),
            register_name: Some(id),
            required: false,
            reason,
        });
    };
    if let Some(pair) = &d.pair {
        at(
            PlaceKind::Pair,
            r.key_path("pair"),
            pair.source.as_deref(),
            Reason::None,
        );
    }
    if let Some(text) = &d.string {
        at(
            PlaceKind::Text,
            r.key_path("string"),
            text.source.as_deref(),
            Reason::None,
        );
    }
    if let Some((rule, path)) = &r.repeat_needs_change {
        at(
            PlaceKind::RepeatNeedsChange,
            path.clone(),
            Some(&rule.source),
            Reason::None,
        );
    }
    if let Some((f, path)) = &r.function_codes {
        at(
            PlaceKind::RegisterFunctions,
            path.clone(),
            Some(&f.source),
            Reason::None,
        );
    }
    if let Some(limit) = &d.max_relative {
        at(
            PlaceKind::RelativeLimit,
            r.key_path("max_relative"),
            Some(&limit.source),
            Reason::None,
        );
    }
    for (k, o) in &d.by_variant {
        at(
            PlaceKind::ByVariant(k),
            r.key_path("by_variant").key(k),
            o.source.as_deref(),
            Reason::None,
        );
    }
    for (ai, a) in d.address_alternatives.iter().enumerate() {
        at(
            PlaceKind::AddressAlternative(ai),
            r.key_path("address_alternatives").index(ai),
            Some(&a.source),
            Reason::None,
        );
    }
    if let Some(model::Scale::Selected(sel)) = &d.scale {
        for (ci, c) in sel.cases.iter().enumerate() {
            at(
                PlaceKind::ScaleCase(ci),
                r.cases_path().index(ci),
                c.source.as_deref(),
                Reason::None,
            );
        }
    }
    if let Some(ix) = &d.indexed {
        let ip = r.key_path("indexed");
        at(
            PlaceKind::Indexed,
            ip.clone(),
            Some(&ix.source),
            Reason::None,
        );
        for (ei, e) in ix.entries.iter().enumerate() {
            at(
                PlaceKind::IndexedEntry(ei),
                ip.key("entries").index(ei),
                Some(&e.source),
                Reason::None,
            );
        }
    }
    conflicts(w, &d.conflicts, r.key_path("conflicts"), Some((ri, id)));
}
