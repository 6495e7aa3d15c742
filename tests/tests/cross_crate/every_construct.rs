//! The fixture drive of another vendor (`tests/fixtures/acme-vf1/`, with its own fictional
//! manual) uses what the shipped maps do not: 32-bit values in two registers (both word orders,
//! signed and unsigned, read-only and writable), decimals chosen by a field of another register,
//! slave addresses up to 254, a frame gap stated in milliseconds, protocol limits with their own
//! citations, a broadcast whose rules are not printed, serial formats chosen by a parameter, a
//! password read as a lock state and executed only when it changes, and a signedness the manual
//! leaves open. Here it goes through the
//! export, the reference document, the semantic diff, the simulator and the client over a real
//! socket; `yaml_is_enough.rs` compiles its generated module and runs the demo on it, and
//! `cli/tests/cli/live.rs` reads and writes its pairs with the tool.

use drivemap_test_support::paths;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use drivemap_live::LiveSettings;
use drivemap_live::codec::Value;
use drivemap_review::diff::ChangeKind;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::width::{Width, WordOrder};
use drivemap_runtime::planner::Poller;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{client::Client, error::Error, error::Refusal};
use drivemap_sim::{
    SimOptions, Simulator, clock::ManualClock, server::TcpFraming, server::TcpServer,
};

fn fixture() -> PathBuf {
    paths::fixture("acme-vf1/acme-vf1.yaml")
}

fn map() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&fixture())
        .expect("fixture map")
}

/// The exported register `id`.
fn exported(export: &serde_json::Value, id: &str) -> serde_json::Value {
    export["registers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == id)
        .unwrap_or_else(|| panic!("{id} exported"))
        .clone()
}

#[test]
fn export_doc_and_diff_say_what_the_pairs_are() {
    let d = map();
    let export = d.export();
    let register = |id: &str| exported(&export, id);
    let energy = register("energy_counter");
    assert_eq!(energy["words"], 2);
    assert_eq!(energy["word_order"], "high_first");
    assert_eq!(energy["word_order_source"], "acme-vf1.txt:34");
    assert_eq!(register("motor_speed")["word_order"], "low_first");
    assert_eq!(register("output_frequency")["words"], 1);
    assert!(register("output_frequency")["word_order"].is_null());
    assert_eq!(
        register("motor_current")["scale_selected_by"],
        "display_status.current_decimals"
    );
    assert_eq!(export["protocol"]["slave_address"]["max"], 254);

    let doc = drivemap_review::reference::render(&d, "acme-vf1.yaml");
    assert!(
        doc.contains("| 2200h – 2201h (32-bit pair, high word first, `acme-vf1.txt:34`) |"),
        "{doc}"
    );
    assert!(
        doc.contains("2206h – 2207h (32-bit pair, low word first"),
        "{doc}"
    );
    assert!(doc.contains("at least 10 ms (`acme-vf1.txt:44`)"), "{doc}");
    assert!(doc.contains("1 ..= 254"), "{doc}");

    // Swapping a pair's word order, or making it one register, is a breaking change.
    let text = std::fs::read_to_string(fixture()).unwrap();
    let swapped = text.replace(
        "pair: {order: low_first, source: \"acme-vf1.txt:38\"}",
        "pair: {order: high_first, source: \"acme-vf1.txt:38\"}",
    );
    let single = swapped.replacen(
        "        pair: {order: high_first, source: \"acme-vf1.txt:34\"}\n",
        "",
        1,
    );
    assert_ne!(single, swapped);
    let ctx = drivemap_map::Loader::new();
    let new = ctx.load_str("acme-vf1.yaml", &single).unwrap();
    let diff = drivemap_review::diff::compare(&d, &new);
    let widths: Vec<(&str, Option<&str>, Option<&str>)> = diff
        .changes
        .iter()
        .filter(|c| c.kind == ChangeKind::WidthChanged)
        .map(|c| (c.subject.as_str(), c.old.as_deref(), c.new.as_deref()))
        .collect();
    assert_eq!(
        widths,
        [
            (
                "energy_counter",
                Some("32-bit pair, high word first"),
                Some("one register")
            ),
            (
                "motor_speed",
                Some("32-bit pair, low word first"),
                Some("32-bit pair, high word first")
            ),
        ]
    );
    assert!(diff.breaking() >= 2);
}

/// The simulator serving the fixture at slave 254 over Modbus TCP, and a client with the map's
/// profile (lowered at run time).
struct Bench {
    server: TcpServer,
    client: Client<TcpTransport>,
    map: drivemap_map::Map,
    sim: drivemap_sim::server::SharedSim,
}

fn bench() -> Bench {
    let map = map();
    let mut sim = Simulator::new(
        map.clone(),
        SimOptions::new()
            .slave(254)
            .clock(Arc::new(ManualClock::new())),
    )
    .unwrap();
    sim.set("energy_counter", 12345.6).unwrap();
    sim.set_raw("running_hours", 131_072).unwrap();
    sim.set("motor_speed", -1234.5).unwrap();
    sim.set_raw("display_status", 0x0200).unwrap(); // two decimals
    sim.set_raw("motor_current", 1234).unwrap();
    let sim = drivemap_sim::server::shared(sim);
    let server =
        TcpServer::spawn(Arc::clone(&sim), "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
    let link =
        TcpTransport::connect(server.local_addr().to_string(), Duration::from_secs(2)).unwrap();
    let client = Client::new(link, drivemap_live::leak_profile(&map));
    Bench {
        server,
        client,
        map,
        sim,
    }
}

#[test]
fn the_simulator_serves_pairs_whole_and_the_client_reads_them_as_one_value() {
    let mut b = bench();
    let rows = |id: &str| b.map.register(id).unwrap().plan();
    assert_eq!(
        rows("energy_counter").info.width,
        Width::Pair(WordOrder::HighFirst)
    );
    assert_eq!(b.client.profile().timing.frame_gap_us, Some(10_000));

    // Planned reads: the monitors and the pairs, at slave 254.
    let ids = [
        "energy_counter",
        "running_hours",
        "motor_speed",
        "display_status",
        "motor_current",
    ];
    let infos: Vec<_> = b.map.registers().map(|r| r.plan().info).collect();
    let wanted = ids
        .iter()
        .map(|id| (rows(id).info.table, rows(id).info.address));
    let mut poller = Poller::new(b.client.profile(), &infos, wanted).unwrap();
    poller.poll(&mut b.client, 254);
    let raw = |i: usize| poller.raw(i, rows(ids[i]).info.width).unwrap().unwrap();
    assert_eq!(raw(0), 123_456);
    assert_eq!(
        rows("energy_counter").decode_number(raw(0), &()),
        Ok(12345.6)
    );
    assert_eq!(raw(1), 131_072, "beyond one word");
    assert_eq!(rows("motor_speed").decode_number(raw(2), &()), Ok(-1234.5));
    // The current's decimals follow the display status's high byte.
    let mut settings = LiveSettings::default();
    settings.absorb(&b.map, 0x2300, raw(3) as u16);
    match drivemap_live::codec::decode(
        &b.map,
        b.map.register("motor_current").unwrap(),
        raw(4),
        &settings,
    ) {
        Ok(Value::Quantity { value, .. }) => assert_eq!(value, 12.34),
        other => panic!("{other:?}"),
    }

    // A signed pair written whole through the gate; the simulated drive holds the value.
    let position = rows("position_setpoint");
    let word = position.encode_number(-123_456.0, &()).unwrap();
    b.client
        .write_rule(254, &position.write_rule(), 0x2204, word)
        .unwrap();
    let held = b.sim.lock().unwrap().value("position_setpoint").unwrap();
    assert_eq!(held.as_f64(), Some(-123_456.0));
    assert!(matches!(
        position.encode_number(1_000_001.0, &()),
        Err(drivemap_runtime::core::scale::ValueError::OutOfRange { .. })
    ));
    // Half of it is refused by the gate before anything is sent.
    match b.client.write_register(254, 0x2205, 1) {
        Err(Error::Refused(Refusal::SplitPair { register, address })) => {
            assert_eq!((register, address), ("position_setpoint", 0x2205))
        }
        other => panic!("{other:?}"),
    }
    b.server.stop();
}

#[test]
fn the_simulator_refuses_half_a_pair_from_a_master_without_the_map() {
    let b = bench();
    // A generic master (no write table, so no gate of the map) sends the first word alone.
    static GENERIC: Profile = Profile {
        slave_min: 1,
        slave_max: 254,
        ..Profile::GENERIC
    };
    let link =
        TcpTransport::connect(b.server.local_addr().to_string(), Duration::from_secs(2)).unwrap();
    let mut generic = Client::new(link, &GENERIC);
    match generic.write_registers(254, 0x2204, &[0x0001]) {
        Err(e) => assert_eq!(e.exception().map(|x| x.code), Some(0x02), "{e}"),
        Ok(()) => panic!("half a pair was written"),
    }
    // Both words in one request are taken.
    generic
        .write_registers(254, 0x2204, &[0x0001, 0xE240])
        .unwrap();
    let held = b.sim.lock().unwrap().value("position_setpoint").unwrap();
    assert_eq!(held.as_f64(), Some(123_456.0));
    b.server.stop();
}

/// The protocol and register constructs besides pairs, through export, doc, diff, the simulator
/// and the client: function codes and request limits with their own citations, a broadcast whose
/// rules are not printed (never sent), serial formats chosen by a parameter (a format it does not
/// list is refused before a port is opened), a password read as a lock state and executed only
/// when it changes (the client writes the intermediate), and a signedness the manual leaves open.
#[test]
fn limits_broadcast_formats_read_meanings_and_repeats_through_every_tool() {
    let d = map();
    let export = d.export();
    let limits = &export["protocol"]["limits"];
    assert_eq!(limits["function_codes"]["source"], "acme-vf1.txt:7");
    assert_eq!(limits["max_read"]["source"], "acme-vf1.txt:8");
    let broadcast = &export["protocol"]["broadcast"];
    assert_eq!(
        broadcast["not_printed"],
        "slave 0 is named a broadcast; no functions or registers are printed for it"
    );
    let formats: Vec<&str> = export["protocol"]["serial"]["formats"]["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["format"].as_str().unwrap())
        .collect();
    assert_eq!(formats, ["8N1", "8E1", "8N2"]);
    let register = |id: &str| exported(&export, id);
    let password = register("keypad_password");
    assert_eq!(password["repeat_needs_change"]["between_raw"], 0);
    assert_eq!(password["read_values"][1]["id"], "locked");
    assert_eq!(
        register("heatsink_temperature")["unknown"][0]["what"],
        "signed"
    );

    let doc = drivemap_review::reference::render(&d, "acme-vf1.yaml");
    for expected in [
        "| Function codes | 03h, 06h, 10h | `acme-vf1.txt:7` |",
        "| Registers per request | at most 16 per read, 16 per write | `acme-vf1.txt:8` |",
        "broadcast exists, rules not printed: slave 0 is named a broadcast",
        "only the formats communication_format selects: 0 = 8N1, 1 = 8E1, 2 = 8N2",
        "repeat needs a change: 0 between",
        "written as a word, read as codes",
        "heatsink_temperature, signedness: the manual gives the unit only",
    ] {
        assert!(doc.contains(expected), "{expected:?} not in\n{doc}");
    }

    // Changing what a read means or the repeat rule is a breaking change.
    let text = std::fs::read_to_string(fixture()).unwrap();
    let changed = text
        .replace(
            "repeat_needs_change: {between: 0, source: \"acme-vf1.txt:51\"}",
            "repeat_needs_change: {between: 1, source: \"acme-vf1.txt:51\"}",
        )
        .replace(
            "{value: 1, id: locked, name: Locked,",
            "{value: 2, id: locked, name: Locked,",
        );
    let new = drivemap_map::Loader::new()
        .load_str("acme-vf1.yaml", &changed)
        .unwrap();
    let diff = drivemap_review::diff::compare(&d, &new);
    let kinds: Vec<ChangeKind> = diff
        .changes
        .iter()
        .filter(|c| c.subject == "keypad_password")
        .map(|c| c.kind)
        .collect();
    assert!(
        kinds.contains(&ChangeKind::RepeatNeedsChangeChanged),
        "{kinds:?}"
    );
    assert!(kinds.contains(&ChangeKind::ReadMeaningChanged), "{kinds:?}");
    assert!(diff.breaking() >= 2);

    // The simulator and the client over TCP at slave 254.
    let mut b = bench();
    let plan = b.map.register("keypad_password").unwrap().plan();
    let rule = plan.write_rule();
    let repeat = plan.repeat_needs_change.expect("the map's rule");
    b.sim.lock().unwrap().set_raw("keypad_password", 1).unwrap(); // locked
    for _ in 0..2 {
        b.client
            .write_changed(254, &rule, 0x2011, repeat.between, 1234)
            .unwrap();
    }
    let sim = b.sim.lock().unwrap();
    assert_eq!(
        sim.executed("keypad_password").unwrap(),
        4,
        "0, 1234, 0, 1234: each write changed the value"
    );
    assert_eq!(sim.last_written("keypad_password").unwrap(), Some(1234));
    drop(sim);
    let mut word = [0u16; 1];
    b.client.read_holding(254, 0x2011, &mut word).unwrap();
    match drivemap_live::codec::decode(
        &b.map,
        b.map.register("keypad_password").unwrap(),
        u32::from(word[0]),
        &LiveSettings::default(),
    ) {
        Ok(Value::Code { id, .. }) => assert_eq!(id.as_deref(), Some("locked")),
        other => panic!("read as the lock state: {other:?}"),
    }

    // No broadcast reaches the wire: the manual does not print what one may do.
    match b.client.write_rule(0, &rule, 0x2011, 5) {
        Err(Error::Refused(Refusal::BroadcastRulesNotPrinted { drive, .. })) => {
            assert_eq!(drive, "acme-vf1")
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        b.sim
            .lock()
            .unwrap()
            .last_written("keypad_password")
            .unwrap(),
        Some(1234)
    );

    // Serial formats: 8E1 and 8N2 are listed, 8E2 is not.
    use drivemap_runtime::transport::serial::{Parity, SerialOptions, StopBits};
    let profile = b.client.profile();
    let line = |parity, stop| SerialOptions::new("/dev/null", 19200).line(profile, parity, stop);
    assert_eq!(line(Parity::Even, None).unwrap().stop_bits, StopBits::One);
    assert!(line(Parity::None, Some(StopBits::Two)).is_ok());
    match line(Parity::Even, Some(StopBits::Two)) {
        Err(Refusal::SerialFormat(f)) => assert_eq!(f.formats.selected_by, "communication_format"),
        other => panic!("{other:?}"),
    }
    b.server.stop();
}
