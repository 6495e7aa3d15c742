//! Differences outside the registers: drive metadata and variant axes (the protocol profile is
//! `profile.rs`'s).

use drivemap_map::Map;

use super::{ChangeKind, Collector, HEAD, same};

pub(super) fn meta(c: &mut Collector, old: &Map, new: &Map) {
    let (a, b) = (old.meta(), new.meta());
    let id = &b.id;
    let drivemap_map::facts::DriveMeta {
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
        let text = |m: &drivemap_map::facts::DriveMeta| {
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

pub(super) fn variants(c: &mut Collector, old: &Map, new: &Map) {
    let subject = "variants";
    for a in old.variants() {
        let Some(b) = new.variants().iter().find(|b| b.id == a.id) else {
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
        let drivemap_map::facts::VariantAxis {
            id: _,
            name: _,
            options: _,
        } = b;
        let mut docs = Vec::new();
        if a.name != b.name {
            docs.push("name".to_owned());
        }
        for o in &a.options {
            let drivemap_map::facts::VariantOption {
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
        let order = |x: &drivemap_map::facts::VariantAxis| {
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
        if let (Some(x), Some(y)) = (a.options.first(), b.options.first())
            && x.id != y.id
        {
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
    for b in new.variants() {
        if !old.variants().iter().any(|a| a.id == b.id) {
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
