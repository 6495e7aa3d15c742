//! Printing a diff: plain text for a terminal (optionally coloured), Markdown for a review
//! (quoting the manual line each side cites), or GitHub workflow annotations on the map's lines.

use std::fmt::Write as _;

use crate::review::Manuals;

use super::{Change, ChangeKind, DriveDiff, Severity, classify};

/// Output format of `drivemap diff`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Plain text for a terminal.
    Text,
    /// Markdown, for pasting into a review; quotes the manual line each side cites.
    Md,
    /// GitHub workflow annotations on the changed lines of the map (`::error` for breaking
    /// changes, `::warning` for the rest).
    Github,
    /// JSON for tools: every change with its kind, severity, both sides, both citations and
    /// the manual lines they point at.
    Json,
}

fn heading(d: &DriveDiff) -> String {
    if d.changes.is_empty() {
        format!("{}: no changes", d.drive)
    } else {
        format!(
            "{}: {} breaking, {} compatible",
            d.drive,
            d.breaking(),
            d.compatible()
        )
    }
}

/// The change's label, and the part it concerns unless the label already says it.
fn change(c: &Change) -> String {
    let label = c.kind.label();
    if c.what.is_empty() || label.contains(c.what.as_str()) {
        label.to_owned()
    } else {
        format!("{label} — {}", c.what)
    }
}

fn title(c: &Change) -> String {
    format!("{}: {}", c.subject, change(c))
}

/// Terminal text. `color` adds ANSI colours to the severities.
pub fn text(diffs: &[DriveDiff], color: bool) -> String {
    let mut out = String::new();
    for d in diffs {
        let _ = writeln!(out, "{}", heading(d));
        for c in &d.changes {
            let sev = format!("{:<10}", c.severity().to_string());
            let sev = match (color, c.severity()) {
                (false, _) => sev,
                (true, Severity::Breaking) => format!("\x1b[1;31m{sev}\x1b[0m"),
                (true, Severity::Compatible) => format!("\x1b[32m{sev}\x1b[0m"),
            };
            let _ = writeln!(out, "  {sev}  {}", title(c));
            let pad = " ".repeat(14);
            if c.old.is_some() || c.new.is_some() {
                let _ = writeln!(
                    out,
                    "{pad}{} → {}",
                    c.old.as_deref().unwrap_or("(none)"),
                    c.new.as_deref().unwrap_or("(none)")
                );
            }
            let _ = writeln!(
                out,
                "{pad}old: {} · new: {}",
                c.old_source.as_deref().unwrap_or("—"),
                c.new_source.as_deref().unwrap_or("—")
            );
            let _ = writeln!(out, "{pad}why: {}", c.reason());
        }
    }
    if diffs.len() > 1 {
        let b: usize = diffs.iter().map(DriveDiff::breaking).sum();
        let k: usize = diffs.iter().map(DriveDiff::compatible).sum();
        let _ = writeln!(
            out,
            "{} maps compared: {b} breaking, {k} compatible",
            diffs.len()
        );
    }
    out
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|")
        .replace('<', "&lt;")
        .replace(['\n', '\r'], " ")
}

fn cite(s: Option<&str>, manuals: Option<&Manuals>) -> String {
    match s {
        None => "—".into(),
        Some(s) => match manuals.and_then(|m| m.quote(s)) {
            Some(q) => format!("`{s}`: “{}”", cell(&q)),
            None => format!("`{s}`"),
        },
    }
}

/// Markdown: a section per drive with a table of changes; each citation is followed by the
/// manual line it points at when the manuals are at hand.
pub fn markdown(diffs: &[DriveDiff], manuals: Option<&Manuals>) -> String {
    let mut out = String::new();
    for d in diffs {
        let _ = writeln!(out, "### {}\n", heading(d));
        if d.changes.is_empty() {
            continue;
        }
        let _ = writeln!(
            out,
            "| | Subject | Change | Old | New | Old citation | New citation | Why |\n\
             |---|---|---|---|---|---|---|---|"
        );
        for c in &d.changes {
            let sev = match c.severity() {
                Severity::Breaking => "**breaking**",
                Severity::Compatible => "compatible",
            };
            let change = cell(&change(c));
            let _ = writeln!(
                out,
                "| {sev} | `{}` | {change} | {} | {} | {} | {} | {} |",
                c.subject,
                c.old.as_deref().map(cell).unwrap_or_else(|| "—".into()),
                c.new.as_deref().map(cell).unwrap_or_else(|| "—".into()),
                cite(c.old_source.as_deref(), manuals),
                cite(c.new_source.as_deref(), manuals),
                c.reason()
            );
        }
        out.push('\n');
    }
    if diffs.len() > 1 {
        let b: usize = diffs.iter().map(DriveDiff::breaking).sum();
        let k: usize = diffs.iter().map(DriveDiff::compatible).sum();
        let _ = writeln!(
            out,
            "{} maps compared: {b} breaking, {k} compatible.",
            diffs.len()
        );
    }
    out
}

/// The classification table: every change kind, its severity and why.
pub fn kinds(format: Format) -> String {
    let mut out = String::new();
    match format {
        Format::Text => {
            let w = ChangeKind::ALL
                .iter()
                .map(|k| k.label().chars().count())
                .max()
                .unwrap_or(0);
            for &k in ChangeKind::ALL {
                let (sev, why) = classify(k);
                let label = k.label();
                let pad = " ".repeat(w - label.chars().count());
                let _ = writeln!(out, "{label}{pad}  {:<10}  {why}", sev.to_string());
            }
        }
        Format::Json => {
            let kinds: Vec<serde_json::Value> = ChangeKind::ALL
                .iter()
                .map(|&k| {
                    let (sev, why) = classify(k);
                    serde_json::json!({"kind": k.label(), "severity": sev.to_string(), "why": why})
                })
                .collect();
            out = serde_json::to_string_pretty(&kinds).unwrap_or_default();
            out.push('\n');
        }
        Format::Md | Format::Github => {
            let _ = writeln!(out, "| Change | Severity | Why |\n|---|---|---|");
            for &k in ChangeKind::ALL {
                let (sev, why) = classify(k);
                let _ = writeln!(out, "| {} | {sev} | {why} |", k.label());
            }
        }
    }
    out
}

/// Escapes an annotation's message (`%`, CR, LF).
fn escape_data(s: &str) -> String {
    s.replace('%', "%25")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

/// Escapes an annotation's property (`%`, CR, LF, `:`, `,`).
fn escape_property(s: &str) -> String {
    escape_data(s).replace(':', "%3A").replace(',', "%2C")
}

/// GitHub workflow annotations: one per change, on its line of the map; the message gives the
/// change, both sides, why, and the manual line each side cites.
pub fn github(diffs: &[DriveDiff], manuals: Option<&Manuals>) -> String {
    let mut out = String::new();
    for d in diffs {
        for c in &d.changes {
            let level = match c.severity() {
                Severity::Breaking => "error",
                Severity::Compatible => "warning",
            };
            let mut props = Vec::new();
            if let Some(at) = &c.at {
                props.push(format!("file={}", escape_property(&at.file)));
                props.push(format!("line={}", at.line));
            }
            props.push(format!(
                "title={}",
                escape_property(&format!("drivemap diff: {} {}", d.drive, c.severity()))
            ));
            let mut message = title(c);
            if c.old.is_some() || c.new.is_some() {
                let _ = write!(
                    message,
                    ": {} → {}",
                    c.old.as_deref().unwrap_or("(none)"),
                    c.new.as_deref().unwrap_or("(none)")
                );
            }
            let _ = write!(message, "\nwhy: {}", c.reason());
            for (side, source) in [("old", &c.old_source), ("new", &c.new_source)] {
                if let Some(s) = source {
                    match manuals.and_then(|m| m.quote(s)) {
                        Some(q) => {
                            let _ = write!(message, "\n{side}: {s}: “{q}”");
                        }
                        None => {
                            let _ = write!(message, "\n{side}: {s}");
                        }
                    }
                }
            }
            let _ = writeln!(
                out,
                "::{level} {}::{}",
                props.join(","),
                escape_data(&message)
            );
        }
    }
    out
}

/// JSON: `{"drives": [{"drive", "breaking", "compatible", "changes": [...]}], "breaking",
/// "compatible"}`; each change gives `severity`, `kind` (the label of `--kinds`), `subject`,
/// `what`, `old`, `new`, `old_source`, `new_source`, `old_quote` and `new_quote` (the manual
/// lines cited, when the manuals are at hand), `why`, and `at` (`file`, `line`, `column` in
/// the new map).
pub fn json(diffs: &[DriveDiff], manuals: Option<&Manuals>) -> String {
    let quote = |s: &Option<String>| {
        s.as_deref()
            .and_then(|s| manuals.and_then(|m| m.quote(s)))
            .map_or(serde_json::Value::Null, serde_json::Value::from)
    };
    let drives: Vec<serde_json::Value> = diffs
        .iter()
        .map(|d| {
            let changes: Vec<serde_json::Value> = d
                .changes
                .iter()
                .map(|c| {
                    serde_json::json!({
                        "severity": c.severity().to_string(),
                        "kind": c.kind.label(),
                        "subject": c.subject,
                        "what": c.what,
                        "old": c.old,
                        "new": c.new,
                        "old_source": c.old_source,
                        "new_source": c.new_source,
                        "old_quote": quote(&c.old_source),
                        "new_quote": quote(&c.new_source),
                        "why": c.reason(),
                        "at": c.at.as_ref().map(|at| serde_json::json!({
                            "file": at.file.as_ref(),
                            "line": at.line,
                            "column": at.col,
                        })),
                    })
                })
                .collect();
            serde_json::json!({
                "drive": d.drive,
                "breaking": d.breaking(),
                "compatible": d.compatible(),
                "changes": changes,
            })
        })
        .collect();
    let doc = serde_json::json!({
        "drives": drives,
        "breaking": diffs.iter().map(DriveDiff::breaking).sum::<usize>(),
        "compatible": diffs.iter().map(DriveDiff::compatible).sum::<usize>(),
    });
    let mut out = serde_json::to_string_pretty(&doc).unwrap_or_default();
    out.push('\n');
    out
}
