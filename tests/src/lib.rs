//! Shared test helpers of the cross-crate tests.

use std::path::{Path, PathBuf};

#[cfg(unix)]
pub mod line_bench;

/// The workspace root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits in the workspace")
        .to_path_buf()
}

/// A scratch workspace for building against another maps directory: `<dir>/maps` holding a copy
/// of the shipped maps plus `extra` (a map file), and `<dir>/app/src` for an application crate
/// with the workspace's `Cargo.lock` (so an offline build needs nothing new). Returns `(maps,
/// app)`.
pub fn maps_and_app(dir: &Path, extra: &Path) -> (PathBuf, PathBuf) {
    let root = workspace();
    let maps = dir.join("maps");
    let app = dir.join("app");
    std::fs::create_dir_all(&maps).expect("maps dir");
    std::fs::create_dir_all(app.join("src")).expect("app dir");
    for map in drivemap_map::find_maps(&root.join("maps")).expect("maps/") {
        std::fs::copy(&map, maps.join(map.file_name().expect("a file"))).expect("copy a map");
    }
    std::fs::copy(extra, maps.join(extra.file_name().expect("a file"))).expect("copy the new map");
    std::fs::copy(root.join("Cargo.lock"), app.join("Cargo.lock")).expect("copy Cargo.lock");
    (maps, app)
}
