//! `drivemap diff` reports a change to a ratio scale (`scale: {counts, equals}`) on the fictional
//! Borealis BF6 (`tests/fixtures/borealis-bf6`): other counts or another value they equal is a
//! scale change that names both ratios; a ratio replaced by a decimal factor is one too.

use drivemap_test_support::paths;

use drivemap_review::diff::{self, render};

fn fixture() -> String {
    std::fs::read_to_string(paths::fixture("borealis-bf6/borealis-bf6.yaml")).unwrap()
}

fn read(text: &str) -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load_str("borealis-bf6.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn diff_text(new: &str) -> String {
    let d = diff::compare(&read(&fixture()), &read(new));
    render::text(&[d], false)
}

#[test]
fn a_ratio_changed_is_reported_with_both_ratios() {
    let f = fixture();
    let unchanged = diff_text(&f);
    assert!(!unchanged.contains("scale"), "{unchanged}");
    let monitor = "address: 0x0011, access: r, unit: Hz, scale: {counts: 3600, equals: 60.0}";
    assert!(f.contains(monitor), "the fixture's output frequency moved");
    for (new, shown) in [
        (
            "scale: {counts: 6000, equals: 60.0}",
            "6000 = 60 Hz (0.01 Hz per count, exact)",
        ),
        (
            "scale: {counts: 3600, equals: 50.0}",
            "3600 = 50 Hz (1/72 (≈0.013889) Hz per count, exact)",
        ),
        ("scale: 0.01", "0.01 Hz"),
    ] {
        let changed = f.replace(
            monitor,
            &monitor.replace("scale: {counts: 3600, equals: 60.0}", new),
        );
        let out = diff_text(&changed);
        assert!(
            out.contains("output_frequency")
                && out.contains("3600 = 60 Hz (1/60 (≈0.016667) Hz per count, exact)")
                && out.contains(shown),
            "{new}: {out}"
        );
    }
}
