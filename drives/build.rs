//! Generates one module per map of `maps/` (or of `$DRIVEMAP_MAPS`): every map with the default
//! feature `all-drives`, else only the maps whose feature is enabled (`yaskawa-v7`, …).
//!
//! Cargo features have to be declared in `Cargo.toml`, so a map added to `maps/` has none of its
//! own until a line is added there; until then it is built with `all-drives` (the default), and
//! this script says so in a warning. Any map, declared or not, can also be selected by id in the
//! environment variable `DRIVEMAP_DRIVES` (comma-separated, e.g. in an application's
//! `.cargo/config.toml` under `[env]`), which needs no edit of this crate.

use std::path::{Path, PathBuf};

/// The Cargo feature of a drive id, as Cargo passes it to build scripts.
fn feature_env(id: &str) -> String {
    format!(
        "CARGO_FEATURE_{}",
        id.to_uppercase().replace(['-', '.'], "_")
    )
}

/// Feature names declared in this crate's `Cargo.toml`.
fn declared_features(manifest_dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(manifest_dir.join("Cargo.toml")).unwrap_or_default();
    let mut in_features = false;
    let mut names = Vec::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            in_features = line == "[features]";
        } else if in_features && let Some((name, _)) = line.split_once('=') {
            names.push(name.trim().trim_matches('"').to_owned());
        }
    }
    names
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let dir = std::env::var_os("DRIVEMAP_MAPS")
        .map(PathBuf::from)
        .unwrap_or_else(|| manifest.join("maps"));
    // `drives/maps` links to the repository's `maps/` (the one place maps are edited), and
    // `cargo package` stores the files, so the packaged crate builds from its own copy. Errors
    // name `/…/maps/<id>.yaml` (the link resolved), as `drivemap check` does for that path.
    let dir = dir.canonicalize().unwrap_or(dir);
    println!("cargo:rerun-if-env-changed=DRIVEMAP_MAPS");
    println!("cargo:rerun-if-env-changed=DRIVEMAP_DRIVES");
    let selected: Vec<String> = std::env::var("DRIVEMAP_DRIVES")
        .unwrap_or_default()
        .split(',')
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.is_empty())
        .collect();
    println!("cargo:rerun-if-changed={}", dir.display());
    println!("cargo:rerun-if-changed=Cargo.toml");
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
    let declared = declared_features(&manifest);
    let mut config = drivemap_codegen::Config::new();
    for map in &maps {
        let id = map
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !declared.contains(&id) {
            println!(
                "cargo:warning={} has no feature of its own in drives/Cargo.toml; it is built with \
                 `all-drives` only (add `{id} = []` under [features] to select it alone, or \
                 select it with DRIVEMAP_DRIVES={id})",
                map.display()
            );
        }
        if all || selected.contains(&id) || std::env::var_os(feature_env(&id)).is_some() {
            config.map(map);
        }
    }
    for id in &selected {
        if !maps
            .iter()
            .any(|m| m.file_stem().is_some_and(|s| s == id.as_str()))
        {
            eprintln!(
                "DRIVEMAP_DRIVES names `{id}`, which has no map in {}",
                dir.display()
            );
            std::process::exit(1);
        }
    }
    if let Err(e) = config.compile() {
        eprintln!("{e}");
        std::process::exit(1);
    }
}
