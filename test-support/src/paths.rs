//! Where the workspace's files are, for every test, bench and example that reads one: the test
//! fixtures (`tests/fixtures/`, described in its `README.md`), the shipped maps (`maps/`) and
//! the rest of the repository. The one place that knows the layout, instead of relative paths
//! (`../tests/fixtures`, `../../maps`) written from each crate's directory.
//!
//! ```
//! use drivemap_test_support::paths;
//!
//! let acme = paths::fixture("acme-vf1/acme-vf1.yaml");
//! assert!(acme.is_file());
//! assert!(paths::shipped_map("yaskawa-v7").is_file());
//! ```

use std::path::{Path, PathBuf};

/// The workspace root: the directory of the workspace's `Cargo.toml`.
pub fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("test-support/ sits in the workspace")
}

/// The fixtures' tree, `tests/fixtures/`.
pub fn fixtures() -> PathBuf {
    workspace().join("tests").join("fixtures")
}

/// A file or directory of the fixtures' tree: `fixture("acme-vf1/acme-vf1.yaml")` is
/// `tests/fixtures/acme-vf1/acme-vf1.yaml`.
pub fn fixture(path: impl AsRef<Path>) -> PathBuf {
    fixtures().join(path)
}

/// The shipped maps' directory, `maps/`.
pub fn maps() -> PathBuf {
    workspace().join("maps")
}

/// A shipped map by its drive id: `shipped_map("yaskawa-v7")` is `maps/yaskawa-v7.yaml`.
pub fn shipped_map(id: &str) -> PathBuf {
    maps().join(format!("{id}.yaml"))
}

/// The path of `path` as written from the workspace root (`tests/fixtures/...`), for a message
/// or an expected output that must not depend on where the repository is checked out; `path`
/// itself when it is outside the workspace.
pub fn from_workspace(path: &Path) -> &Path {
    path.strip_prefix(workspace()).unwrap_or(path)
}
