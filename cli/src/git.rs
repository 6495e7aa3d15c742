//! The maps of a git revision for `drivemap diff --git`, written to a temporary directory so that
//! a variant map and its base are both read as of that revision. The diff itself is the
//! library's (`drivemap_review::diff`).

use std::io;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{SystemTime, UNIX_EPOCH};

/// A directory removed (with its contents) when dropped.
#[derive(Debug)]
pub(crate) struct TempDir(PathBuf);

impl TempDir {
    /// Creates a fresh directory under the system's temporary directory.
    pub(crate) fn new(prefix: &str) -> io::Result<TempDir> {
        let nanos = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        let base = std::env::temp_dir();
        for i in 0..1000u32 {
            let path = base.join(format!("{prefix}-{}-{nanos}-{i}", std::process::id()));
            match std::fs::create_dir(&path) {
                Ok(()) => return Ok(TempDir(path)),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
        Err(io::Error::new(
            io::ErrorKind::AlreadyExists,
            "no free temporary directory name",
        ))
    }

    /// The directory.
    pub(crate) fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Why the maps of a revision could not be had from git.
#[derive(Debug, thiserror::Error)]
pub(crate) enum GitError {
    /// `git` could not be started.
    #[error("cannot run git: {0}")]
    Spawn(io::Error),
    /// A git command failed; its arguments and what it said.
    #[error("git {args} failed: {stderr}")]
    Failed {
        /// The arguments given.
        args: String,
        /// Its standard error, trimmed.
        stderr: String,
    },
    /// Not a revision (empty, or an option).
    #[error("`{0}` is not a revision")]
    NotARevision(String),
    /// The temporary directory or a map in it could not be written.
    #[error("{path}: {source}")]
    Write {
        /// The file or directory.
        path: String,
        /// The operating system's reason.
        source: io::Error,
    },
}

fn git(dir: &Path, args: &[&str]) -> Result<Vec<u8>, GitError> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .map_err(GitError::Spawn)?;
    if !out.status.success() {
        return Err(GitError::Failed {
            args: args.join(" "),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_owned(),
        });
    }
    Ok(out.stdout)
}

/// Writes the `*.yaml` maps of `maps_dir` as they are in revision `rev` into a new temporary
/// directory, under the same file names.
pub(crate) fn maps_at(maps_dir: &Path, rev: &str) -> Result<TempDir, GitError> {
    if rev.is_empty() || rev.starts_with('-') {
        return Err(GitError::NotARevision(rev.to_owned()));
    }
    let listing = git(maps_dir, &["ls-tree", "--name-only", "-z", rev, "--", "./"])?;
    let tmp = TempDir::new("drivemap-diff").map_err(|source| GitError::Write {
        path: "temporary directory".into(),
        source,
    })?;
    for name in listing.split(|b| *b == 0).filter(|n| !n.is_empty()) {
        let name = String::from_utf8_lossy(name).into_owned();
        if !(name.ends_with(".yaml") || name.ends_with(".yml")) || name.contains('/') {
            continue;
        }
        let text = git(maps_dir, &["show", &format!("{rev}:./{name}")])?;
        let path = tmp.path().join(&name);
        std::fs::write(&path, text).map_err(|source| GitError::Write {
            path: path.display().to_string(),
            source,
        })?;
    }
    Ok(tmp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_dirs_are_fresh_and_removed() {
        let a = TempDir::new("drivemap-test").unwrap();
        let b = TempDir::new("drivemap-test").unwrap();
        assert_ne!(a.path(), b.path());
        std::fs::write(a.path().join("x.yaml"), "x").unwrap();
        let kept = a.path().to_path_buf();
        drop(a);
        assert!(!kept.exists());
        assert!(b.path().is_dir());
    }

    #[test]
    fn options_are_not_revisions() {
        assert!(maps_at(Path::new("."), "--output=/tmp/x").is_err());
        assert!(maps_at(Path::new("."), "").is_err());
    }
}
