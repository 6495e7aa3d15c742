//! Machine output that joins: every JSON and CSV record `read`, `poll`, `probe` and `scan`
//! print names the drive id and the slave, `address` is a number (the manual's notation in
//! `address_text`), and each JSON output validates against its JSON Schema under
//! `docs/schema/` (Python's `jsonschema` in the interop venv: `tests/interop/install.sh`).
//! The CSV headers are the schemas' property lists, so a column added in one place and not the
//! other fails here. The drive is `drivemap simulate` at slave 7 behind a Modbus TCP gateway.

use drivemap_test_support::paths;

use crate::common;

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use common::{drivemap, repo};

const DRIVE: &str = "ptlk-tds-v8";
const SLAVE: u8 = 7;

fn schema(name: &str) -> PathBuf {
    repo()
        .join("docs")
        .join("schema")
        .join(format!("{name}.schema.json"))
}

/// The interop venv's Python with `jsonschema`, or the test fails naming the install step.
fn python() -> PathBuf {
    let python = repo().join("target/interop-venv/bin/python");
    let ok = Command::new(&python)
        .args(["-c", "import jsonschema"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        ok,
        "{} with jsonschema is missing: run tests/interop/install.sh",
        python.display()
    );
    python
}

/// Validates each JSON document of `docs` against the schema `name`; fails naming every error
/// with its path in the document.
fn validate(name: &str, docs: &[serde_json::Value]) {
    const SCRIPT: &str = "import json, sys, jsonschema
schema = json.load(open(sys.argv[1]))
jsonschema.Draft202012Validator.check_schema(schema)
v = jsonschema.Draft202012Validator(schema)
bad = 0
for i, doc in enumerate(json.load(sys.stdin)):
    for e in v.iter_errors(doc):
        bad += 1
        print(f'document {i}: at /{\"/\".join(map(str, e.absolute_path))}: {e.message}')
sys.exit(1 if bad else 0)
";
    let mut child = Command::new(python())
        .args(["-c", SCRIPT])
        .arg(schema(name))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run python");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::to_string(docs).unwrap().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{name}.schema.json rejects the output:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The property names of a schema (or of one of its `$defs`), in file order.
fn properties(name: &str, def: Option<&str>) -> Vec<String> {
    let text = std::fs::read_to_string(schema(name)).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let node = match def {
        Some(d) => &s["$defs"][d],
        None => &s,
    };
    node["properties"]
        .as_object()
        .expect("properties")
        .keys()
        .cloned()
        .collect()
}

/// `drivemap simulate` at slave 7 behind a gateway; killed on drop.
struct Sim(common::Sim);

impl Sim {
    fn start() -> Sim {
        let slave = SLAVE.to_string();
        Sim(common::Sim::start(&[
            "--drive",
            DRIVE,
            "--gateway",
            "127.0.0.1:0",
            "--slave",
            &slave,
        ]))
    }

    /// Runs `drivemap <command> --drive <id> --gateway <addr> --slave 7 <args...>`.
    fn run(&self, command: &str, args: &[&str]) -> (i32, String, String) {
        let mut all = vec![command, "--drive", DRIVE, "--gateway", &self.0.addr];
        let slave = SLAVE.to_string();
        all.extend_from_slice(&["--slave", &slave, "--timeout", "2s"]);
        all.extend_from_slice(args);
        drivemap(&all)
    }
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("not JSON ({e}):\n{text}"))
}

/// Parses `0024h` (or decimal digits) into the address it names.
fn parse_address_text(t: &str) -> u64 {
    match t.strip_suffix('h') {
        Some(hex) => u64::from_str_radix(hex, 16).unwrap(),
        None => t.parse().unwrap(),
    }
}

/// A reading record names the drive and slave; its address is the number its text names.
fn assert_joins(r: &serde_json::Value) {
    assert_eq!(r["drive"], DRIVE, "{r}");
    assert_eq!(r["slave"], SLAVE, "{r}");
    let address = r["address"].as_u64().unwrap_or_else(|| panic!("{r}"));
    let text = r["address_text"].as_str().unwrap();
    assert_eq!(parse_address_text(text), address, "{r}");
}

/// CSV rows as maps of header to cell; asserts the header is `expected`.
fn csv_rows(text: &str, expected: &[String]) -> Vec<Vec<(String, String)>> {
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_owned)
        .collect();
    assert_eq!(&header, expected, "CSV header");
    lines
        .map(|line| header.iter().cloned().zip(split_csv(line)).collect())
        .collect()
}

/// One CSV line's cells (RFC 4180 quoting; no line breaks inside cells in these outputs).
fn split_csv(line: &str) -> Vec<String> {
    let mut cells = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                cells.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(String::new()),
            (c, _) => cells.last_mut().unwrap().push(c),
        }
    }
    cells
}

fn cell<'a>(row: &'a [(String, String)], name: &str) -> &'a str {
    &row.iter().find(|(h, _)| h == name).unwrap().1
}

#[test]
fn read_and_poll_records_name_the_drive_and_slave_and_match_the_schema() {
    let sim = Sim::start();
    let regs = ["frequency_command", "Bn-01", "inverter_status"];
    let mut args = vec!["--format", "json"];
    args.extend_from_slice(&regs);
    let (code, out, err) = sim.run("read", &args);
    assert_eq!(code, 0, "{err}");
    let records: Vec<serde_json::Value> = json(&out).as_array().unwrap().clone();
    assert_eq!(records.len(), 3, "{out}");
    records.iter().for_each(assert_joins);
    // Bn-01 is at 0200h in the manual; through the gateway (RTU addressing) the same number.
    assert_eq!(records[1]["address"], 0x200, "{out}");
    assert_eq!(records[1]["address_text"], "0200h", "{out}");
    assert!(records[2]["fields"].is_object(), "{out}");
    validate("reading", &records);

    // poll: one JSON object a line, each a record of the same schema.
    let (code, out, err) = sim.run(
        "poll",
        &["--format", "json", "--count", "2", "--interval", "10ms"],
    );
    assert_eq!(code, 0, "{err}");
    let lines: Vec<serde_json::Value> = out.lines().map(json).collect();
    assert!(lines.len() >= 2, "{out}");
    lines.iter().for_each(assert_joins);
    validate("reading", &lines);

    // CSV: the header is the schema's properties (less `fields`, JSON only), in order.
    let header: Vec<String> = properties("reading", None)
        .into_iter()
        .filter(|p| p != "fields")
        .collect();
    let mut args = vec!["--format", "csv"];
    args.extend_from_slice(&regs);
    let (code, out, err) = sim.run("read", &args);
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out, &header);
    assert_eq!(rows.len(), 3, "{out}");
    for row in &rows {
        assert_eq!(cell(row, "drive"), DRIVE);
        assert_eq!(cell(row, "slave"), SLAVE.to_string());
        let address: u64 = cell(row, "address").parse().expect("a number");
        assert_eq!(parse_address_text(cell(row, "address_text")), address);
    }
    let (code, out, err) = sim.run(
        "poll",
        &["--format", "csv", "--count", "2", "--interval", "10ms"],
    );
    assert_eq!(code, 0, "{err}");
    for row in csv_rows(&out, &header) {
        assert_eq!(cell(&row, "drive"), DRIVE);
        assert_eq!(cell(&row, "slave"), SLAVE.to_string());
    }
}

#[test]
fn a_failed_read_is_a_record_of_the_schema_too() {
    let sim = Sim::start();
    // Slave 9 is not behind the gateway: no value, an error record naming slave 9.
    let (code, out, err) = drivemap(&[
        "read",
        "--drive",
        DRIVE,
        "--gateway",
        &sim.0.addr,
        "--slave",
        "9",
        "--timeout",
        "100ms",
        "--format",
        "json",
        "Bn-01",
    ]);
    assert_eq!(code, 1, "{out}{err}");
    let records: Vec<serde_json::Value> = json(&out).as_array().unwrap().clone();
    assert_eq!(records[0]["status"], "error", "{out}");
    assert_eq!(records[0]["slave"], 9, "{out}");
    assert_eq!(records[0]["drive"], DRIVE, "{out}");
    validate("reading", &records);
}

#[test]
fn probe_and_scan_reports_match_their_schemas_and_their_csv_names_drive_and_slave() {
    let sim = Sim::start();
    let (code, out, err) = sim.run("probe", &["--format", "json"]);
    assert!(code == 0 || code == 1, "{err}");
    let report = json(&out);
    assert_eq!(report["drive"], DRIVE);
    assert_eq!(report["slave"], SLAVE);
    let findings: Vec<&serde_json::Value> = report["disagreements"]
        .as_array()
        .unwrap()
        .iter()
        .chain(report["unchecked"].as_array().unwrap())
        .collect();
    assert!(!findings.is_empty(), "the TDS-V8 has write-only registers");
    for f in &findings {
        let address = f["address"].as_u64().unwrap_or_else(|| panic!("{f}"));
        assert_eq!(
            parse_address_text(f["address_text"].as_str().unwrap()),
            address
        );
    }
    validate("probe", std::slice::from_ref(&report));

    let (_, out, err) = sim.run("probe", &["--format", "csv"]);
    let mut header: Vec<String> = ["drive", "slave", "result"].map(String::from).to_vec();
    header.extend(properties("probe", Some("finding")));
    let rows = csv_rows(&out, &header);
    assert_eq!(rows.len(), findings.len(), "{out}{err}");
    for row in &rows {
        assert_eq!(cell(row, "drive"), DRIVE);
        assert_eq!(cell(row, "slave"), SLAVE.to_string());
        let address: u64 = cell(row, "address").parse().expect("a number");
        assert_eq!(parse_address_text(cell(row, "address_text")), address);
    }

    let (code, out, err) = drivemap(&[
        "scan",
        "--gateway",
        &sim.0.addr,
        "--slaves",
        "6-8",
        "--timeout",
        "200ms",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let report = json(&out);
    assert_eq!(report["found"][0]["slave"], SLAVE, "{out}");
    assert_eq!(report["found"][0]["maps"][0]["drive"], DRIVE, "{out}");
    validate("scan", &[report]);
    let (code, out, err) = drivemap(&[
        "scan",
        "--gateway",
        &sim.0.addr,
        "--slaves",
        "7",
        "--format",
        "csv",
    ]);
    assert_eq!(code, 0, "{err}");
    let header: Vec<String> = [
        "slave",
        "line",
        "answer",
        "rank",
        "drive",
        "score",
        "consistent",
        "inconsistent",
        "refused",
        "unanswered",
        "tried",
    ]
    .map(String::from)
    .to_vec();
    let rows = csv_rows(&out, &header);
    assert_eq!(cell(&rows[0], "slave"), SLAVE.to_string());
    assert_eq!(cell(&rows[0], "drive"), DRIVE);
}

#[test]
fn every_shipped_map_exports_to_the_export_schema() {
    let mut docs = Vec::new();
    for path in drivemap_map::find_maps(&paths::maps()).unwrap() {
        let (code, out, err) = drivemap(&["export", path.to_str().unwrap()]);
        assert_eq!(code, 0, "{}: {err}", path.display());
        let doc = json(&out);
        let id = path.file_stem().unwrap().to_string_lossy();
        assert_eq!(doc["drive"]["id"], *id);
        docs.push(doc);
    }
    assert!(docs.len() >= 5);
    // And a map whose manual prints no protocol fact: `protocol.not_printed` and the facts'
    // `not_printed` reasons (tests/fixtures/halden-h1).
    let halden = paths::fixture("halden-h1/halden-h1.yaml");
    let (code, out, err) = drivemap(&["export", halden.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let doc = json(&out);
    assert!(doc["protocol"]["not_printed"].is_object(), "{out}");
    docs.push(doc);
    validate("export", &docs);
}

/// A record carries the map's address and the wire's under names that say which: the ACN's
/// RTU offset (-1) sends its 0100h as PDU address 00FFh, its Modbus TCP offset (0) as 0100h.
#[test]
fn records_carry_the_maps_address_and_the_pdu_address_on_the_wire() {
    for (link, pdu) in [("--rtu-tcp", 0x00FF), ("--tcp", 0x0100)] {
        let sim = common::Sim::start(&["--drive", "automationdirect-acn", link, "0"]);
        let (code, out, err) = drivemap(&[
            "read",
            "--drive",
            "automationdirect-acn",
            link,
            sim.addr.as_str(),
            "--format",
            "json",
            "0x0100",
        ]);
        assert_eq!(code, 0, "{link}: {err}");
        let records: Vec<serde_json::Value> = json(&out).as_array().unwrap().clone();
        assert_eq!(records[0]["address"], 0x0100, "{link}: {out}");
        assert_eq!(records[0]["address_text"], "0100h", "{link}: {out}");
        assert_eq!(records[0]["pdu_address"], pdu, "{link}: {out}");
        validate("reading", &records);
        // CSV: the same, in its own column.
        let (code, out, err) = drivemap(&[
            "read",
            "--drive",
            "automationdirect-acn",
            link,
            sim.addr.as_str(),
            "--format",
            "csv",
            "0x0100",
        ]);
        assert_eq!(code, 0, "{link}: {err}");
        let header: Vec<String> = properties("reading", None)
            .into_iter()
            .filter(|p| p != "fields")
            .collect();
        let rows = csv_rows(&out, &header);
        assert_eq!(
            cell(&rows[0], "pdu_address"),
            pdu.to_string(),
            "{link}: {out}"
        );
    }
}
