//! Differences of registers: matching old and new registers (by id, then renames by address and
//! parameter number), then comparing address, access, value kind, scale, unit, ranges per variant
//! and per selected case, defaults, enumeration codes, bit fields, documentation and citations.
//! Access, table, write restriction and transports are compared on the lowered plans
//! ([`Drive::register_plan`]): what the generated code and the write gate act on.

use std::collections::{BTreeMap, BTreeSet};

use crate::ir::{Drive, Register, ValueKind};
use drivemap_core::register::{Access, WriteRestriction};

use crate::model::{DefaultValue, EnumValue, Field, Scale};
use crate::validate::field_span;

use super::{ChangeKind, Collector, json, same};
use crate::describe;
use crate::facts::{self, FactKey, RegisterFacts};

pub(super) fn registers(c: &mut Collector, old: &Drive, new: &Drive) {
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
    let plan = drive.register_plan(r);
    let mut s = format!(
        "{} {} at {}, {}",
        r.def.name,
        describe::kind(plan),
        describe::address(r.def.address),
        describe::access(plan.info.access)
    );
    if let Some(u) = &r.def.unit {
        s += &format!(", {u}");
    }
    if let Some(sc) = &r.def.scale {
        s += &format!(
            ", scale {}",
            describe::scale(drive, sc, r.def.unit.as_deref().unwrap_or(""))
        );
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
    (a.readable(), a.writable())
}

fn strictness(w: WriteRestriction) -> u8 {
    match w {
        WriteRestriction::None => 0,
        WriteRestriction::Stopped => 1,
        WriteRestriction::PrgMode => 2,
    }
}

/// A row of the table of simple differences: whether the two sides differ, the kind, which
/// part, and the two sides as text.
type Row = (
    bool,
    ChangeKind,
    &'static str,
    Option<String>,
    Option<String>,
);

/// Alternative addresses: a change of an address or condition, or of their citations alone.
fn alternatives(a: &crate::model::Register, b: &crate::model::Register) -> Row {
    let what = "alternative addresses";
    if same(&a.address_alternatives, &b.address_alternatives) {
        return (false, ChangeKind::CitationChanged, what, None, None);
    }
    let text = |d: &crate::model::Register| {
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
    let addresses = |d: &crate::model::Register| {
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
            Some(text(a)),
            Some(text(b)),
        )
    }
}

fn register(c: &mut Collector, old: &Drive, r: &Register, new: &Drive, n: &Register) {
    // Every key of a register, and what the IR adds to it, is compared below: a key added to
    // the schema fails to compile here until it is.
    let crate::model::Register {
        id: _,                   // matching, RegisterRenamed
        param: _,                // ParamChanged
        name: _,                 // NameChanged
        address: _,              // RegisterMoved
        access: _,               // on the plan (with the group's default)
        modbus_table: _,         // on the plan
        unit: _,                 // UnitChanged
        scale: _,                // scale()
        signed: _,               // SignednessChanged
        pair: _,                 // WidthChanged, citations()
        min: _,                  // ranges()
        max: _,                  // ranges()
        max_relative: _,         // RelativeLimitChanged
        default: _,              // defaults()
        by_variant: _,           // ranges(), defaults(), documentation(), citations()
        address_alternatives: _, // AddressAlternativesChanged
        values: _,               // enum_codes()
        fields: _,               // fields()
        read_values: _,          // ReadMeaningChanged, enum_codes()
        repeat_needs_change: _,  // on the IR register (with the group's)
        indexed: _,              // IndexedChanged, CitationChanged (indexed.rs)
        function_codes: _,       // on the IR register (with the group's)
        write_restriction: _,    // on the plan
        transports: _,           // on the plan
        display_steps: _,        // documentation()
        repeat: _,               // expanded by the IR: one register per instance
        source: _,               // CitationChanged
        indirect: _,             // documentation()
        notes: _,                // documentation()
        conflicts: _,            // documentation()
        unknown: _,              // documentation()
    } = &n.def;
    let Register {
        def: _,
        access: _,              // on the plan
        table: _,               // on the plan
        write_restriction: _,   // on the plan
        transports: _,          // on the plan
        broadcast: _,           // BroadcastMembershipChanged
        group: _,               // GroupChanged
        path: _,                // where it is written
        repeat_needs_change: _, // RepeatNeedsChangeChanged, citations()
        function_codes: _,      // FunctionCodesChanged, citations()
        index: _,               // its place in the map's list, not a property
    } = n;
    let subject = describe::register(n);
    let order = u32::from(n.def.address) + 1;
    let (pr, pn) = (old.register_plan(r), new.register_plan(n));
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

    let (fa, fb) = (facts::register(old, r), facts::register(new, n));
    // The facts of both sides compared row by row: (differs, kind, what, old, new); the codes of
    // a read meaning, compared code by code, between the two tables.
    let row = |f: &RegisterFacts, key, none: &str| {
        Some(
            f.get(key)
                .map_or_else(|| none.to_owned(), |x| x.value.clone()),
        )
    };
    let t = |x: bool, yes: &str, no: &str| Some(if x { yes } else { no }.to_owned());
    let (ra, rb) = (pr.restriction, pn.restriction);
    let (ta, tb) = (pr.transports, pn.transports);
    let ((read_a, write_a), (read_b, write_b)) = (can(pr.info.access), can(pn.info.access));
    let (ga, gb) = (&old.group_of(r).id, &new.group_of(n).id);
    let codes = |x: &Register| {
        x.function_codes
            .as_ref()
            .map(|(f, _)| (f.codes.clone(), f.refusal()))
    };
    let indexed = super::indexed::change(a.indexed.as_ref(), b.indexed.as_ref());
    let identity: Vec<Row> = vec![
        (
            a.address != b.address,
            ChangeKind::RegisterMoved,
            "",
            Some(describe::address(a.address)),
            Some(describe::address(b.address)),
        ),
        alternatives(a, b),
        (
            a.name != b.name,
            ChangeKind::NameChanged,
            "",
            Some(fa.name.clone()),
            Some(fb.name.clone()),
        ),
        (
            a.param != b.param,
            ChangeKind::ParamChanged,
            "",
            fa.param.clone(),
            fb.param.clone(),
        ),
        (
            pr.info.table != pn.info.table,
            ChangeKind::TableChanged,
            "table",
            Some(describe::table(pr.info.table).into()),
            Some(describe::table(pn.info.table).into()),
        ),
        (
            ga != gb,
            ChangeKind::GroupChanged,
            "group",
            Some(ga.clone()),
            Some(gb.clone()),
        ),
        (
            r.broadcast != n.broadcast,
            ChangeKind::BroadcastMembershipChanged,
            "broadcast",
            t(r.broadcast, "broadcast only", "addressed"),
            t(n.broadcast, "broadcast only", "addressed"),
        ),
        (
            pr.info.access != pn.info.access,
            if (read_a && !read_b) || (write_a && !write_b) {
                ChangeKind::AccessNarrowed
            } else {
                ChangeKind::AccessWidened
            },
            "access",
            row(&fa, FactKey::Access, ""),
            row(&fb, FactKey::Access, ""),
        ),
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
        ),
        (
            pr.repeat_needs_change.map(|x| x.between) != pn.repeat_needs_change.map(|x| x.between),
            ChangeKind::RepeatNeedsChangeChanged,
            "repeat needs change",
            row(&fa, FactKey::RepeatNeedsChange, "none"),
            row(&fb, FactKey::RepeatNeedsChange, "none"),
        ),
        match indexed {
            Some((kind, x, y)) => (true, kind, "indexed access", x, y),
            None => (
                false,
                ChangeKind::IndexedChanged,
                "indexed access",
                None,
                None,
            ),
        },
        (
            codes(r) != codes(n),
            ChangeKind::FunctionCodesChanged,
            "function codes",
            row(&fa, FactKey::FunctionCodes, "every function of the drive"),
            row(&fb, FactKey::FunctionCodes, "every function of the drive"),
        ),
        (
            fa.get(FactKey::RelativeLimit) != fb.get(FactKey::RelativeLimit),
            ChangeKind::RelativeLimitChanged,
            "limit",
            row(&fa, FactKey::RelativeLimit, "none"),
            row(&fb, FactKey::RelativeLimit, "none"),
        ),
    ];
    let after: Vec<Row> = vec![
        (
            pr.read_values != pn.read_values,
            ChangeKind::ReadMeaningChanged,
            "read meaning",
            row(&fa, FactKey::ReadValues, "as written"),
            row(&fb, FactKey::ReadValues, "as written"),
        ),
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
        ),
        (
            a.signed != b.signed,
            ChangeKind::SignednessChanged,
            "signedness",
            t(a.signed, "signed", "unsigned"),
            t(b.signed, "signed", "unsigned"),
        ),
        (
            r.width() != n.width(),
            ChangeKind::WidthChanged,
            "width",
            Some(describe::width(r.width())),
            Some(describe::width(n.width())),
        ),
    ];
    let table = |c: &mut Collector, rows: Vec<Row>| {
        for (differs, kind, what, x, y) in rows {
            if differs {
                push(c, kind, what, x, y);
            }
        }
    };
    table(c, identity);
    if pr.read_values == pn.read_values && !same(&a.read_values, &b.read_values) {
        enum_codes(
            c,
            &subject,
            "read ",
            &a.read_values,
            &b.read_values,
            src.clone(),
            order,
        );
    }
    table(c, after);
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
    ranges(c, new, r, n, &subject, order);
    defaults(c, r, n, &subject, order);
    documentation(c, r, n, &subject, order);
    citations(c, r, n, &subject, order);
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
    let units = (
        r.def.unit.as_deref().unwrap_or(""),
        n.def.unit.as_deref().unwrap_or(""),
    );
    let text = |d: &Drive, s: &Option<Scale>, unit: &str| match s {
        None => "none".to_owned(),
        Some(s) => describe::scale(d, s, unit),
    };
    let whole = |c: &mut Collector| {
        c.push(
            ChangeKind::ScaleChanged,
            subject,
            "scale",
            (Some(text(old, a, units.0)), src.0.clone()),
            (Some(text(new, b, units.1)), src.1.clone()),
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
    let selector = describe::setting(new, sa.unwrap_or_default());
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
                (
                    Some(describe::scale(old, x, units.0)),
                    xs.clone().or(src.0.clone()),
                ),
                (Some("none".into()), src.1.clone()),
                order,
            ),
            Some((y, _, _, ys)) if !same(*x, *y) => c.push(
                ChangeKind::ScaleChanged,
                subject,
                &what,
                (
                    Some(describe::scale(old, x, units.0)),
                    xs.clone().or(src.0.clone()),
                ),
                (
                    Some(describe::scale(new, y, units.1)),
                    ys.clone().or(src.1.clone()),
                ),
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
                (
                    Some(describe::scale(new, y, units.1)),
                    ys.clone().or(src.1.clone()),
                ),
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

fn ranges(c: &mut Collector, new: &Drive, r: &Register, n: &Register, subject: &str, order: u32) {
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
        let overrides = |o: Option<&crate::model::VariantOverride>| {
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
                            "range when {} = {}",
                            describe::setting(new, sa),
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
    if a.indirect != b.indirect {
        parts.push("indirect citation");
    }
    let variant_docs = |d: &crate::model::Register| {
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

/// Citations of a register's parts that no other comparison shows when they alone change: the
/// word order's, the repeat rule's, each variant override's.
fn citations(c: &mut Collector, r: &Register, n: &Register, subject: &str, order: u32) {
    let (a, b) = (&r.def, &n.def);
    let pair = |d: &crate::model::Register| d.pair.as_ref().and_then(|p| p.source.clone());
    if r.width() == n.width() && pair(a) != pair(b) {
        c.push(
            ChangeKind::CitationChanged,
            subject,
            "word order",
            (None, pair(a)),
            (None, pair(b)),
            order,
        );
    }
    let repeat = |x: &Register| {
        x.repeat_needs_change
            .as_ref()
            .map(|(rule, _)| (rule.between.to_bits(), rule.source.clone()))
    };
    if let (Some((x, xs)), Some((y, ys))) = (repeat(r), repeat(n)) {
        if x == y && xs != ys {
            c.push(
                ChangeKind::CitationChanged,
                subject,
                "repeat needs change",
                (None, Some(xs)),
                (None, Some(ys)),
                order,
            );
        }
    }
    let functions = |x: &Register| {
        x.function_codes
            .as_ref()
            .map(|(f, _)| ((f.codes.clone(), f.refusal()), f.source.clone()))
    };
    if let (Some((x, xs)), Some((y, ys))) = (functions(r), functions(n))
        && x == y
        && xs != ys
    {
        c.push(
            ChangeKind::CitationChanged,
            subject,
            "function codes",
            (None, Some(xs)),
            (None, Some(ys)),
            order,
        );
    }
    let options: BTreeSet<&String> = a.by_variant.keys().chain(b.by_variant.keys()).collect();
    for option in options {
        let source = |d: &crate::model::Register| {
            d.by_variant.get(option).and_then(|o| {
                let crate::model::VariantOverride {
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
            c.push(
                ChangeKind::CitationChanged,
                subject,
                &format!("({option})"),
                (None, source(a)),
                (None, source(b)),
                order,
            );
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
        let Field {
            id: _,
            name: _,
            bit: _,
            bits: _,
            values: _,
            source: _,
            indirect: _,
            notes: _,
        } = y;
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
        if x.notes != y.notes || x.indirect != y.indirect {
            c.push(
                ChangeKind::DocumentationChanged,
                subject,
                &format!("field {} notes or indirect citation", y.id),
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
