//! Function codes per register (`function_codes:`, issue 25 item 3) on the fictional Halvard
//! HX-2 (`tests/fixtures/halvard-hx2`): 10h is accepted on registers 0001h-0004h only, register
//! 0002h is written with 10h only (06h answered with 02h), the monitor area 0100h-0103h is read
//! with 04h only. The client's write gate, against the simulator of the same map, through a
//! link that records every frame on the wire.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_map::Map;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::planner::Poller;
use drivemap_runtime::{client::Client, client::ClientOptions, error::Error, error::Refusal};
use drivemap_sim::{SimOptions, Simulator, clock::ManualClock};
use drivemap_test_support::sim_link::SimLink;
use proptest::prelude::*;

fn map() -> Map {
    let path = paths::fixture("halvard-hx2/halvard-hx2.yaml");
    drivemap_map::Loader::new()
        .load(&path)
        .expect("fixture map")
}

fn client(drive: &Map) -> Client<SimLink> {
    let sim = Simulator::new(
        drive.clone(),
        SimOptions::new().clock(Arc::new(ManualClock::new())),
    )
    .unwrap();
    let options = ClientOptions {
        timeout: Duration::from_micros(20),
        retries: 0,
        request_gap: Duration::ZERO,
        ..ClientOptions::default()
    };
    Client::with_options(
        SimLink::new(TransportKind::Rtu, sim),
        drive.plan().profile,
        options,
    )
}

/// The (function, first address, quantity) of an RTU request frame.
fn request(frame: &[u8]) -> (u8, u16, u16) {
    let f = frame[1];
    let address = u16::from_be_bytes([frame[2], frame[3]]);
    let quantity = match f {
        0x03 | 0x04 | 0x10 => u16::from_be_bytes([frame[4], frame[5]]),
        _ => 1,
    };
    (f, address, quantity)
}

/// Every frame on the wire used a function each register it covers accepts (per the map's
/// lowered plan); the first violation otherwise.
fn violation(drive: &Map, link: &SimLink) -> Option<String> {
    for sent in &link.log {
        let (f, address, quantity) = request(&sent.frame);
        let table = if f == 0x04 {
            Table::Input
        } else {
            Table::Holding
        };
        for a in address..address.saturating_add(quantity) {
            for r in drive.registers() {
                let plan = r.plan();
                if plan.info.table == table
                    && (plan.info.address..plan.info.address + plan.info.width.count()).contains(&a)
                    && !plan.functions.allows(f)
                {
                    return Some(format!(
                        "{f:02X}h reached the wire at {a:04X}h ({}), which accepts only {:02X?}",
                        plan.info.id, plan.functions.codes
                    ));
                }
            }
        }
    }
    None
}

#[derive(Debug, Clone)]
enum Op {
    /// `write_register`: one word by address.
    Word(u16, u16),
    /// `write_registers`: a block by address (10h).
    Block(u16, Vec<u16>),
    /// `write_rule`: a register by its map rule.
    Rule(usize, u16),
}

/// Addresses around the map's registers (and a few that hold none).
fn address() -> impl Strategy<Value = u16> {
    prop_oneof![0x0000u16..=0x0006, 0x000Fu16..=0x0014, 0x0100u16..=0x0104]
}

fn op(writable: usize) -> impl Strategy<Value = Op> {
    prop_oneof![
        (address(), 0u16..700).prop_map(|(a, v)| Op::Word(a, v)),
        (address(), prop::collection::vec(0u16..700, 1..=4)).prop_map(|(a, v)| Op::Block(a, v)),
        (0..writable, 0u16..700).prop_map(|(i, v)| Op::Rule(i, v)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Random writes through the client (by address, by block, by rule) against the simulator
    /// of the map: nothing reaches the wire with a function a register it covers does not
    /// accept, and the drive never answers one with "illegal function" or "illegal data
    /// address" for the function. On the code before `function_codes`, `write_register(0002h)`
    /// went out as 06h and `write_registers(0010h, ..)` as 10h.
    #[test]
    fn no_function_a_register_refuses_reaches_the_wire(
        ops in prop::collection::vec(op(7), 1..12)
    ) {
        let drive = map();
        let mut c = client(&drive);
        let rules = drive.plan().profile.writes;
        prop_assert_eq!(rules.len(), 7);
        for op in &ops {
            let outcome = match op {
                Op::Word(a, v) => c.write_register(1, *a, *v),
                Op::Block(a, v) => c.write_registers(1, *a, v),
                Op::Rule(i, v) => {
                    let rule = &rules[*i];
                    c.write_rule(1, rule, rule.address, u32::from(*v))
                }
            };
            if let Err(Error::Exception { exception, .. }) = &outcome {
                // What the drive refuses for a function is its `refused_with`; anything the
                // gate let through may only be refused for its value or address.
                prop_assert!(
                    exception.code != 0x01,
                    "{op:?}: the drive answered illegal function: {outcome:?}"
                );
            }
        }
        let v = violation(&drive, c.transport());
        prop_assert!(v.is_none(), "{}", v.unwrap_or_default());
    }
}

#[test]
fn one_word_goes_out_with_the_function_its_register_accepts() {
    let drive = map();
    let mut c = client(&drive);
    // 0002h accepts 10h only: one word goes out as a 10h request of one register.
    c.write_register(1, 0x0002, 1234).unwrap();
    // 0010h (the parameters) accepts 06h only; 0001h both: 06h.
    c.write_register(1, 0x0010, 5000).unwrap();
    c.write_register(1, 0x0001, 1).unwrap();
    let functions: Vec<(u8, u16, u16)> = c
        .transport()
        .log
        .iter()
        .map(|s| request(&s.frame))
        .collect();
    assert_eq!(
        functions,
        [(0x10, 0x0002, 1), (0x06, 0x0010, 1), (0x06, 0x0001, 1)]
    );
    let sim = &c.transport().sim;
    assert_eq!(sim.raw("frequency_command").unwrap(), 1234);
    assert_eq!(sim.raw("maximum_frequency").unwrap(), 5000);
}

#[test]
fn a_block_over_a_register_refusing_10h_is_refused_not_split() {
    let drive = map();
    let mut c = client(&drive);
    // 0001h-0004h accept 10h: one request.
    c.write_registers(1, 0x0001, &[1, 1000, 50, 50]).unwrap();
    // 0010h-0011h accept 06h only: refused before the wire, naming the register and citation.
    let e = c.write_registers(1, 0x0010, &[5000, 8]).unwrap_err();
    match &e {
        Error::Refused(Refusal::FunctionNotAccepted {
            register,
            address,
            function,
            accepted,
            citation,
        }) => {
            assert_eq!(
                (*register, *address, *function, *accepted, *citation),
                (
                    "maximum_frequency",
                    0x0010,
                    0x10,
                    &[0x03u8, 0x06][..],
                    "halvard-hx2.txt:9"
                )
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(
        e.to_string()
            .contains("maximum_frequency at 0010h accepts only 03h, 06h (`halvard-hx2.txt:9`)"),
        "{e}"
    );
    // A block that starts on 0004h and runs into 0005h (no register) is the drive's to refuse
    // by address; one that reaches 0010h from 000Fh is refused by the gate.
    assert!(matches!(
        c.write_registers(1, 0x000F, &[0, 5000]),
        Err(Error::Refused(_))
    ));
    assert_eq!(c.transport().log.len(), 1, "only the first block was sent");
}

#[test]
fn the_simulator_answers_a_refused_function_with_the_maps_exception() {
    let drive = map();
    let mut sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let mut exception = |frame: &[u8]| {
        let mut f = frame.to_vec();
        let crc = drivemap_runtime::crc::crc16(&f);
        f.extend_from_slice(&crc.to_le_bytes());
        let mut out = [0u8; 256];
        let n = sim.handle(TransportKind::Rtu, &f, &mut out).reply.unwrap();
        (out[1] & 0x80 != 0).then_some(out[2]).filter(|_| n == 5)
    };
    // 06h to 0002h: 02h (refused_with: 0x02); 10h to 0010h: 01h (the default).
    assert_eq!(exception(&[1, 0x06, 0x00, 0x02, 0x00, 0x10]), Some(0x02));
    assert_eq!(
        exception(&[1, 0x10, 0x00, 0x10, 0x00, 0x01, 0x02, 0x13, 0x88]),
        Some(0x01)
    );
    // 03h over the monitor area's addresses finds no holding register there (02h); 04h reads.
    assert_eq!(exception(&[1, 0x03, 0x01, 0x00, 0x00, 0x01]), Some(0x02));
    assert_eq!(exception(&[1, 0x04, 0x01, 0x00, 0x00, 0x04]), None);
    // What each register accepts is served: 10h to 0002h, 06h to 0010h.
    assert_eq!(
        exception(&[1, 0x10, 0x00, 0x02, 0x00, 0x01, 0x02, 0x03, 0xE8]),
        None
    );
    assert_eq!(exception(&[1, 0x06, 0x00, 0x10, 0x13, 0x88]), None);
}

#[test]
fn the_planner_reads_the_monitor_area_with_04h_only() {
    let drive = map();
    let plan = drive.plan();
    let profile = plan.profile;
    // The plans carry the functions; the planner keeps the two tables apart and plans the
    // monitors as one 04h read.
    let mut poller = Poller::new(
        profile,
        plan.registers,
        [
            (Table::Input, 0x0100),
            (Table::Input, 0x0103),
            (Table::Holding, 0x0001),
            (Table::Holding, 0x0010),
        ],
    )
    .unwrap();
    let reads: Vec<(Table, u16, u16)> = poller
        .plan()
        .map(|(t, r)| (t, r.address, r.quantity))
        .collect();
    assert!(reads.contains(&(Table::Input, 0x0100, 4)), "{reads:?}");
    let mut c = client(&drive);
    let stats = poller.poll(&mut c, 1);
    assert_eq!(stats.splits, 0, "{stats:?}");
    assert!(poller.get(Table::Input, 0x0103).unwrap().is_ok());
    assert!(violation(&drive, c.transport()).is_none());
}

/// `export`, `doc`, `diff` and the generated module all show the functions a register accepts.
#[test]
fn export_doc_diff_and_generated_code_show_the_functions() {
    let drive = map();
    let export = drive.export();
    let register = |id: &str| {
        export["registers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["id"] == id)
            .unwrap()
            .clone()
    };
    assert_eq!(
        register("frequency_command")["function_codes"],
        serde_json::json!({"codes": [3, 16], "refused_with": 2, "source": "halvard-hx2.txt:11"})
    );
    // A group's list reaches its registers; a register without one exports null.
    assert_eq!(
        register("stop_mode")["function_codes"]["source"],
        "halvard-hx2.txt:9"
    );
    assert!(register("operation_command")["function_codes"].is_null());

    let doc = drivemap_review::reference::render(&drive, "halvard-hx2.yaml");
    assert!(doc.contains("functions 03h/10h only"), "{doc}");
    assert!(
        doc.contains(
            "Function codes: accepts only 03h, 10h; another function is answered with exception \
             02h (illegal data address) (`halvard-hx2.txt:11`)"
        ),
        "{doc}"
    );

    let code = drivemap_codegen::generate::drive_module(
        &drive,
        &drivemap_codegen::generate::Options {
            runtime: "::drivemap_runtime".parse().unwrap(),
            source_name: "halvard-hx2.yaml".into(),
        },
    )
    .unwrap();
    // The plan's rows wrap at the printer's width: joined again, a row is one expression.
    let rows = code
        .lines()
        .map(str::trim)
        .fold(String::new(), |mut all, l| {
            if !l.starts_with('.') && !all.is_empty() {
                all.push(' ');
            }
            all.push_str(l);
            all
        });
    assert!(
        rows.contains(".functions(Functions::only(&[0x03, 0x10], 0x02, \"halvard-hx2.txt:11\"))"),
        "{code}"
    );
    assert!(
        code.contains("Function codes: accepts only 03h, 06h; another function is answered with exception 01h (illegal function) (`halvard-hx2.txt:9`)"),
        "{code}"
    );

    // diff: a changed list is breaking; a moved citation alone is a citation change.
    let text = std::fs::read_to_string(paths::fixture("halvard-hx2/halvard-hx2.yaml")).unwrap();
    let read = |t: &str| {
        drivemap_map::Loader::new()
            .load_str("halvard-hx2.yaml", t)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let kinds = |t: &str| -> Vec<(String, drivemap_review::diff::ChangeKind)> {
        drivemap_review::diff::compare(&drive, &read(t))
            .changes
            .iter()
            .map(|c| (c.subject.clone(), c.kind))
            .collect()
    };
    let widened = text.replace(
        "function_codes: {codes: [0x03, 0x06], source: \"halvard-hx2.txt:9\"}",
        "function_codes: {codes: [0x03, 0x06, 0x10], source: \"halvard-hx2.txt:9\"}",
    );
    let changes = kinds(&widened);
    assert_eq!(changes.len(), 3, "{changes:?}");
    assert!(
        changes
            .iter()
            .all(|(_, k)| *k == drivemap_review::diff::ChangeKind::FunctionCodesChanged),
        "{changes:?}"
    );
    let moved = text.replace(
        "refused_with: 0x02, source: \"halvard-hx2.txt:11\"",
        "refused_with: 0x02, source: \"halvard-hx2.txt:12\"",
    );
    assert_eq!(
        kinds(&moved),
        [(
            "frequency_command".to_string(),
            drivemap_review::diff::ChangeKind::CitationChanged
        )]
    );
    let dropped = text.replace(
        "        function_codes: {codes: [0x03, 0x10], refused_with: 0x02, source: \"halvard-hx2.txt:11\"}\n",
        "",
    );
    let diff = drivemap_review::diff::compare(&drive, &read(&dropped));
    assert_eq!(diff.breaking(), 1, "{:?}", diff.changes);
}

/// `check` verifies the manual's example frames against each register's functions: the
/// fixture's 06h write to 0002h is printed with its refusal (exception 02h) and verifies; the
/// same frame without the refusal is an error at its function byte.
#[test]
fn example_frames_are_checked_against_the_registers_functions() {
    let drive = map();
    let v = drivemap_live::examples::verify(&drive);
    assert!(v.errors.is_empty(), "{:?}", v.errors);
    assert_eq!(v.clean, 4);

    let text = std::fs::read_to_string(paths::fixture("halvard-hx2/halvard-hx2.yaml")).unwrap();
    let refusal = text.find("  - id: frequency_with_06h_refused").unwrap();
    let unrefused = drivemap_map::Loader::new()
        .load_str("halvard-hx2.yaml", &text[..refusal])
        .unwrap();
    let v = drivemap_live::examples::verify(&unrefused);
    let errors: Vec<String> = v.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains(
            "example `frequency_with_06h`, byte 2 (06): function 06h to 0002h: `frequency_command` \
             accepts only 03h, 10h (`halvard-hx2.txt:11`)"
        ),
        "{errors:?}"
    );
}
