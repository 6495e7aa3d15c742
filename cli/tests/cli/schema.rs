//! Schema versions: a map of an earlier schema version loads by its meaning with warnings that
//! name what changed, `drivemap migrate` rewrites it in the current one, and `drivemap diff`
//! compares maps of different versions (also `--git` across the change) by their meaning.
//!
//! The fixture `tests/fixtures/acme-vf1/schema-1/acme-vf1.yaml` is the fixture drive as it would
//! have been written in schema 1 (before the hex-only rule of commit abfacec): decimal addresses
//! and codes, and the manual's "41H" mistyped as `code: 41` (41 decimal = 29H).

use drivemap_test_support::paths;

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{Scratch, command, repo, run};

fn old_map() -> PathBuf {
    paths::fixture("acme-vf1/schema-1/acme-vf1.yaml")
}

fn new_map() -> PathBuf {
    paths::fixture("acme-vf1/acme-vf1.yaml")
}

fn drivemap(dir: &Path, args: &[&str]) -> (i32, String, String) {
    run(command()
        .args(args)
        .current_dir(dir)
        .env("DRIVEMAP_MANUALS", paths::fixture("acme-vf1/manuals")))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The diff of the schema-1 fixture against today's map: only the exception whose code the
/// old schema read as decimal 41 (29H); none of its 25 decimal addresses and codes.
const EXPECTED: &str = "acme-vf1: 1 breaking, 1 compatible
  breaking    protocol: exception removed — exception 29h
              Interlock active → (none)
              old: acme-vf1.txt:13 · new: —
              why: the drive's meaning of the code is no longer known to the profile
  compatible  protocol: exception added — exception 41h
              (none) → Interlock active
              old: — · new: acme-vf1.txt:13
              why: one more exception code is named
";

#[test]
fn a_schema_1_map_loads_with_warnings_naming_what_changed() {
    let (code, out, err) = drivemap(&repo(), &["check", s(&old_map())]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(out.starts_with("ok "), "{out}");
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains(": warning")).collect();
    // The file's warning, then one per address or code written in decimal (22 addresses,
    // function code 16, exception codes 41 ... and nothing for codes 0-9).
    assert!(
        warnings[0].contains(":1:1: warning: this map states no `schema:`, so it is schema 1")
            && warnings[0].contains("Changed since: schema 2 reads addresses and codes as the manual prints them, in hex")
            && warnings[0].contains("`drivemap migrate"),
        "{err}"
    );
    let per_value = warnings
        .iter()
        .filter(|w| w.contains("as schema 1 reads it"))
        .count();
    assert_eq!(per_value, 26, "{err}");
    assert!(
        err.contains(
            "acme-vf1.yaml:39:14: warning: protocol.exceptions[3].code: exception code 41 is \
             decimal 41 (29H), as schema 1 reads it; schema 2 writes it 0x29"
        ),
        "{err}"
    );
    assert!(
        err.contains(
            "acme-vf1.yaml:62:18: warning in register `control_word`: \
             groups[0].registers[0].address: address 8192 is decimal 8192 (2000H), as schema 1 \
             reads it; schema 2 writes it 0x2000"
        ),
        "{err}"
    );
    // `--strict` wants the current schema.
    let (code, out, err) = drivemap(&repo(), &["check", "--strict", s(&old_map())]);
    assert_eq!(code, 1, "{out}\n{err}");
    assert!(
        err.contains(":1:1: error: this map states no `schema:`"),
        "{err}"
    );
    assert!(err.contains("(--strict: run `drivemap migrate`)"), "{err}");
}

#[test]
fn diff_across_schema_versions_reports_only_what_changed_in_meaning() {
    let (code, out, err) = drivemap(&repo(), &["diff", s(&old_map()), s(&new_map())]);
    assert_eq!((code, out.as_str()), (1, EXPECTED), "{err}");
    assert!(err.contains("states no `schema:`"), "{err}");
    assert!(err.contains("note: 26 address(es) and code(s)"), "{err}");
    // The other way round, the same two changes reversed.
    let (code, out, _) = drivemap(&repo(), &["diff", s(&new_map()), s(&old_map())]);
    assert_eq!(code, 1);
    assert!(
        out.contains("exception removed — exception 41h")
            && out.contains("exception added — exception 29h"),
        "{out}"
    );
}

#[test]
fn migrate_rewrites_in_the_current_schema_with_the_same_meaning() {
    let sc = Scratch::new("schema-migrate");
    let file = sc.0.join("acme-vf1.yaml");
    std::fs::copy(old_map(), &file).unwrap();
    let (code, out, err) = drivemap(&sc.0, &["migrate", "--check", "acme-vf1.yaml"]);
    assert_eq!(code, 1, "{out}\n{err}");
    assert!(
        out.contains(
            "acme-vf1.yaml: schema 1 -> 2, 26 value(s) would be rewritten (nothing written)"
        ),
        "{out}"
    );
    assert_eq!(
        std::fs::read_to_string(&file).unwrap(),
        std::fs::read_to_string(old_map()).unwrap()
    );
    let (code, out, err) = drivemap(&sc.0, &["migrate", "acme-vf1.yaml"]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        out.contains("acme-vf1.yaml:39:14: `41` -> `0x29` (protocol.exceptions[3].code)"),
        "{out}"
    );
    assert!(
        out.contains("acme-vf1.yaml:27:34: `16` -> `0x10` (protocol.function_codes.codes[2])"),
        "{out}"
    );
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("\nschema: 2\ndrive:\n"), "{text}");
    assert!(
        text.contains("{code: 0x29, name: Interlock active"),
        "{text}"
    );
    // Same meaning: no change against the old file; read with no warning; strict check passes.
    let (code, out, err) = drivemap(&sc.0, &["diff", s(&old_map()), "acme-vf1.yaml"]);
    assert_eq!((code, out.as_str()), (0, "acme-vf1: no changes\n"), "{err}");
    let (code, out, err) = drivemap(&sc.0, &["check", "--strict", "acme-vf1.yaml"]);
    assert_eq!(code, 0, "{out}\n{err}");
    // (The one warning left is the fixture's slave addresses above 247.)
    assert!(!err.contains("schema"), "{err}");
    // A second run has nothing to do.
    let (code, out, _) = drivemap(&sc.0, &["migrate", "--check", "acme-vf1.yaml"]);
    assert_eq!(
        (code, out.as_str()),
        (0, "acme-vf1.yaml: already schema 2\n")
    );
}

fn git(dir: &Path, args: &[&str]) {
    let st = Command::new("git")
        .args(args)
        .current_dir(dir)
        .env("GIT_AUTHOR_NAME", "t")
        .env("GIT_AUTHOR_EMAIL", "t@example.invalid")
        .env("GIT_COMMITTER_NAME", "t")
        .env("GIT_COMMITTER_EMAIL", "t@example.invalid")
        .env("GIT_CONFIG_GLOBAL", "/dev/null")
        .output()
        .expect("git");
    assert!(
        st.status.success(),
        "git {args:?}: {}",
        String::from_utf8_lossy(&st.stderr)
    );
}

#[test]
fn diff_git_across_a_schema_change_compares_meaning_and_names_the_revision() {
    let sc = Scratch::new("schema-git");
    let maps = sc.0.join("maps");
    std::fs::create_dir_all(&maps).unwrap();
    git(&sc.0, &["init", "-q"]);
    std::fs::copy(old_map(), maps.join("acme-vf1.yaml")).unwrap();
    git(&sc.0, &["add", "."]);
    git(&sc.0, &["commit", "-q", "-m", "schema 1"]);
    std::fs::copy(new_map(), maps.join("acme-vf1.yaml")).unwrap();
    let (code, out, err) = drivemap(&sc.0, &["diff", "--git", "HEAD", "maps/acme-vf1.yaml"]);
    assert_eq!((code, out.as_str()), (1, EXPECTED), "{err}");
    // The old side is named by revision, never by a temporary path.
    assert!(
        err.starts_with("HEAD:maps/acme-vf1.yaml:1:1: warning: this map states no `schema:`"),
        "{err}"
    );
    assert!(!err.contains("drivemap-diff"), "{err}");
    // An old revision that no schema reads is an error naming the revision too.
    std::fs::write(maps.join("acme-vf1.yaml"), "schema: 9\n").unwrap();
    git(&sc.0, &["commit", "-q", "-am", "a future schema"]);
    std::fs::copy(new_map(), maps.join("acme-vf1.yaml")).unwrap();
    let (code, _, err) = drivemap(&sc.0, &["diff", "--git", "HEAD", "maps/acme-vf1.yaml"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("HEAD:maps/acme-vf1.yaml:1:9: error: schema: the map is written in schema 9"),
        "{err}"
    );
}
