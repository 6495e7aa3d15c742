//! drivemap map front end: YAML register maps of AC drives → a validated [`Map`] and its plan.
//!
//! A [`Loader`] reads a map file (or text, or an edited [`Tree`]): the YAML is read into a
//! located tree, a variant map is merged onto its base, the model is expanded and checked one
//! concern per pass, and lowering decides what every register means — all problems of a file
//! come back at once as [`Diagnostics`]. A [`Map`] gives:
//!
//! - the plan ([`MapPlan`], [`Map::plan`], [`RegisterRef::plan`]): what every register means on
//!   the wire, decided once, in the vocabulary crate's types that generated code prints;
//! - the facts view ([`facts`], [`Map::facts`], [`RegisterRef::facts`]): what the map says of
//!   each register and of the protocol, as rows of label, value and citation and as typed values,
//!   and the map's own records (groups, variants, conflicts, gaps), in the types the map writes
//!   them in; [`Map::written`] and [`RegisterRef::written`] name every key of the map and of
//!   each register (what `drivemap diff` compares);
//! - locations ([`RegisterRef::location`], [`Map::locate`]) for diagnostics of a tool's own;
//! - [`export`] (`drivemap export`), and [`migrate`] for files of an older schema.
//!
//! Text about a map has one wording, [`describe`], shared by the generated rustdoc
//! (`drivemap-codegen`), the Markdown reference and the semantic diff (`drivemap-review`) and the
//! command line's messages.
//!
//! This crate has no code generator in it (no `syn`, `quote`, `prettyplease`): the run-time tools
//! (`drivemap-live`, `drivemap-sim`, the `drivemap` command line) read maps through it alone.
#![doc = include_str!("../README.md")]
#![warn(unreachable_pub, missing_docs, unnameable_types)]

// The map as written and its expansion, checks and lowering: private. What a consumer reads is
// the `Map` a `Loader` gives, its plan (`MapPlan`) and its facts view (`facts`).
mod diagnostic;
mod hex;
mod hints;
mod loader;
mod map;
mod ratio;
mod schema;
mod stated;

mod load;
mod lower;
mod names;
mod source;
mod validate;

// The expanded map, its model and the map's own records: private. A consumer reads them
// through `Map`, `RegisterRef` and the facts view, which re-exports the records' types.
mod citations;
mod command_profile;
mod examples;
mod indexed;
mod ir;
mod model;
mod others;

pub mod describe;
pub mod export;
pub mod facts;
pub mod migrate;
pub mod modicon;

pub use diagnostic::{Diagnostic, Diagnostics, Loc};
pub use loader::{
    Loader, MAX_YAML_ALIAS_NODES, MAX_YAML_BYTES, MAX_YAML_DEPTH, parse_map, parse_yaml, too_large,
};
pub use lower::{CodeSlot, MapPlan, Quantity, SettingsPlan};
pub use map::{Map, RegisterRef};
/// A YAML file read into a tree whose every node keeps where it was written.
pub use source::{Node as Tree, NodeKind as TreeKind, Path as TreePath};

use std::path::{Path, PathBuf};

/// The `*.yaml` files of a directory, sorted by name.
pub fn find_maps(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut maps: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "yaml" || e == "yml") && p.is_file())
        .collect();
    maps.sort();
    Ok(maps)
}

/// The manuals directory: `$DRIVEMAP_MANUALS`, else `../shared/manuals` beside the repository
/// that holds `maps_dir`, if it exists. Citations are checked against it when found.
pub fn default_manuals_dir(maps_dir: &Path) -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("DRIVEMAP_MANUALS") {
        return Some(PathBuf::from(dir));
    }
    let abs = maps_dir.canonicalize().ok()?;
    abs.ancestors()
        .map(|a| a.join("shared").join("manuals"))
        .find(|p| p.is_dir())
}
