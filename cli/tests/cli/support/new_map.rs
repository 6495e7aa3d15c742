//! A copy of the repository's `maps/` and `docs/` with one new map added, the way a contributor
//! adds a drive: the fixture drive of another vendor (`tests/fixtures/acme-vf1`) copied into
//! `maps/`, its manual beside the others, and its documents made by the one command
//! `drivemap doc --drive <id> --docs docs`. The per-map tests run over the copy with no other
//! change: a new map is covered without a test edit.

use std::path::{Path, PathBuf};

/// The copy; removed on drop.
pub struct NewMap {
    base: PathBuf,
    /// The repository-shaped root: `maps/`, `docs/drives/`, `docs/coverage/`.
    pub root: PathBuf,
    /// The manuals of every map of the copy (links to the shipped maps' manuals and the new one).
    pub manuals: PathBuf,
    /// The new drive's id.
    pub id: &'static str,
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
}

impl NewMap {
    pub fn new(name: &str) -> NewMap {
        let repo = crate::common::repo();
        let base =
            std::env::temp_dir().join(format!("drivemap-newmap-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let root = base.join("repo");
        copy_dir(&repo.join("maps"), &root.join("maps"));
        copy_dir(&repo.join("docs/drives"), &root.join("docs/drives"));
        copy_dir(&repo.join("docs/coverage"), &root.join("docs/coverage"));
        let fixture = repo.join("tests/fixtures/acme-vf1");
        std::fs::copy(
            fixture.join("acme-vf1.yaml"),
            root.join("maps/acme-vf1.yaml"),
        )
        .unwrap();
        let manuals = base.join("shared/manuals");
        std::fs::create_dir_all(&manuals).unwrap();
        let shipped = drivemap_map::default_manuals_dir(&repo.join("maps"))
            .expect("the shipped maps' manuals (shared/manuals or DRIVEMAP_MANUALS)");
        for dir in [shipped, fixture.join("manuals")] {
            for e in std::fs::read_dir(&dir).unwrap() {
                let p = e.unwrap().path().canonicalize().unwrap();
                let _ = std::os::unix::fs::symlink(&p, manuals.join(p.file_name().unwrap()));
            }
        }
        let n = NewMap {
            base,
            root,
            manuals,
            id: "acme-vf1",
        };
        let (code, out, err) =
            n.drivemap(&["doc", "--maps", "maps", "--drive", n.id, "--docs", "docs"]);
        assert_eq!(code, 0, "{out}{err}");
        n
    }

    /// Runs drivemap in the copy's root with its manuals.
    pub fn drivemap(&self, args: &[&str]) -> (i32, String, String) {
        crate::common::run(
            crate::common::command()
                .args(args)
                .current_dir(&self.root)
                .env("DRIVEMAP_MANUALS", &self.manuals),
        )
    }
}

impl Drop for NewMap {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.base);
    }
}
