//! Builds the shipped maps into the binary: every `maps/*.yaml` of the repository becomes an
//! entry `(drive id, YAML text)` of `BUILTIN_MAPS` (`$OUT_DIR/builtin_maps.rs`), so `drivemap`
//! works from any directory once installed, and a new map needs no edit here.
//!
//! `cli/maps` is a symbolic link to the repository's `maps/` (the one place maps are edited);
//! `cargo package` stores the files it points to, so the packaged crate carries the maps. No
//! map found is an error: a `drivemap` without maps would check nothing and say nothing.

use std::path::{Path, PathBuf};

fn main() {
    // The manifest directory at run time: `env!` would bake in the directory the build script
    // was compiled in, so a target directory copied from another checkout embeds its maps.
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let maps = Path::new(&manifest).join("maps");
    println!("cargo::rerun-if-changed={}", maps.display());
    let mut files: Vec<PathBuf> = std::fs::read_dir(&maps)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.retain(|p| p.extension().is_some_and(|e| e == "yaml") && p.is_file());
    files.sort();
    if files.is_empty() {
        eprintln!(
            "error: no maps to build into drivemap: {} has no *.yaml file (it links to the \
             repository's maps/; a packaged drivemap carries a copy)",
            maps.display()
        );
        std::process::exit(1);
    }
    let mut out = String::from(
        "/// The shipped maps, `(drive id, YAML text)`, sorted by id.\n\
         pub(crate) static BUILTIN_MAPS: &[(&str, &str)] = &[\n",
    );
    for f in &files {
        println!("cargo::rerun-if-changed={}", f.display());
        let id = f.file_stem().expect("a file name").to_string_lossy();
        let abs = f.canonicalize().expect("a map path");
        out += &format!(
            "    ({id:?}, include_str!({:?})),\n",
            abs.display().to_string()
        );
    }
    out += "];\n";
    let dest = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("builtin_maps.rs");
    std::fs::write(dest, out).expect("writing builtin_maps.rs");
}
