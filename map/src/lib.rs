//! drivemap map front end: YAML register maps of AC drives → validated IR → the drive plan.
//!
//! Data flows one way: [`source`] reads YAML into a located tree, [`load`] merges variant maps
//! onto their base and deserializes the [`model`], [`ir`] expands it, [`validate`] checks it one
//! concern per pass, [`lower`] decides what every register means (the drive plan). [`facts`] is the
//! one view of a register's facts and of the protocol's (rows of label, value and citation, and
//! the same facts as typed values) that printers read; [`export`] writes the typed values as JSON. [`citations`]
//! lists every place of a map that carries a citation; [`others`] says what each citation
//! outside the registers must mention.
//!
//! Text about a map has one wording, [`describe`], shared by the generated rustdoc
//! (`drivemap-codegen`), the Markdown reference and the semantic diff (`drivemap-review`) and the
//! command line's messages.
//!
//! This crate has no code generator in it (no `syn`, `quote`, `prettyplease`): the run-time tools
//! (`drivemap-live`, `drivemap-sim`, the `drivemap` command line) read maps through it alone.

pub mod citations;
pub mod command_profile;
pub mod describe;
pub mod diagnostic;
pub mod examples;
pub mod export;
pub mod facts;
pub mod hex;
pub mod hints;
pub mod indexed;
pub mod ir;
pub mod load;
mod loader;
pub mod lower;
mod map;
pub mod migrate;
pub mod model;
pub mod names;
pub mod others;
pub mod ratio;
pub mod schema;
pub mod source;
pub mod stated;
pub mod validate;

pub use diagnostic::{Diagnostic, Diagnostics, Loc};
pub use ir::Drive;
pub use loader::{Loader, MAX_YAML_BYTES, parse_map, parse_yaml, too_large};
pub use lower::MapPlan;
pub use map::{Map, RegisterRef};
/// A YAML file read into a tree whose every node keeps where it was written.
pub use source::{Node as Tree, NodeKind as TreeKind, Path as TreePath};

use std::path::{Path, PathBuf};

/// Reads, expands and validates one map file. All problems of the file are returned at once.
pub fn read_map(path: &Path, ctx: &validate::Context) -> Result<Drive, Diagnostics> {
    let loaded = load::load(path).map_err(Diagnostics::from)?;
    finish(&loaded, ctx)
}

/// Like [`read_map`], sharing the trees of map files already read (and their bases) through
/// `cache`: reading every map of a directory with one cache reads each file once, however
/// long its chain of `extends`.
pub fn read_map_cached(
    path: &Path,
    ctx: &validate::Context,
    cache: &load::TreeCache,
) -> Result<Drive, Diagnostics> {
    let loaded = load::load_cached(path, cache).map_err(Diagnostics::from)?;
    finish(&loaded, ctx)
}

/// Like [`read_map`] for YAML held in memory (`extends` is not available).
pub fn read_map_str(name: &str, text: &str, ctx: &validate::Context) -> Result<Drive, Diagnostics> {
    let loaded = load::load_str(name, text).map_err(Diagnostics::from)?;
    finish(&loaded, ctx)
}

/// Like [`read_map`] for one version of a map kept under any file name (`old.yaml`,
/// `tds-before.yaml`): the rule that a map's file is named `<drive id>.yaml`, which matters for a
/// maps directory, is not applied. `drivemap diff old.yaml new.yaml` reads maps so.
pub fn read_map_version(path: &Path, ctx: &validate::Context) -> Result<Drive, Diagnostics> {
    let loaded = load::load(path).map_err(Diagnostics::from)?;
    let mut drive = ir::expand(&loaded).map_err(Diagnostics::from)?;
    drive.file = path.with_file_name(format!("{}.yaml", drive.meta.id));
    let errors = validate::validate(&drive, ctx);
    if errors.is_empty() {
        drive.file = path.to_path_buf();
        Ok(drive)
    } else {
        Err(errors.into())
    }
}

/// Like [`read_map_str`], resolving `extends` through `base`, which gives the name and YAML text
/// of a base map by drive id (maps built into a program).
pub fn read_map_str_with(
    name: &str,
    text: &str,
    ctx: &validate::Context,
    base: &load::BaseResolver<'_>,
) -> Result<Drive, Diagnostics> {
    let loaded = load::load_str_with(name, text, base).map_err(Diagnostics::from)?;
    finish(&loaded, ctx)
}

/// Like [`read_map_str_with`] for a map already parsed into a tree ([`source::parse_map`]):
/// for tools that edit a map's tree before reading it.
pub fn read_map_tree_with(
    name: &str,
    tree: source::Node,
    ctx: &validate::Context,
    base: &load::BaseResolver<'_>,
) -> Result<Drive, Diagnostics> {
    let loaded = load::load_tree_with(name, tree, base).map_err(Diagnostics::from)?;
    finish(&loaded, ctx)
}

fn finish(loaded: &load::LoadedMap, ctx: &validate::Context) -> Result<Drive, Diagnostics> {
    let drive = ir::expand(loaded).map_err(Diagnostics::from)?;
    let errors = validate::validate(&drive, ctx);
    if errors.is_empty() {
        Ok(drive)
    } else {
        Err(errors.into())
    }
}

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
