//! Strings (text in registers) through the tool, with the fictional Lumen LX2 of
//! `tests/fixtures/lumen-lx2/` (model name and software version in holding registers, high byte
//! first; serial number in input registers, low byte first): `drivemap simulate` serves the
//! manual's examples, `drivemap read`/`poll` read each string whole and show it quoted, the
//! records carry it escaped, text a drive sends with control bytes is shown escaped, a write is
//! refused before the wire, `probe` agrees, `export` describes it and `diff` calls a change of
//! length or byte order breaking.

use crate::common;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use drivemap_sim::SimulatedSlave;

use common::{Framing, Scratch, Sim, command, drivemap_fixture, drivemap_in, repo, serve};

fn fixture() -> PathBuf {
    repo().join("tests/fixtures/lumen-lx2")
}

fn live(addr: &str, flag: &str, rest: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        rest[0],
        "--maps",
        ".",
        "--drive",
        "lumen-lx2",
        flag,
        addr,
        "--timeout",
        "2s",
    ];
    args.extend_from_slice(&rest[1..]);
    drivemap_fixture(&fixture(), &args)
}

fn row<'a>(out: &'a str, id: &str) -> &'a str {
    out.lines()
        .find(|l| l.starts_with(&format!("{id} ")))
        .unwrap_or_else(|| panic!("no row {id} in {out}"))
}

fn simulate() -> Sim {
    let f = fixture();
    Sim::listening(command().current_dir(&f).env("DRIVEMAP_MAPS", &f).args([
        "simulate",
        "--maps",
        ".",
        "--drive",
        "lumen-lx2",
        "--tcp",
        "0",
    ]))
}

#[test]
fn read_and_poll_show_the_simulated_manuals_examples_quoted() {
    let sim = simulate();
    let (code, out, err) = live(
        &sim.addr,
        "--tcp",
        &["read", "model_name", "software_version", "serial_number"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(row(&out, "model_name").contains("\"LX2-0750-E\""), "{out}");
    assert!(
        row(&out, "model_name").contains("4C58 322D 3037 3530 2D45 0000 0000 0000h"),
        "{out}"
    );
    assert!(row(&out, "software_version").contains("\"V1.04\""), "{out}");
    // Input registers, low byte first: "SN" is 4E53h.
    assert!(
        row(&out, "serial_number").contains("\"SN2407A113\""),
        "{out}"
    );
    assert!(row(&out, "serial_number").contains("4E53 3432"), "{out}");

    let (code, out, err) = live(
        &sim.addr,
        "--tcp",
        &["read", "--format", "json", "serial_number"],
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rec = &v[0];
    assert_eq!(rec["text"], "SN2407A113", "{out}");
    assert!(rec["value"].is_null() && rec["raw"].is_null(), "{out}");
    assert_eq!(rec["status"], "ok");

    let (code, out, err) = live(
        &sim.addr,
        "--tcp",
        &["read", "--format", "csv", "model_name"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines().nth(1).unwrap().contains(",LX2-0750-E,,ok,"),
        "{out}"
    );

    let (code, out, err) = live(
        &sim.addr,
        "--tcp",
        &[
            "poll",
            "--count",
            "2",
            "--interval",
            "50ms",
            "model_name",
            "output_frequency",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.matches("\"LX2-0750-E\"").count(), 2, "{out}");
}

#[test]
fn a_string_is_read_in_one_request_of_all_its_registers() {
    // A slave that refuses any read not exactly the string's span would fail the read; the
    // simulated slave counts requests instead: one 03h request for 8 registers, one 04h for 6.
    let map = drivemap_map::Loader::new()
        .load(&fixture().join("lumen-lx2.yaml"))
        .expect("fixture map");
    let (addr, slave) = serve(
        SimulatedSlave::new(1, drivemap_live::leak_profile(&map)),
        Framing::Tcp,
    );
    fill(&slave, 0x2100, b"LX2-0750-E", false, false);
    let (code, out, err) = live(&addr, "--tcp", &["read", "model_name"]);
    assert_eq!(code, 0, "{err}");
    assert!(row(&out, "model_name").contains("\"LX2-0750-E\""), "{out}");
}

/// Writes `text` at `address` of the slave, two bytes a word, in the order given, padded with
/// NUL to eight registers.
fn fill(
    slave: &Arc<Mutex<SimulatedSlave>>,
    address: u16,
    text: &[u8],
    low_first: bool,
    input: bool,
) {
    let mut s = slave.lock().unwrap();
    for i in 0..8u16 {
        let at = |k: usize| text.get(2 * usize::from(i) + k).copied().unwrap_or(0);
        let (a, b) = (at(0), at(1));
        let word = if low_first {
            u16::from_le_bytes([a, b])
        } else {
            u16::from_be_bytes([a, b])
        };
        if input {
            s.set_input(address + i, word);
        } else {
            s.set_holding(address + i, word);
        }
    }
}

#[test]
fn text_from_the_wire_is_shown_escaped_never_raw() {
    let map = drivemap_map::Loader::new()
        .load(&fixture().join("lumen-lx2.yaml"))
        .expect("fixture map");
    let (addr, slave) = serve(
        SimulatedSlave::new(1, drivemap_live::leak_profile(&map)),
        Framing::Tcp,
    );
    // An escape sequence that would clear a terminal, a quote, a backslash and a byte above
    // ASCII, then space padding; the serial number low byte first.
    fill(&slave, 0x2100, b"A\x1b[2J\"\\\xff   ", false, false);
    fill(&slave, 0x3000, b"SN\x07", true, true);
    let (code, out, err) = live(&addr, "--tcp", &["read", "model_name", "serial_number"]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains('\x1b') && !out.contains('\x07'), "{out:?}");
    assert!(
        row(&out, "model_name").contains(r#""A\x1B[2J\"\\\xFF""#),
        "{out}"
    );
    assert!(row(&out, "serial_number").contains(r#""SN\x07""#), "{out}");
    let (code, out, err) = live(&addr, "--tcp", &["read", "--format", "json", "model_name"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v[0]["text"], r#"A\x1B[2J\"\\\xFF"#, "{out}");
}

#[test]
fn a_write_to_a_string_is_refused_before_the_wire() {
    let sim = simulate();
    let (code, _, err) = live(&sim.addr, "--tcp", &["write", "model_name=X"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("model_name is read-only; nothing written"),
        "{err}"
    );
    let (_, out, _) = live(&sim.addr, "--tcp", &["read", "model_name"]);
    assert!(row(&out, "model_name").contains("\"LX2-0750-E\""), "{out}");
}

#[test]
fn probe_reads_the_strings_and_agrees() {
    let sim = simulate();
    let (code, out, err) = live(&sim.addr, "--tcp", &["probe"]);
    assert_eq!(code, 0, "{out}{err}");
    // 2000h-2002h, the two strings of 2100h-210Bh in one 03h request, the serial number in one
    // 04h request: every register read agrees (a string's text is any bytes).
    assert!(
        out.contains("checked 6 readable register(s) in 3 request(s): 6 agree, 0 disagree"),
        "{out}"
    );
}

#[test]
fn export_describes_a_string_and_diff_calls_its_layout_breaking() {
    let (code, out, err) = drivemap_fixture(
        &fixture(),
        &["export", "--format", "json", "lumen-lx2.yaml"],
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let reg = |id: &str| {
        v["registers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["id"] == id)
            .unwrap()
            .clone()
    };
    let serial = reg("serial_number");
    assert_eq!(serial["words"], 6);
    assert_eq!(serial["access"], "r");
    assert_eq!(
        serial["string"],
        serde_json::json!({"registers": 6, "byte_order": "low_first", "example": "SN2407A113", "source": "lumen-lx2.txt:23"})
    );
    assert!(reg("frequency_command").get("string").is_none());

    let s = Scratch::new("strings-diff");
    let base = std::fs::read_to_string(fixture().join("lumen-lx2.yaml")).unwrap();
    let from = "string: {registers: 6, byte_order: low_first,";
    assert!(base.contains(from));
    for (name, to, what) in [
        (
            "longer",
            "string: {registers: 8, byte_order: low_first,",
            "text in 8 registers",
        ),
        (
            "order",
            "string: {registers: 6, byte_order: high_first,",
            "high byte first",
        ),
    ] {
        let path = s.0.join(format!("{name}.yaml"));
        std::fs::write(&path, base.replace(from, to)).unwrap();
        let old = fixture().join("lumen-lx2.yaml");
        let (code, out, err) = drivemap_in(
            &s.0,
            &["diff", old.to_str().unwrap(), path.to_str().unwrap()],
        );
        assert_eq!(code, 1, "{name}: a breaking change exits 1: {out}{err}");
        assert!(
            out.starts_with("lumen-lx2: 1 breaking, 0 compatible\n"),
            "{name}: {out}"
        );
        assert!(
            out.contains("serial_number: width or word order changed"),
            "{name}: {out}"
        );
        assert!(out.contains(what), "{name}: {out}");
    }
}

#[test]
fn home_assistant_reads_a_string_as_text_and_node_red_decodes_it() {
    let (code, ha, err) = drivemap_fixture(
        &fixture(),
        &[
            "export",
            "--format",
            "home-assistant",
            "--all",
            "--tcp",
            "192.0.2.10:502",
            "lumen-lx2.yaml",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let sensor = |name: &str| {
        let start = ha
            .find(&format!("name: \"lumen-lx2 {name}\""))
            .unwrap_or_else(|| panic!("{ha}"));
        let rest = &ha[start..];
        rest[..rest[1..].find("- name:").map_or(rest.len(), |e| e + 1)].to_owned()
    };
    let model = sensor("Model name");
    assert!(
        model.contains("data_type: string\n        count: 8\n"),
        "{model}"
    );
    assert!(!model.contains("swap"), "{model}");
    let serial = sensor("Serial number");
    assert!(serial.contains("input_type: input"), "{serial}");
    assert!(
        serial.contains("data_type: string\n        count: 6\n        swap: byte\n"),
        "{serial}"
    );
    // Home Assistant's own schema (tests/interop/install.sh, as
    // `home_assistant_export_passes_home_assistants_own_modbus_schema` requires).
    let python = repo().join("target/ha-venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run tests/interop/install.sh",
        python.display()
    );
    let s = Scratch::new("strings-ha");
    let file = s.0.join("lumen-lx2.yaml");
    std::fs::write(&file, &ha).unwrap();
    let out = std::process::Command::new(&python)
        .arg(repo().join("tests/interop/ha_check_modbus.py"))
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );

    let (code, flow, err) = drivemap_fixture(
        &fixture(),
        &[
            "export",
            "--format",
            "node-red",
            "--all",
            "--tcp",
            "192.0.2.10:502",
            "lumen-lx2.yaml",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        flow.contains("w.slice(0, 6).map(x => String.fromCharCode(x & 255, x >> 8))"),
        "the serial number, low byte first: {flow}"
    );
    let (code, toml, err) = drivemap_fixture(
        &fixture(),
        &[
            "export",
            "--format",
            "telegraf",
            "--all",
            "--tcp",
            "192.0.2.10:502",
            "lumen-lx2.yaml",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        toml.contains("# Serial number: text, left out of Telegraf's fields"),
        "{toml}"
    );
    assert!(!toml.contains("name = \"serial_number\""), "{toml}");
}
