//! The maps of a git revision for `drivemap diff --git`, written to a temporary directory so that
//! a variant map and its base are both read as of that revision. The diff itself is the
//! library's (`drivemap_codegen::diff`).

use std::io;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{SystemTime, UNIX_EPOCH};

/// A directory removed (with its contents) when dropped.
#[derive(Debug)]
pub struct TempDir(PathBuf);

impl TempDir {
    /// Creates a fresh directory under the system's temporary directory.
    pub fn new(prefix: &str) -> io::Result<TempDir> {
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
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn git(dir: &Path, args: &[&str]) -> Result<Vec<u8>, String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .map_err(|e| format!("cannot run git: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "git {} failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(out.stdout)
}

/// Writes the `*.yaml` maps of `maps_dir` as they are in revision `rev` into a new temporary
/// directory, under the same file names.
pub fn maps_at(maps_dir: &Path, rev: &str) -> Result<TempDir, String> {
    if rev.is_empty() || rev.starts_with('-') {
        return Err(format!("`{rev}` is not a revision"));
    }
    let listing = git(maps_dir, &["ls-tree", "--name-only", "-z", rev, "--", "./"])?;
    let tmp = TempDir::new("drivemap-diff").map_err(|e| format!("temporary directory: {e}"))?;
    for name in listing.split(|b| *b == 0).filter(|n| !n.is_empty()) {
        let name = String::from_utf8_lossy(name).into_owned();
        if !(name.ends_with(".yaml") || name.ends_with(".yml")) || name.contains('/') {
            continue;
        }
        let text = git(maps_dir, &["show", &format!("{rev}:./{name}")])?;
        std::fs::write(tmp.path().join(&name), text)
            .map_err(|e| format!("{}: {e}", tmp.path().join(&name).display()))?;
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
