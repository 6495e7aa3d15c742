//! Printing a diff: plain text for a terminal (optionally coloured) or Markdown for a review.

use std::fmt::Write as _;

use super::{Change, ChangeKind, DriveDiff, Severity, classify};

/// Output format of `drivemap diff`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Plain text for a terminal.
    Text,
    /// Markdown, for pasting into a review.
    Md,
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

fn cite(s: Option<&str>) -> String {
    s.map(|s| format!("`{s}`")).unwrap_or_else(|| "—".into())
}

/// Markdown: a section per drive with a table of changes.
pub fn markdown(diffs: &[DriveDiff]) -> String {
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
                cite(c.old_source.as_deref()),
                cite(c.new_source.as_deref()),
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
        Format::Md => {
            let _ = writeln!(out, "| Change | Severity | Why |\n|---|---|---|");
            for &k in ChangeKind::ALL {
                let (sev, why) = classify(k);
                let _ = writeln!(out, "| {} | {sev} | {why} |", k.label());
            }
        }
    }
    out
}
