//! Roles are lowered to plan rows, bit positions and codes: `tests/fixtures/crafted/maps/roles-drive.yaml`
//! read, validated and lowered, and every place of its `MapPlan::roles` checked. The errors of
//! `validate::roles_valid` are in `tests/fixtures/crafted/errors/e46-*` .. `e56-*`.

use drivemap_test_support::paths;

use drivemap_core::roles::{Edge, FieldRole, NumberField, Role, Target};
use drivemap_map::MapPlan;

fn drive() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&paths::fixture("crafted/maps/roles-drive.yaml"))
        .unwrap_or_else(|d| panic!("{d}"))
}

/// The plan row of register `id`.
fn row(plan: &MapPlan, id: &str) -> u16 {
    let i = plan
        .registers
        .iter()
        .position(|r| r.info.id == id)
        .unwrap_or_else(|| panic!("no register `{id}` in the plan"));
    u16::try_from(i).unwrap()
}

fn targets(plan: &MapPlan, role: Role) -> Vec<Target> {
    plan.roles.of(role).map(|p| p.target).collect()
}

#[test]
fn a_two_bit_run_code_lowers_to_its_row_bits_and_codes() {
    let drive = drive();
    let plan = drive.plan();
    let command = row(plan, "operation_command");
    let run = targets(plan, Role::Run);
    assert_eq!(
        run,
        [
            Target::Field(FieldRole {
                row: command,
                lsb: 4,
                width: 2,
                on: &[2],
                off: Some(1),
                edge: Edge::Level,
            }),
            Target::Field(FieldRole {
                row: row(plan, "broadcast_command"),
                lsb: 0,
                width: 1,
                on: &[1],
                off: Some(0),
                edge: Edge::Level,
            }),
        ]
    );
    let Target::Field(f) = run[0] else {
        unreachable!()
    };
    // Run writes 10b into bits 4-5 and keeps the other bits; stop writes 01b.
    assert_eq!(f.put(0x0005, f.code(true)), 0x0025);
    assert_eq!(f.put(0x0025, f.code(false)), 0x0015);
    let first = plan.roles.of(Role::Run).next().unwrap();
    assert_eq!(first.source, "manual.txt:20");
}

#[test]
fn every_role_of_the_fixture_lowers_to_its_place() {
    let drive = drive();
    let plan = drive.plan();
    let command = row(plan, "operation_command");
    let state = row(plan, "state");
    // A 1-bit field whose 1 means forward: reverse is on at 0, off at 1.
    assert_eq!(
        targets(plan, Role::Reverse),
        [Target::Field(FieldRole {
            row: command,
            lsb: 0,
            width: 1,
            on: &[0],
            off: Some(1),
            edge: Edge::Level,
        })]
    );
    assert_eq!(
        targets(plan, Role::FaultReset),
        [Target::Field(FieldRole {
            row: command,
            lsb: 2,
            width: 1,
            on: &[1],
            off: Some(0),
            edge: Edge::Edge,
        })]
    );
    assert_eq!(
        targets(plan, Role::FrequencyReference),
        [Target::Register(row(plan, "frequency_reference"))]
    );
    assert_eq!(
        targets(plan, Role::OutputCurrent),
        [Target::Register(row(plan, "output_current"))]
    );
    // A status listed by code ids: the codes' numbers.
    assert_eq!(
        targets(plan, Role::Running),
        [Target::Field(FieldRole {
            row: state,
            lsb: 0,
            width: 2,
            on: &[1, 2],
            off: Some(0),
            edge: Edge::Level,
        })]
    );
    assert_eq!(
        targets(plan, Role::Fault),
        [Target::Field(FieldRole {
            row: state,
            lsb: 3,
            width: 1,
            on: &[1],
            off: Some(0),
            edge: Edge::Level,
        })]
    );
    match targets(plan, Role::MaxFrequency)[..] {
        [Target::External { slot, name }] => {
            assert_eq!(name, "max_output_frequency");
            assert!(usize::from(slot) < plan.settings.quantities.len());
        }
        ref other => panic!("max_frequency lowered to {other:?}"),
    }
    // Roles the map does not give have no place; places come in the order of `Role::ALL`.
    assert!(!plan.roles.has(Role::OutputFrequency));
    assert_eq!(plan.roles.places.len(), 9);
    let order: Vec<Role> = plan.roles.places.iter().map(|p| p.role).collect();
    let mut sorted = order.clone();
    sorted.sort_by_key(|r| Role::ALL.iter().position(|a| a == r));
    assert_eq!(order, sorted);
}

/// The acme-vf1 fixture's fault code is the status word's high byte (acme-vf1.txt:58), then its register: lowered
/// once to the row, bits and sign the trait and the simulator read.
#[test]
fn a_fault_code_in_a_byte_lowers_to_a_number_field() {
    let drive = drivemap_map::Loader::new()
        .load(&paths::fixture("acme-vf1/acme-vf1.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let plan = drive.plan();
    assert_eq!(
        targets(plan, Role::FaultCode),
        [
            Target::NumberField(NumberField {
                row: row(plan, "status_word"),
                lsb: 8,
                width: 8,
                signed: false,
                scale: drivemap_core::scale::Decimal::ONE,
            }),
            Target::Register(row(plan, "fault_code")),
        ]
    );
}

/// `signed` and `scale` on a number field, and `edge: {unknown: ..}` on a command, lower as
/// written.
#[test]
fn a_signed_scaled_field_and_an_unknown_edge_lower_as_written() {
    let text = std::fs::read_to_string(paths::fixture("acme-vf1/acme-vf1.yaml")).unwrap();
    let text = text
        .replace(
            "{register: status_word, field: active_fault, source",
            "{register: status_word, field: active_fault, signed: true, source",
        )
        .replace(
            "{register: output_current, source: \"acme-vf1.txt:30\"}",
            "{register: status_word, field: active_fault, scale: 0.5, source: \"acme-vf1.txt:30\"}",
        )
        .replace(
            "field: fault_reset, edge: true,",
            "field: fault_reset, edge: {unknown: \"no timing printed\"},",
        );
    let dir = std::env::temp_dir().join(format!("drivemap-roles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("acme-vf1.yaml");
    std::fs::write(&path, text).unwrap();
    let drive = drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|d| panic!("{d}"));
    let plan = drive.plan();
    let status = row(plan, "status_word");
    assert_eq!(
        targets(plan, Role::FaultCode)[0],
        Target::NumberField(NumberField {
            row: status,
            lsb: 8,
            width: 8,
            signed: true,
            scale: drivemap_core::scale::Decimal::ONE,
        })
    );
    assert_eq!(
        targets(plan, Role::OutputCurrent),
        [Target::NumberField(NumberField {
            row: status,
            lsb: 8,
            width: 8,
            signed: false,
            scale: drivemap_core::scale::Decimal::new(5, 1),
        })]
    );
    let [Target::Field(reset)] = targets(plan, Role::FaultReset)[..] else {
        panic!("fault_reset is not a field");
    };
    assert_eq!(reset.edge, Edge::NotPrinted("no timing printed"));
    std::fs::remove_dir_all(&dir).ok();
}
