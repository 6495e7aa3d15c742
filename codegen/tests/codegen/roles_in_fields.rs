//! The generated `ROLES` of a map with a number role on a field and a reset whose edge or level
//! the manual does not print (the brenner-fx4 fixture): both are in the generated constants, and
//! the module is the same plan the map lowers to (the `drive_trait` tests run compiled drives).

use drivemap_test_support::paths;

use drivemap_codegen::generate::{Options, drive_module};

#[test]
fn a_number_field_and_an_unknown_edge_are_generated() {
    let drive = drivemap_map::Loader::new()
        .load(&paths::fixture("brenner-fx4/brenner-fx4.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let options = Options {
        runtime: "::drivemap_runtime".parse().unwrap(),
        source_name: "brenner-fx4.yaml".into(),
    };
    let code = drive_module(&drive, &options).unwrap();
    // The line with `needle` and the lines that continue it (a line longer than the printer's
    // width goes on, deeper indented, on the next), joined.
    let line = |needle: &str| {
        let lines: Vec<&str> = code.lines().collect();
        let first = lines
            .iter()
            .position(|l| l.contains(needle))
            .unwrap_or_else(|| panic!("no line with {needle} in:\n{code}"));
        let indent = |l: &str| l.len() - l.trim_start().len();
        let mut joined = lines[first].trim().to_owned();
        for l in &lines[first + 1..] {
            if indent(l) <= indent(lines[first]) {
                break;
            }
            joined.push(' ');
            joined.push_str(l.trim());
        }
        joined
    };
    let row = drive
        .plan()
        .registers
        .iter()
        .position(|r| r.info.id == "state_word")
        .unwrap();
    assert_eq!(
        line("role: Role::FaultCode"),
        format!(
            "/* state_word, signed bits 8-15 */ Place {{ role: Role::FaultCode, target: Target::NumberField(NumberField {{ row: {row}, lsb: 8, width: 8, signed: true, scale: Decimal::new(1, 0) }}), transports: Transports::ALL, source: \"brenner-fx4.txt:17\", shared_with: None }},"
        )
    );
    assert!(
        line("role: Role::FaultReset").contains(
            "edge: Edge::NotPrinted(\"the guide names the bit (1 = reset) but not whether the drive acts on its 0 to 1 transition or while it is 1\")"
        ),
        "{}",
        line("role: Role::FaultReset")
    );
    assert!(
        code.contains("use super::rt::roles::{Edge, FieldRole, NumberField, Place, Role, Target};"),
        "{code}"
    );
}
