//! Example frames through the command: `drivemap check` verifies every example of a map against
//! the codec and the map (the fictional Orbis Q5 of `tests/fixtures/orbis-q5/`, whose manual
//! misprints one CRC, and every shipped map), a wrong CRC not recorded in `conflicts:` fails the
//! check at its byte, and `export`, `doc` and `diff` show the examples.

use drivemap_test_support::paths;

use crate::common;

use std::path::{Path, PathBuf};

use common::{command, repo, run};

fn fixture() -> PathBuf {
    paths::fixture("orbis-q5")
}

fn drivemap(args: &[&str], manuals: &Path) -> (i32, String, String) {
    run(command().args(args).env("DRIVEMAP_MANUALS", manuals))
}

/// A copy of the fixture map with `edit` applied, in a directory of its own.
fn edited(name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "drivemap-cli-examples-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("orbis-q5.yaml");
    let text = std::fs::read_to_string(fixture().join("orbis-q5.yaml")).unwrap();
    std::fs::write(&path, edit(text)).unwrap();
    path
}

#[test]
fn check_verifies_the_fixture_s_examples_and_names_the_recorded_crc() {
    let map = fixture().join("orbis-q5.yaml");
    let (code, out, err) = drivemap(
        &["check", map.to_str().unwrap()],
        &fixture().join("manuals"),
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("example frames: 11 of 12 verified, 1 contradicting as recorded"),
        "{out}"
    );
    assert!(
        err.contains(
            "orbis-q5.yaml:108:25: warning: example `frequency_too_high_refused`, byte 5 (62): CRC: the frame ends in 02 62, the CRC-16 of the bytes before it is 02 61 (low byte first); recorded in `conflicts:` as \"CRC of the refused-write example\""
        ),
        "{err}"
    );
}

#[test]
fn an_unrecorded_wrong_crc_fails_check_at_its_byte() {
    let map = edited("unmarked", |t| {
        t.replace("    conflict: CRC of the refused-write example\n", "")
    });
    let (code, out, err) = drivemap(
        &["check", map.to_str().unwrap()],
        &fixture().join("manuals"),
    );
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        err.contains(&format!(
            "{}:108:25: error: example `frequency_too_high_refused`, byte 5 (62): CRC",
            map.display()
        )),
        "{err}"
    );
    assert!(out.contains("FAIL"), "{out}");
    assert!(out.contains("example frames: 11 of 12 verified"), "{out}");
}

/// Every map of `maps/`, whatever its id, has its examples verified by `check`: the expected
/// counts come from the map itself (its frames, and those recorded as a `conflict`), so a map
/// added to `maps/` is covered with no edit here.
#[test]
fn check_verifies_every_example_of_the_shipped_maps() {
    let maps = paths::maps();
    let (code, out, err) = drivemap(
        &["check", "--maps", maps.to_str().unwrap()],
        &repo().join("../shared/manuals"),
    );
    assert_eq!(code, 0, "{out}{err}");
    let paths = drivemap_map::find_maps(&maps).unwrap();
    assert!(
        paths.len() >= 5,
        "{} maps in {}",
        paths.len(),
        maps.display()
    );
    let mut frames_seen = 0;
    for path in paths {
        let drive = drivemap_map::Loader::new()
            .load(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let id = drive.id();
        let line = out
            .lines()
            .find(|l| l.contains(&format!("({id}:")))
            .unwrap_or_else(|| panic!("{id} not checked: {out}"));
        assert!(line.starts_with("ok "), "{line}");
        let total = drive.examples().len();
        let recorded = drive
            .examples()
            .iter()
            .filter(|e| e.conflict.is_some())
            .count();
        frames_seen += total;
        let expected = match (total, recorded) {
            (0, _) => None,
            (n, 0) => Some(format!("example frames: {n} of {n} verified;")),
            (n, c) => Some(format!(
                "example frames: {} of {n} verified, {c} contradicting as recorded;",
                n - c
            )),
        };
        match expected {
            Some(frames) => assert!(line.contains(&frames), "{id}: {line}, expected {frames}"),
            None => assert!(!line.contains("example frames"), "{id}: {line}"),
        }
        // One warning per recorded frame (not one per byte that differs), each naming its
        // conflict.
        let warnings: Vec<&str> = err
            .lines()
            .filter(|l| {
                let file = l.split(':').next().map(Path::new);
                file.and_then(Path::file_name) == path.file_name()
                    && l.contains(": warning: example `")
            })
            .collect();
        assert_eq!(warnings.len(), recorded, "{id}: {warnings:#?}");
        for e in drive.examples().iter().filter(|e| e.conflict.is_some()) {
            let topic = e.conflict.as_deref().unwrap();
            assert!(
                warnings
                    .iter()
                    .any(|w| w.contains(&format!("example `{}`", e.id))
                        && w.ends_with(&format!("recorded in `conflicts:` as \"{topic}\""))),
                "{id}: no warning for `{}`: {warnings:#?}",
                e.id
            );
        }
    }
    assert!(frames_seen > 0, "no shipped map has example frames");
    assert!(!err.contains(": error"), "{err}");
}

#[test]
fn export_doc_and_diff_show_the_examples() {
    let map = fixture().join("orbis-q5.yaml");
    let manuals = fixture().join("manuals");
    let (code, out, err) = drivemap(&["export", map.to_str().unwrap()], &manuals);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    let first = &json["examples"][0];
    assert_eq!(first["id"], "read_monitors");
    assert_eq!(first["bytes"], "01 03 00 10 00 02 C5 CE");
    assert_eq!(
        first["frame"],
        serde_json::json!([1, 3, 0, 16, 0, 2, 197, 206])
    );
    assert_eq!(first["source"], "orbis-q5.txt:17-18");
    assert_eq!(json["examples"].as_array().unwrap().len(), 12);

    let (code, out, err) = drivemap(&["doc", map.to_str().unwrap()], &manuals);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("## Example frames"), "{out}");
    assert!(
        out.contains("| `frequency_too_high_refused` | RTU response to `frequency_too_high` | `01 86 03 02 62` | exception 03h; contradicts the codec or the map: conflict \"CRC of the refused-write example\" | `orbis-q5.txt:31` |"),
        "{out}"
    );

    let changed = edited("diff", |t| {
        t.replacen("01 06 00 02 0B B8 2F 48", "01 06 00 02 0B B9 EE 88", 1)
    });
    let (_, out, err) = drivemap(
        &["diff", map.to_str().unwrap(), changed.to_str().unwrap()],
        &manuals,
    );
    assert!(
        out.contains("example frame `set_frequency`")
            && out.contains("`01 06 00 02 0B B8 2F 48`")
            && out.contains("`01 06 00 02 0B B9 EE 88`"),
        "{out}{err}"
    );
}
