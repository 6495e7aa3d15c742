//! `drivemap import` through the binary, as a user runs it: a draft from a fixture manual that
//! `drivemap check --require-manuals` accepts as a draft (every citation verified by content),
//! the report, and `--merge` against a map with a register missing and a default changed.

mod common;

use std::path::PathBuf;
use std::process::Command;

use common::{command, repo};

fn drivemap() -> Command {
    let mut c = command();
    c.env(
        "DRIVEMAP_MANUALS",
        repo().join("tests/fixtures/import/manuals"),
    );
    c
}

fn tmp(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("drivemap-cli-import-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_draft_checks_as_a_draft_with_every_citation_verified() {
    let dir = tmp("draft");
    let draft = dir.join("kestrel-k20.yaml");
    let report = dir.join("report.md");
    let manual = repo().join("tests/fixtures/import/manuals/kestrel-k20.txt");
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(&manual)
        .args(["--id", "kestrel-k20", "-o"])
        .arg(&draft)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("9 rows proposed"), "{stderr}");
    let yaml = std::fs::read_to_string(&draft).unwrap();
    assert!(
        yaml.contains("\ndraft:\n  by: \"drivemap import\""),
        "{yaml}"
    );
    let report = std::fs::read_to_string(&report).unwrap();
    assert!(report.contains("protocol.max_write: not found"), "{report}");

    let out = drivemap()
        .args(["check", "--require-manuals"])
        .arg(&draft)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("warning: a draft (made by drivemap import)"),
        "{text}"
    );
    assert!(text.contains("0 unverified"), "{text}");

    // `coverage` reads the draft's citations: every row of the manual's tables is covered.
    let out = drivemap().arg("coverage").arg(&draft).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains(" 0 uncited"), "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merge_proposes_what_the_map_lacks_and_names_what_disagrees() {
    let dir = tmp("merge");
    let truth =
        std::fs::read_to_string(repo().join("tests/fixtures/import/orion-od5.yaml")).unwrap();
    // A map that lacks P2.04 and says 70.00 Hz where the manual prints a 60.00 default.
    let map: String = truth
        .lines()
        .filter(|l| !l.contains("param: P2.04"))
        .map(|l| l.replace("max: 400.0, default: 60.0", "max: 400.0, default: 70.0"))
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join("orion-od5.yaml");
    std::fs::write(&path, map).unwrap();
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(repo().join("tests/fixtures/import/manuals/orion-od5.txt"))
        .arg("--merge")
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("# 1 rows the map lacks"), "{text}");
    assert!(
        text.contains("param: \"P2.04\"") && text.contains("source: \"orion-od5.txt:40\""),
        "{text}"
    );
    assert!(
        text.contains("# 1 registers where the map and the manual's row disagree"),
        "{text}"
    );
    assert!(
        text.contains("maximum_frequency (orion-od5.txt:21)")
            && text.contains("default: map 70 / manual 60"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
