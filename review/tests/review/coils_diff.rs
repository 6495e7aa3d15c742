//! `diff`, `doc` and the citation and coverage review on coils and discrete inputs (the fixture
//! `tests/fixtures/tindra-tc4`): a coil moved to another table, a bit limit lowered, a role moved
//! from one coil to another are reported with their kinds; `doc` shows a coil's table and states;
//! every citation of the coil and input rows is verified by content and every row of the coil
//! and input tables is covered.

use drivemap_test_support::paths;

use drivemap_review::diff::{ChangeKind, compare};

const FILE: &str = "tindra-tc4/tindra-tc4.yaml";

fn tindra(replace: &[(&str, &str)]) -> drivemap_map::Map {
    let mut text = std::fs::read_to_string(paths::fixture(FILE)).unwrap();
    for (from, to) in replace {
        assert!(text.contains(from), "no {from}");
        text = text.replace(from, to);
    }
    drivemap_map::Loader::new()
        .load_str("tindra-tc4.yaml", &text)
        .unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn a_coils_table_its_bit_limits_and_its_roles_are_compared() {
    let old = tindra(&[]);
    let new = tindra(&[
        // The jog coil read as a discrete input (another space: 02h, never written).
        (
            "{id: jogging, param: JG, name: Jogging, address: 0x0008,",
            "{id: jogging, param: JG, name: Jogging, address: 0x0008, modbus_table: discrete_input, access: r,",
        ),
        (
            "max_read_bits: {value: 32, source",
            "max_read_bits: {value: 16, source",
        ),
        (
            "    - {register: operation_command, source: \"tindra-tc4.txt:44\"}",
            "    - {register: free_run_stop, source: \"tindra-tc4.txt:44\"}",
        ),
    ]);
    let d = compare(&old, &new);
    let find = |what: &str, subject: &str| {
        d.changes
            .iter()
            .find(|c| c.what == what && c.subject.starts_with(subject))
            .unwrap_or_else(|| panic!("no `{what}` of {subject} in {:#?}", d.changes))
    };
    let table = find("table", "jogging");
    assert_eq!(table.kind, ChangeKind::TableChanged);
    assert_eq!(
        (table.old.as_deref(), table.new.as_deref()),
        (Some("coil"), Some("discrete input"))
    );
    let limit = find("max_read_bits", "protocol");
    assert_eq!(limit.kind, ChangeKind::MaxRequestLowered);
    assert_eq!(
        (limit.old.as_deref(), limit.new.as_deref()),
        (Some("32"), Some("16"))
    );
    assert!(
        d.changes
            .iter()
            .any(|c| c.kind == ChangeKind::RoleRepointed && c.what == "run"),
        "{:#?}",
        d.changes
    );
    // The same map against itself: nothing.
    assert!(compare(&old, &tindra(&[])).changes.is_empty());
}

#[test]
fn doc_shows_a_coils_table_and_its_states() {
    let drive = tindra(&[]);
    let doc = drivemap_review::reference::render(&drive, "tindra-tc4.yaml");
    assert!(
        doc.contains(
            "| 0001h |  | Operation command | `operation_command` | read/write<br>coil (01h/05h/0Fh) |  | 1 on, 0 off |"
        ),
        "{doc}"
    );
    assert!(
        doc.contains("| 0003h | IRDY | Inverter ready | `inverter_ready` | read-only<br>discrete input (02h) |"),
        "{doc}"
    );
    assert!(
        doc.contains("| Coils and discrete inputs per request | at most 32 per read (01h/02h), 16 per write (0Fh)"),
        "{doc}"
    );
}

/// The citations of the coil and input rows are verified by content (each row prints its number
/// and name), and coverage finds the coil list and the discrete-input list as tables of the
/// manual with every row covered (the reserved coil 0005h by its "(Reserved)").
#[test]
fn coil_rows_are_verified_and_covered() {
    use drivemap_review::review::{Manuals, coverage, verify_citations};
    let drive = tindra(&[]);
    let mut manuals = Manuals::new(paths::fixture("tindra-tc4/manuals").as_ref());
    manuals.load_for(&drive);
    let checks = verify_citations(&drive, &manuals);
    let unverified: Vec<_> = checks.iter().filter(|c| !c.verified()).collect();
    assert!(unverified.is_empty(), "{unverified:#?}");
    let coil_rows = checks
        .iter()
        .filter(|c| {
            ["operation_command", "operation_status", "free_run_stop"]
                .contains(&c.register.as_str())
        })
        .count();
    assert!(coil_rows >= 3, "{checks:#?}");
    let report = coverage(&drive, &manuals, &[]);
    assert!(report.uncited.is_empty(), "{:#?}", report.uncited);
    let tables: Vec<(Option<&str>, usize, usize)> = report
        .tables
        .iter()
        .map(|t| (t.group.as_deref(), t.rows, t.uncited))
        .collect();
    assert!(tables.contains(&(Some("Coil list"), 9, 0)), "{tables:?}");
    assert!(
        tables.contains(&(Some("Discrete input list"), 7, 0)),
        "{tables:?}"
    );
}
