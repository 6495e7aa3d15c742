//! `drivemap diff` reports a change to indexed access (`indexed:`) on the fictional Tarrow TM-44
//! (`tests/fixtures/tarrow-tm44`): an entry re-indexed, re-ranged, added or removed is an
//! "indexed access changed" (breaking); a citation moved is a "citation changed".

use drivemap_test_support::paths;

use drivemap_review::diff::{self, render};

fn fixture() -> String {
    std::fs::read_to_string(paths::fixture("tarrow-tm44/tarrow-tm44.yaml")).unwrap()
}

fn read(text: &str) -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load_str("tarrow-tm44.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn diff_text(new: &str) -> String {
    let d = diff::compare(&read(&fixture()), &read(new));
    render::text(&[d], false)
}

#[test]
fn an_entry_changed_added_or_removed_is_reported() {
    let f = fixture();
    assert!(!diff_text(&f).contains("indexed"), "{}", diff_text(&f));
    let reindexed = f.replace(
        "{index: 3, id: maximum_frequency",
        "{index: 4, id: maximum_frequency",
    );
    let out = diff_text(&reindexed);
    assert!(out.contains("indexed access changed"), "{out}");
    assert!(
        out.contains("3 maximum_frequency") && out.contains("4 maximum_frequency"),
        "{out}"
    );
    let ranged = f.replace("min: 10.0, max: 60.0", "min: 10.0, max: 50.0");
    let out = diff_text(&ranged);
    assert!(
        out.contains("indexed access changed") && out.contains("10..=50"),
        "{out}"
    );
    let removed: String = f
        .lines()
        .filter(|l| !l.contains("id: slave_address"))
        .map(|l| format!("{l}\n"))
        .collect();
    let out = diff_text(&removed);
    assert!(
        out.contains("indexed access changed") && out.contains("9 slave_address"),
        "{out}"
    );
    let gone: String = f
        .lines()
        .take_while(|l| l.trim() != "indexed:")
        .map(|l| format!("{l}\n"))
        .collect();
    let out = diff_text(&gone);
    assert!(
        out.contains("indexed access changed") && out.contains("none"),
        "{out}"
    );
}

#[test]
fn a_citation_moved_is_a_citation_change() {
    let moved = fixture().replace("tarrow-tm44.txt:21\"}", "tarrow-tm44.txt:22\"}");
    let out = diff_text(&moved);
    assert!(out.contains("citation changed"), "{out}");
    assert!(!out.contains("indexed access changed"), "{out}");
}

/// The export lists the pair with its entries (engineering and raw limits, access, citation)
/// and the `unknown` reason; the Markdown reference prints them in an "Indexed access" section.
#[test]
fn export_and_doc_show_the_pair_and_its_entries() {
    let drive = read(&fixture());
    let export = drive.export();
    let pair = &export["indexed"][0];
    assert_eq!(pair["register"], "parameter_value");
    assert_eq!(pair["value_address"], 45);
    assert_eq!(pair["index_register"], "parameter_index");
    assert_eq!(pair["index_address"], 44);
    assert_eq!(pair["index_readable"], true);
    assert_eq!(
        (pair["index_min"].clone(), pair["index_max"].clone()),
        (1.into(), 40.into())
    );
    assert_eq!(pair["source"], "tarrow-tm44.txt:14");
    assert!(
        pair["unknown"]
            .as_str()
            .unwrap()
            .contains("reserved for factory use")
    );
    let max = &pair["entries"][2];
    assert_eq!(max["id"], "maximum_frequency");
    assert_eq!(max["index"], 3);
    assert_eq!(
        (max["raw_min"].clone(), max["raw_max"].clone()),
        (1000.into(), 6000.into())
    );
    assert_eq!(max["access"], "rw");
    assert_eq!(pair["entries"][5]["access"], "r");
    assert_eq!(max["source"], "tarrow-tm44.txt:20");
    let doc = drivemap_review::reference::render(&drive, "tarrow-tm44.yaml");
    assert!(doc.contains("## Indexed access"), "{doc}");
    assert!(doc.contains("Write the entry's index to `parameter_index` (44 (002Ch)), then read or write `parameter_value` (45 (002Dh))"), "{doc}");
    assert!(
        doc.contains("| 3 | `maximum_frequency` | Maximum frequency | Hz | 0.01 | 10 ..= 60 Hz | R/W | `tarrow-tm44.txt:20` |"),
        "{doc}"
    );
    assert!(
        doc.contains("| 12 | `total_running_hours` | Total running hours | h | 1 |"),
        "{doc}"
    );
    assert!(doc.contains("Entries not listed: indices 4-6"), "{doc}");
    // A map without pairs exports an empty list and prints no section.
    let plain: String = fixture()
        .lines()
        .take_while(|l| l.trim() != "- id: parameter_value")
        .map(|l| format!("{l}\n"))
        .collect();
    let drive = read(&plain);
    assert_eq!(drive.export()["indexed"], serde_json::json!([]));
    assert!(!drivemap_review::reference::render(&drive, "x.yaml").contains("Indexed access"));
}
