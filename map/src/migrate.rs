//! Rewriting a map file in the current schema, keeping its meaning (`drivemap migrate`).

use crate::diagnostic::Diagnostics;

pub use crate::hex::{Reread, Slot};
pub use crate::schema::{CURRENT, Migrated};

/// Rewrites one map file's `text` (named `name` in diagnostics) in schema [`CURRENT`]: every
/// number its version reads otherwise than the current one is written as the current one
/// reads it, comments and layout kept; the result is read back and compared value by value.
pub fn migrate(name: &str, text: &str) -> Result<Migrated, Diagnostics> {
    crate::schema::migrate(&name.into(), text).map_err(Diagnostics::from)
}

/// How a file is named in diagnostics: relative to the current directory when possible.
pub fn display_name(path: &std::path::Path) -> std::sync::Arc<str> {
    crate::load::display_name(path)
}
