//! The reference's "Indexed access" section: each index/value register pair (`indexed:`) with
//! the entries the manual lists (index, id, name, scale, range, access, citation) and the
//! `unknown` reason when the list is missing or incomplete.

use std::fmt::Write as _;

use drivemap_core::register::Access;
use drivemap_map::Map;

use super::{addr, cell, cite, code};

pub(super) fn section(out: &mut String, drive: &Map) {
    let pairs: Vec<_> = drive
        .registers()
        .filter_map(|r| Some((r, r.indexed()?)))
        .collect();
    if pairs.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Indexed access\n");
    for (r, ix) in pairs {
        let index = drive.register(&ix.by);
        let index_at = index
            .map(|i| format!(" ({})", addr(drive, i.address())))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "### {} {} — {}\n\nWrite the entry's index to {}{index_at}, then read or write {} ({}): the client's `read_entry`/`write_entry` do both in one call. Source: {}.\n",
            addr(drive, r.address()),
            code(r.id()),
            cell(r.name()),
            code(&ix.by),
            code(r.id()),
            addr(drive, r.address()),
            cite(Some(&ix.source)),
        );
        if !ix.entries.is_empty() {
            let _ = writeln!(
                out,
                "| Index | Entry | Name | Unit | Scale | Range | Access | Source |\n|---|---|---|---|---|---|---|---|"
            );
            for e in &ix.entries {
                let range =
                    drivemap_map::describe::range(e.min, e.max, e.unit.as_deref().unwrap_or(""));
                let access = match e.access.unwrap_or(r.plan().info.access) {
                    Access::Read => "R",
                    Access::Write => "W",
                    Access::ReadWrite => "R/W",
                };
                let _ = writeln!(
                    out,
                    "| {} | {} | {} | {} | {} | {} | {access} | {} |",
                    e.index,
                    code(&e.id),
                    cell(&e.name),
                    cell(e.unit.as_deref().unwrap_or("")),
                    e.scale.unwrap_or(1.0),
                    cell(&range),
                    cite(Some(&e.source)),
                );
            }
            let _ = writeln!(out);
        }
        if let Some(why) = &ix.unknown {
            let what = if ix.entries.is_empty() {
                "Entries not printed in the manual"
            } else {
                "Entries not listed"
            };
            let _ = writeln!(out, "{what}: {}\n", cell(why));
        }
    }
}
