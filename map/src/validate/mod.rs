//! Validation: one concern per file, every finding located, all findings of a map at once.
//!
//! Each pass reads the [`Drive`] and appends [`Diagnostic`]s; none stops the others, so a user
//! fixing a map sees everything wrong with it in one run.

use std::collections::HashMap;
use std::path::Path;

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;

mod access_consistent;
mod addresses_non_overlapping;
mod bit_fields_valid;
mod bits_valid;
mod citations_present;
mod conflicts_recorded;
mod enum_codes_fit;
mod examples_valid;
mod function_codes_valid;
mod identifiers_unique;
mod identifiers_valid;
mod indexed_valid;
mod limits_consistent;
mod manuals_declared;
mod modicon_references;
mod number_fields;
mod numbers_finite;
mod pairs_valid;
pub(crate) mod protocol_stated;
mod protocol_valid;
mod ratio_scales;
mod read_param_valid;
mod read_values_valid;
mod references_resolve;
mod relative_limits_valid;
mod repeat_needs_change_valid;
mod roles_valid;
mod serial_valid;
mod status_codes;
mod strings_valid;
mod timing_valid;
mod value_kind_single;

pub(crate) use crate::names::pascal_case;
// Read by drivemap-review until it reads the `Map` alone (transitional, see the crate root).
pub use crate::names::field_span;
pub use citations_present::{parse_citation, parse_page_citation};
pub(crate) use identifiers_valid::is_identifier;

/// What validation may consult beyond the map itself.
#[derive(Debug, Clone, Default)]
pub(crate) struct Context {
    /// Line count of each manual file, when the manuals directory is available; citations are
    /// then checked to fall inside the file.
    pub manual_lines: HashMap<String, usize>,
}

impl Context {
    /// Reads the line counts of the `*.txt` manuals in `dir`. A missing directory gives an
    /// empty context (citations are then checked for form and manual name only).
    pub(crate) fn with_manuals(dir: &Path) -> Context {
        let mut manual_lines = HashMap::new();
        if let Ok(entries) = std::fs::read_dir(dir) {
            for entry in entries.flatten() {
                let path = entry.path();
                if path.extension().is_some_and(|e| e == "txt")
                    && let (Some(name), Ok(text)) =
                        (path.file_name(), std::fs::read_to_string(&path))
                {
                    manual_lines.insert(name.to_string_lossy().into_owned(), text.lines().count());
                }
            }
        }
        Context { manual_lines }
    }
}

/// Runs every pass over a drive and returns all findings.
pub(crate) fn validate(drive: &Drive, ctx: &Context) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    identifiers_valid::check(drive, &mut out);
    identifiers_unique::check(drive, &mut out);
    manuals_declared::check(drive, &mut out);
    citations_present::check(drive, ctx, &mut out);
    value_kind_single::check(drive, &mut out);
    addresses_non_overlapping::check(drive, &mut out);
    pairs_valid::check(drive, &mut out);
    strings_valid::check(drive, &mut out);
    modicon_references::check(drive, &mut out);
    bit_fields_valid::check(drive, &mut out);
    bits_valid::check(drive, &mut out);
    enum_codes_fit::check(drive, &mut out);
    limits_consistent::check(drive, &mut out);
    ratio_scales::check(drive, &mut out);
    references_resolve::check(drive, &mut out);
    access_consistent::check(drive, &mut out);
    protocol_valid::check(drive, &mut out);
    timing_valid::check(drive, &mut out);
    serial_valid::check(drive, &mut out);
    protocol_stated::check(drive, &mut out);
    roles_valid::check(drive, &mut out);
    crate::command_profile::check(drive, &mut out);
    repeat_needs_change_valid::check(drive, &mut out);
    function_codes_valid::check(drive, &mut out);
    relative_limits_valid::check(drive, &mut out);
    read_values_valid::check(drive, &mut out);
    read_param_valid::check(drive, &mut out);
    numbers_finite::check(drive, &mut out);
    conflicts_recorded::check(drive, &mut out);
    indexed_valid::check(drive, &mut out);
    examples_valid::check(drive, &mut out);
    // On the lowered roles: only once everything else holds.
    if out.is_empty() {
        status_codes::check(drive, &mut out);
    }
    out
}

/// Whether `a` and `b` are in one address space: the same table, both broadcast or neither, and
/// a transport in common (a register on no listed transport is on all).
fn shares_space(a: &crate::ir::Register, b: &crate::ir::Register) -> bool {
    let transports = match (&a.transports, &b.transports) {
        (Some(x), Some(y)) => x.iter().any(|t| y.contains(t)),
        _ => true,
    };
    a.broadcast == b.broadcast && a.table == b.table && transports
}

/// The ids of the registers read as settings: scale and address selectors, and the quantities
/// limits and scales are relative to.
fn settings_read(drive: &crate::ir::Drive) -> Vec<&str> {
    drive
        .selectors()
        .iter()
        .chain(drive.references().iter())
        .map(|r| r.id())
        .collect()
}
