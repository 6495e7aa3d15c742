//! Differences outside the registers: drive metadata, variant axes, the protocol profile.

use std::collections::BTreeSet;

use crate::ir::Drive;
use crate::model::TransportName;

use super::{ChangeKind, Collector, HEAD, json, same};
use crate::describe;

pub(super) fn meta(c: &mut Collector, old: &Drive, new: &Drive) {
    let (a, b) = (&old.meta, &new.meta);
    let id = &b.id;
    let crate::model::DriveMeta {
        id: _,
        extends: _,
        vendor: _,
        models: _,
        manuals: _,
        description: _,
    } = b;
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
        let text = |m: &crate::model::DriveMeta| {
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

pub(super) fn variants(c: &mut Collector, old: &Drive, new: &Drive) {
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
        let crate::model::VariantAxis {
            id: _,
            name: _,
            options: _,
        } = b;
        let mut docs = Vec::new();
        if a.name != b.name {
            docs.push("name".to_owned());
        }
        for o in &a.options {
            let crate::model::VariantOption {
                id: _,
                name: _,
                source: _,
            } = o;
            if let Some(p) = b.options.iter().find(|p| p.id == o.id) {
                if o.name != p.name {
                    docs.push(format!("option {} name", o.id));
                }
                if o.source != p.source {
                    c.push(
                        ChangeKind::CitationChanged,
                        subject,
                        &format!("{} option {}", a.id, o.id),
                        (None, o.source.clone()),
                        (None, p.source.clone()),
                        HEAD,
                    );
                }
            }
        }
        let order = |x: &crate::model::VariantAxis| {
            x.options.iter().map(|o| o.id.clone()).collect::<Vec<_>>()
        };
        let (oa, ob) = (order(a), order(b));
        let common = |x: &[String], y: &[String]| {
            x.iter()
                .filter(|i| y.contains(i))
                .cloned()
                .collect::<Vec<_>>()
        };
        if common(&oa, &ob) != common(&ob, &oa) {
            docs.push("option order".to_owned());
        }
        if !docs.is_empty() {
            c.push(
                ChangeKind::DocumentationChanged,
                subject,
                &format!("{}: {}", a.id, docs.join(", ")),
                (Some(format!("{} ({})", a.name, oa.join(", "))), None),
                (Some(format!("{} ({})", b.name, ob.join(", "))), None),
                HEAD,
            );
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

pub(super) fn protocol(c: &mut Collector, old: &Drive, new: &Drive) {
    let (a, b) = (&old.protocol, &new.protocol);
    let s = "protocol";
    let src = (a.source.clone(), b.source.clone());
    // Each key of the protocol is compared below, in this order.
    let crate::model::Protocol {
        transports: _,
        function_codes: _,
        max_read: _,
        max_write: _,
        slave_address: _,
        broadcast: _,
        exceptions: _,
        commands: _,
        eeprom: _,
        addressing: _,
        timing: _,
        serial: _,
        source: _,
        notes: _,
        indirect: _,
    } = b;

    let ta: BTreeSet<TransportName> = a.transports.iter().copied().collect();
    let tb: BTreeSet<TransportName> = b.transports.iter().copied().collect();
    for t in ta.difference(&tb) {
        c.push(
            ChangeKind::TransportRemoved,
            s,
            "transports",
            (Some(t.to_string()), src.0.clone()),
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
            (Some(t.to_string()), src.1.clone()),
            HEAD,
        );
    }

    let fa: BTreeSet<u8> = a.function_codes.codes.iter().copied().collect();
    let fb: BTreeSet<u8> = b.function_codes.codes.iter().copied().collect();
    let removed: Vec<u8> = fa.difference(&fb).copied().collect();
    let added: Vec<u8> = fb.difference(&fa).copied().collect();
    if !removed.is_empty() {
        c.push(
            ChangeKind::FunctionCodeRemoved,
            s,
            &format!("function codes: {}", describe::functions(&removed)),
            (
                Some(describe::functions(&a.function_codes.codes)),
                src.0.clone(),
            ),
            (
                Some(describe::functions(&b.function_codes.codes)),
                src.1.clone(),
            ),
            HEAD,
        );
    }
    if !added.is_empty() {
        c.push(
            ChangeKind::FunctionCodeAdded,
            s,
            &format!("function codes: {}", describe::functions(&added)),
            (
                Some(describe::functions(&a.function_codes.codes)),
                src.0.clone(),
            ),
            (
                Some(describe::functions(&b.function_codes.codes)),
                src.1.clone(),
            ),
            HEAD,
        );
    }

    {
        // The list's citation and why it is the working list.
        let crate::model::FunctionCodes {
            codes: _,
            source: sa,
            unknown: ua,
        } = &a.function_codes;
        let crate::model::FunctionCodes {
            codes: _,
            source: sb,
            unknown: ub,
        } = &b.function_codes;
        if ua != ub {
            c.push(
                ChangeKind::DocumentationChanged,
                s,
                "function codes: not printed",
                (ua.clone(), sa.clone()),
                (ub.clone(), sb.clone()),
                HEAD,
            );
        } else if sa != sb {
            c.push(
                ChangeKind::CitationChanged,
                s,
                "function codes",
                (None, sa.clone()),
                (None, sb.clone()),
                HEAD,
            );
        }
    }
    for (what, la, lb, modbus) in [
        (
            "max_read",
            &a.max_read,
            &b.max_read,
            drivemap_core::stated::MODBUS_MAX_READ,
        ),
        (
            "max_write",
            &a.max_write,
            &b.max_write,
            drivemap_core::stated::MODBUS_MAX_WRITE,
        ),
    ] {
        let crate::model::Limit {
            value: x,
            source: xs,
            unknown: xu,
        } = la;
        let crate::model::Limit {
            value: y,
            source: ys,
            unknown: yu,
        } = lb;
        // The working numbers: an unprinted limit is the Modbus one.
        let (x, y) = (x.unwrap_or(modbus), y.unwrap_or(modbus));
        if x != y && xu != yu {
            c.push(
                ChangeKind::DocumentationChanged,
                s,
                &format!("{what}: not printed"),
                (xu.clone(), xs.clone()),
                (yu.clone(), ys.clone()),
                HEAD,
            );
        }
        if x == y {
            if xu != yu {
                c.push(
                    ChangeKind::DocumentationChanged,
                    s,
                    &format!("{what}: not printed"),
                    (xu.clone(), xs.clone()),
                    (yu.clone(), ys.clone()),
                    HEAD,
                );
            } else if xs != ys {
                c.push(
                    ChangeKind::CitationChanged,
                    s,
                    what,
                    (None, xs.clone()),
                    (None, ys.clone()),
                    HEAD,
                );
            }
        }
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
                (Some(x.to_string()), xs.clone().or(src.0.clone())),
                (Some(y.to_string()), ys.clone().or(src.1.clone())),
                HEAD,
            );
        }
    }

    let (sa, sb) = (&a.slave_address, &b.slave_address);
    let ((a_min, a_max), (b_min, b_max)) = (sa.range(), sb.range());
    if a_min != b_min || a_max != b_max {
        let kind = if b_min > a_min || b_max < a_max {
            ChangeKind::SlaveRangeNarrowed
        } else {
            ChangeKind::SlaveRangeWidened
        };
        c.push(
            kind,
            s,
            "slave address",
            (Some(format!("{a_min} ..= {a_max}")), sa.source.clone()),
            (Some(format!("{b_min} ..= {b_max}")), sb.source.clone()),
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

    not_printed(c, a, b);
    broadcast(c, old, new);
    exceptions(c, a, b);
    commands(c, a, b);

    let offsets = |p: &crate::model::Protocol| {
        p.addressing
            .as_ref()
            .map(|x| (x.rtu_offset, x.tcp_offset))
            .unwrap_or((0, 0))
    };
    let asrc = |p: &crate::model::Protocol| p.addressing.as_ref().map(|x| x.source.clone());
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
        let src = |p: &crate::model::Protocol| p.timing.as_ref().and_then(|t| t.source.clone());
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
        let src = |p: &crate::model::Protocol| p.serial.as_ref().map(|t| t.source.clone());
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
        let src = |p: &crate::model::Protocol| p.eeprom.as_ref().map(|t| t.source.clone());
        let text = |p: &crate::model::Protocol| {
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
    if a.notes != b.notes || a.indirect != b.indirect {
        c.push(
            ChangeKind::DocumentationChanged,
            s,
            "notes or indirect citation",
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
    let text = |x: &Option<crate::model::Broadcast>| {
        x.as_ref().map(|x| {
            if let Some(why) = &x.unknown {
                return describe::broadcast_not_printed(why);
            }
            let mut t = describe::functions(&x.functions);
            if !x.registers.is_empty() {
                t += &format!(" to {}", x.registers.join(", "));
            }
            t
        })
    };
    let src = |x: &Option<crate::model::Broadcast>| x.as_ref().map(|x| x.source.clone());
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

fn exceptions(c: &mut Collector, a: &crate::model::Protocol, b: &crate::model::Protocol) {
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

fn commands(c: &mut Collector, a: &crate::model::Protocol, b: &crate::model::Protocol) {
    let s = "protocol";
    let text = |x: &crate::model::Command| {
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

/// A protocol fact that became not printed (`unknown:`), printed again, or whose reason
/// changed: `slave_address: not printed`, the reasons as the old and new values. (Function
/// codes, limits and broadcast report theirs where their figures are compared.) A change of
/// the working figure it brings (a slave range 1 ..= 32 becoming the Modbus 1 ..= 247) is
/// reported on its own.
fn not_printed(c: &mut Collector, a: &crate::model::Protocol, b: &crate::model::Protocol) {
    use drivemap_core::stated::ProtocolFact as F;
    let s = "protocol";
    for fact in [
        F::SlaveAddress,
        F::Exceptions,
        F::Serial,
        F::Timing,
        F::FrameGap,
        F::InterCharTimeout,
        F::ResponseTime,
        F::RequestGap,
    ] {
        let (x, y) = (
            drivemap_map::stated::why(a, fact),
            drivemap_map::stated::why(b, fact),
        );
        if x.as_ref().map(|u| &u.why) != y.as_ref().map(|u| &u.why) {
            let side = |u: Option<drivemap_map::stated::Unprinted>| match u {
                Some(u) => (Some(u.why), u.source),
                None => (Some("printed".to_owned()), None),
            };
            c.push(
                ChangeKind::DocumentationChanged,
                s,
                &format!("{}: not printed", fact.key()),
                side(x),
                side(y),
                HEAD,
            );
        } else if fact == F::Exceptions
            && let (Some(x), Some(y)) = (x, y)
            && x.source != y.source
        {
            // The other facts' citations are compared with their figures.
            c.push(
                ChangeKind::CitationChanged,
                s,
                "exceptions: not printed",
                (None, x.source),
                (None, y.source),
                HEAD,
            );
        }
    }
}
