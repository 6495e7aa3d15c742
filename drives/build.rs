//! Generates one module per map of `maps/`: every map with the default feature `all-drives`,
//! else only the maps whose feature is enabled (`yaskawa-v7`, …).
//!
//! What the crate contains depends on its files and its features only: the maps are those of
//! `maps/` (a link to the repository's `maps/`; the packaged crate carries a copy), selected by
//! the `CARGO_FEATURE_*` variables Cargo sets for the features enabled. No other environment
//! variable is read here. An application with a map of its own generates it in its own
//! `build.rs` with `drivemap_codegen::Config` (`examples/custom-drive/`).
//!
//! Cargo features are declared in `Cargo.toml`, never generated, so a map added to `maps/` has
//! no feature of its own until a line `<id> = []` is added under `[features]`; until then it is
//! built with `all-drives` only. This script does not read the manifest to find out: it writes
//! `#[cfg(feature = "<id>")]` for every map into `features.rs`, and rustc, which Cargo tells the
//! declared features (`--check-cfg`), warns about a map without one (`unexpected_cfgs`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The Cargo feature of a drive id, as Cargo passes it to build scripts.
fn feature_env(id: &str) -> String {
    format!(
        "CARGO_FEATURE_{}",
        id.to_uppercase().replace(['-', '.'], "_")
    )
}

/// The drive id of a map file: its name without `.yaml`.
fn id_of(map: &Path) -> String {
    map.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));
    // `drives/maps` links to the repository's `maps/` (the one place maps are edited), and
    // `cargo package` stores the files, so the packaged crate builds from its own copy. Errors
    // name `/…/maps/<id>.yaml` (the link resolved), as `drivemap check` does for that path.
    let dir = manifest.join("maps");
    let dir = dir.canonicalize().unwrap_or(dir);
    // The directory, for a map added or removed; the generator names each map it reads.
    println!("cargo:rerun-if-changed={}", dir.display());
    let maps = match drivemap_map::find_maps(&dir) {
        Ok(maps) => maps,
        Err(e) => {
            eprintln!("reading maps from {}: {e}", dir.display());
            std::process::exit(1);
        }
    };
    if maps.is_empty() {
        eprintln!(
            "no maps in {}: drivemap-drives generates its modules from them",
            dir.display()
        );
        std::process::exit(1);
    }
    let all = std::env::var_os("CARGO_FEATURE_ALL_DRIVES").is_some();
    let mut config = drivemap_codegen::Config::new();
    let mut features = String::from(
        "// One line per map of `maps/`: rustc warns about a feature Cargo.toml does not declare\n\
         // (`unexpected_cfgs`), i.e. about a map without a feature of its own; add `<id> = []`\n\
         // under [features] in drives/Cargo.toml to select it alone.\n",
    );
    for map in &maps {
        let id = id_of(map);
        let _ = writeln!(features, "#[cfg(feature = {id:?})]\nconst _: () = ();");
        if all || std::env::var_os(feature_env(&id)).is_some() {
            config.map(map);
        }
    }
    if let Err(e) = std::fs::write(out.join("features.rs"), features) {
        eprintln!("writing {}: {e}", out.join("features.rs").display());
        std::process::exit(1);
    }
    if let Err(e) = config.compile() {
        eprintln!("{e}");
        std::process::exit(1);
    }
}
