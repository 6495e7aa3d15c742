//! `diff` reports a protocol fact becoming not printed (`unknown:`) or printed again, with the
//! reasons as the two sides, and the change of working figure it brings on its own. The map is
//! the fixture `tests/fixtures/halden-h1` (every protocol fact `unknown:`).

use drivemap_test_support::paths;

use drivemap_review::diff::{ChangeKind, compare};

fn halden(replace: &[(&str, &str)]) -> drivemap_map::Map {
    let mut text = std::fs::read_to_string(paths::fixture("halden-h1/halden-h1.yaml")).unwrap();
    for (from, to) in replace {
        let line = text
            .lines()
            .find(|l| l.starts_with(from))
            .unwrap_or_else(|| panic!("no line {from}"))
            .to_owned();
        text = text.replace(&line, to);
    }
    drivemap_map::Loader::new()
        .load_str("halden-h1.yaml", &text)
        .unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn a_fact_becoming_printed_or_not_printed_is_reported_with_its_reason() {
    let unknown = halden(&[]);
    let printed = halden(&[
        (
            "  slave_address:",
            "  slave_address: {min: 1, max: 31, source: \"halden-h1.txt:7\"}",
        ),
        (
            "  timing:",
            "  timing: {frame_gap_chars: 3.5, source: \"halden-h1.txt:9\"}",
        ),
    ]);
    let d = compare(&unknown, &printed);
    let find = |what: &str| {
        d.changes
            .iter()
            .find(|c| c.what == what)
            .unwrap_or_else(|| panic!("no `{what}` in {:#?}", d.changes))
    };
    let slave = find("slave_address: not printed");
    assert_eq!(slave.kind, ChangeKind::DocumentationChanged);
    assert_eq!(
        slave.old.as_deref(),
        Some("set with F-20, whose settings the note does not list")
    );
    assert_eq!(slave.new.as_deref(), Some("printed"));
    // The working range 1 ..= 247 becomes the printed 1 ..= 31: a change of its own.
    let range = find("slave address");
    assert_eq!(range.kind, ChangeKind::SlaveRangeNarrowed);
    assert_eq!(range.old.as_deref(), Some("1 ..= 247"));
    assert_eq!(range.new.as_deref(), Some("1 ..= 31"));
    let timing = find("timing: not printed");
    assert_eq!(timing.new.as_deref(), Some("printed"));

    // The other way: the fact becomes not printed.
    let back = compare(&printed, &unknown);
    let slave = back
        .changes
        .iter()
        .find(|c| c.what == "slave_address: not printed")
        .unwrap();
    assert_eq!(slave.old.as_deref(), Some("printed"));
    assert_eq!(slave.new_source.as_deref(), Some("halden-h1.txt:7"));
    // Only the reason changes: reported too.
    let reworded = halden(&[(
        "  exceptions:",
        "  exceptions: {unknown: \"no exception codes are printed\", source: \"halden-h1.txt:9\"}",
    )]);
    let d = compare(&unknown, &reworded);
    assert!(
        d.changes.iter().any(|c| c.what == "exceptions: not printed"
            && c.new.as_deref() == Some("no exception codes are printed")),
        "{:#?}",
        d.changes
    );
    // Nothing changed: nothing reported.
    assert!(compare(&unknown, &halden(&[])).changes.is_empty());
}
