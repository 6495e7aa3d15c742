//! Every register cites its row in a manual: `file:line` for a text manual, `<manual id>:p<page>`
//! for a manual with no text at hand; every citation anywhere names one of the map's manuals of
//! the matching kind and, when the text manuals are at hand, a line inside the file.

use crate::citations::{PlaceKind, Reason, citation_places};
use crate::diagnostic::Diagnostic;
use crate::examples::parse_range_citation;
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
    if let Some(&lines) = ctx.manual_lines.get(file)
        && line > lines
    {
        out.push(drive.error(
            &path,
            register,
            format!("citation `{source}` points past the end of `{file}` ({lines} lines)"),
        ));
    }
}

/// An example frame's citation: one line or a line range (`file:first-last`) of a declared text
/// manual, inside the file.
fn cite_range(
    drive: &Drive,
    ctx: &Context,
    out: &mut Vec<Diagnostic>,
    id: &str,
    source: &str,
    path: &Path,
) {
    let message = match parse_range_citation(source) {
        None => format!("citation `{source}` is not `file:line` or `file:first-last`"),
        Some((file, _, _)) if !drive.meta.text_manuals().any(|m| m == file) => format!(
            "citation `{source}` names `{file}`, which is not a text manual of `drive.manuals`"
        ),
        Some((file, _, last)) => match ctx.manual_lines.get(file) {
            Some(&lines) if last > lines => {
                format!("citation `{source}`: {file} has {lines} lines")
            }
            _ => return,
        },
    };
    out.push(drive.error(path, None, format!("example `{id}`: {message}")));
}

/// `indirect: <reason>` marks a citation as deliberately indirect: it needs the citation it
/// qualifies and a reason.
fn indirect(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    reason: Option<&str>,
    source: Option<&str>,
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

/// How a kind of place is checked here: the form of its citation, and whether a finding about
/// its `indirect` key names the register (it does for a register's own row, values and
/// fields).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Form {
    /// `file:line` or `<manual id>:p<page>` ([`cite`]).
    Line,
    /// `file:line` or `file:first-last` of a text manual (an example frame, [`cite_range`]).
    Range,
}

fn rules(kind: &PlaceKind<'_>) -> (Form, bool) {
    use PlaceKind as K;
    match kind {
        K::Example(_) => (Form::Range, false),
        K::Register | K::Value(_) | K::ReadValue(_) | K::Field(_) | K::FieldValue { .. } => {
            (Form::Line, true)
        }
        _ => (Form::Line, false),
    }
}

/// Every citation place ([`citation_places`]): a required one is present, each citation names
/// a manual of the map in the right form (and a line inside it), an `indirect` key has a reason
/// and a citation to qualify.
pub(super) fn check(drive: &Drive, ctx: &Context, out: &mut Vec<Diagnostic>) {
    if drive.meta.manuals.is_empty() {
        out.push(drive.error(
            &Path::root().key("drive").key("manuals"),
            None,
            "a map must name the manuals it was transcribed from",
        ));
    }
    for place in citation_places(drive) {
        let (form, names_register) = rules(&place.kind);
        let register = place.register_name;
        match (place.source, form) {
            (None, _) if place.required => out.push(drive.error(
                &place.item_path(),
                register,
                "missing citation: add `source: <manual file>:<line>` pointing at the register's row",
            )),
            (Some(s), Form::Line) => cite(drive, ctx, out, s, place.path.clone(), register),
            (Some(s), Form::Range) => {
                if let PlaceKind::Example(i) = place.kind {
                    cite_range(drive, ctx, out, &drive.examples[i].id, s, &place.path);
                }
            }
            _ => {}
        }
        if let Reason::Indirect(reason) = place.reason {
            indirect(
                drive,
                out,
                reason,
                place.source,
                place.item_path().key("indirect"),
                register.filter(|_| names_register),
            );
        }
    }
}
