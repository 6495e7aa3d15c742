//! Indexed access (`indexed:`) read from the fictional Tarrow TM-44 (`tests/fixtures/tarrow-tm44`,
//! register 44 selects, register 45 carries the value) and lowered once into the plan. The
//! refusals of `validate::indexed_valid` are in `tests/fixtures/crafted/errors/indexed-*`.

use drivemap_test_support::paths;

use drivemap_core::register::{Access, Table};
use drivemap_core::scale::{Decimal, RawRange};

fn drive() -> drivemap_map::Map {
    let dir = &paths::fixture("tarrow-tm44");
    drivemap_map::Loader::new()
        .manuals(dir.join("manuals"))
        .load(&dir.join("tarrow-tm44.yaml"))
        .unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn the_pair_and_its_entries_are_lowered_into_the_plan() {
    let drive = drive();
    let plan = drive.plan();
    assert_eq!(plan.indexed.len(), 1);
    let pair = &plan.indexed[0];
    assert_eq!(
        (pair.register, pair.value_address, pair.table),
        ("parameter_value", 45, Table::Holding)
    );
    assert_eq!(
        (pair.index_register, pair.index_address),
        ("parameter_index", 44)
    );
    assert!(pair.index_readable);
    assert_eq!(pair.index_range, RawRange::new(1, 40));
    assert_eq!(pair.index_below_value(), Some(true));
    assert_eq!(pair.source, "tarrow-tm44.txt:14");
    assert!(pair.unknown.unwrap().contains("reserved for factory use"));
    let listed: Vec<(u16, &str)> = pair.entries.iter().map(|e| (e.index, e.id)).collect();
    assert_eq!(
        listed,
        [
            (1, "acceleration_time"),
            (2, "deceleration_time"),
            (3, "maximum_frequency"),
            (7, "motor_rated_current"),
            (9, "slave_address"),
            (12, "total_running_hours"),
        ]
    );
    let max = pair.entry("maximum_frequency").unwrap();
    assert_eq!(max.scale, Decimal::new(1, 2));
    assert_eq!(max.range, RawRange::new(1000, 6000));
    assert_eq!(
        (max.unit, max.access, max.source),
        ("Hz", Access::ReadWrite, "tarrow-tm44.txt:20")
    );
    // The gate's rule for the entry: the value register's address, the entry's range.
    assert_eq!(
        (max.rule.register, max.rule.address, max.rule.raw),
        ("maximum_frequency", 45, max.range)
    );
    assert_eq!(max.encode(50.0), Ok(5000));
    assert!(max.encode(60.01).is_err() && max.encode(50.005).is_err());
    let hours = pair.entry("total_running_hours").unwrap();
    assert_eq!(
        (hours.access, hours.range),
        (Access::Read, RawRange::new(0, 65000))
    );
}

#[test]
fn a_pair_without_a_printed_list_keeps_its_reason() {
    let text = std::fs::read_to_string(paths::fixture("tarrow-tm44/tarrow-tm44.yaml")).unwrap();
    let start = text.find("          entries:").unwrap();
    let end = text.find("          unknown:").unwrap();
    let text = format!("{}{}", &text[..start], &text[end..])
        .replace("indices 4-6", "the manual prints no list; indices 4-6");
    let drive = drivemap_map::Loader::new()
        .load_str("tarrow-tm44.yaml", &text)
        .unwrap_or_else(|d| panic!("{d}"));
    let pair = &drive.plan().indexed[0];
    assert!(pair.entries.is_empty());
    assert!(
        pair.unknown
            .unwrap()
            .starts_with("the manual prints no list")
    );
}
