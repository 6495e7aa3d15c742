//! Protocol facts the manual does not print (`unknown:`): how a map says so, what `check`
//! refuses or warns about, and what the lowered profile and the export carry in their place.
//! The fixture `tests/fixtures/halden-h1` is a fictional drive whose manual prints none of them.

use drivemap_test_support::paths;

use std::path::PathBuf;

use drivemap_core::stated::{ProtocolFact, Stated};

fn halden() -> PathBuf {
    paths::fixture("halden-h1/halden-h1.yaml")
}

fn halden_text() -> String {
    std::fs::read_to_string(halden()).unwrap()
}

fn read(text: &str) -> Result<drivemap_map::Map, String> {
    drivemap_map::Loader::new()
        .load_str("halden-h1.yaml", text)
        .map_err(|d| d.to_string())
}

/// The fixture with its `protocol:` line `key: ...` replaced by `line` (the whole line).
fn with_line(key: &str, line: &str) -> String {
    let text = halden_text();
    let prefix = format!("  {key}:");
    let mut found = false;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with(&prefix) {
                found = true;
                line.to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(found, "no `{key}` line in the fixture");
    out.join("\n") + "\n"
}

#[test]
fn a_map_whose_manual_prints_no_protocol_fact_loads_with_the_modbus_figures_in_the_profile() {
    let drive = drivemap_map::Loader::new()
        .load(&halden())
        .unwrap_or_else(|d| panic!("{d}"));
    assert!(
        drive.protocol_warnings().is_empty(),
        "every fact is cited or unknown"
    );
    let plan = drive.plan();
    let p = plan.profile;
    assert_eq!((p.max_read, p.max_write), (125, 123));
    assert_eq!((p.slave_min, p.slave_max), (1, 247));
    assert_eq!(p.timing.frame_gap_chars, 3.5);
    assert!(p.exceptions.is_empty());
    let facts: Vec<ProtocolFact> = p.not_printed.iter().map(|n| n.fact).collect();
    assert_eq!(
        facts,
        [
            ProtocolFact::MaxRead,
            ProtocolFact::MaxWrite,
            ProtocolFact::SlaveAddress,
            ProtocolFact::Exceptions,
            ProtocolFact::Serial,
            ProtocolFact::Timing,
        ]
    );
    assert_eq!(
        p.max_write_stated(),
        Stated::NotPrinted("the note prints no register count for function 10H")
    );
    assert_eq!(
        p.slave_range_stated(),
        Stated::NotPrinted("set with F-20, whose settings the note does not list")
    );
    let slave = p.why_not_printed(ProtocolFact::SlaveAddress).unwrap();
    assert_eq!(slave.source, Some("halden-h1.txt:7"));
    assert_eq!(
        p.max_write_stated().or(16),
        16,
        "the caller's fallback stands in"
    );
}

#[test]
fn printed_facts_stay_printed_in_the_profile() {
    let drive = drivemap_map::Loader::new()
        .load(&paths::shipped_map("ptlk-tds-v8"))
        .unwrap_or_else(|d| panic!("{d}"));
    let p = drive.plan().profile;
    assert!(p.not_printed.is_empty(), "{:?}", p.not_printed);
    assert_eq!(p.max_write_stated(), Stated::Printed(16));
    assert_eq!(p.slave_range_stated(), Stated::Printed((1, 31)));
}

/// Each shipped map: no protocol number without a source or an `unknown`.
#[test]
fn the_shipped_maps_cite_or_mark_every_protocol_number() {
    for entry in std::fs::read_dir(paths::maps()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        let drive = drivemap_map::Loader::new()
            .load(&path)
            .unwrap_or_else(|d| panic!("{d}"));
        let w = drive.protocol_warnings();
        assert!(w.is_empty(), "{}: {w:?}", path.display());
    }
}

#[test]
fn a_plain_number_is_a_warning_naming_its_place() {
    let text = with_line("max_read", "  max_read: 16");
    let drive = read(&text).unwrap();
    let w = drive.protocol_warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].loc.line, 16);
    assert!(
        w[0].message.contains("max_read 16 has no source"),
        "{}",
        w[0].message
    );
    // With a source it is quiet, and the profile uses it.
    let text = with_line(
        "max_read",
        "  max_read: {value: 16, source: \"halden-h1.txt:5\"}",
    );
    let drive = read(&text).unwrap();
    assert!(drive.protocol_warnings().is_empty());
    assert_eq!(drive.plan().profile.max_read, 16);
}

#[test]
fn a_fact_neither_given_nor_unknown_or_both_is_refused_where_it_is() {
    for (key, line, says) in [
        (
            "max_read",
            "  max_read: {source: \"halden-h1.txt:5\"}",
            "`max_read` needs its number (`value`) or why",
        ),
        (
            "slave_address",
            "  slave_address: {param: F-20, source: \"halden-h1.txt:7\"}",
            "give the slave-address range (`min` and `max`) or why",
        ),
        (
            "slave_address",
            "  slave_address: {unknown: \"not printed\", min: 1}",
            "gives no `min`",
        ),
        (
            "slave_address",
            "  slave_address: {unknown: \" \"}",
            "needs its reason",
        ),
        (
            "serial",
            "  serial: {unknown: \"not printed\", baud_rates: [9600]}",
            "give no `baud_rates`",
        ),
        (
            "serial",
            "  serial: {baud_rates: [9600], source: \"halden-h1.txt:8\"}",
            "serial settings need `parities`",
        ),
        (
            "exceptions",
            "  exceptions: {unknown: \"\"}",
            "exception list marked unknown needs its reason",
        ),
        (
            "timing",
            "  timing: {unknown: \"none\", frame_gap_chars: 3.5}",
            "gives no `frame_gap_chars`",
        ),
        (
            "timing",
            "  timing: {response_time: {unknown: \"none\", ms: 5}, source: \"halden-h1.txt:9\"}",
            "gives no `ms`, `bits` or `chars`",
        ),
        (
            "timing",
            "  timing: {frame_gap: {unknown: \"none\"}, frame_gap_chars: 3.5, source: \"halden-h1.txt:9\"}",
            "`frame_gap` is marked not printed",
        ),
    ] {
        let err = read(&with_line(key, line)).expect_err(line);
        assert!(err.contains(says), "{line}: {err}");
        assert!(err.contains("halden-h1.yaml:"), "{line}: {err}");
    }
}

#[test]
fn export_writes_each_unprinted_fact_explicitly() {
    let drive = drivemap_map::Loader::new().load(&halden()).unwrap();
    let out = drive.export();
    let p = &out["protocol"];
    assert_eq!(p["max_read"], 125);
    assert_eq!(p["max_write"], 123);
    assert_eq!(p["slave_address"]["min"], 1);
    assert_eq!(p["slave_address"]["max"], 247);
    assert_eq!(
        p["slave_address"]["not_printed"],
        "set with F-20, whose settings the note does not list"
    );
    assert!(p["slave_address"].get("unknown").is_none());
    assert_eq!(p["timing"]["frame_gap_chars"], 3.5);
    assert_eq!(
        p["not_printed"]["serial"]["why"],
        "the note refers to the controller documentation for the line settings"
    );
    assert_eq!(p["not_printed"]["serial"]["source"], "halden-h1.txt:8");
    assert_eq!(
        p["not_printed"]["exceptions"]["used"],
        "the standard Modbus exception names"
    );
    assert_eq!(p["limits"]["max_write"]["value"], 123);
    let keys: Vec<&String> = p["not_printed"].as_object().unwrap().keys().collect();
    assert_eq!(
        keys,
        [
            "max_read",
            "max_write",
            "slave_address",
            "exceptions",
            "serial",
            "timing"
        ]
    );
    // A map printing everything writes no `not_printed`.
    let tds = drivemap_map::Loader::new()
        .load(&paths::shipped_map("ptlk-tds-v8"))
        .unwrap();
    assert!(tds.export()["protocol"].get("not_printed").is_none());
}

/// The map round-trips: each `unknown` form serializes as it was written.
#[test]
fn unknown_forms_serialize_as_written() {
    let drive = drivemap_map::Loader::new().load(&halden()).unwrap();
    let yaml = serde_yaml::to_string(&drive.protocol()).unwrap();
    for part in [
        "max_read:\n  unknown: the note prints no register count for function 03H",
        "exceptions:\n  unknown: exception responses are mentioned, no codes are listed",
        "serial:\n  unknown: the note refers to the controller documentation for the line settings",
    ] {
        assert!(yaml.contains(part), "{part}\nin\n{yaml}");
    }
    let back: drivemap_map::facts::Protocol = serde_yaml::from_str(&yaml).unwrap();
    assert_eq!(back.max_read.value, None);
    assert_eq!(back.exceptions.unknown, drive.protocol().exceptions.unknown);
    assert_eq!(back.slave_address.range(), (1, 247));
}
