//! Every register cites its row in a manual: `file:line` for a text manual, `<manual id>:p<page>`
//! for a manual with no text at hand; every citation anywhere names one of the map's manuals of
//! the matching kind and, when the text manuals are at hand, a line inside the file.

use crate::diagnostic::Diagnostic;
use crate::hints::closest;
use crate::ir::Drive;
use crate::source::Path;
use crate::validate::Context;

/// Splits `file:line` (a line of a text manual).
pub fn parse_citation(s: &str) -> Option<(&str, usize)> {
    let (file, line) = s.rsplit_once(':')?;
    let line: usize = line.trim().parse().ok()?;
    (!file.is_empty() && line > 0).then_some((file, line))
}

/// Splits `<manual id>:p<page>` (a page of a manual with no text at hand).
pub fn parse_page_citation(s: &str) -> Option<(&str, u32)> {
    let (manual, page) = s.rsplit_once(':')?;
    let page = page.trim().strip_prefix('p')?;
    if !page.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let page: u32 = page.parse().ok()?;
    (!manual.is_empty() && page > 0).then_some((manual, page))
}

pub(super) fn cite(
    drive: &Drive,
    ctx: &Context,
    out: &mut Vec<Diagnostic>,
    source: &str,
    path: Path,
    register: Option<&str>,
) {
    let manuals = &drive.meta.manuals;
    let unlisted = |name: &str| {
        let hint = closest(name, manuals.iter().map(|m| m.name()))
            .map(|c| format!(" (did you mean `{c}`?)"))
            .unwrap_or_default();
        format!("citation `{source}` names `{name}`, which is not among `drive.manuals`{hint}")
    };
    if let Some((id, _)) = parse_page_citation(source) {
        let message = match manuals.iter().find(|m| m.name() == id) {
            Some(m) if m.text_file().is_some() => format!(
                "citation `{source}` cites a page of `{id}`, a text manual: cite its line, `{id}:<line>`"
            ),
            Some(_) => return,
            None => unlisted(id),
        };
        out.push(drive.error(&path, register, message));
        return;
    }
    let Some((file, line)) = parse_citation(source) else {
        out.push(drive.error(
            &path,
            register,
            format!(
                "citation `{source}` is neither `file:line` (a text manual) nor `<manual id>:p<page>` (a manual cited by page)"
            ),
        ));
        return;
    };
    match manuals.iter().find(|m| m.name() == file) {
        Some(m) if m.text_file().is_none() => {
            out.push(drive.error(
                &path,
                register,
                format!(
                    "citation `{source}` cites a line of `{file}`, a manual with no text at hand: cite its page, `{file}:p<page>`"
                ),
            ));
            return;
        }
        Some(_) => {}
        None => {
            out.push(drive.error(&path, register, unlisted(file)));
            return;
        }
    }
    if let Some(&lines) = ctx.manual_lines.get(file) {
        if line > lines {
            out.push(drive.error(
                &path,
                register,
                format!("citation `{source}` points past the end of `{file}` ({lines} lines)"),
            ));
        }
    }
}

/// `indirect: <reason>` marks a citation as deliberately indirect: it needs the citation it
/// qualifies and a reason.
fn indirect(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    reason: &Option<String>,
    source: &Option<String>,
    path: Path,
    register: Option<&str>,
) {
    match (reason, source) {
        (Some(r), _) if r.trim().is_empty() => out.push(drive.error(
            &path,
            register,
            "`indirect` needs a reason: why the cited line does not show the item itself",
        )),
        (Some(_), None) => out.push(drive.error(
            &path,
            register,
            "`indirect` qualifies a citation, but there is no `source`",
        )),
        _ => {}
    }
}

fn opt(
    drive: &Drive,
    ctx: &Context,
    out: &mut Vec<Diagnostic>,
    source: &Option<String>,
    path: Path,
    register: Option<&str>,
) {
    if let Some(s) = source {
        cite(drive, ctx, out, s, path, register);
    }
}

pub fn check(drive: &Drive, ctx: &Context, out: &mut Vec<Diagnostic>) {
    if drive.meta.manuals.is_empty() {
        out.push(drive.error(
            &Path::root().key("drive").key("manuals"),
            None,
            "a map must name the manuals it was transcribed from",
        ));
    }
    let proto = Path::root().key("protocol");
    let p = &drive.protocol;
    opt(drive, ctx, out, &p.source, proto.key("source"), None);
    opt(
        drive,
        ctx,
        out,
        &p.slave_address.source,
        proto.key("slave_address").key("source"),
        None,
    );
    if let Some(b) = &p.broadcast {
        cite(
            drive,
            ctx,
            out,
            &b.source,
            proto.key("broadcast").key("source"),
            None,
        );
    }
    for (i, e) in p.exceptions.iter().enumerate() {
        cite(
            drive,
            ctx,
            out,
            &e.source,
            proto.key("exceptions").index(i).key("source"),
            None,
        );
    }
    for (i, c) in p.commands.iter().enumerate() {
        cite(
            drive,
            ctx,
            out,
            &c.source,
            proto.key("commands").index(i).key("source"),
            None,
        );
    }
    if let Some(e) = &p.eeprom {
        cite(
            drive,
            ctx,
            out,
            &e.source,
            proto.key("eeprom").key("source"),
            None,
        );
    }
    if let Some(a) = &p.addressing {
        cite(
            drive,
            ctx,
            out,
            &a.source,
            proto.key("addressing").key("source"),
            None,
        );
    }
    if let Some(s) = &p.serial {
        cite(
            drive,
            ctx,
            out,
            &s.source,
            proto.key("serial").key("source"),
            None,
        );
        if let Some(f) = &s.formats {
            let fp = proto.key("serial").key("formats");
            cite(drive, ctx, out, &f.source, fp.key("source"), None);
            for (i, c) in f.cases.iter().enumerate() {
                opt(
                    drive,
                    ctx,
                    out,
                    &c.source,
                    fp.key("cases").index(i).key("source"),
                    None,
                );
            }
        }
    }
    opt(
        drive,
        ctx,
        out,
        &p.function_codes.source,
        proto.key("function_codes").key("source"),
        None,
    );
    for (name, limit) in [("max_read", &p.max_read), ("max_write", &p.max_write)] {
        opt(
            drive,
            ctx,
            out,
            &limit.source,
            proto.key(name).key("source"),
            None,
        );
    }
    if let Some(t) = &p.timing {
        let tp = proto.key("timing");
        opt(drive, ctx, out, &t.source, tp.key("source"), None);
        if let Some(i) = &t.frame_gap {
            opt(
                drive,
                ctx,
                out,
                &i.source,
                tp.key("frame_gap").key("source"),
                None,
            );
        }
        if let Some(i) = &t.inter_char_timeout {
            opt(
                drive,
                ctx,
                out,
                &i.source,
                tp.key("inter_char_timeout").key("source"),
                None,
            );
        }
        if let Some(i) = &t.response_time {
            opt(
                drive,
                ctx,
                out,
                &i.source,
                tp.key("response_time").key("source"),
                None,
            );
        }
    }
    // `indirect` on roles, protocol items, readings of conflicts and gaps (review reads their
    // citations by content, `review::others`).
    for o in crate::others::other_citations(drive) {
        if o.indirect_key {
            let mut at = o.path.clone();
            at.0.pop();
            indirect(drive, out, &o.indirect, &o.source, at.key("indirect"), None);
        }
    }
    for (ai, axis) in drive.variants.iter().enumerate() {
        for (oi, o) in axis.options.iter().enumerate() {
            opt(
                drive,
                ctx,
                out,
                &o.source,
                Path::root()
                    .key("variants")
                    .index(ai)
                    .key("options")
                    .index(oi)
                    .key("source"),
                None,
            );
        }
    }
    for g in &drive.groups {
        opt(drive, ctx, out, &g.source, g.path.key("source"), None);
    }
    for (id, places) in &drive.roles {
        for (i, p) in places.iter().enumerate() {
            let path = Path::root().key("roles").key(id).index(i).key("source");
            opt(drive, ctx, out, &p.source, path, p.register.as_deref());
        }
    }
    for (i, g) in drive.gaps.iter().enumerate() {
        cite(
            drive,
            ctx,
            out,
            &g.source,
            Path::root().key("gaps").index(i).key("source"),
            None,
        );
    }
    for (i, r) in drive.removed.iter().enumerate() {
        cite(
            drive,
            ctx,
            out,
            &r.source,
            Path::root().key("removed").index(i).key("source"),
            Some(&r.id),
        );
    }
    for (ci, c) in drive.conflicts.iter().enumerate() {
        for (ri, reading) in c.readings.iter().enumerate() {
            let rp = Path::root()
                .key("conflicts")
                .index(ci)
                .key("readings")
                .index(ri)
                .key("source");
            cite(drive, ctx, out, &reading.source, rp, None);
        }
    }
    for r in &drive.registers {
        let rid = Some(r.id());
        match &r.def.source {
            None => out.push(drive.error(
                &r.path,
                rid,
                "missing citation: add `source: <manual file>:<line>` pointing at the register's row",
            )),
            Some(s) => cite(drive, ctx, out, s, r.key_path("source"), rid),
        }
        indirect(
            drive,
            out,
            &r.def.indirect,
            &r.def.source,
            r.key_path("indirect"),
            rid,
        );
        if let Some(pair) = &r.def.pair {
            let path = r.key_path("pair").key("source");
            opt(drive, ctx, out, &pair.source, path, rid);
        }
        for (fi, f) in r.def.fields.iter().enumerate() {
            let fp = r.key_path("fields").index(fi);
            opt(drive, ctx, out, &f.source, fp.key("source"), rid);
            indirect(drive, out, &f.indirect, &f.source, fp.key("indirect"), rid);
            for (vi, v) in f.values.iter().enumerate() {
                let vp = fp.key("values").index(vi);
                indirect(drive, out, &v.indirect, &v.source, vp.key("indirect"), rid);
                opt(
                    drive,
                    ctx,
                    out,
                    &v.source,
                    fp.key("values").index(vi).key("source"),
                    rid,
                );
            }
        }
        for key in ["values", "read_values"] {
            let list = match key {
                "values" => &r.def.values,
                _ => &r.def.read_values,
            };
            for (vi, v) in list.iter().enumerate() {
                let vp = r.key_path(key).index(vi);
                indirect(drive, out, &v.indirect, &v.source, vp.key("indirect"), rid);
                opt(drive, ctx, out, &v.source, vp.key("source"), rid);
            }
        }
        if let Some((rule, path)) = &r.repeat_needs_change {
            cite(drive, ctx, out, &rule.source, path.key("source"), rid);
        }
        if let Some((f, path)) = &r.function_codes {
            cite(drive, ctx, out, &f.source, path.key("source"), rid);
        }
        if let Some(limit) = &r.def.max_relative {
            cite(
                drive,
                ctx,
                out,
                &limit.source,
                r.key_path("max_relative").key("source"),
                rid,
            );
        }
        for (k, o) in &r.def.by_variant {
            opt(
                drive,
                ctx,
                out,
                &o.source,
                r.key_path("by_variant").key(k).key("source"),
                rid,
            );
        }
        for (ai, a) in r.def.address_alternatives.iter().enumerate() {
            cite(
                drive,
                ctx,
                out,
                &a.source,
                r.key_path("address_alternatives").index(ai).key("source"),
                rid,
            );
        }
        if let Some(crate::model::Scale::Selected(sel)) = &r.def.scale {
            for (ci, c) in sel.cases.iter().enumerate() {
                opt(
                    drive,
                    ctx,
                    out,
                    &c.source,
                    r.key_path("scale").key("cases").index(ci).key("source"),
                    rid,
                );
            }
        }
        for (ci, c) in r.def.conflicts.iter().enumerate() {
            for (ri, reading) in c.readings.iter().enumerate() {
                let rp = r
                    .key_path("conflicts")
                    .index(ci)
                    .key("readings")
                    .index(ri)
                    .key("source");
                cite(drive, ctx, out, &reading.source, rp, rid);
            }
        }
    }
}
