//! The facts view (`drivemap_map::facts`): one row per fact of a register, worded once and
//! cited, in the plan's row order, serializable for tools.

use drivemap_test_support::paths;

use std::path::PathBuf;

use drivemap_core::kind::ConversionKind;
use drivemap_map::facts::{self, FactKey, Figure, ProtocolKey, RegisterFacts};

fn acme() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&paths::fixture("acme-vf1/acme-vf1.yaml"))
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
    let all = drive.facts().registers;
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
    let all = drive.facts().registers;
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
    let all = drive.facts().registers;
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
    let view = drive.facts();
    assert_eq!(view.registers.len(), drive.registers().len());
    let plan = drive.plan();
    let mut rows: Vec<usize> = Vec::new();
    for (f, r) in view.registers.iter().zip(drive.registers()) {
        let row = f.row;
        assert_eq!(plan.registers[row].info.id, r.id(), "{}", f.id);
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
    assert_eq!(rows.len(), drive.registers().len(), "one row per register");
}

#[test]
fn the_view_serializes_with_kind_names_and_labels() {
    let drive = acme();
    let json = serde_json::to_value(drive.facts()).unwrap();
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

fn read(path: PathBuf) -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|d| panic!("{d}"))
}

fn keys(p: &facts::ProtocolFacts) -> Vec<ProtocolKey> {
    p.rows.iter().map(|r| r.key).collect()
}

#[test]
fn the_protocol_is_one_row_per_fact_with_its_figure_and_citation() {
    use ProtocolKey as K;
    let v7 = read(paths::shipped_map("yaskawa-v7"));
    let p = v7.protocol_facts();
    assert_eq!(
        keys(&p),
        [
            K::Transports,
            K::FunctionCodes,
            K::RegistersPerRequest,
            K::MaxRead,
            K::MaxWrite,
            K::SlaveAddress,
            K::Broadcast,
            K::Addressing,
            K::Timing,
            K::FrameGap,
            K::InterCharTimeout,
            K::ResponseTime,
            K::ResponseDelay,
            K::RequestGap,
            K::Serial,
            K::Eeprom,
        ]
    );
    let get = |k| p.get(k).unwrap_or_else(|| panic!("no {k:?} row"));
    let read_limit = get(K::MaxRead);
    assert_eq!(read_limit.value, "8");
    assert_eq!(read_limit.figure, Figure::Count(8));
    assert_eq!(
        read_limit.citation.as_deref(),
        Some("000_032dced3a1e91a75.txt:299")
    );
    assert_eq!(get(K::MaxWrite).figure, Figure::Count(16));
    // Two citations: beside each limit, none in the whole's column.
    let whole = get(K::RegistersPerRequest);
    assert_eq!(whole.citation, None);
    assert!(
        whole
            .value
            .starts_with("at most 8 per read, 16 per write. max_read (`"),
        "{}",
        whole.value
    );
    assert_eq!(
        get(K::SlaveAddress).figure,
        Figure::Range { min: 1, max: 32 }
    );
    assert_eq!(
        get(K::Broadcast).figure,
        Figure::Broadcast {
            functions: vec![0x06, 0x10],
            registers: vec![]
        }
    );
    // Each timing figure is a row; the timing gathers them as `drivemap doc` prints it.
    let gap = get(K::FrameGap).not_printed.clone().expect("not printed");
    assert_eq!(
        gap.fallback.as_deref(),
        Some("3.5 characters, the Modbus RTU rule")
    );
    assert_eq!(
        get(K::RequestGap).value,
        "master waits 24 bit times + 10 ms after each reply (`003_8bcf5d50afb8e230.txt:284`)"
    );
    assert_eq!(get(K::ResponseDelay).value, "response delay set by n156");
    let parts: Vec<&str> = (p.rows.iter())
        .filter(|r| r.key.part_of() == Some(K::Timing))
        .map(|r| r.value.as_str())
        .collect();
    assert_eq!(get(K::Timing).value, parts.join("; "));
    assert_eq!(get(K::Eeprom).figure, Figure::Count(100_000));
    // The rows `drivemap doc` prints stand alone.
    let wholes: Vec<&str> = p.wholes().map(|r| r.label).collect();
    assert_eq!(
        wholes,
        [
            "Transports",
            "Function codes",
            "Registers per request",
            "Slave address",
            "Broadcast",
            "Addressing",
            "Timing",
            "Serial line",
            "EEPROM endurance"
        ]
    );
    let codes: Vec<&str> = p.exceptions.iter().map(|e| e.code.as_str()).collect();
    assert_eq!(codes, ["01h", "02h", "03h", "21h", "22h"]);
    let enter = &p.commands[0];
    assert_eq!(
        (enter.id.as_str(), enter.kind_text, enter.writes.as_slice()),
        (
            "enter",
            "persist (writes EEPROM)",
            &["0900h ← 0000h".to_owned()][..]
        )
    );
    assert_eq!(enter.words, [(0x0900, 0)]);
}

#[test]
fn a_fact_the_manual_does_not_print_says_why_and_what_is_used_instead() {
    use ProtocolKey as K;
    let halden = read(paths::fixture("halden-h1/halden-h1.yaml"));
    let p = halden.protocol_facts();
    let not_printed = |k| {
        let r = p.get(k).unwrap_or_else(|| panic!("no {k:?} row"));
        let n = r
            .not_printed
            .clone()
            .unwrap_or_else(|| panic!("{k:?} printed"));
        (n.why.trim().to_owned(), n.fallback, r.citation.clone())
    };
    assert_eq!(
        not_printed(K::SlaveAddress),
        (
            "set with F-20, whose settings the note does not list".to_owned(),
            Some("the Modbus range 1 ..= 247".to_owned()),
            Some("halden-h1.txt:7".to_owned())
        )
    );
    // The working figure is the fallback's.
    assert_eq!(
        p.get(K::SlaveAddress).unwrap().figure,
        Figure::Range { min: 1, max: 247 }
    );
    assert_eq!(p.get(K::MaxRead).unwrap().figure, Figure::Count(125));
    assert_eq!(
        not_printed(K::MaxRead).1.as_deref(),
        Some("the Modbus limit (125)")
    );
    assert_eq!(
        not_printed(K::MaxWrite).1.as_deref(),
        Some("the Modbus limit (123)")
    );
    for k in [K::Serial, K::Exceptions, K::Timing] {
        let (why, fallback, _) = not_printed(k);
        assert!(!why.is_empty() && fallback.is_some(), "{k:?}");
        let fact = k.fact().expect("a fact a map can mark");
        assert_eq!(fallback.as_deref(), Some(fact.fallback()), "{k:?}");
    }
    // A timing not printed has no figures of its own.
    assert!(p.rows.iter().all(|r| r.key.part_of() != Some(K::Timing)));
    // A printed fact has no reason.
    assert!(p.get(K::Transports).unwrap().not_printed.is_none());
}

#[test]
fn the_drive_facts_serialize_the_protocol_rows() {
    let drive = acme();
    let json = serde_json::to_value(drive.facts()).unwrap();
    let rows = json["protocol"]["rows"].as_array().expect("protocol rows");
    let broadcast = rows.iter().find(|r| r["key"] == "broadcast").unwrap();
    assert_eq!(broadcast["label"], "Broadcast");
    assert_eq!(broadcast["citation"], "acme-vf1.txt:47");
    assert!(
        broadcast["not_printed"]["why"]
            .as_str()
            .unwrap()
            .contains("slave 0 is named a broadcast"),
        "{broadcast}"
    );
    let read = rows.iter().find(|r| r["key"] == "max_read").unwrap();
    assert_eq!(read["figure"], serde_json::json!({"count": 16}));
    assert_eq!(json["protocol"]["exceptions"][3]["code"], "41h");
    assert!(
        read.get("entry").is_none(),
        "the map's entry is not repeated"
    );
}
