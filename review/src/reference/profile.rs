//! The reference's "Command profile" section: the control-word state machine of a drive run
//! through one (`profile:`), resolved with the standard it names — the control and status
//! registers, each state by status-word mask and value, each transition by control word with
//! the states it is taken from, the paths of run, stop, coast, quick stop and fault reset — each
//! with the manual line the map cites.

use std::fmt::Write as _;

use drivemap_map::Map;

use super::{cell, cite, code};

pub(super) fn section(out: &mut String, drive: &Map) {
    let Some(spec) = drive.profile() else {
        return;
    };
    let p = spec.resolved();
    let standard = match (&p.standard, &p.name) {
        (Some(s), Some(n)) => format!("{} ({})", code(s), cell(n)),
        (Some(s), None) => code(s),
        _ => "the map's own".into(),
    };
    let _ = writeln!(
        out,
        "## Command profile\n\nThe drive runs through a control-word state machine: {standard}. \
         The drive trait walks it (run, stop, coast, quick stop, fault reset as paths below); \
         the simulator follows it. Control word {}, status word {}. Source: {}.\n",
        code(p.control.as_deref().unwrap_or("?")),
        code(p.status.as_deref().unwrap_or("?")),
        cite(p.source.as_deref()),
    );
    if let Some(spec) = &p.spec {
        let _ = writeln!(out, "Specification: {}.\n", cell(spec));
    }
    if let Some(on) = &p.power_on {
        let _ = writeln!(
            out,
            "At power-on: {}. Source: {}.\n",
            code(&on.state),
            cite(on.source.as_deref())
        );
    }
    let _ = writeln!(out, "| State | Mask | Value | Source |\n|---|---|---|---|");
    for (id, s) in &p.states {
        let _ = writeln!(
            out,
            "| {} | {:04X}h | {:04X}h | {} |",
            code(id),
            s.mask.map_or(0, |w| w.0),
            s.value.map_or(0, |w| w.0),
            cite(s.source.as_deref())
        );
    }
    let _ = writeln!(
        out,
        "\n| Transition | Word | Kept bits | Edge bits | From | To | Within | Source |\n|---|---|---|---|---|---|---|---|"
    );
    for (id, t) in &p.transitions {
        let list = |v: &[String]| v.iter().map(|s| code(s)).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            out,
            "| {} | {:04X}h | {:04X}h | {:04X}h | {} | {} | {} ms | {} |",
            code(id),
            t.word.map_or(0, |w| w.0),
            t.keep.map_or(0, |w| w.0),
            t.edge.map_or(0, |w| w.0),
            list(t.from.as_deref().unwrap_or_default()),
            t.to.as_deref().map(code).unwrap_or_default(),
            t.limit_ms.unwrap_or(0),
            cite(t.source.as_deref())
        );
    }
    let _ = writeln!(out, "\n| Path | Via | Ends in |\n|---|---|---|");
    for (id, path) in &p.paths {
        let list = |v: &[String]| v.iter().map(|s| code(s)).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            out,
            "| {} | {} | {} |",
            code(id),
            list(&path.via),
            list(&path.to)
        );
    }
    out.push('\n');
}
