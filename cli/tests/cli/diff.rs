//! `drivemap diff` end to end: golden output in both formats, exit codes, a scale edit of a
//! shipped map, and `--git` with a variant map whose base changed.

use drivemap_test_support::paths;

use crate::common;

use std::path::Path;
use std::process::Command;

use common::{Scratch, drivemap_in, repo};

fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "`{from}` must occur once");
    text.replace(from, to)
}

/// The fixture map with one change of several kinds.
fn fixture_pair(s: &Scratch) -> (String, String) {
    let base = std::fs::read_to_string(paths::fixture("crafted/cli/example-drive.yaml")).unwrap();
    let mut new = edit(&base, "scale: 0.1, min: 50.0", "scale: 0.01, min: 50.0");
    new = edit(
        &new,
        "{id: fault_count, name: Fault count",
        "{id: fault_counter, name: Fault count",
    );
    new = edit(
        &new,
        "          - {value: 2, id: percent_of_max",
        "          - {value: 3, id: rpm, name: r/min, source: \"manual.txt:42\"}\n          - {value: 2, id: percent_of_max",
    );
    new = edit(&new, "max: 510.0", "max: 520.0");
    new = edit(
        &new,
        "    - {code: 0x22, name: Write mode error, description: Written while running, source: \"manual.txt:17\"}\n",
        "",
    );
    new = edit(
        &new,
        "source: \"manual.txt:47\"",
        "source: \"manual.txt:50\"",
    );
    std::fs::create_dir_all(s.0.join("old")).unwrap();
    std::fs::create_dir_all(s.0.join("new")).unwrap();
    std::fs::write(s.0.join("old/example-drive.yaml"), base).unwrap();
    std::fs::write(s.0.join("new/example-drive.yaml"), new).unwrap();
    (
        "old/example-drive.yaml".to_owned(),
        "new/example-drive.yaml".to_owned(),
    )
}

#[test]
fn golden_text_and_markdown() {
    let s = Scratch::new("diff-golden");
    let (old, new) = fixture_pair(&s);
    let (code, text, err) = drivemap_in(&s.0, &["diff", &old, &new]);
    assert_eq!(code, 1, "breaking changes exit 1: {err}");
    insta::assert_snapshot!("example_drive_diff_text", text);
    let (code, md, err) = drivemap_in(&s.0, &["diff", "--format", "md", &old, &new]);
    assert_eq!(code, 1, "{err}");
    insta::assert_snapshot!("example_drive_diff_md", md);
}

#[test]
fn compatible_only_exits_0_and_identical_maps_report_no_changes() {
    let s = Scratch::new("diff-compatible");
    let base = std::fs::read_to_string(paths::fixture("crafted/cli/example-drive.yaml")).unwrap();
    let new = edit(&base, "max: 510.0", "max: 520.0");
    for dir in ["old", "new"] {
        std::fs::create_dir_all(s.0.join(dir)).unwrap();
    }
    std::fs::write(s.0.join("old/example-drive.yaml"), &base).unwrap();
    std::fs::write(s.0.join("new/example-drive.yaml"), new).unwrap();
    let (old, new) = ("old/example-drive.yaml", "new/example-drive.yaml");
    let (code, out, err) = drivemap_in(&s.0, &["diff", old, new]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("example-drive: 0 breaking, 1 compatible\n"),
        "{out}"
    );
    assert!(out.contains("range widened — range (v400)"), "{out}");
    let (code, out, _) = drivemap_in(&s.0, &["diff", old, old]);
    assert_eq!(code, 0);
    assert_eq!(out, "example-drive: no changes\n");
}

#[test]
fn one_scale_edit_of_a_shipped_map_is_exactly_one_breaking_change_with_both_citations() {
    let s = Scratch::new("diff-tds");
    let original = std::fs::read_to_string(repo().join("maps/ptlk-tds-v8.yaml")).unwrap();
    let from = "{id: accel_time_1, param: Bn-01, name: Acceleration time 1, address: 0x0200, unit: s, scale: 0.1,";
    let edited = edit(&original, from, &from.replace("scale: 0.1,", "scale: 1,"));
    std::fs::write(s.0.join("ptlk-tds-v8.yaml"), edited).unwrap();
    let old = repo().join("maps/ptlk-tds-v8.yaml");
    let (code, out, err) = drivemap_in(&s.0, &["diff", old.to_str().unwrap(), "ptlk-tds-v8.yaml"]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(
        out,
        "ptlk-tds-v8: 1 breaking, 0 compatible\n\
         \x20 breaking    accel_time_1 (Bn-01): scale changed\n\
         \x20             0.1 s → 1 s\n\
         \x20             old: 002_661580cce154f322.txt:455 · new: 002_661580cce154f322.txt:455\n\
         \x20             why: the same engineering value becomes another raw word (or needs other settings)\n"
    );
    // Two versions of one map compare under any file names.
    std::fs::rename(s.0.join("ptlk-tds-v8.yaml"), s.0.join("tds-edited.yaml")).unwrap();
    let (code, renamed, err) =
        drivemap_in(&s.0, &["diff", old.to_str().unwrap(), "tds-edited.yaml"]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(renamed, out);
}

fn git(dir: &Path, args: &[&str]) {
    let ok = Command::new("git")
        .args([
            "-c",
            "user.name=drivemap test",
            "-c",
            "user.email=test@invalid",
        ])
        .args(args)
        .current_dir(dir)
        .output()
        .expect("git is needed for `drivemap diff --git`");
    assert!(
        ok.status.success(),
        "git {args:?}: {}",
        String::from_utf8_lossy(&ok.stderr)
    );
}

#[test]
fn git_revision_with_a_variant_map_reads_its_base_from_the_same_revision() {
    let s = Scratch::new("diff-git");
    let maps = s.0.join("maps");
    std::fs::create_dir_all(&maps).unwrap();
    for m in ["yaskawa-v7.yaml", "yaskawa-j7.yaml", "ptlk-tds-v8.yaml"] {
        std::fs::copy(paths::maps().join(m), maps.join(m)).unwrap();
    }
    git(&s.0, &["init", "-q"]);
    git(&s.0, &["add", "."]);
    git(&s.0, &["commit", "-q", "-m", "maps"]);
    // Edit the base map: the J7 inherits the register, so it changes too.
    let v7 = std::fs::read_to_string(maps.join("yaskawa-v7.yaml")).unwrap();
    let from =
        "name: Output Voltage (U-04)\n        address: 0x0028\n        unit: V\n        scale: 1\n";
    std::fs::write(
        maps.join("yaskawa-v7.yaml"),
        edit(&v7, from, &from.replace("scale: 1\n", "scale: 2\n")),
    )
    .unwrap();
    std::fs::remove_file(maps.join("ptlk-tds-v8.yaml")).unwrap();
    std::fs::copy(
        paths::fixture("crafted/cli/example-drive.yaml"),
        maps.join("example-drive.yaml"),
    )
    .unwrap();

    let (code, out, err) = drivemap_in(&s.0, &["diff", "--git", "HEAD", "--maps", "maps"]);
    assert_eq!(code, 1, "{err}");
    let headings: Vec<&str> = out.lines().filter(|l| !l.starts_with(' ')).collect();
    assert_eq!(
        headings,
        [
            "example-drive: 0 breaking, 1 compatible",
            "ptlk-tds-v8: 1 breaking, 0 compatible",
            "yaskawa-j7: 1 breaking, 0 compatible",
            "yaskawa-v7: 1 breaking, 0 compatible",
            "4 maps compared: 3 breaking, 1 compatible",
        ],
        "{out}"
    );
    assert!(
        out.contains("  compatible  example-drive: drive added\n"),
        "{out}"
    );
    assert!(
        out.contains("  breaking    ptlk-tds-v8: drive removed\n"),
        "{out}"
    );
    assert_eq!(
        out.matches("output_voltage: scale changed\n              1 V → 2 V\n")
            .count(),
        2,
        "{out}"
    );

    // One map, by drive id; Markdown.
    let (code, md, err) = drivemap_in(
        &s.0,
        &[
            "diff",
            "--git",
            "HEAD",
            "yaskawa-j7",
            "--maps",
            "maps",
            "--format",
            "md",
        ],
    );
    assert_eq!(code, 1, "{err}");
    assert!(
        md.starts_with("### yaskawa-j7: 1 breaking, 0 compatible\n"),
        "{md}"
    );
    assert!(
        md.contains("| **breaking** | `output_voltage` | scale changed | 1 V | 2 V |"),
        "{md}"
    );

    // A map by path, unchanged since the revision.
    let (code, out, err) = drivemap_in(&s.0, &["diff", "--git", "HEAD", "maps/yaskawa-j7.yaml"]);
    assert_eq!((code, err.as_str()), (1, ""));
    assert!(out.starts_with("yaskawa-j7: 1 breaking"), "{out}");

    // A map by path that is gone from the working tree.
    let (code, out, err) = drivemap_in(&s.0, &["diff", "--git", "HEAD", "maps/ptlk-tds-v8.yaml"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        out.starts_with(
            "ptlk-tds-v8: 1 breaking, 0 compatible\n  breaking    ptlk-tds-v8: drive removed\n"
        ),
        "{out}"
    );

    // A revision that does not exist.
    let (code, _, err) = drivemap_in(&s.0, &["diff", "--git", "no-such-rev", "--maps", "maps"]);
    assert_eq!(code, 2);
    assert!(err.contains("git ls-tree"), "{err}");
}

#[test]
fn kinds_table_lists_every_kind() {
    let (code, out, _) = drivemap_in(&repo(), &["diff", "--kinds", "--format", "md"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("| Change | Severity | Why |\n|---|---|---|\n"));
    assert!(out.contains("| scale changed | breaking |"));
    assert!(out.contains("| register added | compatible |"));
    assert!(out.lines().count() > 60);
}

/// The review: the run role deleted and reverse pointed at the run bit. Every format
/// shows both as breaking, with the manual line each side cites quoted (md, json).
#[test]
fn roles_removed_or_re_pointed_are_breaking_in_every_format_with_their_lines_quoted() {
    let s = Scratch::new("diff-roles");
    let base = std::fs::read_to_string(paths::fixture("crafted/cli/example-drive.yaml")).unwrap();
    let roles = "roles:\n  run:\n    - {register: command, field: run, source: \"manual.txt:20\"}\n  \
                 reverse:\n    - {register: command, field: reverse, source: \"manual.txt:20\"}\n  \
                 running:\n    - {register: status, field: running, source: \"manual.txt:33\"}\ngaps:";
    let old = edit(&base, "gaps:", roles);
    let mut new = edit(
        &old,
        "  run:\n    - {register: command, field: run, source: \"manual.txt:20\"}\n",
        "",
    );
    new = edit(
        &new,
        "{register: command, field: reverse,",
        "{register: command, field: run,",
    );
    new = edit(
        &new,
        "field: running, source: \"manual.txt:33\"",
        "field: running, source: \"manual.txt:34\"",
    );
    std::fs::write(s.0.join("old.yaml"), old).unwrap();
    std::fs::write(s.0.join("new.yaml"), new).unwrap();
    let manuals = paths::fixture("crafted/cli/manuals");
    let run = |format: &str| {
        let out = common::command()
            .args(["diff", "--format", format, "old.yaml", "new.yaml"])
            .current_dir(&s.0)
            .env("DRIVEMAP_MANUALS", &manuals)
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let text = run("text");
    assert!(
        text.starts_with("example-drive: 2 breaking, 1 compatible\n"),
        "{text}"
    );
    assert!(
        text.contains(
            "  breaking    roles: role removed — run\n\
             \x20             field `run` (bit 0) of command (0001h), on 1, off 0 → (none)\n\
             \x20             old: manual.txt:20 · new: —\n"
        ),
        "{text}"
    );
    assert!(
        text.contains(
            "  breaking    roles: role re-pointed — reverse\n\
             \x20             field `reverse` (bit 1) of command (0001h), on 1, off 0 → field `run` (bit 0) of command (0001h), on 1, off 0\n"
        ),
        "{text}"
    );
    assert!(
        text.contains("  compatible  roles: citation changed — running\n"),
        "{text}"
    );
    let md = run("md");
    let line20 = "“0001H \\| Operation command \\| bit 0 1: run; bit 1 1: reverse; bits 4-5 mode 0: Local, 2: Remote”";
    assert!(
        md.contains(&format!(
            "| **breaking** | `roles` | role removed — run | field `run` (bit 0) of command (0001h), on 1, off 0 | — | `manual.txt:20`: {line20} | — |"
        )),
        "{md}"
    );
    let json: serde_json::Value = serde_json::from_str(&run("json")).unwrap();
    let changes = json["drives"][0]["changes"].as_array().unwrap();
    let kinds: Vec<(&str, &str)> = changes
        .iter()
        .map(|c| (c["kind"].as_str().unwrap(), c["severity"].as_str().unwrap()))
        .collect();
    assert_eq!(
        kinds,
        [
            ("role re-pointed", "breaking"),
            ("role removed", "breaking"),
            ("citation changed", "compatible")
        ]
    );
    assert_eq!(json["breaking"], 2);
    let repointed = &changes[0];
    assert_eq!(repointed["what"], "reverse");
    assert_eq!(repointed["old_source"], "manual.txt:20");
    assert_eq!(
        repointed["old_quote"],
        "0001H | Operation command | bit 0 1: run; bit 1 1: reverse; bits 4-5 mode 0: Local, 2: Remote"
    );
    assert_eq!(repointed["at"]["file"], "new.yaml");
    assert_eq!(
        changes[2]["new_quote"],
        "0024H to 002FH: page missing from this copy"
    );
}
