//! Masters nobody on this project wrote — mbpoll (libmodbus), pymodbus, minimalmodbus — against
//! our simulated Yaskawa V7, over a socat pseudo-terminal pair (Modbus RTU, and Modbus ASCII for
//! pymodbus) and over TCP (Modbus TCP, RTU frames, ASCII frames); and mbpoll's coil and
//! discrete-input reads and writes (`-t 0`, `-t 1`) against the simulated coil drive of
//! `tests/fixtures/tindra-tc4`.
//!
//! Each master runs the same scenario: read, single and multiple writes, loop-back, an
//! out-of-range write that must come back as the V7's exception 21h, a read of an unknown and of
//! a write-only register (02h), a stopped-only parameter written while running (22h), and a
//! broadcast that is executed and never answered. The simulator runs in this process on a
//! manual clock; every request it handles is recorded. A missing peer fails the test with the
//! install step (tests/interop/install.sh).

use drivemap_test_support::paths;

use crate::interop_support;

use std::process::Command;
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::serial::{Parity, SerialOptions};
use drivemap_sim::{
    Outcome, SimOptions, server::SerialServer, server::TcpFraming, server::TcpServer,
};
use interop_support::{PtyPair, Sim, python, require_tool, run_with_limit, script};
use serde_json::Value;

/// Slave 1 of a V7 with its defaults, except that the network on `link` is selected as the source
/// of run commands and of the reference (n003/n004): at the factory setting the drive ignores
/// the reference and run commands the masters write.
fn v7(link: TransportKind) -> Sim {
    Sim::new(
        "yaskawa-v7",
        SimOptions::new().slave(1).network_source(link),
    )
}

fn serve_tcp(sim: &Sim, framing: TcpFraming) -> TcpServer {
    TcpServer::spawn(sim.sim.clone(), "127.0.0.1:0", framing, Some(sim.logger()))
        .expect("serving on loopback")
}

fn serve_pty(sim: &Sim, path: &str) -> SerialServer {
    let options = SerialOptions::new(path, 9600).parity(Parity::None);
    SerialServer::spawn(sim.sim.clone(), options, Some(sim.logger())).expect("serving the pty")
}

/// What the simulator must have seen after the scenario, whichever master ran it.
fn check_drive_side(sim: &Sim, master: &str) {
    sim.wait_broadcasts(1);
    let records = sim.records();
    let broadcasts: Vec<_> = records
        .iter()
        .filter(|r| r.slave == 0)
        .map(|r| r.outcome)
        .collect();
    assert_eq!(
        broadcasts,
        [Outcome::Broadcast { executed: true }],
        "{master}: one broadcast, executed, not answered"
    );
    let exceptions: Vec<u8> = records
        .iter()
        .filter_map(|r| match r.outcome {
            Outcome::Exception { code, .. } => Some(code),
            _ => None,
        })
        .collect();
    assert_eq!(
        exceptions,
        [0x21, 0x02, 0x02, 0x22],
        "{master}: {records:?}"
    );
    sim.with(|s| {
        let state = s.state().unwrap();
        assert!(
            !state.run_command,
            "{master}: the broadcast stopped the drive"
        );
        assert_eq!(
            state.reference_hz, 30.0,
            "{master}: broadcast 15000 = 50 % of n011"
        );
        assert_eq!(s.stats().broadcasts_executed, 1);
        assert_eq!(
            s.raw("n019").unwrap(),
            100,
            "{master}: refused writes left n019 alone"
        );
    });
}

/// The scenario's results as the Python masters print them.
fn steps(output: &std::process::Output, master: &str) -> Vec<(String, Value)> {
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{master} failed: {}\n{text}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    text.lines()
        .map(|l| {
            let v: Value = serde_json::from_str(l).unwrap_or_else(|e| panic!("{master}: {l}: {e}"));
            (v["step"].as_str().unwrap_or("").to_string(), v)
        })
        .collect()
}

fn check_python_steps(steps: &[(String, Value)], master: &str) {
    let expect: &[(&str, &str, Value)] = &[
        ("read", "values", serde_json::json!([4, 0, 0, 0])),
        ("write_single", "ok", Value::Null),
        ("read_back", "values", serde_json::json!([300])),
        ("out_of_range", "exception", serde_json::json!(0x21)),
        ("unknown_register", "exception", serde_json::json!(0x02)),
        ("write_only", "exception", serde_json::json!(0x02)),
        ("write_multiple", "ok", Value::Null),
        ("status_running", "values", serde_json::json!([5])),
        ("while_running", "exception", serde_json::json!(0x22)),
        ("loop_back", "values", serde_json::json!([0xA537])),
        ("broadcast", "ok", Value::Null),
        ("status_after_broadcast", "values", serde_json::json!([4])),
    ];
    let names: Vec<&str> = steps.iter().map(|(s, _)| s.as_str()).collect();
    let wanted: Vec<&str> = expect.iter().map(|(s, _, _)| *s).collect();
    assert_eq!(names, wanted, "{master}: steps");
    for ((step, got), (_, key, value)) in steps.iter().zip(expect) {
        assert!(got.get("error").is_none(), "{master}: {step} failed: {got}");
        match *key {
            // A write answered normally (pymodbus shows the echo as registers, minimalmodbus as ok).
            "ok" => assert!(got.get("exception").is_none(), "{master}: {step}: {got}"),
            _ => assert_eq!(&got[*key], value, "{master}: {step}: {got}"),
        }
    }
}

#[test]
fn pymodbus_master_over_modbus_tcp() {
    let py = python(&["pymodbus"]);
    let sim = v7(TransportKind::Tcp);
    let server = serve_tcp(&sim, TcpFraming::ModbusTcp);
    let mut cmd = Command::new(py);
    cmd.arg(script("pymodbus_master.py"))
        .args(["--tcp", &server.local_addr().to_string()]);
    let out = run_with_limit(cmd, Duration::from_secs(60));
    check_python_steps(&steps(&out, "pymodbus/TCP"), "pymodbus/TCP");
    check_drive_side(&sim, "pymodbus/TCP");
}

#[test]
fn pymodbus_master_over_rtu_on_a_pty_pair() {
    let py = python(&["pymodbus", "serial"]);
    let pty = PtyPair::new();
    let sim = v7(TransportKind::Rtu);
    let _server = serve_pty(&sim, &pty.paths[0]);
    let mut cmd = Command::new(py);
    cmd.arg(script("pymodbus_master.py"))
        .args(["--serial", &pty.paths[1], "--baud", "9600"]);
    let out = run_with_limit(cmd, Duration::from_secs(60));
    check_python_steps(&steps(&out, "pymodbus/RTU"), "pymodbus/RTU");
    check_drive_side(&sim, "pymodbus/RTU");
}

/// Modbus ASCII: pymodbus's ASCII framer as the master of the same simulated V7, served as
/// ASCII on a pty pair and as ASCII frames over TCP; the same scenario and the same drive-side
/// checks as over RTU. The pty line is 8N1: pyserial cannot set the inter-byte timeout
/// pymodbus asks for on a pseudo-terminal at 7 data bits with parity (EINVAL).
#[test]
fn pymodbus_master_over_ascii_on_a_pty_pair() {
    let py = python(&["pymodbus", "serial"]);
    let pty = PtyPair::new();
    let sim = v7(TransportKind::Ascii);
    let options = SerialOptions::new(&pty.paths[0], 9600)
        .parity(Parity::None)
        .ascii(8)
        .expect("8 data bits");
    let _server =
        SerialServer::spawn(sim.sim.clone(), options, Some(sim.logger())).expect("serving the pty");
    let mut cmd = Command::new(py);
    cmd.arg(script("pymodbus_master.py")).args([
        "--serial",
        &pty.paths[1],
        "--baud",
        "9600",
        "--ascii",
    ]);
    let out = run_with_limit(cmd, Duration::from_secs(60));
    check_python_steps(&steps(&out, "pymodbus/ASCII"), "pymodbus/ASCII");
    check_drive_side(&sim, "pymodbus/ASCII");
    assert!(
        sim.records()
            .iter()
            .all(|r| r.transport == TransportKind::Ascii),
        "pymodbus/ASCII: every request taken as ASCII"
    );
}

#[test]
fn pymodbus_master_over_ascii_over_tcp() {
    let py = python(&["pymodbus"]);
    let sim = v7(TransportKind::AsciiOverTcp);
    let server = serve_tcp(&sim, TcpFraming::AsciiOverTcp);
    let mut cmd = Command::new(py);
    cmd.arg(script("pymodbus_master.py")).args([
        "--tcp",
        &server.local_addr().to_string(),
        "--ascii",
    ]);
    let out = run_with_limit(cmd, Duration::from_secs(60));
    check_python_steps(
        &steps(&out, "pymodbus/ASCII over TCP"),
        "pymodbus/ASCII over TCP",
    );
    check_drive_side(&sim, "pymodbus/ASCII over TCP");
}

#[test]
fn minimalmodbus_master_over_rtu_on_a_pty_pair() {
    let py = python(&["minimalmodbus", "serial"]);
    let pty = PtyPair::new();
    let sim = v7(TransportKind::Rtu);
    let _server = serve_pty(&sim, &pty.paths[0]);
    let mut cmd = Command::new(py);
    cmd.arg(script("minimalmodbus_master.py"))
        .args(["--serial", &pty.paths[1], "--baud", "9600"]);
    let out = run_with_limit(cmd, Duration::from_secs(60));
    check_python_steps(&steps(&out, "minimalmodbus/RTU"), "minimalmodbus/RTU");
    check_drive_side(&sim, "minimalmodbus/RTU");
}

#[test]
fn minimalmodbus_master_over_rtu_over_tcp() {
    let py = python(&["minimalmodbus", "serial"]);
    let sim = v7(TransportKind::Rtu);
    let server = serve_tcp(&sim, TcpFraming::RtuOverTcp);
    let mut cmd = Command::new(py);
    cmd.arg(script("minimalmodbus_master.py"))
        .args(["--rtu-tcp", &server.local_addr().to_string()]);
    let out = run_with_limit(cmd, Duration::from_secs(60));
    check_python_steps(&steps(&out, "minimalmodbus/TCP"), "minimalmodbus/TCP");
    check_drive_side(&sim, "minimalmodbus/TCP");
}

/// One mbpoll invocation: `link` selects the transport, `args` the request.
fn mbpoll(link: &[String], args: &[&str]) -> (bool, String) {
    let mut cmd = Command::new("mbpoll");
    cmd.args(["-0", "-1", "-o", "0.5", "-v"])
        .args(args)
        .args(link);
    let out = run_with_limit(cmd, Duration::from_secs(20));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// Register values mbpoll printed as `[32]: \t4`.
fn mbpoll_values(text: &str) -> Vec<u16> {
    text.lines()
        .filter_map(|l| {
            let (reference, value) = l.split_once("]:")?;
            reference.trim_start().strip_prefix('[')?;
            value.trim().parse().ok()
        })
        .collect()
}

/// The mbpoll scenario. mbpoll has no 08h loop-back, and accepts slave 0 (broadcast) only on
/// TCP, where libmodbus then waits in vain for a reply.
fn mbpoll_scenario(link: Vec<String>, tcp: bool, sim: &Sim) {
    let with = |values: &[&str], args: &[&str]| {
        let mut link = link.clone();
        link.extend(values.iter().map(|v| v.to_string()));
        mbpoll(&link, args)
    };
    let read =
        |reference: &str, count: &str| mbpoll(&link, &["-a", "1", "-r", reference, "-c", count]);
    let (ok, text) = read("32", "4");
    assert!(ok, "{text}");
    assert_eq!(mbpoll_values(&text), [4, 0, 0, 0], "{text}");
    // 06h for one value: mbpoll's -v shows the function code in the frame.
    let (ok, text) = with(&["300"], &["-a", "1", "-r", "2"]);
    assert!(ok && text.contains("[06][00][02][01][2C]"), "{text}");
    let (_, text) = read("35", "1");
    assert_eq!(mbpoll_values(&text), [300], "{text}");
    // Out of range: libmodbus has no name for 21h ("Invalid exception code"); the frame shows it.
    let (ok, text) = with(&["60001"], &["-a", "1", "-r", "275"]);
    assert!(!ok && text.contains("<86><21>"), "{text}");
    let (ok, text) = read("1536", "1");
    assert!(!ok && text.contains("Illegal data address"), "{text}");
    let (ok, text) = read("2304", "1");
    assert!(!ok && text.contains("<83><02>"), "{text}");
    // 10h: run forward at 45.0 Hz.
    let (ok, text) = with(&["1", "450"], &["-a", "1", "-r", "1"]);
    assert!(ok && text.contains("[10][00][01][00][02][04]"), "{text}");
    let (_, text) = read("32", "1");
    assert_eq!(mbpoll_values(&text), [5], "{text}");
    let (ok, text) = with(&["50"], &["-a", "1", "-r", "275"]);
    assert!(!ok && text.contains("<86><22>"), "{text}");
    if tcp {
        // Unit 0: the drive executes and stays silent, so libmodbus times out.
        let (ok, text) = with(&["0", "15000"], &["-a", "0", "-r", "1"]);
        assert!(!ok && text.contains("timed out"), "{text}");
        let (_, text) = read("32", "1");
        assert_eq!(mbpoll_values(&text), [4], "{text}");
        check_drive_side(sim, "mbpoll/TCP");
    } else {
        let (ok, text) = with(&["0", "15000"], &["-a", "0", "-r", "1"]);
        assert!(!ok, "mbpoll refuses slave 0 on RTU: {text}");
        let exceptions: Vec<u8> = sim
            .records()
            .iter()
            .filter_map(|r| match r.outcome {
                Outcome::Exception { code, .. } => Some(code),
                _ => None,
            })
            .collect();
        assert_eq!(exceptions, [0x21, 0x02, 0x02, 0x22]);
    }
}

#[test]
fn mbpoll_master_over_modbus_tcp() {
    require_tool("mbpoll", &["-V"]);
    let sim = v7(TransportKind::Tcp);
    let server = serve_tcp(&sim, TcpFraming::ModbusTcp);
    let link = vec![
        "-m".into(),
        "tcp".into(),
        "-p".into(),
        server.local_addr().port().to_string(),
        "127.0.0.1".into(),
    ];
    mbpoll_scenario(link, true, &sim);
}

#[test]
fn mbpoll_master_over_rtu_on_a_pty_pair() {
    require_tool("mbpoll", &["-V"]);
    let pty = PtyPair::new();
    let sim = v7(TransportKind::Rtu);
    let _server = serve_pty(&sim, &pty.paths[0]);
    let link = vec![
        "-m".into(),
        "rtu".into(),
        "-b".into(),
        "9600".into(),
        "-P".into(),
        "none".into(),
        pty.paths[1].clone(),
    ];
    mbpoll_scenario(link, false, &sim);
}

/// The simulated coil drive (`tests/fixtures/tindra-tc4`), its network selected on `link`.
fn tindra(link: TransportKind) -> Sim {
    let path = paths::fixture("tindra-tc4/tindra-tc4.yaml");
    let map = drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Sim::of(map, SimOptions::new().slave(1).network_source(link))
}

/// mbpoll's coils (`-t 0`: 01h, 05h, 0Fh) and discrete inputs (`-t 1`: 02h) against the coil
/// drive: the states the simulator holds, the frames libmodbus sends, the drive's exceptions,
/// and the run coil running the drive model (PDU addresses: `-0` makes `-r 0` coil 0001h).
fn mbpoll_coil_scenario(link: Vec<String>, sim: &Sim) {
    let with = |values: &[&str], args: &[&str]| {
        let mut link = link.clone();
        link.extend(values.iter().map(|v| v.to_string()));
        mbpoll(&link, args)
    };
    let read = |table: &str, reference: &str, count: &str| {
        mbpoll(
            &link,
            &["-a", "1", "-t", table, "-r", reference, "-c", count],
        )
    };
    sim.with(|s| s.set("multi_speed_2", 1.0).unwrap());
    let (ok, text) = read("0", "0", "9");
    assert!(ok && text.contains("[01][00][00][00][09]"), "{text}");
    assert_eq!(mbpoll_values(&text), [0, 0, 0, 0, 0, 0, 1, 0, 0], "{text}");
    let (ok, text) = read("1", "0", "7");
    assert!(ok && text.contains("[02][00][00][00][07]"), "{text}");
    let inputs = mbpoll_values(&text);
    assert_eq!((inputs[0], inputs[2]), (0, 1), "stopped, ready: {text}");
    // 05h for one coil (FF00h), 0Fh for two.
    let (ok, text) = with(&["1"], &["-a", "1", "-t", "0", "-r", "5"]);
    assert!(ok && text.contains("[05][00][05][FF][00]"), "{text}");
    let (ok, text) = with(&["0", "0"], &["-a", "1", "-t", "0", "-r", "5"]);
    assert!(
        ok && text.contains("[0F][00][05][00][02][01][00]"),
        "{text}"
    );
    assert_eq!(
        sim.with(|s| (
            s.raw("multi_speed_1").unwrap(),
            s.raw("multi_speed_2").unwrap()
        )),
        (0, 0)
    );
    // The reserved coil 0005h (PDU 4) and more inputs than the manual's 32: 02h and 03h.
    let (ok, text) = read("0", "4", "1");
    assert!(!ok && text.contains("Illegal data address"), "{text}");
    let (ok, text) = read("1", "0", "40");
    assert!(!ok && text.contains("Illegal data value"), "{text}");
    // The run coil runs the drive model; the operation status input shows it.
    sim.with(|s| s.set("output_frequency_setting", 30.0).unwrap());
    let (ok, text) = with(&["1"], &["-a", "1", "-t", "0", "-r", "0"]);
    assert!(ok, "{text}");
    sim.clock.advance(Duration::from_secs(2));
    let (_, text) = read("1", "0", "1");
    assert_eq!(mbpoll_values(&text), [1], "{text}");
    assert!(sim.with(|s| s.state().unwrap().run_command));
    let exceptions: Vec<u8> = sim
        .records()
        .iter()
        .filter_map(|r| match r.outcome {
            Outcome::Exception { code, .. } => Some(code),
            _ => None,
        })
        .collect();
    assert_eq!(exceptions, [0x02, 0x03]);
}

#[test]
fn mbpoll_reads_and_writes_the_simulators_coils_over_modbus_tcp() {
    require_tool("mbpoll", &["-V"]);
    let sim = tindra(TransportKind::Tcp);
    let server = serve_tcp(&sim, TcpFraming::ModbusTcp);
    let link = vec![
        "-m".into(),
        "tcp".into(),
        "-p".into(),
        server.local_addr().port().to_string(),
        "127.0.0.1".into(),
    ];
    mbpoll_coil_scenario(link, &sim);
}

#[test]
fn mbpoll_reads_and_writes_the_simulators_coils_over_rtu_on_a_pty_pair() {
    require_tool("mbpoll", &["-V"]);
    let pty = PtyPair::new();
    let sim = tindra(TransportKind::Rtu);
    let _server = serve_pty(&sim, &pty.paths[0]);
    let link = vec![
        "-m".into(),
        "rtu".into(),
        "-b".into(),
        "9600".into(),
        "-P".into(),
        "none".into(),
        pty.paths[1].clone(),
    ];
    mbpoll_coil_scenario(link, &sim);
}
