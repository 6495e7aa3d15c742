//! `drivemap export --format node-red` run by the real tool: Node-RED with
//! node-red-contrib-modbus (installed under target/interop-node by tests/interop/install.sh;
//! the test fails when they are missing) loads the exported flow on loopback, its admin API lists
//! every node of the flow with a type that loaded without error, and the flow's reads of a
//! `drivemap simulate` drive give the values `drivemap read` gives for the same registers.

use drivemap_test_support::paths;

use crate::common;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use serde_json::Value;

use common::{Sim, command, drivemap_builtin, repo};

/// A child process killed when the test ends, pass or fail.
struct Peer(Child);

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `drivemap simulate --tcp 0 ARGS`; returns it and its address.
fn simulate(args: &[&str]) -> (Sim, String) {
    let sim = Sim::listening(command().args(["simulate", "--tcp", "0"]).args(args));
    let addr = sim.addr.clone();
    (sim, addr)
}

/// `GET path` on the Node-RED admin API: status and body.
fn get(port: u16, path: &str) -> Option<(u16, String)> {
    let mut s = TcpStream::connect(("127.0.0.1", port)).ok()?;
    s.set_read_timeout(Some(Duration::from_secs(10))).ok()?;
    write!(
        s,
        "GET {path} HTTP/1.0\r\nHost: 127.0.0.1\r\nAccept: application/json\r\nConnection: close\r\n\r\n"
    )
    .ok()?;
    let mut text = String::new();
    s.read_to_string(&mut text).ok()?;
    let (head, body) = text.split_once("\r\n\r\n")?;
    let status = head.split_whitespace().nth(1)?.parse().ok()?;
    Some((status, body.to_owned()))
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn node_red_dir() -> PathBuf {
    repo().join("target").join("interop-node")
}

#[test]
fn the_exported_flow_loads_in_node_red_and_reads_the_values_drivemap_reads() {
    let red = node_red_dir().join("node_modules/node-red/red.js");
    let modbus = node_red_dir().join("node_modules/node-red-contrib-modbus/package.json");
    assert!(
        red.is_file() && modbus.is_file(),
        "Node-RED or node-red-contrib-modbus is missing under {}: run tests/interop/install.sh",
        node_red_dir().display()
    );

    // A V7 on Modbus TCP, started with settings the flow shows and running at 30 Hz.
    let sets = ["--set", "n152=1", "--set", "n018=0"];
    let (_sim, addr) = simulate(&[
        "--drive",
        "yaskawa-v7",
        "--network-source",
        "--time-scale",
        "1000",
        "--quiet",
        "--set",
        "n152=1",
        "--set",
        "n018=0",
        "--set",
        "n011=55.5",
        "--set",
        "n019=2.5",
    ]);
    let (code, _, err) = drivemap_builtin(
        &[
            &["write", "--drive", "yaskawa-v7", "--tcp", &addr][..],
            &sets,
            &[
                "tcp_frequency_reference=30",
                "tcp_digital_input_command=terminal_s1=on",
            ],
        ]
        .concat(),
    );
    assert_eq!(code, 0, "drivemap write: {err}");

    let registers = "output_frequency,output_current,n011,n019,n152,n003,status_signal_1";
    let (code, flow, err) = drivemap_builtin(
        &[
            &[
                "export",
                "--drive",
                "yaskawa-v7",
                "--format",
                "node-red",
                "--tcp",
                &addr,
                "--interval",
                "200ms",
                "--register",
                registers,
            ][..],
            &sets,
        ]
        .concat(),
    );
    assert_eq!(code, 0, "drivemap export: {err}");
    let red_flow = RedFlow::start(&red, &flow);
    // What drivemap reads now (the drive has reached 30 Hz; nothing changes from here).
    let (code, read, err) = drivemap_builtin(
        &[
            &[
                "read",
                "--drive",
                "yaskawa-v7",
                "--tcp",
                &addr,
                "--format",
                "json",
            ][..],
            &sets,
            &registers.split(',').collect::<Vec<_>>(),
        ]
        .concat(),
    );
    assert_eq!(code, 0, "drivemap read: {err}");
    let read: Vec<Value> = serde_json::from_str(&read).expect("read --format json");
    let expected: Vec<(String, f64)> = read
        .iter()
        .map(|r| {
            (
                r["register"].as_str().unwrap().to_owned(),
                r["value"].as_f64().unwrap_or_else(|| panic!("{r}")),
            )
        })
        .collect();
    assert_eq!(expected.len(), 7, "{read:?}");
    assert!(
        expected.contains(&("output_frequency".into(), 30.0))
            && expected.contains(&("max_output_frequency".into(), 55.5)),
        "{expected:?}"
    );

    red_flow.wait_for(&expected);
}

/// The coil fixture's flow (`tests/fixtures/tindra-tc4`): Node-RED's `modbus-read` nodes of
/// `dataType` `Coil` and `Input` read the simulated drive's coils and discrete inputs, and the
/// decoding nodes give each the 1 or 0 `drivemap read` gives, beside a register's value.
#[test]
fn the_coil_flow_reads_coils_and_discrete_inputs_in_node_red() {
    let red = node_red_dir().join("node_modules/node-red/red.js");
    assert!(
        red.is_file(),
        "Node-RED is missing under {}: run tests/interop/install.sh",
        node_red_dir().display()
    );
    let dir = paths::fixture("tindra-tc4");
    let maps = dir.to_string_lossy().into_owned();
    let with_maps = |args: &[&str]| {
        let out = command()
            .args(args)
            .env("DRIVEMAP_MAPS", &maps)
            .output()
            .unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let sim = Sim::listening(
        command()
            .args(["simulate", "--tcp", "0", "--drive", "tindra-tc4"])
            .args(["--network-source", "--time-scale", "1000", "--quiet"])
            .env("DRIVEMAP_MAPS", &maps),
    );
    let addr = sim.addr.clone();
    let link = ["--drive", "tindra-tc4", "--tcp", addr.as_str()];
    let (code, _, err) = with_maps(
        &[
            &["write"][..],
            &link,
            &["CF2=on", "F001=20", "operation_command=1"],
        ]
        .concat(),
    );
    assert_eq!(code, 0, "drivemap write: {err}");
    let registers =
        "multi_speed_1,multi_speed_2,operation_command,operation_status,inverter_ready,d081";
    let (code, flow, err) = with_maps(
        &[
            &["export"][..],
            &link,
            &[
                "--format",
                "node-red",
                "--interval",
                "200ms",
                "--register",
                registers,
            ],
        ]
        .concat(),
    );
    assert_eq!(code, 0, "drivemap export: {err}");
    assert!(
        flow.contains("\"dataType\": \"Coil\"") || flow.contains("\"dataType\":\"Coil\""),
        "{flow}"
    );
    let red_flow = RedFlow::start(&red, &flow);
    let (code, read, err) = with_maps(
        &[
            &["read"][..],
            &link,
            &["--format", "json"],
            &registers.split(',').collect::<Vec<_>>(),
        ]
        .concat(),
    );
    assert_eq!(code, 0, "drivemap read: {err}");
    let read: Vec<Value> = serde_json::from_str(&read).expect("read --format json");
    let expected: Vec<(String, f64)> = read
        .iter()
        .map(|r| {
            (
                r["register"].as_str().unwrap().to_owned(),
                r["value"].as_f64().unwrap_or_else(|| panic!("{r}")),
            )
        })
        .collect();
    // The run coil and the running input on, CF1 off, CF2 on.
    assert!(
        expected.contains(&("operation_command".into(), 1.0))
            && expected.contains(&("operation_status".into(), 1.0))
            && expected.contains(&("multi_speed_1".into(), 0.0))
            && expected.contains(&("multi_speed_2".into(), 1.0)),
        "{expected:?}"
    );
    red_flow.wait_for(&expected);
}

/// Node-RED running one flow on loopback, the modules from target/interop-node; killed when
/// dropped.
struct RedFlow {
    _red: Peer,
    port: u16,
    tab: String,
    dir: PathBuf,
    log: PathBuf,
}

impl RedFlow {
    /// Starts Node-RED with `flow` and waits until its admin API lists every node of the flow,
    /// each of a type that loaded without error.
    fn start(red: &std::path::Path, flow: &str) -> RedFlow {
        let nodes: Vec<Value> = serde_json::from_str::<Value>(flow)
            .expect("the flow is JSON")
            .as_array()
            .expect("a flow is an array of nodes")
            .clone();
        let tab = nodes.iter().find(|n| n["type"] == "tab").expect("a tab")["id"]
            .as_str()
            .unwrap()
            .to_owned();

        // Node-RED on loopback with the flow, the modules from target/interop-node.
        // One directory per flow: the tests of one process run flows side by side.
        static FLOWS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = FLOWS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("drivemap-node-red-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::os::unix::fs::symlink(
            node_red_dir().join("node_modules"),
            dir.join("node_modules"),
        )
        .unwrap();
        let flows = dir.join("flows.json");
        std::fs::write(&flows, flow).unwrap();
        let port = free_port();
        std::fs::write(
            dir.join("settings.js"),
            format!(
                "module.exports = {{ uiHost: '127.0.0.1', uiPort: {port}, flowFile: 'flows.json', \
                 logging: {{ console: {{ level: 'info' }} }}, editorTheme: {{ tours: false }} }};\n"
            ),
        )
        .unwrap();
        let log = dir.join("node-red.log");
        let _red = Peer(
            Command::new("node")
                .arg(red)
                .args(["--userDir"])
                .arg(&dir)
                .args(["--settings"])
                .arg(dir.join("settings.js"))
                .stdout(std::fs::File::create(&log).unwrap())
                .stderr(Stdio::null())
                .spawn()
                .expect("start node (Node-RED)"),
        );
        let log_text = || std::fs::read_to_string(&log).unwrap_or_default();

        // The admin API answers once the flows are started.
        let deadline = Instant::now() + Duration::from_secs(90);
        let listed = loop {
            if let Some((200, body)) = get(port, "/flows")
                && log_text().contains("Started flows")
            {
                break body;
            }
            assert!(
                Instant::now() < deadline,
                "Node-RED did not start its flows in 90 s; its log:\n{}",
                log_text()
            );
            thread::sleep(Duration::from_millis(250));
        };
        assert!(
            !log_text().contains("Waiting for missing types"),
            "a node type of the flow did not load:\n{}",
            log_text()
        );
        let listed: Vec<Value> = serde_json::from_str(&listed).expect("/flows is JSON");
        for n in &nodes {
            assert!(
                listed.iter().any(|l| l["id"] == n["id"]),
                "/flows lacks {}",
                n["id"]
            );
        }
        // Every type the flow uses is one Node-RED loaded, without an error.
        let (status, body) = get(port, "/nodes").expect("/nodes answers");
        assert_eq!(status, 200, "{body}");
        let node_sets: Vec<Value> = serde_json::from_str(&body).expect("/nodes is JSON");
        let types: Vec<&str> = nodes.iter().filter_map(|n| n["type"].as_str()).collect();
        for ty in types.iter().filter(|t| **t != "tab") {
            let set = node_sets
                .iter()
                .find(|s| {
                    s["types"]
                        .as_array()
                        .is_some_and(|t| t.iter().any(|x| x == ty))
                })
                .unwrap_or_else(|| panic!("no node set provides `{ty}`: {body}"));
            assert_eq!(set["enabled"], true, "{ty}: {set}");
            assert_ne!(set["loaded"], false, "{ty}: {set}");
            assert!(set.get("err").is_none_or(Value::is_null), "{ty}: {set}");
        }
        assert!(
            types.contains(&"modbus-read") && types.contains(&"modbus-client"),
            "{types:?}"
        );

        RedFlow {
            _red,
            port,
            tab,
            dir,
            log,
        }
    }

    fn log_text(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// Waits (60 s at most) until the flow context, where the decoding function nodes keep the
    /// values, holds `expected`.
    fn wait_for(&self, expected: &[(String, f64)]) {
        let (port, tab) = (self.port, &self.tab);
        // The flow's values, kept in its flow context by the decoding function nodes.
        let deadline = Instant::now() + Duration::from_secs(60);
        let mut last = String::new();
        loop {
            if let Some((200, body)) = get(port, &format!("/context/flow/{tab}")) {
                let context: Value = serde_json::from_str(&body).unwrap_or(Value::Null);
                let value = |id: &str| -> Option<f64> {
                    let v = &context["memory"][id];
                    v["msg"].as_str()?.parse().ok()
                };
                if expected
                    .iter()
                    .all(|(id, want)| value(id).is_some_and(|got| (got - want).abs() < 1e-9))
                {
                    break;
                }
                last = body;
            }
            assert!(
                Instant::now() < deadline,
                "the flow's values never matched drivemap read's {expected:?}; flow context: {last}\nNode-RED log:\n{}",
                self.log_text()
            );
            thread::sleep(Duration::from_millis(250));
        }
    }
}

impl Drop for RedFlow {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
