//! A manual that numbers its registers in decimal (the fictional Zenith Z3 of
//! `tests/fixtures/zenith-z3/`, `address_format: decimal`): `drivemap coverage` finds its rows
//! (register numbers `1`, `2`, ... `45`, not only parameter numbers), a manual in which it finds
//! none is an error, and the tool names a register by its number (`read 45`), its parameter
//! number (`read P-01`), the hex of its number (`read 2DH`) or its Modicon reference
//! (`read 40046`) against a simulated drive, and shows its address as printed (`45`).

use drivemap_test_support::paths;

use crate::common;

use std::path::PathBuf;

use drivemap_sim::SimulatedSlave;

use common::{Framing, drivemap_fixture, serve};

fn fixture() -> PathBuf {
    paths::fixture("zenith-z3")
}

#[test]
fn coverage_counts_the_rows_of_a_decimal_manual() {
    let (code, out, err) = drivemap_fixture(&fixture(), &["coverage", "zenith-z3.yaml"]);
    assert_eq!(code, 0, "{err}");
    // Five rows numbered only (1, 2, 10, 11, 12) and four with a parameter number (45-48);
    // P-04 (register 48) is left out of the map.
    assert_eq!(
        out,
        "zenith-z3: 2 tables, 9 rows, 8 cited, 0 gaps, 1 uncited\n  \
         zenith-z3.txt:11-15  Control and monitor registers            rows    5  cited    5  gaps   0  uncited   0\n  \
         zenith-z3.txt:16-19  Parameters                               rows    4  cited    3  gaps   0  uncited   1\n\
         uncited zenith-z3.txt:19  P-04  `48 P-04 Carrier frequency, 1 kHz, 2 to 16 kHz, factory setting 8 kHz`\n"
    );
}

#[test]
fn a_manual_with_no_rows_found_is_an_error_not_a_success() {
    // The same drive transcribed as if its manual printed hex, without parameter numbers:
    // nothing on the manual's lines reads as one of its rows.
    let text = std::fs::read_to_string(fixture().join("zenith-z3.yaml")).unwrap();
    let mut hex = text.replace("address_format: decimal\n", "");
    for (dec, hexa) in [
        ("45", "0x002D"),
        ("46", "0x002E"),
        ("47", "0x002F"),
        ("10", "0x000A"),
        ("11", "0x000B"),
        ("12", "0x000C"),
        ("1", "0x0001"),
        ("2", "0x0002"),
    ] {
        hex = hex.replace(&format!("address: {dec},"), &format!("address: {hexa},"));
        hex = hex.replace(&format!("address: {dec}\n"), &format!("address: {hexa}\n"));
    }
    for p in ["P-01", "P-02", "P-03"] {
        hex = hex.replace(&format!("param: {p}, "), "");
    }
    assert!(
        !hex.contains("param: P") && !hex.contains(", address: 4"),
        "{hex}"
    );
    let dir = std::env::temp_dir().join(format!("drivemap-z3-hex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let map = dir.join("zenith-z3.yaml");
    std::fs::write(&map, hex).unwrap();
    let (code, out, err) = drivemap_fixture(&fixture(), &["coverage", map.to_str().unwrap()]);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("zenith-z3.yaml: no register rows found in zenith-z3.txt"),
        "{err}"
    );
    assert!(err.contains("address_format: decimal"), "{err}");
}

#[test]
fn read_by_register_number_and_parameter_number_against_the_simulator() {
    let map = drivemap_map::Loader::new()
        .load(&fixture().join("zenith-z3.yaml"))
        .expect("fixture map");
    let mut slave = SimulatedSlave::new(1, drivemap_live::leak_profile(&map));
    slave.set_holding(45, 125); // P-01 acceleration time 12.5 s
    slave.set_holding(10, 4321); // output frequency 43.21 Hz
    let (addr, _) = serve(slave, Framing::RtuOverTcp);
    let read = |names: &[&str]| {
        let mut args = vec![
            "read",
            "--maps",
            ".",
            "--drive",
            "zenith-z3",
            "--rtu-tcp",
            &addr,
            "--timeout",
            "2s",
        ];
        args.extend_from_slice(names);
        drivemap_fixture(&fixture(), &args)
    };
    // The Modicon reference 40046 (holding register PDU address 45) too: the map's numbers
    // stay below 10000, so five digits cannot be one of its own.
    for name in ["45", "P-01", "2DH", "acceleration_time", "40046", "400046"] {
        let (code, out, err) = read(&[name]);
        assert_eq!(code, 0, "{name}: {err}");
        let row = out
            .lines()
            .find(|l| l.starts_with("acceleration_time "))
            .unwrap_or_else(|| panic!("{name}: no row in {out}"));
        assert!(row.contains("12.5 s"), "{name}: {row}");
        // The address as the manual prints it: 45, not 002Dh.
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(
            cells[..3],
            ["acceleration_time", "(P-01)", "45"],
            "{name}: {row}"
        );
    }
    let (code, out, err) = read(&["10"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("43.21 Hz"), "{out}");
    // A number no register has: refused before the wire, with what is near.
    let (code, _, err) = read(&["49"]);
    assert_ne!(code, 0);
    assert!(err.contains("zenith-z3 has no register `49`"), "{err}");
}

/// `diff` shows a decimal-numbered map's addresses as the manual prints them: `45 → 49`, not
/// `002Dh → 0031h`.
#[test]
fn diff_shows_a_decimal_maps_addresses_in_decimal() {
    let text = std::fs::read_to_string(fixture().join("zenith-z3.yaml")).unwrap();
    let moved = text.replace("address: 45, unit: s", "address: 49, unit: s");
    assert_ne!(moved, text, "the fixture has acceleration_time at 45");
    let dir = std::env::temp_dir().join(format!("drivemap-z3-diff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let new = dir.join("zenith-z3.yaml");
    std::fs::write(&new, moved).unwrap();
    let old = fixture().join("zenith-z3.yaml");
    let (code, out, err) =
        common::run(common::command().args(["diff", old.to_str().unwrap(), new.to_str().unwrap()]));
    let _ = std::fs::remove_dir_all(&dir);
    assert!(code == 0 || code == 1, "{out}{err}");
    assert!(
        out.contains("register moved") && out.contains("45 → 49"),
        "{out}"
    );
    assert!(!out.contains("002Dh"), "{out}");
}

/// A role re-pointed in a decimal-numbered map is shown with the manual's numbers:
/// `output_frequency (10)` → `frequency_command (2)`.
#[test]
fn diff_shows_a_decimal_maps_role_places_in_decimal() {
    let text = std::fs::read_to_string(fixture().join("zenith-z3.yaml")).unwrap();
    assert!(
        !text.contains("\nroles:"),
        "the fixture has no roles of its own"
    );
    let with_role = |register: &str| {
        format!(
            "{text}roles:\n  output_frequency:\n    - {{register: {register}, source: \"zenith-z3.txt:13\"}}\n"
        )
    };
    let dir = std::env::temp_dir().join(format!("drivemap-z3-roles-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("old")).unwrap();
    std::fs::create_dir_all(dir.join("new")).unwrap();
    let old = dir.join("old/zenith-z3.yaml");
    let new = dir.join("new/zenith-z3.yaml");
    std::fs::write(&old, with_role("output_frequency")).unwrap();
    std::fs::write(&new, with_role("frequency_command")).unwrap();
    let (code, out, err) =
        common::run(common::command().args(["diff", old.to_str().unwrap(), new.to_str().unwrap()]));
    let _ = std::fs::remove_dir_all(&dir);
    assert!(code == 0 || code == 1, "{out}{err}");
    assert!(
        out.contains("output_frequency (10)") && out.contains("frequency_command (2)"),
        "{out}"
    );
    assert!(!out.contains("000Ah"), "{out}");
}
