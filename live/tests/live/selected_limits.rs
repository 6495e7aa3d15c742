//! A range a mode parameter selects (`limits: {selected_by: P1300}`, the fictional
//! `tests/fixtures/lindgren-lg7`) in parameter sets: a restore writes the control mode before
//! the registers whose range it selects, whatever order the set lists them in.

use drivemap_test_support::paths;

use drivemap_live::paramset::restore_order;

#[test]
fn restore_writes_the_selector_before_the_ranges_it_selects() {
    let path = paths::fixture("lindgren-lg7/lindgren-lg7.yaml");
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    let regs: Vec<_> = ["maximum_frequency", "motor_overload_factor", "control_mode"]
        .iter()
        .map(|id| drive.register_by_id(id).unwrap())
        .collect();
    let order: Vec<&str> = restore_order(&drive, &regs)
        .iter()
        .map(|r| r.id())
        .collect();
    assert_eq!(order[0], "control_mode", "{order:?}");
    assert_eq!(order.len(), 3);
}
