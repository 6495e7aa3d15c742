//! `drivemap diff` reports a change to indexed access (`indexed:`) on the fictional Tarrow TM-44
//! (`tests/fixtures/tarrow-tm44`): an entry re-indexed, re-ranged, added or removed is an
//! "indexed access changed" (breaking); a citation moved is a "citation changed".

use drivemap_map::validate::Context;
use drivemap_review::diff::{self, render};

fn fixture() -> String {
    std::fs::read_to_string("../tests/fixtures/tarrow-tm44/tarrow-tm44.yaml").unwrap()
}

fn read(text: &str) -> drivemap_map::Drive {
    drivemap_map::read_map_str("tarrow-tm44.yaml", text, &Context::default())
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
