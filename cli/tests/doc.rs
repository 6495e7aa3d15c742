//! `drivemap doc`: the Markdown reference of a fixture map (golden), and the committed
//! references of every shipped map (regenerated and compared).

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn drivemap(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_drivemap"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("run drivemap");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn fixture_reference_golden() {
    let (code, out, err) = drivemap(&["doc", "cli/tests/fixtures/example-drive.yaml"]);
    assert_eq!(code, 0, "{err}");
    insta::assert_snapshot!("example_drive_doc", out);
}

#[test]
fn shipped_map_references_are_current() {
    let maps = repo().join("maps");
    let docs = repo().join("docs").join("drives");
    let mut ids = Vec::new();
    let mut stale = Vec::new();
    for entry in std::fs::read_dir(&maps).expect("maps directory") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        let id = path.file_stem().unwrap().to_string_lossy().into_owned();
        let (code, fresh, err) = drivemap(&["doc", "--maps", "maps", "--drive", &id]);
        assert_eq!(code, 0, "drivemap doc --drive {id} failed: {err}");
        let committed = std::fs::read_to_string(docs.join(format!("{id}.md"))).unwrap_or_default();
        if committed != fresh {
            stale.push(format!(
                "docs/drives/{id}.md is stale: run `cargo run -p drivemap -- doc --drive {id} -o docs/drives/{id}.md`"
            ));
        }
        ids.push(id);
    }
    assert!(ids.len() >= 5, "expected the shipped maps, found {ids:?}");
    for entry in std::fs::read_dir(&docs).expect("docs/drives") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if let Some(id) = name.strip_suffix(".md") {
            if !ids.iter().any(|i| i == id) {
                stale.push(format!("docs/drives/{name} documents no map in maps/"));
            }
        }
    }
    assert!(stale.is_empty(), "{}", stale.join("\n"));
}

#[test]
fn output_file_and_unknown_drive() {
    let dir = std::env::temp_dir().join(format!("drivemap-doc-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("tds.md");
    let (code, out, err) = drivemap(&[
        "doc",
        "--maps",
        "maps",
        "--drive",
        "ptlk-tds-v8",
        "-o",
        file.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.is_empty(), "with -o nothing goes to stdout");
    assert!(
        err.starts_with(&format!("wrote {}: 187 registers, ", file.display())),
        "{err}"
    );
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("# PTLK TDS-V8 / TEK-DRIVE — `ptlk-tds-v8`\n"));
    assert!(text.contains(
        "| 0200h | Bn-01 | Acceleration time 1 | `accel_time_1` | read/write | s | 0.1 s | 0 ..= 6000 s |"
    ));
    std::fs::remove_dir_all(&dir).unwrap();

    let (code, _, err) = drivemap(&["doc", "--maps", "maps", "--drive", "ptlk-tds-v9"]);
    assert_eq!(code, 2);
    assert!(err.contains("no map for drive `ptlk-tds-v9`"), "{err}");
}

/// The timing row states the master's wait after a reply, which the client keeps by default.
#[test]
fn the_timing_row_states_the_request_gap() {
    let (code, out, err) = drivemap(&["doc", "--maps", "maps", "--drive", "yaskawa-v7"]);
    assert_eq!(code, 0, "{err}");
    let row = out
        .lines()
        .find(|l| l.starts_with("| Timing |"))
        .expect("a timing row");
    assert!(
        row.contains(
            "master waits 24 bit times + 10 ms after each reply (`003_8bcf5d50afb8e230.txt:284`)"
        ),
        "{row}"
    );
}
