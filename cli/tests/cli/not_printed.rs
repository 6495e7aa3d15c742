//! The command line on a drive whose manual prints no protocol fact (the fictional Halden H1 of
//! `tests/fixtures/halden-h1/`, every fact `unknown:`): `doc` says "not printed in the manual"
//! with each reason, `scan` warns that it scans the Modbus range 1-247 for want of a printed
//! one (and finds the simulated drive), `read` on a serial line names the serial defaults it
//! uses, and `export` writes the unknowns explicitly (validated against
//! `docs/schema/export.schema.json` by `machine_output.rs`).

use drivemap_test_support::paths;

use crate::common;

use std::path::PathBuf;
use std::sync::Arc;

use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};

use common::drivemap_fixture;

fn fixture() -> PathBuf {
    paths::fixture("halden-h1")
}

#[test]
fn check_accepts_the_map_and_doc_says_each_fact_is_not_printed_with_its_reason() {
    let (code, out, err) = drivemap_fixture(&fixture(), &["check", "halden-h1.yaml"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(!err.contains("warning"), "{err}");
    let (code, doc, err) = drivemap_fixture(&fixture(), &["doc", "halden-h1.yaml"]);
    assert_eq!(code, 0, "{err}");
    for row in [
        "| Slave address | not printed in the manual: set with F-20, whose settings the note does not list; used instead: the Modbus range 1 ..= 247 | `halden-h1.txt:7` |",
        "| Serial line | not printed in the manual: the note refers to the controller documentation for the line settings; used instead: the line's own settings (default 9600 baud, no parity, 8 data bits, 1 stop bit) | `halden-h1.txt:8` |",
        "| Exception codes | not printed in the manual: exception responses are mentioned, no codes are listed; used instead: the standard Modbus exception names | `halden-h1.txt:9` |",
        "| Timing | not printed in the manual: the note prints no frame gap, inter-character timeout or response time; used instead: the Modbus RTU rule: 3.5 characters between frames |  |",
        "at most 125 per read, 123 per write. max_read not printed in the manual: the note prints no register count for function 03H; used instead: the Modbus limit (125)",
    ] {
        assert!(doc.contains(row), "{row}\nnot in\n{doc}");
    }
}

#[test]
fn scan_warns_that_it_scans_the_modbus_range_and_finds_the_drive() {
    let drive = drivemap_map::Loader::new()
        .load(&fixture().join("halden-h1.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let sim = Simulator::new(drive, SimOptions::new().slave(200)).unwrap();
    let sim = drivemap_sim::server::shared(sim);
    let server =
        TcpServer::spawn(Arc::clone(&sim), "127.0.0.1:0", TcpFraming::Gateway, None).unwrap();
    let addr = server.local_addr().to_string();
    let (code, out, err) = drivemap_fixture(
        &fixture(),
        &[
            "scan",
            "--gateway",
            &addr,
            "--drive",
            "halden-h1",
            "--timeout",
            "20ms",
            "--format",
            "json",
        ],
    );
    server.stop();
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        err.contains(
            "warning: halden-h1: slave-address range not printed in the manual: set with F-20, \
             whose settings the note does not list (halden-h1.txt:7); scanning 1-247, the Modbus \
             unicast range"
        ),
        "{err}"
    );
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["found"][0]["slave"], 200, "{out}");
    // Slaves given on the command line: no warning, the scan relies on no unprinted range.
    let (_, _, err) = drivemap_fixture(
        &fixture(),
        &[
            "scan",
            "--tcp",
            "127.0.0.1:9",
            "--drive",
            "halden-h1",
            "--slaves",
            "1-3",
            "--timeout",
            "1ms",
        ],
    );
    assert!(!err.contains("slave-address range not printed"), "{err}");
}

#[test]
fn a_serial_link_names_the_defaults_it_uses_for_settings_not_printed() {
    // The port does not exist: the warning comes before the port is opened.
    let (code, _, err) = drivemap_fixture(
        &fixture(),
        &[
            "read",
            "--drive",
            "halden-h1",
            "--serial",
            "/nonexistent/ttyUSB9",
            "--slave",
            "1",
            "output_frequency",
        ],
    );
    assert_ne!(code, 0);
    assert!(
        err.contains(
            "warning: halden-h1: serial settings (baud rate, parity, character format) not printed \
             in the manual: the note refers to the controller documentation for the line settings \
             (halden-h1.txt:8); using 9600 baud, parity none, 1 stop bit(s), the runtime's defaults"
        ),
        "{err}"
    );
    // The settings given: nothing is assumed, nothing is said.
    let (_, _, err) = drivemap_fixture(
        &fixture(),
        &[
            "read",
            "--drive",
            "halden-h1",
            "--serial",
            "/nonexistent/ttyUSB9",
            "--baud",
            "19200",
            "--parity",
            "even",
            "--stop-bits",
            "1",
            "--slave",
            "1",
            "output_frequency",
        ],
    );
    assert!(!err.contains("serial settings"), "{err}");
}

#[test]
fn export_writes_the_unknowns_and_its_schema_names_every_fact() {
    let (code, out, err) = drivemap_fixture(&fixture(), &["export", "halden-h1.yaml"]);
    assert_eq!(code, 0, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    let np = &doc["protocol"]["not_printed"];
    assert_eq!(np["max_write"]["used"], "123 registers, the Modbus limit");
    assert_eq!(
        np["timing"]["why"],
        "the note prints no frame gap, inter-character timeout or response time"
    );
    assert_eq!(doc["protocol"]["slave_address"]["max"], 247);
    // The schema's `not_printed` names exactly the facts a map can mark.
    let schema: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(paths::workspace().join("docs/schema/export.schema.json"))
            .unwrap(),
    )
    .unwrap();
    let keys =
        &schema["properties"]["protocol"]["properties"]["not_printed"]["propertyNames"]["enum"];
    let want: Vec<&str> = drivemap_runtime::core::stated::ProtocolFact::ALL
        .iter()
        .map(|f| f.key())
        .collect();
    assert_eq!(keys, &serde_json::json!(want));
    for k in np.as_object().unwrap().keys() {
        assert!(want.contains(&k.as_str()), "{k}");
    }
}
