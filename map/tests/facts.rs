//! The facts view (`drivemap_map::facts`): one row per fact of a register, worded once and
//! cited, in the plan's row order, serializable for tools.

use std::path::Path;

use drivemap_core::ConversionKind;
use drivemap_map::facts::{self, FactKey, RegisterFacts};
use drivemap_map::validate::Context;

fn acme() -> drivemap_map::Drive {
    drivemap_map::read_map(
        Path::new("../tests/fixtures/acme-vf1/acme-vf1.yaml"),
        &Context::default(),
    )
    .unwrap_or_else(|d| panic!("{d}"))
}

fn of<'a>(all: &'a [RegisterFacts], id: &str) -> &'a RegisterFacts {
    all.iter()
        .find(|f| f.id == id)
        .unwrap_or_else(|| panic!("no facts for {id}"))
}

fn row(f: &RegisterFacts, key: FactKey) -> (&str, &str, Option<&str>) {
    let r = f
        .get(key)
        .unwrap_or_else(|| panic!("{}: no {key:?} row", f.id));
    (r.label, r.value.as_str(), r.citation.as_deref())
}

#[test]
fn a_pair_has_its_span_and_cited_width() {
    let drive = acme();
    let all = facts::facts(&drive).registers;
    let energy = of(&all, "energy_counter");
    assert_eq!(
        row(energy, FactKey::Address),
        ("address", "2200h – 2201h", None)
    );
    assert_eq!(
        row(energy, FactKey::Width),
        (
            "width",
            "32-bit pair, high word first",
            Some("acme-vf1.txt:34")
        )
    );
    assert_eq!(row(energy, FactKey::Scale), ("scale", "0.1 kWh", None));
    assert_eq!(row(energy, FactKey::Access), ("access", "read-only", None));
    assert_eq!(energy.kind, ConversionKind::Decimal);
    assert_eq!(energy.source.as_deref(), Some("acme-vf1.txt:35"));
    // A single register has no width row and one address.
    let display = of(&all, "display_status");
    assert!(display.get(FactKey::Width).is_none());
    assert_eq!(row(display, FactKey::Address).1, "2300h");
    assert_eq!(display.kind, ConversionKind::Bits);
    assert!(
        display.get(FactKey::Scale).is_none(),
        "bits have no scale row"
    );
}

#[test]
fn a_selected_scale_is_a_row_naming_the_selector_and_a_table_of_cases() {
    let drive = acme();
    let all = facts::facts(&drive).registers;
    let current = of(&all, "motor_current");
    assert_eq!(current.kind, ConversionKind::Selected);
    assert!(current.get(FactKey::Scale).is_none());
    let (label, value, _) = row(current, FactKey::SelectedBy);
    assert_eq!(label, "scale");
    assert!(value.starts_with("selected by "), "{value}");
    let cases: Vec<(&str, &str)> = current
        .cases
        .iter()
        .map(|c| (c.codes.as_str(), c.scale.as_str()))
        .collect();
    assert_eq!(cases, [("0", "1 A"), ("1", "0.1 A"), ("2", "0.01 A")]);
}

#[test]
fn read_meanings_and_repeat_rules_are_rows_with_their_citation() {
    let drive = acme();
    let all = facts::facts(&drive).registers;
    let password = of(&all, "keypad_password");
    assert_eq!(row(password, FactKey::Range).1, "0 ..= 9999");
    assert_eq!(row(password, FactKey::ReadValues).1, "0 Unlocked, 1 Locked");
    let (_, rule, cite) = row(password, FactKey::RepeatNeedsChange);
    assert!(
        rule.contains("0 is written before any other value"),
        "{rule}"
    );
    assert_eq!(cite, Some("acme-vf1.txt:51"));
}

#[test]
fn every_register_has_its_plan_row_and_the_kind_the_plan_decided() {
    let drive = acme();
    let view = facts::facts(&drive);
    assert_eq!(view.registers.len(), drive.registers.len());
    let plan = drive.plan();
    let mut rows: Vec<usize> = Vec::new();
    for (f, r) in view.registers.iter().zip(&drive.registers) {
        let row = f.row;
        assert_eq!(plan.registers[row].info.id, r.def.id, "{}", f.id);
        assert_eq!(
            f.kind,
            ConversionKind::of(&plan.registers[row].conversion),
            "{}",
            f.id
        );
        rows.push(row);
    }
    rows.sort_unstable();
    rows.dedup();
    assert_eq!(rows.len(), drive.registers.len(), "one row per register");
}

#[test]
fn the_view_serializes_with_kind_names_and_labels() {
    let drive = acme();
    let json = serde_json::to_value(facts::facts(&drive)).unwrap();
    assert_eq!(json["drive"], "acme-vf1");
    let energy = json["registers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == "energy_counter")
        .unwrap();
    assert_eq!(energy["kind"], "decimal");
    assert_eq!(energy["rows"][1]["key"], "width");
    assert_eq!(energy["rows"][1]["citation"], "acme-vf1.txt:34");
}
