//! Review against the manual: citations checked by content (`drivemap check`), uncited rows
//! (`drivemap coverage`), the manual's words in `drivemap diff` (Markdown and GitHub
//! annotations). The fixture map `fixtures/example-drive.yaml` cites `fixtures/manuals/manual.txt`.

use drivemap_test_support::paths;

use crate::common;
use crate::new_map;

use std::path::{Path, PathBuf};

use common::{Scratch, command, repo, run};

fn fixture_manuals() -> PathBuf {
    paths::fixture("crafted/cli/manuals")
}

/// Runs drivemap in `dir`; `manuals` sets `DRIVEMAP_MANUALS`.
fn drivemap(dir: &Path, manuals: Option<&Path>, args: &[&str]) -> (i32, String, String) {
    let mut cmd = command();
    cmd.args(args).current_dir(dir);
    if let Some(m) = manuals {
        cmd.env("DRIVEMAP_MANUALS", m);
    }
    run(&mut cmd)
}

fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "`{from}` must occur once");
    text.replace(from, to)
}

fn fixture() -> String {
    std::fs::read_to_string(paths::fixture("crafted/cli/example-drive.yaml")).unwrap()
}

const MAX_VOLTAGE_SOURCE: &str = "        source: \"manual.txt:41\"\n      - id: frequency_units";

#[test]
fn the_fixture_map_verifies_against_its_manual() {
    let (code, out, err) = drivemap(
        &repo(),
        Some(&fixture_manuals()),
        &[
            "check",
            "--strict",
            "tests/fixtures/crafted/cli/example-drive.yaml",
        ],
    );
    assert_eq!((code, err.as_str()), (0, ""), "{out}");
    assert_eq!(
        out,
        "ok   tests/fixtures/crafted/cli/example-drive.yaml (example-drive: 19 registers; \
         protocol 13 of 13, conflicts 4 of 4, gaps 1 of 1 verified; \
         citations: 47 of 47 verified, 0 indirect, 0 unverified)\n"
    );
}

#[test]
fn a_citation_moved_to_the_next_row_is_reported_with_the_line_and_whose_row_it_is() {
    let s = Scratch::new("review-moved");
    let moved = edit(
        &fixture(),
        MAX_VOLTAGE_SOURCE,
        &MAX_VOLTAGE_SOURCE.replace(":41", ":42"),
    );
    std::fs::write(s.0.join("example-drive.yaml"), moved).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["check", "example-drive.yaml"],
    );
    assert_eq!(code, 0, "unverified citations are warnings: {err}");
    assert_eq!(
        err,
        "example-drive.yaml:132:9: warning in register `max_voltage`: citation `manual.txt:42` \
         does not mention P-02, 0101h, \"Maximum voltage\": \
         `P-03 | 0102H | Frequency units | 0: 0.1 Hz 1: 0.01 Hz 2: 30000 = 100 % | 0` \
         (the row of `frequency_units (P-03)`); fix the line, or mark it `indirect: <reason>`\n"
    );
    assert!(
        out.contains("46 of 47 verified, 0 indirect, 1 unverified"),
        "{out}"
    );

    let (code, out, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["check", "--strict", "example-drive.yaml"],
    );
    assert_eq!(code, 1, "{out}");
    assert!(
        err.starts_with(
            "example-drive.yaml:132:9: error in register `max_voltage`: citation `manual.txt:42`"
        ),
        "{err}"
    );
    assert!(out.starts_with("FAIL example-drive.yaml"), "{out}");
}

#[test]
fn an_indirect_citation_with_its_reason_is_accepted_and_counted() {
    let s = Scratch::new("review-indirect");
    let marked = edit(
        &fixture(),
        MAX_VOLTAGE_SOURCE,
        &MAX_VOLTAGE_SOURCE.replace(
            "        source: \"manual.txt:41\"",
            "        indirect: \"the fixture's deliberate example of an indirect citation\"\n        source: \"manual.txt:42\"",
        ),
    );
    std::fs::write(s.0.join("example-drive.yaml"), &marked).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["check", "--strict", "example-drive.yaml"],
    );
    assert_eq!((code, err.as_str()), (0, ""), "{out}");
    assert!(
        out.contains("46 of 47 verified, 1 indirect, 0 unverified"),
        "{out}"
    );

    // Without a reason it is a validation error.
    let empty = marked.replace(
        "\"the fixture's deliberate example of an indirect citation\"",
        "\"\"",
    );
    std::fs::write(s.0.join("example-drive.yaml"), empty).unwrap();
    let (code, _, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["check", "example-drive.yaml"],
    );
    assert_eq!(code, 1);
    assert!(
        err.contains(
            "example-drive.yaml:132:9: error in register `max_voltage`: `indirect` needs a reason"
        ),
        "{err}"
    );
}

#[test]
fn a_row_the_map_leaves_out_is_reported_with_its_table() {
    let s = Scratch::new("review-coverage");
    let text = fixture();
    let start = text.find("      - id: carrier_frequency\n").unwrap();
    let end = text[start..].find("  - id: commands\n").unwrap() + start;
    let without = format!("{}{}", &text[..start], &text[end..]);
    std::fs::write(s.0.join("example-drive.yaml"), without).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["coverage", "example-drive.yaml"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("example-drive: 5 tables, 18 rows, 16 cited, 1 gaps, 1 uncited\n"),
        "{out}"
    );
    assert!(
        out.contains("  manual.txt:40-48  Parameters                               rows    9  cited    8  gaps   0  uncited   1\n"),
        "{out}"
    );
    assert!(
        out.ends_with(
            "uncited manual.txt:48  P-10  `P-10 | 0109H | Carrier frequency | 1.0 to 15.0 kHz`\n"
        ),
        "{out}"
    );
    // The whole map covers every row; the page-missing line is a gap.
    std::fs::write(s.0.join("example-drive.yaml"), fixture()).unwrap();
    let (_, out, _) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["coverage", "example-drive.yaml"],
    );
    assert!(
        out.starts_with("example-drive: 5 tables, 18 rows, 17 cited, 1 gaps, 0 uncited\n"),
        "{out}"
    );
}

/// The fixture with a scale edit and a citation moved to the next row.
fn diff_pair(s: &Scratch) {
    let base = fixture();
    let mut new = edit(&base, "scale: 0.1, min: 50.0", "scale: 0.01, min: 50.0");
    new = edit(
        &new,
        "source: \"manual.txt:47\"",
        "source: \"manual.txt:48\"",
    );
    for dir in ["old", "new"] {
        std::fs::create_dir_all(s.0.join(dir)).unwrap();
    }
    std::fs::write(s.0.join("old/example-drive.yaml"), base).unwrap();
    std::fs::write(s.0.join("new/example-drive.yaml"), new).unwrap();
}

#[test]
fn diff_markdown_quotes_the_manual_line_of_both_sides() {
    let s = Scratch::new("review-diff-md");
    diff_pair(&s);
    let (code, md, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &[
            "diff",
            "--format",
            "md",
            "old/example-drive.yaml",
            "new/example-drive.yaml",
        ],
    );
    assert_eq!(code, 1, "a breaking change still exits 1: {err}");
    assert!(
        md.contains(
            "| compatible | `accel_time (P-08)` | citation changed | — | — | \
             `manual.txt:47`: “P-08 \\| 0107H \\| Acceleration time \\| 0.0 to 600.0 s (whole seconds from 100 s) \\| 10.0” | \
             `manual.txt:48`: “P-10 \\| 0109H \\| Carrier frequency \\| 1.0 to 15.0 kHz” |"
        ),
        "{md}"
    );
    assert!(
        md.contains(
            "| **breaking** | `max_frequency (P-01)` | scale changed | 0.1 Hz | 0.01 Hz | \
             `manual.txt:40`: “P-01 \\| 0100H \\| Maximum frequency \\| 50.0 to 400.0 Hz \\| 0.1 Hz \\| 60.0” | \
             `manual.txt:40`: “P-01 \\| 0100H \\| Maximum frequency \\| 50.0 to 400.0 Hz \\| 0.1 Hz \\| 60.0” |"
        ),
        "{md}"
    );
}

#[test]
fn diff_github_annotations_are_exact() {
    let s = Scratch::new("review-diff-github");
    diff_pair(&s);
    let (code, out, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &[
            "diff",
            "--format",
            "github",
            "old/example-drive.yaml",
            "new/example-drive.yaml",
        ],
    );
    assert_eq!(code, 1, "{err}");
    insta::assert_snapshot!("example_drive_diff_github", out);
    // Only compatible changes: warnings, exit 0.
    let base = fixture();
    std::fs::write(
        s.0.join("new/example-drive.yaml"),
        edit(
            &base,
            "source: \"manual.txt:47\"",
            "source: \"manual.txt:48\"",
        ),
    )
    .unwrap();
    let (code, out, _) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &[
            "diff",
            "--format",
            "github",
            "old/example-drive.yaml",
            "new/example-drive.yaml",
        ],
    );
    assert_eq!(code, 0);
    assert!(
        out.starts_with("::warning file=new/example-drive.yaml,line="),
        "{out}"
    );
    assert_eq!(out.lines().count(), 1, "{out}");
}

type Run<'a> = &'a dyn Fn(&[&str]) -> (i32, String, String);

/// The drive ids of the maps in `root/maps`.
fn map_ids(root: &Path) -> Vec<String> {
    drivemap_map::find_maps(&root.join("maps"))
        .expect("maps/")
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect()
}

/// `check --strict` on every map of `root/maps` (run in `root`): all pass, none with an
/// unverified citation. Returns the standard error.
fn every_map_checks_strictly(root: &Path, run: Run<'_>) -> String {
    let files: Vec<String> = map_ids(root)
        .iter()
        .map(|m| format!("maps/{m}.yaml"))
        .collect();
    let mut args = vec!["check", "--strict"];
    args.extend(files.iter().map(String::as_str));
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(out.matches(", 0 unverified)").count(), files.len(), "{out}");
    err
}

/// Every map of `root/maps` has a coverage document `root/docs/coverage/<id>.md` whose
/// generated section is the tool's report.
fn every_coverage_document_is_current(root: &Path, run: Run<'_>) {
    for m in map_ids(root) {
        let doc = format!("docs/coverage/{m}.md");
        let (code, out, err) = run(&["coverage", &m, "--maps", "maps", "--check", &doc]);
        assert_eq!(code, 0, "{m}: {out}{err}");
    }
}

#[test]
fn every_citation_of_the_shipped_maps_verifies_or_is_marked_indirect() {
    let err = every_map_checks_strictly(&repo(), &|a| drivemap(&repo(), None, a));
    // What stderr says: the ACN's printed station IDs 1-250 go beyond Modbus's 247, which is
    // warned about, never refused (`--strict` included); and the manuals' example frames that
    // contradict their maps, each recorded in `conflicts:` (the 003 manual's loop-back fault
    // CRC, in the V7 and J7 maps; the TDS-V8 PLC steps writing its reserved 0002H-0006H), one
    // warning per frame. Nothing else.
    let (acn, frames): (Vec<&str>, Vec<&str>) = err
        .lines()
        .partition(|l| l.starts_with("maps/automationdirect-acn.yaml"));
    assert_eq!(
        acn,
        [
            "maps/automationdirect-acn.yaml:33:27: warning: slave addresses 248..=250 are the \
          manual's, but the Modbus serial-line specification reserves 248-255 (unicast \
          1-247): a standard master or gateway may not reach them"
        ],
        "{err}"
    );
    let recorded: Vec<(&str, &str)> = frames
        .iter()
        .map(|l| {
            assert!(l.contains("; recorded in `conflicts:` as \""), "{l}");
            let map = l.split(':').next().unwrap();
            let id = l.split('`').nth(1).unwrap_or_else(|| panic!("{l}"));
            (map, id)
        })
        .collect();
    assert_eq!(
        recorded,
        [
            ("maps/ptlk-tds-v8.yaml", "plc_step1_command"),
            ("maps/ptlk-tds-v8.yaml", "plc_step2_command"),
            ("maps/ptlk-tds-v8.yaml", "plc_step3_command"),
            ("maps/yaskawa-j7.yaml", "memobus_loop_back_fault_response"),
            ("maps/yaskawa-v7.yaml", "memobus_loop_back_fault_response"),
        ],
        "{err}"
    );
}

#[test]
fn the_coverage_documents_are_the_tools_report() {
    every_coverage_document_is_current(&repo(), &|a| drivemap(&repo(), None, a));
}

/// A map added to `maps/` (and its documents made by `drivemap doc --docs`) is checked and its
/// coverage compared by the same tests, with no edit of them.
#[test]
fn a_new_map_is_checked_and_its_coverage_compared_with_no_test_edit() {
    let n = new_map::NewMap::new("review");
    let run = |a: &[&str]| n.drivemap(a);
    assert!(map_ids(&n.root).iter().any(|m| m == n.id));
    every_map_checks_strictly(&n.root, &run);
    every_coverage_document_is_current(&n.root, &run);
    // And the documents are the command's: a stale one fails.
    let doc = n.root.join(format!("docs/coverage/{}.md", n.id));
    let text = std::fs::read_to_string(&doc).unwrap();
    assert!(text.contains("Total: "), "{text}");
    std::fs::write(&doc, text.replacen("Total: ", "Total: 1 ", 1)).unwrap();
    let (code, _, err) = n.drivemap(&[
        "coverage",
        n.id,
        "--maps",
        "maps",
        "--check",
        &format!("docs/coverage/{}.md", n.id),
    ]);
    assert_eq!(code, 1, "{err}");
}

#[test]
fn strict_without_the_manuals_fails_and_plain_check_does_not() {
    let s = Scratch::new("review-no-manuals");
    std::fs::write(s.0.join("example-drive.yaml"), fixture()).unwrap();
    let (code, out, err) = drivemap(&s.0, None, &["check", "--strict", "example-drive.yaml"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        err.starts_with(
            "example-drive.yaml: error: --strict, but none of the map's manuals is at hand"
        ),
        "{err}"
    );
    let (code, out, _) = drivemap(&s.0, None, &["check", "example-drive.yaml"]);
    assert_eq!(
        (code, out.as_str()),
        (
            0,
            "ok   example-drive.yaml (example-drive: 19 registers; citations not verified: no \
             manuals directory found (set DRIVEMAP_MANUALS, or put the manuals in shared/manuals \
             beside the repository))\n"
        )
    );
}

/// Without its manuals, `check` says on every run that citations were not verified and why
/// (no directory found, a wrong DRIVEMAP_MANUALS, the manual missing from it); with
/// `--require-manuals` that fails the map. A citation past the end of a manual that is at hand
/// is unverified, not silently passed.
#[test]
fn check_says_when_citations_are_not_verified_and_require_manuals_fails() {
    let s = Scratch::new("review-require-manuals");
    std::fs::write(s.0.join("example-drive.yaml"), fixture()).unwrap();
    let run = |manuals: Option<&Path>, args: &[&str]| {
        let mut all = vec!["check"];
        all.extend_from_slice(args);
        all.push("example-drive.yaml");
        drivemap(&s.0, manuals, &all)
    };
    let (code, out, _) = run(None, &["--require-manuals"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.starts_with("FAIL example-drive.yaml"), "{out}");
    assert!(
        out.contains("citations not verified: no manuals directory found"),
        "{out}"
    );

    let wrong = s.0.join("no-such-dir");
    let (code, out, err) = run(Some(&wrong), &[]);
    assert_eq!(code, 0, "{err}");
    let said = format!(
        "citations not verified: DRIVEMAP_MANUALS={} is not a directory",
        wrong.display()
    );
    assert!(out.contains(&said), "{out}");
    let (code, _, err) = run(Some(&wrong), &["--require-manuals"]);
    assert_eq!(code, 1);
    assert!(
        err.contains(&format!("error: --require-manuals, but {said}")),
        "{err}"
    );

    let empty = s.0.join("empty-manuals");
    std::fs::create_dir_all(&empty).unwrap();
    let (code, out, _) = run(Some(&empty), &["--require-manuals"]);
    assert_eq!(code, 1);
    assert!(
        out.contains(&format!(
            "citations not verified: none of the map's manuals (manual.txt) is in {}",
            empty.display()
        )),
        "{out}"
    );

    let (code, out, err) = run(Some(&fixture_manuals()), &["--require-manuals"]);
    assert_eq!((code, err.as_str()), (0, ""), "{out}");
    assert!(!out.contains("not verified"), "{out}");

    // Line 960 of a manual that is at hand but shorter is an error, whatever the flags.
    let past = edit(
        &fixture(),
        MAX_VOLTAGE_SOURCE,
        &MAX_VOLTAGE_SOURCE.replace(":41", ":960"),
    );
    std::fs::write(s.0.join("example-drive.yaml"), past).unwrap();
    let (code, _, err) = run(Some(&fixture_manuals()), &[]);
    assert_eq!(code, 1);
    assert!(
        err.contains("citation `manual.txt:960` points past the end of `manual.txt` (92 lines)"),
        "{err}"
    );
}

fn paged_fixture() -> String {
    std::fs::read_to_string(paths::fixture("crafted/cli/paged-manual.yaml")).unwrap()
}

/// A manual with no text at hand (`id`, `document`, `url`) is cited by page, `acme-um:p42`:
/// `check` verifies the line citations of the text manual and counts the page citations as not
/// verifiable by content, even with `--strict` and `--require-manuals`.
#[test]
fn page_citations_are_counted_not_verified_by_content() {
    let (code, out, err) = drivemap(
        &repo(),
        Some(&fixture_manuals()),
        &[
            "check",
            "--strict",
            "--require-manuals",
            "tests/fixtures/crafted/cli/paged-manual.yaml",
        ],
    );
    assert_eq!((code, err.as_str()), (0, ""), "{out}");
    assert_eq!(
        out,
        "ok   tests/fixtures/crafted/cli/paged-manual.yaml (paged-manual: 2 registers; \
         protocol 2 of 2 verified; citations: 4 of 7 verified, 0 indirect, 0 unverified, \
         3 page citations (not verifiable by content))\n"
    );
}

/// A map citing only manuals with no text needs no manuals directory: `--require-manuals` and
/// `--strict` pass where no manual is at hand.
#[test]
fn a_map_citing_only_pages_needs_no_manuals_directory() {
    let s = Scratch::new("review-pages-only");
    let text = paged_fixture()
        .replace("    - {file: manual.txt, title: Example manual}\n", "")
        .replace("manual.txt:19", "acme-um:p40")
        .replace("manual.txt:20", "acme-um:p41")
        .replace("manual.txt:9", "acme-um:p12");
    assert!(!text.contains("manual.txt:"), "{text}");
    std::fs::write(s.0.join("paged-manual.yaml"), text).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        None,
        &[
            "check",
            "--strict",
            "--require-manuals",
            "paged-manual.yaml",
        ],
    );
    assert_eq!((code, err.as_str()), (0, ""), "{out}");
    assert_eq!(
        out,
        "ok   paged-manual.yaml (paged-manual: 2 registers; citations: 0 of 7 verified, \
         0 indirect, 0 unverified, 7 page citations (not verifiable by content))\n"
    );
}

/// A page citation of a manual the map does not declare, or of a text manual, is an error at
/// the citation; the export carries each manual's title, document number and address.
#[test]
fn page_citations_name_a_declared_manual_and_the_export_describes_it() {
    let s = Scratch::new("review-pages-wrong");
    let text = paged_fixture().replace("acme-um:p42", "manual.txt:p42");
    std::fs::write(s.0.join("paged-manual.yaml"), text).unwrap();
    let (code, _, err) = drivemap(&s.0, None, &["check", "paged-manual.yaml"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(
            "paged-manual.yaml:40:9: error in register `acceleration_time`: citation \
             `manual.txt:p42` cites a page of `manual.txt`, a text manual: cite its line, \
             `manual.txt:<line>`"
        ),
        "{err}"
    );

    let (code, out, err) = drivemap(
        &repo(),
        None,
        &["export", "tests/fixtures/crafted/cli/paged-manual.yaml"],
    );
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        json["drive"]["manuals"],
        serde_json::json!(["manual.txt", "acme-um"])
    );
    assert_eq!(
        json["drive"]["manual_details"][1],
        serde_json::json!({
            "id": "acme-um",
            "title": "VF-1 User Manual",
            "document": "UM-1234 rev C",
            "url": "https://example.com/manuals/um-1234c.pdf"
        })
    );
    assert_eq!(
        json["drive"]["manual_details"][0],
        serde_json::json!({"file": "manual.txt", "title": "Example manual"})
    );
}

/// `check --maps DIR` on a directory with no map is an error naming the directory, not a
/// silent success that checked nothing.
#[test]
fn check_of_an_empty_maps_directory_is_an_error() {
    let s = Scratch::new("empty-maps");
    std::fs::write(s.0.join("notes.txt"), "not a map").unwrap();
    let dir = s.0.display().to_string();
    let (code, out, err) = drivemap(&s.0, None, &["check", "--maps", &dir]);
    assert_ne!(code, 0, "{out}{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains(&format!(
            "{dir}: no maps to check (no *.yaml or *.yml file in the directory)"
        )),
        "{err}"
    );
}

/// The review: a role citing the manual's title line passed `check --strict` (its
/// citations were not read). Roles, protocol items, readings of conflicts and gaps are read like
/// register citations: a citation of an unrelated line fails `--strict`, naming the item and
/// quoting the line; `indirect: <reason>` is the escape, counted as indirect.
#[test]
fn a_role_protocol_conflict_or_gap_citing_an_unrelated_line_fails_strict() {
    let s = Scratch::new("review-others");
    let manuals = paths::fixture("acme-vf1/manuals");
    let map = std::fs::read_to_string(paths::fixture("acme-vf1/acme-vf1.yaml")).unwrap();
    let title = "ACME VF-1 VARIABLE FREQUENCY DRIVE - MODBUS COMMUNICATION MANUAL";
    let role = "{register: control_word, field: run_stop, on: run, off: stop, source: \"acme-vf1.txt:16\"}";
    let slave = "slave_address: {min: 1, max: 254, default: 1, source: \"acme-vf1.txt:5\"}";
    // The counts of the fixture as it is (it grows with the schema): every citation verified.
    std::fs::write(s.0.join("acme-vf1.yaml"), &map).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&manuals),
        &["check", "--strict", "acme-vf1.yaml"],
    );
    assert_eq!(code, 0, "{out}{err}");
    let count = |out: &str, after: &str| -> usize {
        let at = out
            .find(after)
            .unwrap_or_else(|| panic!("`{after}` in {out}"));
        out[at + after.len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let (roles, protocol, all) = (
        count(&out, "roles "),
        count(&out, "protocol "),
        count(&out, "citations: "),
    );
    assert!(
        out.contains(&format!("roles {roles} of {roles}, protocol {protocol} of {protocol} verified; citations: {all} of {all} verified, 0 indirect, 0 unverified")),
        "{out}"
    );
    let mut edited = edit(
        &map,
        role,
        &role.replace("acme-vf1.txt:16", "acme-vf1.txt:1"),
    );
    edited = edit(
        &edited,
        slave,
        &slave.replace("acme-vf1.txt:5", "acme-vf1.txt:1"),
    );
    std::fs::write(s.0.join("acme-vf1.yaml"), &edited).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&manuals),
        &["check", "--strict", "acme-vf1.yaml"],
    );
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        err.contains(&format!(
            "error: citation of role `run` `acme-vf1.txt:1` does not \
             mention field \"Run/stop command\" (bits 0–1) of control_word: `{title}`"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "error: citation of the slave address `acme-vf1.txt:1` does not mention one of \
             `address`, `addresses`, `station`, `slave`, `node`: `{title}`"
        )),
        "{err}"
    );
    assert!(
        out.contains(&format!(
            "roles {} of {roles}, protocol {} of {protocol} verified; citations: {} of {all} \
             verified, 0 indirect, 2 unverified",
            roles - 1,
            protocol - 1,
            all - 2
        )),
        "{out}"
    );
    // Without --strict: warnings, exit 0.
    let (code, _, err) = drivemap(&s.0, Some(&manuals), &["check", "acme-vf1.yaml"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches(": warning: citation of").count(), 2, "{err}");
    // Marked indirect with a reason, both pass and are counted so.
    let mut indirect = edit(
        &edited,
        "on: run, off: stop, source: \"acme-vf1.txt:1\"}",
        "on: run, off: stop, indirect: \"a test of the escape\", source: \"acme-vf1.txt:1\"}",
    );
    indirect = edit(
        &indirect,
        "default: 1, source: \"acme-vf1.txt:1\"}",
        "default: 1, indirect: \"a test of the escape\", source: \"acme-vf1.txt:1\"}",
    );
    std::fs::write(s.0.join("acme-vf1.yaml"), &indirect).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&manuals),
        &["check", "--strict", "acme-vf1.yaml"],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains(&format!(
            "roles {} of {roles}, protocol {} of {protocol} verified; citations: {} of {all} \
             verified, 2 indirect, 0 unverified",
            roles - 1,
            protocol - 1,
            all - 2
        )),
        "{out}"
    );
    // A reading of a conflict and a gap citing the fixture manual's title line.
    let example = fixture();
    let mut edited = edit(
        &example,
        "{source: \"manual.txt:91\", says: \"1-32\"}",
        "{source: \"manual.txt:1\", says: \"1-32\"}",
    );
    edited = edit(
        &edited,
        "description: Page missing from the OCR text, source: \"manual.txt:34\"}",
        "description: Page missing from the OCR text, source: \"manual.txt:1\"}",
    );
    std::fs::write(s.0.join("example-drive.yaml"), &edited).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&fixture_manuals()),
        &["check", "--strict", "example-drive.yaml"],
    );
    assert_eq!(code, 1, "{out}{err}");
    let line1 = "Example drive ED-1 communication manual (fixture for the command-line tests)";
    assert!(
        err.contains(&format!(
            "error: citation of a reading of conflict \"Slave address range\" `manual.txt:1` does \
             not mention one of \"1-32\", 1-32, 1 to 32, 1 ~ 32, 1~32, 1 - 32, 1-32: `{line1}`"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "error: citation of gap 0024h – 002Fh `manual.txt:1` does not mention one of \
             \"not used\", U-05, U-16, 0024h, 002Fh, 0023h, 0030h, `reserved`, `unused`, \
             `missing`: `{line1}`"
        )),
        "{err}"
    );
    assert!(
        out.contains("protocol 13 of 13, conflicts 3 of 4, gaps 0 of 1 verified; citations: 45 of 47 verified, 0 indirect, 2 unverified"),
        "{out}"
    );
}

/// A limit through another quantity (`max_relative`) cites a line read like the others: it must
/// print the percentage or name the quantity the limit is taken of. The fixture's manual does
/// not bound its speed reference by another parameter, so the limit is added to a scratch copy.
#[test]
fn a_limit_through_another_quantity_citing_an_unrelated_line_fails_strict() {
    let s = Scratch::new("review-limit");
    let manuals = paths::fixture("acme-vf1/manuals");
    let map = std::fs::read_to_string(paths::fixture("acme-vf1/acme-vf1.yaml")).unwrap();
    let row = "        address: 0x2001\n";
    let with = |line: u32| {
        edit(
            &map,
            row,
            &format!(
                "{row}        max_relative: {{relative_to: maximum_frequency, percent: 100, \
                 source: \"acme-vf1.txt:{line}\"}}\n"
            ),
        )
    };
    // Line 22 is the row of the maximum frequency: verified.
    std::fs::write(s.0.join("acme-vf1.yaml"), with(22)).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&manuals),
        &["check", "--strict", "acme-vf1.yaml"],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("limits 1 of 1 verified"), "{out}");
    // Line 1 is the manual's title: not verified, and --strict fails naming the limit.
    std::fs::write(s.0.join("acme-vf1.yaml"), with(1)).unwrap();
    let (code, out, err) = drivemap(
        &s.0,
        Some(&manuals),
        &["check", "--strict", "acme-vf1.yaml"],
    );
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        err.contains(
            "error: citation of the limit of speed_reference through maximum_frequency \
             `acme-vf1.txt:1` does not mention"
        ),
        "{err}"
    );
    assert!(out.contains("limits 0 of 1 verified"), "{out}");
}
