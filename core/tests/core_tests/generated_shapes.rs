//! What the generated code builds on: enumerations compare by code (`enumeration!`, `code_eq!`), and a
//! profile's write table is derived from the plan at compile time (`write_rules`).

use std::collections::HashSet;

use drivemap_core::plan::{Conversion, Label, Ranges, RegisterPlan, writable_count, write_rules};
use drivemap_core::register::{Access, Code, Enumeration, RegisterInfo, Table};
use drivemap_core::rule::WriteRule;
use drivemap_core::scale::RawRange;
use drivemap_core::width::Width;

/// An enumeration as the generator prints one.
#[derive(Debug, Clone, Copy)]
enum Unit {
    Tenth,
    Hundredth,
    Unknown(u16),
}

const LABELS: &[Label] = &[
    Label {
        code: 0,
        id: "tenth",
        name: "0.1 Hz",
    },
    Label {
        code: 1,
        id: "hundredth",
        name: "0.01 Hz",
    },
];

drivemap_core::enumeration!(Unit, LABELS, [Tenth, Hundredth]);

#[test]
fn enumerations_are_equal_by_code() {
    assert_eq!(Unit::Unknown(0), Unit::Tenth);
    assert_eq!(Unit::Hundredth, Unit::Unknown(1));
    assert_ne!(Unit::Unknown(2), Unit::Tenth);
    assert_ne!(Unit::Tenth, Unit::Hundredth);
    let set: HashSet<Unit> = [Unit::Tenth, Unit::Unknown(0), Unit::Unknown(1)].into();
    assert_eq!(set.len(), 2, "{set:?}");
    // The label is the variant's, found by variant: an `Unknown` has none, whatever its code.
    assert_eq!(Unit::Hundredth.name(), Some("0.01 Hz"));
    assert_eq!(Unit::Unknown(1).name(), None);
    assert_eq!(Unit::from_code(1).code(), 1);
    assert_eq!(Unit::Unknown(7).to_string(), "unknown code 7");
    assert_eq!(Unit::Tenth.to_string(), "0.1 Hz");
    assert_eq!(Unit::ALL.len(), 2);
}

const fn row(id: &'static str, address: u16, access: Access) -> RegisterPlan {
    let range = RawRange::new(0, 100);
    RegisterPlan::new(
        RegisterInfo {
            id,
            param: None,
            name: id,
            address,
            access,
            table: Table::Holding,
            width: Width::Word,
            broadcast_only: false,
            source: "manual.txt:1",
        },
        "",
        Conversion::Word {
            signed: false,
            range: Ranges::fixed(range),
        },
        range,
    )
}

const PLAN: &[RegisterPlan] = &[
    row("a", 1, Access::ReadWrite),
    row("b", 2, Access::Read),
    row("c", 3, Access::Write),
];

static WRITES: [WriteRule; writable_count(PLAN)] = write_rules(PLAN);

#[test]
fn the_write_table_is_the_writable_rows_rules_in_order() {
    assert_eq!(writable_count(PLAN), 2);
    assert_eq!(WRITES, [PLAN[0].write_rule(), PLAN[2].write_rule()]);
}

#[test]
#[should_panic(expected = "N is not the number of writable rows")]
fn a_write_table_of_another_length_is_refused() {
    let _ = write_rules::<3>(PLAN);
}
