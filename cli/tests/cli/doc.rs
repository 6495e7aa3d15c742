//! `drivemap doc`: the Markdown reference of a fixture map (golden), and the committed
//! references of every shipped map (regenerated and compared).

use crate::common;

use std::path::Path;

use common::{drivemap_in, repo};

/// `drivemap ARGS` in the workspace root.
fn drivemap(args: &[&str]) -> (i32, String, String) {
    drivemap_in(&repo(), args)
}

#[test]
fn fixture_reference_golden() {
    let (code, out, err) = drivemap(&["doc", "tests/fixtures/crafted/cli/example-drive.yaml"]);
    assert_eq!(code, 0, "{err}");
    insta::assert_snapshot!("example_drive_doc", out);
}

use crate::new_map;

type Run<'a> = &'a dyn Fn(&[&str]) -> (i32, String, String);

/// Every map of `root/maps` has its reference `root/docs/drives/<id>.md` as `drivemap doc`
/// makes it (run in `root`), and every reference documents a map. Returns the ids.
fn every_reference_is_current(root: &Path, run: Run<'_>) -> Vec<String> {
    let docs = root.join("docs").join("drives");
    let mut ids = Vec::new();
    let mut stale = Vec::new();
    for path in drivemap_map::find_maps(&root.join("maps")).expect("maps directory") {
        let id = path.file_stem().unwrap().to_string_lossy().into_owned();
        let (code, fresh, err) = run(&["doc", "--maps", "maps", "--drive", &id]);
        assert_eq!(code, 0, "drivemap doc --drive {id} failed: {err}");
        let committed = std::fs::read_to_string(docs.join(format!("{id}.md"))).unwrap_or_default();
        if committed != fresh {
            stale.push(format!(
                "docs/drives/{id}.md is stale: run `drivemap doc --maps maps --drive {id} --docs docs`"
            ));
        }
        ids.push(id);
    }
    for entry in std::fs::read_dir(&docs).expect("docs/drives") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if let Some(id) = name.strip_suffix(".md")
            && !ids.iter().any(|i| i == id)
        {
            stale.push(format!("docs/drives/{name} documents no map in maps/"));
        }
    }
    assert!(stale.is_empty(), "{}", stale.join("\n"));
    ids
}

#[test]
fn shipped_map_references_are_current() {
    let ids = every_reference_is_current(&repo(), &drivemap);
    assert!(ids.len() >= 5, "expected the shipped maps, found {ids:?}");
}

/// A map added to `maps/` has its reference compared by the same test once `drivemap doc
/// --docs` made it; before, the test names the command to run.
#[test]
fn a_new_map_is_documented_with_no_test_edit() {
    let n = new_map::NewMap::new("doc");
    let ids = every_reference_is_current(&n.root, &|a| n.drivemap(a));
    assert!(ids.iter().any(|i| i == n.id), "{ids:?}");
    std::fs::remove_file(n.root.join(format!("docs/drives/{}.md", n.id))).unwrap();
    let stale =
        std::panic::catch_unwind(|| every_reference_is_current(&n.root, &|a| n.drivemap(a)))
            .expect_err("a missing reference is stale");
    let message = stale.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(
        message.contains("docs/drives/acme-vf1.md is stale: run `drivemap doc --maps maps --drive acme-vf1 --docs docs`"),
        "{message}"
    );
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
