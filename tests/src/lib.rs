//! Shared test helpers of the cross-crate tests.
#![doc = include_str!("../README.md")]

use drivemap_test_support::paths;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, MutexGuard, PoisonError};

#[cfg(unix)]
pub mod line_bench;

/// The Rust examples of the repository's `README.md`, compiled as doctests of this crate
/// (`cargo test -p drivemap-tests --doc`), which depends on every crate they use. Not part of
/// the documentation (`cfg(doctest)`): the README is the repository's front page.
#[doc = include_str!("../../README.md")]
#[cfg(doctest)]
pub struct RootReadme;

/// The workspace root.
pub fn workspace() -> PathBuf {
    paths::workspace().to_path_buf()
}

/// `cargo` for a build inside a test ([`drivemap_test_support::cargo::command`]: at a lower
/// priority, its programs in [`nested_target`], what it compiles in the workspace's build
/// directory), with the workspace's `[profile.*]` settings passed as `--config` options (but for
/// those the environment sets, `CARGO_PROFILE_DEV_DEBUG` say, which the nested cargo inherits),
/// so an application outside the workspace, which has no profiles of its own, compiles the
/// registry crates as the workspace does. Add the subcommand and its arguments.
///
/// [`nested_target`]: drivemap_test_support::cargo::nested_target
pub fn nested_cargo() -> Command {
    let mut command = drivemap_test_support::cargo::command();
    for setting in workspace_profiles() {
        command.arg("--config").arg(setting);
    }
    command
}

/// The workspace `Cargo.toml`'s profile settings as `--config` values:
/// `[profile.dev.package."*"]` and `opt-level = 1` give `profile.dev.package."*".opt-level=1`.
fn workspace_profiles() -> Vec<String> {
    let manifest =
        std::fs::read_to_string(workspace().join("Cargo.toml")).expect("the workspace manifest");
    let mut table: Option<&str> = None;
    let mut settings = Vec::new();
    for line in manifest.lines().map(str::trim) {
        if let Some(header) = line.strip_prefix('[') {
            table = header
                .strip_suffix(']')
                .filter(|name| name.starts_with("profile."));
        } else if let (Some(table), Some((key, value))) = (table, line.split_once('='))
            && !line.starts_with('#')
        {
            let key = format!("{table}.{}", key.trim());
            // Cargo's name for it in the environment, which takes precedence over the manifest.
            let variable = format!("CARGO_{}", key.to_uppercase().replace(['.', '-'], "_"));
            if std::env::var_os(variable).is_none() {
                settings.push(format!("{key}={}", value.trim()));
            }
        }
    }
    assert!(
        settings.iter().any(|s| s.starts_with("profile.dev.")),
        "the workspace's Cargo.toml sets no [profile.dev]"
    );
    settings
}

/// A directory for an application crate outside the workspace: `<dir>/src`, and the
/// workspace's `Cargo.lock` (so an offline build needs nothing new). Returns `<dir>`.
pub fn app_dir(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir.join("src")).expect("app dir");
    std::fs::copy(workspace().join("Cargo.lock"), dir.join("Cargo.lock")).expect("copy Cargo.lock");
    dir.to_path_buf()
}

/// The lock the users of [`nested_target`] take turns with (see [`hold_nested_target`]).
///
/// [`nested_target`]: drivemap_test_support::cargo::nested_target
static NESTED: Mutex<()> = Mutex::new(());

/// Keeps the other tests of this process out of [`nested_target`] until the guard is dropped:
/// builds there write the same binaries (the `drivemap` of the workspace copy and of the
/// packaged crates), so a test holds the directory from its build to its last use of what it
/// built. Under nextest each test is a process of its own: there the `nested-target` test group
/// of `.config/nextest.toml` runs these tests one at a time.
///
/// [`nested_target`]: drivemap_test_support::cargo::nested_target
pub fn hold_nested_target() -> MutexGuard<'static, ()> {
    NESTED.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A copy of this checkout with one map file added to its `maps/`: what a contributor has after
/// dropping a YAML file into `maps/`. The drives crate (and the `drivemap` binary's built-in
/// maps) generate from the maps they carry and from nothing in the environment, so building
/// against a new map means building a tree that holds it.
///
/// The copy is one directory, `target/workspace-copy` (build it with [`nested_cargo`]),
/// brought up to date on each call: a file is written
/// only when its content differs and a file the checkout no longer has is removed, so cargo
/// rebuilds only what changed since the last build. Everything but `target` directories and
/// dot-files is copied; symbolic links (`drives/maps`, `cli/maps`) stay links. The guard
/// returned ([`hold_nested_target`]) keeps the other tests of this process out of the copy and
/// of the target directory until it is dropped.
pub fn workspace_with_map(map: &Path) -> (MutexGuard<'static, ()>, PathBuf) {
    let guard = hold_nested_target();
    let root = workspace();
    let copy = workspace().join("target").join("workspace-copy");
    let name = map.file_name().expect("a map file");
    let added = copy.join("maps").join(name);
    sync(&root, &copy, &|p| p == added).expect("copying the workspace");
    let text = std::fs::read(map).expect("reading the new map");
    if std::fs::read(&added).ok().as_ref() != Some(&text) {
        std::fs::write(&added, text).expect("writing the new map");
    }
    (guard, copy)
}

/// Makes `to` hold what `from` holds (see [`workspace_with_map`]); `keep` names the files of
/// `to` to leave in place although `from` lacks them.
fn sync(from: &Path, to: &Path, keep: &dyn Fn(&Path) -> bool) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    let mut names = HashSet::new();
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let name = entry.file_name();
        let kind = entry.file_type()?;
        if name.to_string_lossy().starts_with('.') || (kind.is_dir() && name == "target") {
            continue;
        }
        let (src, dest) = (entry.path(), to.join(&name));
        names.insert(name);
        let old = std::fs::symlink_metadata(&dest).ok();
        if kind.is_symlink() {
            let link = std::fs::read_link(&src)?;
            if std::fs::read_link(&dest).ok() != Some(link.clone()) {
                remove(&dest, old.as_ref())?;
                symlink(&link, &dest)?;
            }
        } else if kind.is_dir() {
            if old.as_ref().is_some_and(|m| !m.is_dir()) {
                remove(&dest, old.as_ref())?;
            }
            sync(&src, &dest, keep)?;
        } else {
            let text = std::fs::read(&src)?;
            let same = old.as_ref().is_some_and(|m| m.is_file())
                && std::fs::read(&dest).ok().as_ref() == Some(&text);
            if !same {
                remove(&dest, old.as_ref())?;
                std::fs::write(&dest, text)?;
            }
        }
    }
    for entry in std::fs::read_dir(to)? {
        let entry = entry?;
        let path = entry.path();
        if !names.contains(&entry.file_name()) && !keep(&path) {
            remove(&path, std::fs::symlink_metadata(&path).ok().as_ref())?;
        }
    }
    Ok(())
}

/// Removes what is at `path` (`old`: its metadata, if anything is there).
fn remove(path: &Path, old: Option<&std::fs::Metadata>) -> std::io::Result<()> {
    match old {
        None => Ok(()),
        Some(m) if m.is_dir() => std::fs::remove_dir_all(path),
        Some(_) => std::fs::remove_file(path),
    }
}

#[cfg(unix)]
fn symlink(link: &Path, at: &Path) -> std::io::Result<()> {
    std::os::unix::fs::symlink(link, at)
}

/// Elsewhere a link is copied as what it points to.
#[cfg(not(unix))]
fn symlink(link: &Path, at: &Path) -> std::io::Result<()> {
    let target = at.parent().unwrap_or(Path::new(".")).join(link);
    if target.is_dir() {
        sync(&target, at, &|_| false)
    } else {
        std::fs::copy(target, at).map(drop)
    }
}
