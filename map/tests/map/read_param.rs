//! `read_param` (a register read from one parameter and written to another, Siemens BICO):
//! what the map may say, refused at its line otherwise; the plan row carries the read number.

use drivemap_test_support::paths;

use drivemap_map::Map;

const FIXTURE: &str = "lindgren-lg7/lindgren-lg7.yaml";

fn load(text: &str) -> Result<Map, String> {
    drivemap_map::Loader::new()
        .load_str("lindgren-lg7.yaml", text)
        .map_err(|d| d.to_string())
}

#[test]
fn the_plan_row_carries_the_read_parameter() {
    let drive = load(&std::fs::read_to_string(paths::fixture(FIXTURE)).unwrap()).unwrap();
    let r = drive.register("r0055.8").expect("found by its read number");
    assert_eq!(r.id(), "fixed_frequency_bit_0");
    assert_eq!(
        (r.param(), r.read_param()),
        (Some("P2200"), Some("r0055.8"))
    );
    assert_eq!(r.plan().read_param, Some("r0055.8"));
    assert_eq!(drive.register("P1300").unwrap().plan().read_param, None);
}

#[test]
fn what_it_cannot_say_is_refused_at_its_line() {
    let text = std::fs::read_to_string(paths::fixture(FIXTURE)).unwrap();
    let at = "        read_param: r0055.8";
    let line = text.lines().position(|l| l == at).unwrap() + 1;
    let cases: [(&str, &str, &str); 4] = [
        ("        param: P2200\n", "", "needs `param`"),
        (
            "        read_param: r0055.8",
            "        read_param: P2200",
            "leave `read_param` out",
        ),
        (
            "        name: Fixed frequency bit 0\n",
            "        name: Fixed frequency bit 0\n        access: r\n",
            "read and written",
        ),
        // A selector read from another parameter than the one written.
        (
            "      - id: control_mode\n        param: P1300\n",
            "      - id: control_mode\n        param: P1300\n        read_param: r0050\n",
            "cannot select a scale",
        ),
    ];
    for (from, to, says) in cases {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let err = load(&bad).expect_err(to);
        assert!(err.contains(says), "{to}: {err}");
        let expect = bad
            .lines()
            .position(|l| {
                l.starts_with("        read_param:")
                    && (to.contains(l) || l == at || l.contains("P2200"))
            })
            .map(|i| i + 1)
            .unwrap_or(line);
        assert!(
            err.contains(&format!("lindgren-lg7.yaml:{expect}:")),
            "{to}: at {expect}: {err}"
        );
    }
}
