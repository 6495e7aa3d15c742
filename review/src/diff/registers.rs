//! Differences of registers: matching old and new registers (by id, then renames by address and
//! parameter number), then comparing each pair aspect by aspect, in the order of `ASPECTS`:
//! address, name, table, access and the other rows of one difference each, then the parts
//! compared one by one (enumeration codes, bit fields, scale and range per variant and per
//! selected case, defaults, documentation, citations).
//! Access, table, write restriction and transports are compared on the lowered plans
//! ([`RegisterRef::plan`]): what the generated code and the write gate act on; the rest on
//! the register's keys as the map writes them ([`RegisterRef::written`]) and its facts.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use drivemap_core::kind::ConversionKind;
use drivemap_core::plan::RegisterPlan;
use drivemap_core::register::{Access, WriteRestriction};
use drivemap_map::RegisterRef;

use drivemap_map::facts::field_span;
use drivemap_map::facts::{BitField as Field, EnumValue, Scale, VariantOverride, WrittenRegister};

use super::{ChangeKind, Collector, Side, json, same};
use drivemap_map::Map;
use drivemap_map::describe;
use drivemap_map::facts::data::ScaleData;
use drivemap_map::facts::{FactKey, RegisterFacts};

/// A register's citation, owned.
fn source(r: RegisterRef<'_>) -> Option<String> {
    r.source().map(str::to_owned)
}

/// Where a register's changes sort: its address.
fn order(r: RegisterRef<'_>) -> u32 {
    u32::from(r.address()) + 1
}

/// The registers of a map by id (the first of an id, as [`Map::register_by_id`] finds it).
fn by_id(map: &Map) -> HashMap<&str, RegisterRef<'_>> {
    let mut out = HashMap::new();
    for r in map.registers() {
        out.entry(r.id()).or_insert(r);
    }
    out
}

pub(super) fn registers(c: &mut Collector, old: &Map, new: &Map) {
    let (old_ids, new_ids) = (by_id(old), by_id(new));
    let mut pairs: Vec<(RegisterRef, RegisterRef)> = Vec::new();
    let mut old_left: Vec<RegisterRef> = Vec::new();
    for r in old.registers() {
        match new_ids.get(r.id()) {
            Some(&n) => pairs.push((r, n)),
            None => old_left.push(r),
        }
    }
    let mut new_left: Vec<RegisterRef> = new
        .registers()
        .filter(|n| !old_ids.contains_key(n.id()))
        .collect();
    // Renamed: same address and parameter number (and table), another id.
    let mut removed = Vec::new();
    for r in old_left {
        let hit = new_left.iter().position(|n| {
            n.address() == r.address()
                && n.param() == r.param()
                && n.written().table == r.written().table
                && n.broadcast_only() == r.broadcast_only()
        });
        match hit {
            Some(i) => {
                let n = new_left.remove(i);
                c.push(
                    ChangeKind::RegisterRenamed,
                    &n.label(),
                    "",
                    (Some(r.id().to_owned()), source(r)),
                    (Some(n.id().to_owned()), source(n)),
                    order(n),
                );
                pairs.push((r, n));
            }
            None => removed.push(r),
        }
    }
    for r in removed {
        c.push(
            ChangeKind::RegisterRemoved,
            &r.label(),
            "",
            (Some(summary(r)), source(r)),
            (None, None),
            order(r),
        );
    }
    for n in new_left {
        c.push(
            ChangeKind::RegisterAdded,
            &n.label(),
            "",
            (None, None),
            (Some(summary(n)), source(n)),
            order(n),
        );
    }
    for (r, n) in pairs {
        register(c, r, n);
    }
}

/// A one-line description of a register: its facts' name, access, unit and range, the
/// plan's kind and the map's scale in one line (a selected scale with its cases).
fn summary(r: RegisterRef<'_>) -> String {
    let f = r.facts();
    let plan = r.plan();
    let access = f.get(FactKey::Access).map_or("", |x| x.value.as_str());
    let mut s = format!(
        "{} {} at {}, {access}",
        f.name,
        describe::kind(plan),
        describe::address_as(r.map().address_format(), f.address),
    );
    if let Some(u) = &f.data.unit {
        s += &format!(", {u}");
    }
    if let Some(sc) = r.scale_text() {
        s += &format!(", scale {sc}");
    }
    if let Some(range) = f.get(FactKey::Range) {
        s += &format!(", {}", range.value);
    }
    s
}

/// The kind of value a conversion converts to: a word, a quantity (whatever its scale), codes
/// or bits. The parts of a value (unit, scale, codes, fields) are compared only between values
/// of one kind.
fn kind_of_value(k: ConversionKind) -> u8 {
    match k {
        ConversionKind::Word => 0,
        ConversionKind::Decimal
        | ConversionKind::Relative
        | ConversionKind::Ratio
        | ConversionKind::Selected => 1,
        ConversionKind::Enum => 2,
        ConversionKind::Bits => 3,
        ConversionKind::Text => 4,
    }
}

fn same_kind(a: RegisterRef<'_>, b: RegisterRef<'_>) -> bool {
    kind_of_value(a.kind()) == kind_of_value(b.kind())
}

fn can(a: Access) -> (bool, bool) {
    (a.readable(), a.writable())
}

fn strictness(w: WriteRestriction) -> u8 {
    match w {
        WriteRestriction::None => 0,
        WriteRestriction::Stopped => 1,
        WriteRestriction::PrgMode => 2,
    }
}

/// The two sides of a register compared, and what every aspect reads of them.
struct Sides<'a> {
    r: RegisterRef<'a>,
    n: RegisterRef<'a>,
    /// Every key of both sides as the maps write them.
    wa: WrittenRegister<'a>,
    wb: WrittenRegister<'a>,
    /// The lowered plans: what the generated code and the write gate act on.
    pr: &'static RegisterPlan,
    pn: &'static RegisterPlan,
    /// The facts views of both sides.
    fa: RegisterFacts,
    fb: RegisterFacts,
    /// The register as the changes name it (the new side's).
    subject: String,
    /// Where its changes sort: the new side's address.
    order: u32,
    /// The register's citation on each side.
    src: (Option<String>, Option<String>),
}

impl<'a> Sides<'a> {
    fn new(r: RegisterRef<'a>, n: RegisterRef<'a>) -> Sides<'a> {
        Sides {
            r,
            n,
            wa: r.written(),
            wb: n.written(),
            pr: r.plan(),
            pn: n.plan(),
            fa: r.facts(),
            fb: n.facts(),
            subject: n.label(),
            order: order(n),
            src: (source(r), source(n)),
        }
    }

    /// The unit of both sides, empty for none.
    fn units(&self) -> (&'a str, &'a str) {
        (
            self.wa.unit.unwrap_or_default(),
            self.wb.unit.unwrap_or_default(),
        )
    }

    /// The map's text of both sides.
    fn defs(&self) -> (&WrittenRegister<'a>, &WrittenRegister<'a>) {
        (&self.wa, &self.wb)
    }

    /// A change of the register's part `what`, cited by the register's citations.
    fn push(
        &self,
        c: &mut Collector,
        kind: ChangeKind,
        what: &str,
        x: Option<String>,
        y: Option<String>,
    ) {
        c.push(
            kind,
            &self.subject,
            what,
            (x, self.src.0.clone()),
            (y, self.src.1.clone()),
            self.order,
        );
    }

    /// A change of the citation of the register's part `what` alone.
    fn cite(&self, c: &mut Collector, what: &str, x: Option<String>, y: Option<String>) {
        c.push(
            ChangeKind::CitationChanged,
            &self.subject,
            what,
            (None, x),
            (None, y),
            self.order,
        );
    }

    /// Both sides' fact `key` as text, `none` where a side has none.
    fn facts(&self, key: FactKey, none: &str) -> (Option<String>, Option<String>) {
        let text = |f: &RegisterFacts| {
            Some(
                f.get(key)
                    .map_or_else(|| none.to_owned(), |x| x.value.clone()),
            )
        };
        (text(&self.fa), text(&self.fb))
    }
}

/// A simple difference: whether the two sides differ, the kind, which part, and the two sides
/// as text; pushed with the register's citations when they differ.
type Row = (
    bool,
    ChangeKind,
    &'static str,
    Option<String>,
    Option<String>,
);

/// One aspect of a register compared.
enum Aspect {
    /// One row ([`Row`]).
    Row(fn(&Sides) -> Row),
    /// A comparison part by part (codes, fields, variants, selected cases), pushing its own
    /// changes with the parts' citations.
    Parts(fn(&mut Collector, &Sides)),
}

/// Every aspect of a register, in the order its changes are reported.
const ASPECTS: &[Aspect] = {
    use Aspect::{Parts, Row};
    &[
        Row(moved),
        Row(alternatives),
        Row(name),
        Row(param),
        Row(reference),
        Row(table),
        Row(group),
        Row(broadcast),
        Row(access),
        Row(write_restriction),
        Row(repeat_needs_change),
        Row(indexed),
        Row(function_codes),
        Row(relative_limit),
        Parts(read_codes),
        Row(read_meaning),
        Row(read_param),
        Row(transports),
        Row(signedness),
        Row(width),
        Row(value_kind),
        Row(unit),
        Parts(scale),
        Parts(codes),
        Parts(fields),
        Parts(range),
        Parts(variant_ranges),
        Parts(case_ranges),
        Parts(defaults),
        Parts(documentation),
        Parts(pair_citation),
        Parts(repeat_citation),
        Parts(function_codes_citation),
        Parts(variant_citations),
        Row(citation),
    ]
};

fn register(c: &mut Collector, r: RegisterRef<'_>, n: RegisterRef<'_>) {
    let s = Sides::new(r, n);
    every_key_compared(&s.wb);
    for aspect in ASPECTS {
        match aspect {
            Aspect::Row(row) => {
                let (differs, kind, what, x, y) = row(&s);
                if differs {
                    s.push(c, kind, what, x, y);
                }
            }
            Aspect::Parts(parts) => parts(c, &s),
        }
    }
}

/// Names every key of a register as the map writes it ([`WrittenRegister`], which names every
/// key of the schema's register in turn) with the aspect that compares it: a key added to the
/// schema fails to compile here until it is compared.
fn every_key_compared(n: &WrittenRegister<'_>) {
    let WrittenRegister {
        id: _,                   // matching, RegisterRenamed
        param: _,                // param
        read_param: _,           // read_param
        name: _,                 // name
        address: _,              // moved
        reference: _,            // reference
        access: _,               // access, on the plan
        table: _,                // table, on the plan
        unit: _,                 // unit
        scale: _,                // scale
        signed: _,               // signedness
        pair: _,                 // width, pair_citation
        string: _,               // width (registers, byte order), pair_citation, documentation
        min: _,                  // range, variant_ranges
        max: _,                  // range, variant_ranges
        default: _,              // defaults
        by_variant: _,           // variant_ranges, defaults, documentation, variant_citations
        max_relative: _,         // relative_limit
        address_alternatives: _, // alternatives
        values: _,               // codes
        fields: _,               // fields
        read_values: _,          // read_meaning, read_codes
        repeat_needs_change: _,  // repeat_needs_change, repeat_citation
        indexed: _,              // indexed (indexed.rs)
        function_codes: _,       // function_codes, function_codes_citation
        write_restriction: _,    // write_restriction, on the plan
        transports: _,           // transports, on the plan
        display_steps: _,        // documentation
        source: _,               // citation
        indirect: _,             // documentation
        notes: _,                // documentation
        conflicts: _,            // documentation
        unknown: _,              // documentation
        broadcast: _,            // broadcast
        group: _,                // group
    } = n;
}

fn moved(s: &Sides) -> Row {
    let (a, b) = s.defs();
    (
        a.address != b.address,
        ChangeKind::RegisterMoved,
        "",
        Some(describe::address_as(s.r.map().address_format(), a.address)),
        Some(describe::address_as(s.n.map().address_format(), b.address)),
    )
}

/// Alternative addresses: a change of an address or condition, or of their citations alone;
/// each side as its facts' rows word it.
fn alternatives(s: &Sides) -> Row {
    let (a, b) = s.defs();
    let what = "alternative addresses";
    if same(&a.address_alternatives, &b.address_alternatives) {
        return (false, ChangeKind::CitationChanged, what, None, None);
    }
    let text = |f: &RegisterFacts| {
        let alts: Vec<String> = f
            .all(FactKey::AlternativeAddress)
            .map(|x| format!("{} if {}", x.value, x.when.as_deref().unwrap_or_default()))
            .collect();
        if alts.is_empty() {
            "none".to_owned()
        } else {
            alts.join("; ")
        }
    };
    let addresses = |d: &WrittenRegister| {
        d.address_alternatives
            .iter()
            .map(|x| json(&(x.address, &x.when)))
            .collect::<Vec<_>>()
    };
    if addresses(a) == addresses(b) {
        (true, ChangeKind::CitationChanged, what, None, None)
    } else {
        (
            true,
            ChangeKind::AddressAlternativesChanged,
            what,
            Some(text(&s.fa)),
            Some(text(&s.fb)),
        )
    }
}

fn name(s: &Sides) -> Row {
    let (a, b) = s.defs();
    (
        a.name != b.name,
        ChangeKind::NameChanged,
        "",
        Some(s.fa.name.clone()),
        Some(s.fb.name.clone()),
    )
}

fn param(s: &Sides) -> Row {
    let (a, b) = s.defs();
    (
        a.param != b.param,
        ChangeKind::ParamChanged,
        "",
        s.fa.param.clone(),
        s.fb.param.clone(),
    )
}

/// The Modicon reference the manual prints beside the register (`reference:`): what `check`
/// holds to the address, rustdoc's alias and the look-up by reference.
fn reference(s: &Sides) -> Row {
    let (a, b) = s.defs();
    (
        a.reference != b.reference,
        ChangeKind::DocumentationChanged,
        "Modicon reference",
        Some(a.reference.unwrap_or("none").to_owned()),
        Some(b.reference.unwrap_or("none").to_owned()),
    )
}

/// The parameter a read returns, when not the one a write sets (BICO): a read of the register
/// means another parameter, so readers of it are broken (breaking, as a read meaning changed).
fn read_param(s: &Sides) -> Row {
    let (a, b) = s.defs();
    (
        a.read_param != b.read_param,
        ChangeKind::ReadMeaningChanged,
        "read parameter",
        s.fa.read_param.clone(),
        s.fb.read_param.clone(),
    )
}

fn table(s: &Sides) -> Row {
    let (ta, tb) = (s.pr.info.table, s.pn.info.table);
    (
        ta != tb,
        ChangeKind::TableChanged,
        "table",
        Some(describe::table(ta).into()),
        Some(describe::table(tb).into()),
    )
}

fn group(s: &Sides) -> Row {
    let (ga, gb) = (s.wa.group, s.wb.group);
    (
        ga != gb,
        ChangeKind::GroupChanged,
        "group",
        Some(ga.to_owned()),
        Some(gb.to_owned()),
    )
}

fn broadcast(s: &Sides) -> Row {
    let text = |r: &WrittenRegister| {
        Some(
            if r.broadcast {
                "broadcast only"
            } else {
                "addressed"
            }
            .into(),
        )
    };
    (
        s.wa.broadcast != s.wb.broadcast,
        ChangeKind::BroadcastMembershipChanged,
        "broadcast",
        text(&s.wa),
        text(&s.wb),
    )
}

fn access(s: &Sides) -> Row {
    let (aa, ab) = (s.pr.info.access, s.pn.info.access);
    let ((read_a, write_a), (read_b, write_b)) = (can(aa), can(ab));
    let (x, y) = s.facts(FactKey::Access, "");
    (
        aa != ab,
        if (read_a && !read_b) || (write_a && !write_b) {
            ChangeKind::AccessNarrowed
        } else {
            ChangeKind::AccessWidened
        },
        "access",
        x,
        y,
    )
}

fn write_restriction(s: &Sides) -> Row {
    let (ra, rb) = (s.pr.restriction, s.pn.restriction);
    (
        ra != rb,
        if strictness(rb) > strictness(ra)
            || (ra != WriteRestriction::None && rb != WriteRestriction::None)
        {
            ChangeKind::WriteRestrictionTightened
        } else {
            ChangeKind::WriteRestrictionRelaxed
        },
        "write restriction",
        Some(describe::write_restriction(ra).into()),
        Some(describe::write_restriction(rb).into()),
    )
}

fn repeat_needs_change(s: &Sides) -> Row {
    let between = |p: &RegisterPlan| p.repeat_needs_change.map(|x| x.between);
    let (x, y) = s.facts(FactKey::RepeatNeedsChange, "none");
    (
        between(s.pr) != between(s.pn),
        ChangeKind::RepeatNeedsChangeChanged,
        "repeat needs change",
        x,
        y,
    )
}

fn indexed(s: &Sides) -> Row {
    let (a, b) = s.defs();
    match super::indexed::change(a.indexed, b.indexed) {
        Some((kind, x, y)) => (true, kind, "indexed access", x, y),
        None => (
            false,
            ChangeKind::IndexedChanged,
            "indexed access",
            None,
            None,
        ),
    }
}

fn function_codes(s: &Sides) -> Row {
    let codes = |x: &WrittenRegister| x.function_codes.map(|f| (f.codes.clone(), f.refusal()));
    let (x, y) = s.facts(FactKey::FunctionCodes, "every function of the drive");
    (
        codes(&s.wa) != codes(&s.wb),
        ChangeKind::FunctionCodesChanged,
        "function codes",
        x,
        y,
    )
}

fn relative_limit(s: &Sides) -> Row {
    let (x, y) = s.facts(FactKey::RelativeLimit, "none");
    (
        s.fa.get(FactKey::RelativeLimit) != s.fb.get(FactKey::RelativeLimit),
        ChangeKind::RelativeLimitChanged,
        "limit",
        x,
        y,
    )
}

/// The codes of a read meaning, compared code by code, when the meaning itself is the same.
fn read_codes(c: &mut Collector, s: &Sides) {
    let (a, b) = s.defs();
    if s.pr.read_values == s.pn.read_values && !same(&a.read_values, &b.read_values) {
        enum_codes(
            c,
            &s.subject,
            "read ",
            a.read_values,
            b.read_values,
            s.src.clone(),
            s.order,
        );
    }
}

fn read_meaning(s: &Sides) -> Row {
    let (x, y) = s.facts(FactKey::ReadValues, "as written");
    (
        s.pr.read_values != s.pn.read_values,
        ChangeKind::ReadMeaningChanged,
        "read meaning",
        x,
        y,
    )
}

fn transports(s: &Sides) -> Row {
    let (ta, tb) = (s.pr.transports, s.pn.transports);
    (
        ta != tb,
        if (!ta.rtu || tb.rtu) && (!ta.tcp || tb.tcp) {
            ChangeKind::TransportsWidened
        } else {
            ChangeKind::TransportsNarrowed
        },
        "transports",
        Some(describe::transports(ta)),
        Some(describe::transports(tb)),
    )
}

fn signedness(s: &Sides) -> Row {
    let (a, b) = s.defs();
    let text = |signed: bool| Some(if signed { "signed" } else { "unsigned" }.into());
    (
        a.signed != b.signed,
        ChangeKind::SignednessChanged,
        "signedness",
        text(a.signed),
        text(b.signed),
    )
}

/// The registers a value takes and their order: a pair's word order, a string's length and
/// byte order (`text layout`); either change is breaking (another value on the wire).
fn width(s: &Sides) -> Row {
    let (a, b) = s.defs();
    let layout = |d: &WrittenRegister, r: RegisterRef<'_>| match d.string {
        Some(t) => describe::text(t.registers, t.byte_order, None),
        None => describe::width(r.width()),
    };
    let text = a.string.is_some() || b.string.is_some();
    let (la, lb) = (layout(a, s.r), layout(b, s.n));
    (
        la != lb,
        ChangeKind::WidthChanged,
        if text { "text layout" } else { "width" },
        Some(la),
        Some(lb),
    )
}

/// Another kind of value (word, quantity, enumeration, bits): the parts of a value (unit,
/// scale, codes, fields) are compared only between values of one kind.
fn value_kind(s: &Sides) -> Row {
    let differs = !same_kind(s.r, s.n);
    (
        differs,
        ChangeKind::ValueKindChanged,
        "value kind",
        differs.then(|| summary(s.r)),
        differs.then(|| summary(s.n)),
    )
}

fn unit(s: &Sides) -> Row {
    let (a, b) = s.defs();
    let text = |d: &WrittenRegister| Some(d.unit.unwrap_or("none").to_owned());
    (
        same_kind(s.r, s.n) && a.unit != b.unit,
        ChangeKind::UnitChanged,
        "unit",
        text(a),
        text(b),
    )
}

/// The codes of two enumerations, code by code.
fn codes(c: &mut Collector, s: &Sides) {
    if (s.r.kind(), s.n.kind()) == (ConversionKind::Enum, ConversionKind::Enum) {
        enum_codes(
            c,
            &s.subject,
            "",
            s.wa.values,
            s.wb.values,
            s.src.clone(),
            s.order,
        );
    }
}

/// The fields of two bit sets, field by field.
fn fields(c: &mut Collector, s: &Sides) {
    if (s.r.kind(), s.n.kind()) == (ConversionKind::Bits, ConversionKind::Bits) {
        bit_fields(
            c,
            &s.subject,
            s.wa.fields,
            s.wb.fields,
            s.src.clone(),
            s.order,
        );
    }
}

/// The register's own citation alone.
fn citation(s: &Sides) -> Row {
    (
        s.src.0 != s.src.1,
        ChangeKind::CitationChanged,
        "",
        None,
        None,
    )
}

/// Scale per selector code; `None` as key for a fixed scale.
type Cases<'a> = BTreeMap<Option<u16>, (&'a Scale, Option<f64>, Option<f64>, Option<String>)>;

fn cases<'a>(d: &WrittenRegister<'a>) -> Option<(Option<&'a str>, Cases<'a>)> {
    match d.scale {
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
            m.insert(None, (s, d.min, d.max, d.source.map(str::to_owned)));
            Some((None, m))
        }
    }
}

/// The worded scale of each selector code, from the facts' case table.
fn case_scales(f: &RegisterFacts) -> BTreeMap<u16, &str> {
    let ScaleData::Selected { cases, .. } = &f.data.scale else {
        return BTreeMap::new();
    };
    (cases.iter().zip(&f.cases))
        .flat_map(|(c, w)| c.when.iter().map(move |code| (*code, w.scale.as_str())))
        .collect()
}

/// The scale, per selector code when both sides select it by the same parameter (each case
/// as the facts word it); between values of one kind only.
fn scale(c: &mut Collector, s: &Sides) {
    let (a, b) = (s.wa.scale, s.wb.scale);
    if !same_kind(s.r, s.n) || same(&a, &b) {
        return;
    }
    if let (Some((Some(sa), ca)), Some((Some(sb), cb))) = (cases(&s.wa), cases(&s.wb))
        && sa == sb
    {
        return scale_cases(c, s, &ca, &cb);
    }
    let text = |r: RegisterRef| r.scale_text().unwrap_or_else(|| "none".to_owned());
    s.push(
        c,
        ChangeKind::ScaleChanged,
        "scale",
        Some(text(s.r)),
        Some(text(s.n)),
    );
}

/// Two scales selected by the same parameter, code by code.
fn scale_cases(c: &mut Collector, s: &Sides, ca: &Cases, cb: &Cases) {
    let Sides {
        fa,
        fb,
        subject,
        order,
        src,
        ..
    } = s;
    let (subject, order) = (subject.as_str(), *order);
    let selector = fb.selector.as_deref().unwrap_or_default();
    let (wa, wb) = (case_scales(fa), case_scales(fb));
    let worded = |w: &BTreeMap<u16, &str>, code: &Option<u16>| {
        code.and_then(|c| w.get(&c)).map(|s| (*s).to_owned())
    };
    let what = |code: &Option<u16>| {
        format!(
            "scale when {selector} = {}",
            code.map(|c| c.to_string()).unwrap_or_default()
        )
    };
    for (code, (x, _, _, xs)) in ca {
        let what = what(code);
        match cb.get(code) {
            None => c.push(
                ChangeKind::ScaleChanged,
                subject,
                &what,
                (worded(&wa, code), xs.clone().or(src.0.clone())),
                (Some("none".into()), src.1.clone()),
                order,
            ),
            Some((y, _, _, ys)) if !same(*x, *y) => c.push(
                ChangeKind::ScaleChanged,
                subject,
                &what,
                (worded(&wa, code), xs.clone().or(src.0.clone())),
                (worded(&wb, code), ys.clone().or(src.1.clone())),
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
    for (code, (_, _, _, ys)) in cb {
        if !ca.contains_key(code) {
            c.push(
                ChangeKind::ScaleCaseAdded,
                subject,
                &what(code),
                (None, src.0.clone()),
                (worded(&wb, code), ys.clone().or(src.1.clone())),
                order,
            );
        }
    }
}

/// Whether going from `a` to `b` refuses something `a` accepted, and whether it accepts
/// something new. `None` limits are unbounded.
pub(super) fn range_change(
    a: (Option<f64>, Option<f64>),
    b: (Option<f64>, Option<f64>),
) -> (bool, bool) {
    let lo = |x: Option<f64>| x.unwrap_or(f64::NEG_INFINITY);
    let hi = |x: Option<f64>| x.unwrap_or(f64::INFINITY);
    let narrowed = lo(b.0) > lo(a.0) || hi(b.1) < hi(a.1);
    let widened = lo(b.0) < lo(a.0) || hi(b.1) > hi(a.1);
    (narrowed, widened)
}

// Old and new side of one range line (bounds, citations) with the line's wording: the
// arguments are already paired; one more struct would only be unpacked here.
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

/// The range (the base, when a variant or selected case does not give its own).
fn range(c: &mut Collector, s: &Sides) {
    let (a, b) = s.defs();
    range_push(
        c,
        &s.subject,
        "range",
        s.units(),
        (a.min, a.max),
        (b.min, b.max),
        s.src.clone(),
        s.order,
    );
}

/// The range of each variant, where either side overrides a bound.
fn variant_ranges(c: &mut Collector, s: &Sides) {
    let (r, n, src) = (s.r, s.n, &s.src);
    let (a, b) = s.defs();
    let options: BTreeSet<&String> = a.by_variant.keys().chain(b.by_variant.keys()).collect();
    for option in options {
        let (oa, ob) = (a.by_variant.get(option), b.by_variant.get(option));
        let overrides =
            |o: Option<&VariantOverride>| o.map(|o| (o.min, o.max)).unwrap_or((None, None));
        let ((mina, maxa), (minb, maxb)) = (overrides(oa), overrides(ob));
        // Bounds neither side overrides follow the base, reported by `range`.
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
            &s.subject,
            &format!("range ({option})"),
            s.units(),
            pick(ea, eb),
            eb,
            osrc,
            s.order,
        );
    }
}

/// The range of each code of a scale both sides select by the same parameter.
fn case_ranges(c: &mut Collector, s: &Sides) {
    let src = &s.src;
    let (Some((Some(sa), ca)), Some((Some(sb), cb))) = (cases(&s.wa), cases(&s.wb)) else {
        return;
    };
    if sa != sb {
        return;
    }
    for (code, (_, mina, maxa, xs)) in &ca {
        if let Some((_, minb, maxb, ys)) = cb.get(code) {
            range_push(
                c,
                &s.subject,
                &format!(
                    "range when {} = {}",
                    s.fb.selector.as_deref().unwrap_or_default(),
                    code.map(|c| c.to_string()).unwrap_or_default()
                ),
                s.units(),
                (*mina, *maxa),
                (*minb, *maxb),
                (xs.clone().or(src.0.clone()), ys.clone().or(src.1.clone())),
                s.order,
            );
        }
    }
}

/// A default as the facts word it, or `none`.
fn default_text(d: Option<&str>) -> String {
    d.unwrap_or("none").to_owned()
}

/// The default, and each variant's, as the facts word them.
fn defaults(c: &mut Collector, s: &Sides) {
    let (subject, order) = (s.subject.as_str(), s.order);
    let (a, b) = s.defs();
    let src = (a.source.map(str::to_owned), b.source.map(str::to_owned));
    let base = |f: &RegisterFacts| default_text(f.get(FactKey::Default).map(|x| x.value.as_str()));
    if !same(&a.default, &b.default) {
        c.push(
            ChangeKind::DefaultChanged,
            subject,
            "default",
            (Some(base(&s.fa)), src.0.clone()),
            (Some(base(&s.fb)), src.1.clone()),
            order,
        );
    }
    // An option's default (none where the option gives none).
    let option_default = |f: &RegisterFacts, option: &str| {
        let v = f.variants.iter().find(|v| v.option == option);
        default_text(v.and_then(|v| v.default.as_deref()))
    };
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
                    Some(option_default(&s.fa, option)),
                    oa.and_then(|o| o.source.clone()).or(src.0.clone()),
                ),
                (
                    Some(option_default(&s.fb, option)),
                    ob.and_then(|o| o.source.clone()).or(src.1.clone()),
                ),
                order,
            );
        }
    }
}

/// Notes, conflicts, unknowns, display steps, indirect citations: one change naming the parts.
fn documentation(c: &mut Collector, s: &Sides) {
    let (subject, order) = (s.subject.as_str(), s.order);
    let (a, b) = s.defs();
    let src = (a.source.map(str::to_owned), b.source.map(str::to_owned));
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
    if a.indirect != b.indirect {
        parts.push("indirect citation");
    }
    if a.string.map(|t| &t.example) != b.string.map(|t| &t.example) {
        parts.push("text example");
    }
    let variant_docs = |d: &WrittenRegister| {
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

// Citations of a register's parts that no other comparison shows when they alone change: the
// word order's, the repeat rule's, the function codes', each variant override's.

fn pair_citation(c: &mut Collector, s: &Sides) {
    let (a, b) = s.defs();
    let pair = |d: &WrittenRegister| d.pair.and_then(|p| p.source.clone());
    if s.r.width() == s.n.width() && pair(a) != pair(b) {
        s.cite(c, "word order", pair(a), pair(b));
    }
    let text = |d: &WrittenRegister| d.string.and_then(|t| t.source.clone());
    if s.r.width() == s.n.width() && text(a) != text(b) {
        s.cite(c, "text layout", text(a), text(b));
    }
}

fn repeat_citation(c: &mut Collector, s: &Sides) {
    let repeat = |x: &WrittenRegister| {
        x.repeat_needs_change
            .map(|rule| (rule.between.to_bits(), rule.source.clone()))
    };
    if let (Some((x, xs)), Some((y, ys))) = (repeat(&s.wa), repeat(&s.wb))
        && x == y
        && xs != ys
    {
        s.cite(c, "repeat needs change", Some(xs), Some(ys));
    }
}

fn function_codes_citation(c: &mut Collector, s: &Sides) {
    let functions = |x: &WrittenRegister| {
        x.function_codes
            .map(|f| ((f.codes.clone(), f.refusal()), f.source.clone()))
    };
    if let (Some((x, xs)), Some((y, ys))) = (functions(&s.wa), functions(&s.wb))
        && x == y
        && xs != ys
    {
        s.cite(c, "function codes", Some(xs), Some(ys));
    }
}

fn variant_citations(c: &mut Collector, s: &Sides) {
    let (a, b) = s.defs();
    let options: BTreeSet<&String> = a.by_variant.keys().chain(b.by_variant.keys()).collect();
    for option in options {
        let source = |d: &WrittenRegister| {
            d.by_variant.get(option).and_then(|o| {
                let VariantOverride {
                    min: _,
                    max: _,
                    default: _,
                    unknown: _,
                    source,
                } = o;
                source.clone()
            })
        };
        if source(a) != source(b) {
            s.cite(c, &format!("({option})"), source(a), source(b));
        }
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
        let EnumValue {
            value: _,
            id: _,
            name: _,
            source: _,
            indirect: _,
        } = x;
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
                } else if x.indirect != y.indirect {
                    c.push(
                        ChangeKind::DocumentationChanged,
                        subject,
                        &format!("{what} indirect citation"),
                        (x.indirect.clone(), xs),
                        (y.indirect.clone(), ys),
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

/// The fields of two bit sets: matched, then compared field by field.
fn bit_fields(
    c: &mut Collector,
    subject: &str,
    a: &[Field],
    b: &[Field],
    src: (Option<String>, Option<String>),
    order: u32,
) {
    for (x, y) in match_fields(c, subject, a, b, &src, order) {
        field(c, subject, x, y, &src, order);
    }
}

/// Matches the fields by id, then the rest by their bits (renamed); pushes the renamed, removed
/// and added ones and returns the pairs.
fn match_fields<'a>(
    c: &mut Collector,
    subject: &str,
    a: &'a [Field],
    b: &'a [Field],
    src: &(Option<String>, Option<String>),
    order: u32,
) -> Vec<(&'a Field, &'a Field)> {
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
    pairs
}

/// One field on both sides: its bits, its name, its codes, its notes, its citation.
fn field(
    c: &mut Collector,
    subject: &str,
    x: &Field,
    y: &Field,
    src: &(Option<String>, Option<String>),
    order: u32,
) {
    let Field {
        id: _,       // matching, FieldRenamed
        name: _,     // FieldReworded
        bit: _,      // FieldMoved
        bits: _,     // FieldMoved
        values: _,   // enum_codes()
        source: _,   // CitationChanged
        indirect: _, // DocumentationChanged
        notes: _,    // DocumentationChanged
    } = y;
    // The field's citations, the register's where a field has none.
    let fs = (
        x.source.clone().or(src.0.clone()),
        y.source.clone().or(src.1.clone()),
    );
    let what = format!("field {}", y.id);
    let push = |c: &mut Collector, differs: bool, kind, what: &str, sides: (Side, Side)| {
        if differs {
            c.push(kind, subject, what, sides.0, sides.1, order);
        }
    };
    let text = |x: Option<String>, y: Option<String>| ((x, fs.0.clone()), (y, fs.1.clone()));
    push(
        c,
        field_span(x) != field_span(y),
        ChangeKind::FieldMoved,
        &what,
        text(Some(describe::bits(x)), Some(describe::bits(y))),
    );
    push(
        c,
        x.name != y.name,
        ChangeKind::FieldReworded,
        &what,
        text(Some(x.name.clone()), Some(y.name.clone())),
    );
    enum_codes(
        c,
        subject,
        &format!("field {} ", y.id),
        &x.values,
        &y.values,
        fs.clone(),
        order,
    );
    push(
        c,
        x.notes != y.notes || x.indirect != y.indirect,
        ChangeKind::DocumentationChanged,
        &format!("field {} notes or indirect citation", y.id),
        text(None, None),
    );
    push(
        c,
        x.source != y.source,
        ChangeKind::CitationChanged,
        &what,
        ((None, x.source.clone()), (None, y.source.clone())),
    );
}
