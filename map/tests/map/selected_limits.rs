//! A range chosen by a setting while the scale stays fixed (`limits: {selected_by, cases}`,
//! issue 38): it means exactly what a selected scale whose cases all carry the register's own
//! factor and their own limits means (one mechanism: the plan, the facts and the export are the
//! same), and what cannot be expanded is refused at its line.

use drivemap_test_support::paths;

use drivemap_map::Map;

const FIXTURE: &str = "lindgren-lg7/lindgren-lg7.yaml";

fn fixture_text() -> String {
    std::fs::read_to_string(paths::fixture(FIXTURE)).expect("the fixture")
}

fn load(text: &str) -> Result<Map, String> {
    drivemap_map::Loader::new()
        .load_str("lindgren-lg7.yaml", text)
        .map_err(|d| d.to_string())
}

/// The fixture's `limits:` form rewritten as the selected scale with per-case limits that
/// maps/README.md documents under "Scale selected by another parameter".
fn as_scale_cases(text: &str) -> String {
    let from = "        scale: 0.1\n        limits:\n          selected_by: P1300\n          cases:\n            - {when: [0, 1], min: 10.0, max: 400.0, source: \"lindgren-lg7.txt:45\"}\n            - {when: [20], min: 10.0, max: 150.0, source: \"lindgren-lg7.txt:45\"}\n";
    let to = "        scale:\n          selected_by: P1300\n          cases:\n            - {when: [0, 1], scale: 0.1, min: 10.0, max: 400.0, source: \"lindgren-lg7.txt:45\"}\n            - {when: [20], scale: 0.1, min: 10.0, max: 150.0, source: \"lindgren-lg7.txt:45\"}\n";
    assert!(text.contains(from), "the fixture's limits form changed");
    text.replace(from, to)
}

#[test]
fn limits_form_lowers_to_the_plan_of_the_scale_cases() {
    let text = fixture_text();
    let limits = load(&text).expect("the fixture loads");
    let cases = load(&as_scale_cases(&text)).expect("the scale-cases form loads");
    let a = limits.register("motor_overload_factor").unwrap();
    let b = cases.register("motor_overload_factor").unwrap();
    assert_eq!(a.plan(), b.plan(), "the same plan row");
    // The same facts, export and selector slots: nothing downstream tells them apart.
    assert_eq!(limits.export(), cases.export());
    assert_eq!(
        limits
            .selectors()
            .iter()
            .map(|r| r.id())
            .collect::<Vec<_>>(),
        vec!["control_mode"]
    );
    // The selected case's range is the plan's: 400.0 % (4000 raw) under V/f, 150.0 % under
    // vector control; the envelope is their union.
    use drivemap_core::plan::{CaseScale, Conversion};
    let Conversion::Selected { cases, .. } = a.plan().conversion else {
        panic!("a selected conversion: {:?}", a.plan().conversion);
    };
    let ranges: Vec<(Vec<u16>, i64, i64)> = cases
        .iter()
        .map(|c| match c.scale {
            CaseScale::Decimal { range, .. } => (c.codes.to_vec(), range.min, range.max),
            CaseScale::Relative(_) => panic!("a decimal case"),
        })
        .collect();
    assert_eq!(ranges, vec![(vec![0, 1], 100, 4000), (vec![20], 100, 1500)]);
    assert_eq!((a.plan().envelope.min, a.plan().envelope.max), (100, 4000));
}

/// Each refusal at the line of the key concerned, naming what to write.
#[test]
fn what_cannot_be_expanded_is_refused_at_its_line() {
    let text = fixture_text();
    let line_of = |t: &str, needle: &str| t.lines().position(|l| l.contains(needle)).unwrap() + 1;
    let cases: [(&str, &str, &str, &str); 5] = [
        (
            "        scale: 0.1\n        limits:",
            "        scale: 0.1\n        min: 10.0\n        limits:",
            "        min: 10.0",
            "which range applies",
        ),
        (
            "        scale: 0.1\n        limits:",
            "        scale: {relative_to: P1082, full_scale: 1000}\n        limits:",
            "P1082, full_scale: 1000}\n        limits:",
            "needs a fixed decimal `scale`",
        ),
        (
            "        unit: \"%\"\n        scale: 0.1\n        limits:",
            "        limits:",
            "",
            "give the register its `unit`",
        ),
        (
            "          selected_by: P1300",
            "          selected_by: P1301",
            "          selected_by: P1301",
            "P1301",
        ),
        (
            "            - {when: [20], min: 10.0, max: 150.0",
            "            - {when: [21], min: 10.0, max: 150.0",
            "            - {when: [21]",
            "21",
        ),
    ];
    for (from, to, at, says) in cases {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let err = load(&bad).expect_err(to);
        assert!(err.contains(says), "{to}: {err}");
        let line = if at.is_empty() {
            line_of(&bad, "id: motor_overload_factor") + 4
        } else {
            line_of(&bad, at.lines().last().unwrap())
        };
        assert!(
            err.contains(&format!("lindgren-lg7.yaml:{line}:")),
            "{to}: expected at line {line}: {err}"
        );
    }
}
