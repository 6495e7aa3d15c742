//! A manual that prints a Modicon column beside the drive's own register number (the fictional
//! Vesna V2 of `tests/fixtures/vesna-v2/`: `0 40001 WDOG TIME`, and an input table that prints
//! the reference first, `30002 1 OUTPUT FREQUENCY`). The map records the printed reference
//! (`reference: 40024`) and names registers by it (its roles); `check` holds it to the address,
//! the table and `protocol.addressing` and finds the rows by it; `coverage` counts rows keyed by
//! it; the tool reads a register by it; `doc`, `export` and the generated code show it; `diff`
//! reports it changed.

use crate::common;

use std::path::{Path, PathBuf};

use drivemap_sim::SimulatedSlave;

use common::{Framing, drivemap_fixture, repo, serve};

fn fixture() -> PathBuf {
    repo().join("tests/fixtures/vesna-v2")
}

fn map_text() -> String {
    std::fs::read_to_string(fixture().join("vesna-v2.yaml")).unwrap()
}

/// A copy of the fixture's map with `edit` applied, in a scratch directory of its own.
struct Edited {
    dir: PathBuf,
}

impl Edited {
    fn new(tag: &str, edit: impl Fn(String) -> String) -> Edited {
        let text = map_text();
        let edited = edit(text.clone());
        assert_ne!(edited, text, "{tag}: the edit changes the fixture");
        let dir = std::env::temp_dir().join(format!("drivemap-vesna-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("vesna-v2.yaml"), edited).unwrap();
        Edited { dir }
    }

    fn map(&self) -> PathBuf {
        self.dir.join("vesna-v2.yaml")
    }
}

impl Drop for Edited {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn check(map: &Path) -> (i32, String, String) {
    drivemap_fixture(&fixture(), &["check", "--strict", map.to_str().unwrap()])
}

#[test]
fn the_fixture_checks_with_every_citation_verified() {
    let (code, out, err) = check(&fixture().join("vesna-v2.yaml"));
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("citations: 23 of 23 verified, 0 indirect, 0 unverified"),
        "{out}"
    );
}

/// A row that prints the reference and no register number (`30004 Bus volts`) is found by the
/// reference the map records; without it the line mentions nothing of the register (input
/// references are not implied by `protocol.addressing`, which speaks of the 4xxxx numbers).
#[test]
fn a_row_printing_only_the_reference_verifies_through_it() {
    let manuals = std::env::temp_dir().join(format!("drivemap-vesna-m-{}", std::process::id()));
    std::fs::create_dir_all(&manuals).unwrap();
    let text = std::fs::read_to_string(fixture().join("manuals/vesna-v2.txt")).unwrap();
    let only = text.replace("30004 3 DC LINK VOLTAGE 1 V", "30004 Bus volts 1 V");
    assert_ne!(only, text);
    std::fs::write(manuals.join("vesna-v2.txt"), only).unwrap();
    let run = |map: &Path| {
        common::run(
            common::command()
                .args(["check", "--strict", map.to_str().unwrap()])
                .env("DRIVEMAP_MANUALS", &manuals),
        )
    };
    let (code, out, err) = run(&fixture().join("vesna-v2.yaml"));
    let without = Edited::new("noref", |t| {
        t.replace("address: 3, reference: 30004,", "address: 3,")
    });
    let (code_without, out_without, err_without) = run(&without.map());
    let _ = std::fs::remove_dir_all(&manuals);
    assert_eq!(code, 0, "{out}{err}");
    assert_ne!(code_without, 0, "{out_without}{err_without}");
    let all = format!("{out_without}{err_without}");
    assert!(
        all.contains("citation `vesna-v2.txt:26` does not mention"),
        "{all}"
    );
}

#[test]
fn a_reference_of_another_table_is_an_error_naming_both_readings() {
    let edited = Edited::new("table", |t| {
        t.replace(
            "address: 23, reference: 40024",
            "address: 23, reference: 30024",
        )
    });
    let (code, out, err) = check(&edited.map());
    assert_ne!(code, 0);
    let all = format!("{out}{err}");
    let line = map_text()
        .lines()
        .position(|l| l.contains("reference: 40024"))
        .unwrap()
        + 1;
    assert!(
        all.contains(&format!(
            "vesna-v2.yaml:{line}:75: error in register `motor_rated_current`: `reference: 30024` names an input register (its first digit 3), but `motor_rated_current` at register 23 is a holding register; its reference would be 40024"
        )),
        "{all}"
    );
}

#[test]
fn a_reference_the_offset_does_not_give_is_an_error_naming_both_readings() {
    // The manual's column says 40012 for register 11; written 40011 (the row above's).
    let edited = Edited::new("offset", |t| {
        t.replace(
            "address: 11, reference: 40012",
            "address: 11, reference: 40011",
        )
    });
    let (code, out, err) = check(&edited.map());
    assert_ne!(code, 0);
    let all = format!("{out}{err}");
    assert!(
        all.contains("error in register `deceleration_time`: `reference: 40011` is PDU address 000Ah, which the map's addressing makes register 10, but `deceleration_time` is register 11 (PDU address 000Bh on the serial side (offset 0), reference 40012)"),
        "{all}"
    );
    // An addressing offset that disagrees with every printed reference: each one is named.
    let shifted = Edited::new("shift", |t| t.replace("rtu_offset: 0", "rtu_offset: -1"));
    let (code, out, err) = check(&shifted.map());
    assert_ne!(code, 0);
    let all = format!("{out}{err}");
    assert!(
        all.contains("`reference: 40002` is PDU address 0001h, which the map's addressing makes register 2, but `watchdog_action` is register 1 (PDU address 0000h on the serial side (offset -1), reference 40001)"),
        "{all}"
    );
    // Not digits of a reference: said how to write one.
    let bad = Edited::new("form", |t| {
        t.replace("reference: 30004", "reference: \"3004\"")
    });
    let (_, out, err) = check(&bad.map());
    assert!(
        format!("{out}{err}").contains("`reference: 3004` is not a Modicon reference"),
        "{out}{err}"
    );
}

/// Coverage keys the input table's rows (`30002 1 OUTPUT FREQUENCY`) by the register, not by
/// the reference read as a register number.
#[test]
fn coverage_counts_rows_printed_reference_first() {
    let (code, out, err) = drivemap_fixture(&fixture(), &["coverage", "vesna-v2.yaml"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out,
        "vesna-v2: 2 tables, 11 rows, 11 cited, 0 gaps, 0 uncited\n  \
         vesna-v2.txt:14-21  Holding registers                        rows    7  cited    7  gaps   0  uncited   0\n  \
         vesna-v2.txt:24-27  Input registers                          rows    4  cited    4  gaps   0  uncited   0\n"
    );
    // Left out of the map, a row is uncited under the register number it prints.
    let edited = Edited::new("cov", |t| {
        let keep: Vec<&str> = t
            .lines()
            .filter(|l| !l.contains("id: heatsink_temperature"))
            .collect();
        keep.join("\n") + "\n"
    });
    let (code, out, err) =
        drivemap_fixture(&fixture(), &["coverage", edited.map().to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("uncited vesna-v2.txt:27  30  `30031 30 HEATSINK TEMPERATURE 1 degC`"),
        "{out}"
    );
}

#[test]
fn read_by_printed_reference_against_the_simulator() {
    let map = drivemap_map::Loader::new()
        .load(&fixture().join("vesna-v2.yaml"))
        .expect("fixture map");
    let mut slave = SimulatedSlave::new(1, drivemap_live::leak_profile(&map));
    slave.set_holding(23, 1234); // motor rated current 12.34 A
    slave.set_input(1, 4321); // output frequency 43.21 Hz
    let (addr, _) = serve(slave, Framing::RtuOverTcp);
    let read = |name: &str| {
        drivemap_fixture(
            &fixture(),
            &[
                "read",
                "--maps",
                ".",
                "--drive",
                "vesna-v2",
                "--rtu-tcp",
                &addr,
                "--timeout",
                "2s",
                name,
            ],
        )
    };
    for (name, id, value, number) in [
        ("40024", "motor_rated_current", "12.34 A", "23"),
        ("400024", "motor_rated_current", "12.34 A", "23"),
        ("23", "motor_rated_current", "12.34 A", "23"),
        ("30002", "output_frequency", "43.21 Hz", "1"),
    ] {
        let (code, out, err) = read(name);
        assert_eq!(code, 0, "{name}: {err}");
        let row = out
            .lines()
            .find(|l| l.starts_with(&format!("{id} ")))
            .unwrap_or_else(|| panic!("{name}: no row in {out}"));
        assert!(row.contains(value), "{name}: {row}");
        // The address as the manual prints it, in decimal.
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(cells[..2], [id, number], "{name}: {row}");
    }
    // A holding reference reads the holding register; an input reference where the map has
    // no input register is refused.
    let (code, _, err) = read("40003");
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = read("30011");
    assert_ne!(code, 0);
    assert!(err.contains("vesna-v2 has no register `30011`"), "{err}");
}

#[test]
fn doc_export_and_generated_code_show_the_reference() {
    let (code, doc, err) = drivemap_fixture(&fixture(), &["doc", "vesna-v2.yaml"]);
    assert_eq!(code, 0, "{err}");
    assert!(doc.contains("| 23 (0017h), Modicon 40024 |"), "{doc}");
    // The roles name their registers by reference (`register: "30002"`, `"400003"`).
    assert!(
        doc.contains("| `frequency_reference` | `frequency_setpoint` |")
            && doc.contains("| `output_frequency` | `output_frequency` |"),
        "{doc}"
    );
    // The gap in the map's notation, not in hex.
    assert!(doc.contains("| 4 (0004h) – 9 (0009h) |"), "{doc}");
    let (code, json, err) = drivemap_fixture(&fixture(), &["export", "vesna-v2.yaml"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let regs = v["registers"].as_array().unwrap();
    let current = regs
        .iter()
        .find(|r| r["id"] == "motor_rated_current")
        .unwrap();
    assert_eq!(current["reference"], "40024");
    let keys: Vec<&String> = current.as_object().unwrap().keys().collect();
    assert_eq!(keys[3..5], ["address", "reference"]);
    let (code, facts, err) = drivemap_fixture(
        &fixture(),
        &["export", "--format", "facts", "vesna-v2.yaml"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(facts.contains("Modicon reference"), "{facts}");
    assert!(facts.contains("23 (0017h)"), "{facts}");
    let generated = drivemap_codegen::Config::new()
        .map(fixture().join("vesna-v2.yaml"))
        .generate()
        .expect("generates");
    let source = &generated.modules[0].source;
    assert!(
        source.contains("#[doc(alias(\"motor_rated_current\", \"23\", \"40024\"))]"),
        "{source}"
    );
    assert!(source.contains("Modicon reference `40024`"), "{source}");
}

#[test]
fn diff_reports_a_changed_reference_and_names_coil_tables() {
    let edited = Edited::new("diff", |t| {
        t.replace(
            "address: 23, reference: 40024",
            "address: 23, reference: 400024",
        )
        .replace("addresses: [4, 9]", "addresses: [4, 8]")
    });
    let old = fixture().join("vesna-v2.yaml");
    let (code, out, err) = common::run(common::command().args([
        "diff",
        old.to_str().unwrap(),
        edited.map().to_str().unwrap(),
    ]));
    assert!(code == 0 || code == 1, "{out}{err}");
    assert!(
        out.contains("Modicon reference") && out.contains("40024 → 400024"),
        "{out}"
    );
    // The gaps in the map's notation.
    assert!(
        out.contains("4 – 9") && out.contains("4 – 8") && !out.contains("0004h"),
        "{out}"
    );
    // A table change between a register and a coil names both tables' read functions.
    let tindra = repo().join("tests/fixtures/tindra-tc4/tindra-tc4.yaml");
    let text = std::fs::read_to_string(&tindra).unwrap();
    let moved = Edited::new("coil", |_| {
        text.replace(
            "{id: jogging, param: JG, name: Jogging, address: 0x0008,",
            "{id: jogging, param: JG, name: Jogging, address: 0x0008, modbus_table: holding,",
        )
    });
    let dir = moved.dir.join("tindra-tc4.yaml");
    std::fs::rename(moved.map(), &dir).unwrap();
    let (_, out, err) = common::run(common::command().args([
        "diff",
        tindra.to_str().unwrap(),
        dir.to_str().unwrap(),
    ]));
    assert!(
        out.contains("01h coils → 03h holding registers") && !out.contains("03h ↔ 04h"),
        "{out}{err}"
    );
}
