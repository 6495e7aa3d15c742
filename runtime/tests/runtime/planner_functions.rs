//! The read planner and function codes per register (`function_codes:` in a map, lowered into
//! `RegisterPlan::functions`): a register that refuses its table's read function is never read,
//! alone or bridged over, and holding (03h) and input (04h) registers never share a request.

use drivemap_runtime::core::functions::Functions;
use drivemap_runtime::core::plan::{Conversion, Ranges, RegisterPlan};
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::register::{Access, RegisterInfo, Table};
use drivemap_runtime::core::scale::RawRange;
use drivemap_runtime::core::width::Width;
use drivemap_runtime::planner::{PlanError, Poller, Read, ReadableSet};

static PROFILE: Profile = Profile {
    drive_id: "test-drive",
    max_read: 8,
    ..Profile::GENERIC
};

const WORD: RawRange = RawRange { min: 0, max: 65535 };

const fn row(address: u16, table: Table, functions: Functions) -> RegisterPlan {
    RegisterPlan::new(
        RegisterInfo {
            id: "r",
            param: None,
            name: "r",
            address,
            access: Access::ReadWrite,
            table,
            width: Width::Word,
            broadcast_only: false,
            source: "",
        },
        "",
        Conversion::Word {
            signed: false,
            range: Ranges {
                base: WORD,
                by_variant: &[],
            },
        },
        WORD,
    )
    .functions(functions)
}

const WRITE_ONLY_BY_FUNCTION: Functions = Functions::only(&[0x06], 0x01, "m.txt:9");
const ANY: Functions = Functions::ANY;

/// Holding 0020h-0024h, of which 0022h accepts 06h only (a command register a drive writes but
/// never reads); input 0025h-0026h; holding 0027h accepting 03h and 06h.
static REGISTERS: &[RegisterPlan] = &[
    row(0x20, Table::Holding, ANY),
    row(0x21, Table::Holding, ANY),
    row(0x22, Table::Holding, WRITE_ONLY_BY_FUNCTION),
    row(0x23, Table::Holding, ANY),
    row(0x24, Table::Holding, ANY),
    row(
        0x25,
        Table::Input,
        Functions::only(&[0x04], 0x02, "m.txt:10"),
    ),
    row(0x26, Table::Input, ANY),
    row(
        0x27,
        Table::Holding,
        Functions::only(&[0x03, 0x06], 0x01, "m.txt:11"),
    ),
];

fn plan(registers: &[RegisterPlan], wanted: &[(Table, u16)]) -> Vec<(Table, Read)> {
    Poller::new(&PROFILE, registers, wanted.iter().copied())
        .unwrap()
        .plan()
        .collect()
}

#[test]
fn a_register_refusing_the_read_function_is_left_out_of_the_readable_set() {
    let holding = ReadableSet::from_registers(REGISTERS, Table::Holding);
    assert_eq!(holding.addresses(), &[0x20, 0x21, 0x23, 0x24, 0x27]);
    let input = ReadableSet::from_registers(REGISTERS, Table::Input);
    assert_eq!(input.addresses(), &[0x25, 0x26]);
    // The same rows as bare infos know nothing of functions: 0022h is readable then.
    let infos: Vec<RegisterInfo> = REGISTERS.iter().map(|r| r.info).collect();
    assert!(ReadableSet::from_registers(&infos, Table::Holding).contains(0x22));
}

#[test]
fn reads_are_not_bridged_over_a_register_refusing_the_read_function() {
    let wanted = [(Table::Holding, 0x21), (Table::Holding, 0x23)];
    // With the function restriction: two requests around 0022h.
    assert_eq!(
        plan(REGISTERS, &wanted),
        [
            (
                Table::Holding,
                Read {
                    address: 0x21,
                    quantity: 1
                }
            ),
            (
                Table::Holding,
                Read {
                    address: 0x23,
                    quantity: 1
                }
            ),
        ]
    );
    // The same map without it bridges 0022h: one request (what the planner did before).
    let unrestricted: Vec<RegisterPlan> = REGISTERS.iter().map(|r| r.functions(ANY)).collect();
    assert_eq!(
        plan(&unrestricted, &wanted),
        [(
            Table::Holding,
            Read {
                address: 0x21,
                quantity: 3
            }
        )]
    );
}

#[test]
fn holding_and_input_registers_never_share_a_request() {
    // 0024h (holding, 03h), 0025h-0026h (input, 04h) and 0027h (holding): adjacent addresses,
    // but one request per table and function.
    let reads = plan(
        REGISTERS,
        &[
            (Table::Holding, 0x24),
            (Table::Input, 0x25),
            (Table::Input, 0x26),
            (Table::Holding, 0x27),
        ],
    );
    for (table, read) in &reads {
        for a in read.address..=read.last() {
            let r = REGISTERS.iter().find(|r| r.info.address == a).unwrap();
            assert_eq!(r.info.table, *table, "{reads:?}");
        }
    }
    assert!(reads.contains(&(
        Table::Input,
        Read {
            address: 0x25,
            quantity: 2
        }
    )));
}

#[test]
fn wanting_a_register_that_refuses_the_read_function_is_an_error() {
    let e = Poller::new(&PROFILE, REGISTERS, [(Table::Holding, 0x22)]).unwrap_err();
    assert_eq!(
        e,
        PlanError::NotReadable {
            table: Table::Holding,
            address: 0x22
        }
    );
    assert!(e.to_string().contains("function codes"), "{e}");
}
