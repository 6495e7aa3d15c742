//! `drivemap export --format facts`: the facts view of a map as JSON — per register its plan
//! row, conversion kind and rows of label, value and citation — the same words the rustdoc,
//! `drivemap doc` and `drivemap diff` print.

use drivemap_test_support::paths;

use crate::common;

use serde_json::Value;

use common::drivemap_builtin;

fn register<'a>(facts: &'a Value, id: &str) -> &'a Value {
    facts["registers"]
        .as_array()
        .expect("registers")
        .iter()
        .find(|r| r["id"] == id)
        .unwrap_or_else(|| panic!("no register {id}"))
}

fn row<'a>(r: &'a Value, key: &str) -> &'a Value {
    r["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .find(|x| x["key"] == key)
        .unwrap_or_else(|| panic!("{}: no {key} row", r["id"]))
}

#[test]
fn the_facts_of_a_map_are_rows_with_their_citations() {
    let map = paths::fixture("acme-vf1/acme-vf1.yaml");
    let (code, out, err) =
        drivemap_builtin(&["export", "--format", "facts", map.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let facts: Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(facts["drive"], "acme-vf1");
    let energy = register(&facts, "energy_counter");
    assert_eq!(energy["kind"], "decimal");
    assert_eq!(row(energy, "address")["value"], "2200h – 2201h");
    assert_eq!(row(energy, "width")["citation"], "acme-vf1.txt:34");
    assert_eq!(row(energy, "scale")["value"], "0.1 kWh");
    let current = register(&facts, "motor_current");
    assert_eq!(current["kind"], "selected");
    assert_eq!(current["cases"].as_array().map(Vec::len), Some(3));
    let password = register(&facts, "keypad_password");
    assert_eq!(
        row(password, "repeat_needs_change")["citation"],
        "acme-vf1.txt:51"
    );
    // Every register has its plan row.
    for r in facts["registers"].as_array().unwrap() {
        assert!(r["row"].is_u64(), "{}: no plan row", r["id"]);
    }
    // The protocol: one row per fact, worded as `drivemap doc` prints it, with its citation.
    let protocol = facts["protocol"]["rows"].as_array().expect("protocol rows");
    let per_request = protocol
        .iter()
        .find(|r| r["key"] == "registers_per_request")
        .expect("registers per request");
    assert_eq!(per_request["value"], "at most 16 per read, 16 per write");
    assert_eq!(per_request["citation"], "acme-vf1.txt:8");
    let slave = protocol
        .iter()
        .find(|r| r["key"] == "slave_address")
        .unwrap();
    assert_eq!(
        slave["figure"]["range"],
        serde_json::json!({"min": 1, "max": 254})
    );
    assert_eq!(slave["not_printed"], Value::Null);
}

#[test]
fn facts_refuse_poller_options_like_the_json_export() {
    let map = paths::fixture("acme-vf1/acme-vf1.yaml");
    let (code, _, err) = drivemap_builtin(&[
        "export",
        "--format",
        "facts",
        "--all",
        map.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("--register, --all and a link"), "{err}");
}
