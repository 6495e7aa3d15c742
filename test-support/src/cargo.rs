//! Cargo run by a test: the `nested_cargo` tests build applications, a copy of the workspace and
//! the packaged crates, and install the tool, while the other tests run.
//!
//! A test process carries the variables cargo sets for the crate under test
//! (`CARGO_MANIFEST_DIR`, `CARGO_PKG_NAME`, ...). A cargo started from it would pass them on:
//! build scripts that declare them (`cargo:rerun-if-env-changed`, as `ring`'s does) would then
//! look changed to every build started elsewhere, so each nested build and the workspace's own
//! next build would run them again and compile all that depends on them.

use std::ffi::OsStr;
use std::path::PathBuf;
use std::process::Command;

use crate::paths;

/// The workspace's own target directory (`target`, or `CARGO_TARGET_DIR` as cargo gave the
/// test), where its build keeps what it compiled (`CARGO_BUILD_BUILD_DIR` when that is set)
/// and, when no build directory is set apart, its programs (`debug/drivemap`).
pub fn workspace_build_dir() -> PathBuf {
    std::env::var_os("CARGO_BUILD_BUILD_DIR")
        .or_else(|| std::env::var_os("CARGO_TARGET_DIR"))
        .map(PathBuf::from)
        .unwrap_or_else(|| paths::workspace().join("target"))
}

/// Where nested builds put what they make (their programs, `debug/<name>`): `nested` in the
/// workspace's target directory, so they replace none of the workspace's own programs
/// (`target/debug/drivemap`, which other tests run meanwhile).
pub fn nested_target() -> PathBuf {
    workspace_build_dir().join("nested")
}

/// Whether cargo sets `name` for the crate it builds or tests (not for cargo itself).
fn set_for_the_crate(name: &OsStr) -> bool {
    let name = name.to_string_lossy();
    [
        "CARGO_MANIFEST_DIR",
        "CARGO_MANIFEST_PATH",
        "CARGO_MANIFEST_LINKS",
        "CARGO_CRATE_NAME",
        "CARGO_BIN_NAME",
        "CARGO_PRIMARY_PACKAGE",
        "CARGO_TARGET_TMPDIR",
        "CARGO_RUSTC_CURRENT_DIR",
        "OUT_DIR",
    ]
    .contains(&name.as_ref())
        || name.starts_with("CARGO_PKG_")
        || name.starts_with("CARGO_BIN_EXE_")
}

/// `cargo` (the one running the tests, `CARGO`) for a build inside a test: at a lower priority
/// than the tests beside it (`nice -n 10` on Unix: a build is background work, and tests that
/// time a line share the processor with it), without the variables cargo set for the test's
/// crate, compiling into the workspace's build directory ([`workspace_build_dir`], so what the
/// workspace compiled with the same features is not compiled again) and putting its programs
/// in [`nested_target`]. Add the subcommand and its arguments.
pub fn command() -> Command {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut command = if cfg!(unix) {
        let mut nice = Command::new("nice");
        nice.args(["-n", "10"]).arg(cargo);
        nice
    } else {
        Command::new(cargo)
    };
    for (name, _) in std::env::vars_os() {
        if set_for_the_crate(&name) {
            command.env_remove(name);
        }
    }
    command
        .env("CARGO_TARGET_DIR", nested_target())
        .env("CARGO_BUILD_BUILD_DIR", workspace_build_dir());
    command
}
