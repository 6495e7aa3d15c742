//! `drivemap proxy` with masters nobody on this project wrote: mbpoll (libmodbus) and pymodbus
//! at once in front of a simulated V7, what reached the drive read from the simulator's request
//! log (`slave   1  06h  0002h x1    ok`).

use drivemap_test_support::paths;

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use crate::bridge_support::*;

const V7: &str = "yaskawa-v7";

fn python() -> PathBuf {
    let p = paths::workspace()
        .join("target")
        .join("interop-venv")
        .join("bin")
        .join("python");
    assert!(
        p.is_file(),
        "{} is missing: run tests/interop/install.sh",
        p.display()
    );
    p
}

/// mbpoll against the proxy on `port`: `args` the request (0-based references, one poll).
fn mbpoll(port: u16, args: &[&str]) -> (bool, String) {
    let out = Command::new(require("mbpoll"))
        .args([
            "-m",
            "tcp",
            "-0",
            "-1",
            "-o",
            "2",
            "-a",
            "1",
            "-p",
            &port.to_string(),
        ])
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ),
    )
}

/// Writes to `address` (06h or 10h) in the simulator's request log.
fn writes_to(sim: &Proc, address: &str) -> usize {
    sim.output()
        .lines()
        .filter(|l| (l.contains("06h  ") || l.contains("10h  ")) && l.contains(address))
        .count()
}

/// mbpoll and a pymodbus client share the V7's line through `drivemap proxy` at once: pymodbus
/// reads the status words in a loop while mbpoll reads and writes; every pymodbus reply is the
/// four words it asked for; mbpoll's write above n011 is answered 03h and never reaches the
/// drive, its allowed write does, and its run (a command register, from a master not in
/// --allow-commands) is answered 01h and never reaches the drive; a unit not on the line is
/// answered at once.
#[test]
fn third_party_masters_share_the_line_through_the_proxy() {
    let dir = scratch("proxy");
    let (sim, line) = simulated_line_with(&dir, &[(V7, 1)], false);
    let port = free_port();
    let proxy = Proc::spawn(
        "proxy",
        drivemap(),
        &[
            "proxy",
            "--listen",
            &format!("127.0.0.1:{port}"),
            "--drive",
            "yaskawa-v7@1",
            "--rtu-tcp",
            &format!("127.0.0.1:{line}"),
            "--proxy-writes",
            "--allow-commands",
            "127.0.0.2",
        ],
        dir.join("proxy.log"),
        &[],
    );
    wait_for(
        Duration::from_secs(20),
        "the proxy listening",
        &[&proxy],
        || listening(port).then_some(()),
    );
    let script = r#"
import sys, json
from pymodbus.client import ModbusTcpClient
c = ModbusTcpClient("127.0.0.1", port=int(sys.argv[1]), timeout=5, retries=0)
assert c.connect()
bad = 0
for i in range(40):
    r = c.read_holding_registers(0x0020, count=4, device_id=1)
    if r.isError() or len(r.registers) != 4:
        bad += 1
print(json.dumps({"asked": 40, "bad": bad}))
"#;
    let pymodbus = std::thread::spawn({
        let python = python();
        move || {
            Command::new(python)
                .args(["-c", script, &port.to_string()])
                .output()
                .unwrap()
        }
    });
    let max = read_number(V7, 1, line, "max_output_frequency").unwrap();
    // n152 = 0 at the factory: the reference in 0.1 Hz, 1 Hz above n011.
    let above = ((max + 1.0) * 10.0).round().to_string();
    let (ok, text) = mbpoll(port, &["-r", "2", "127.0.0.1", &above]);
    assert!(!ok, "{text}");
    assert!(text.to_lowercase().contains("illegal data value"), "{text}");
    let (ok, text) = mbpoll(port, &["-r", "2", "127.0.0.1", "250"]);
    assert!(ok, "{text}\n{}", proxy.output());
    let (ok, text) = mbpoll(port, &["-r", "1", "127.0.0.1", "1"]);
    assert!(!ok, "{text}");
    assert!(text.to_lowercase().contains("illegal function"), "{text}");
    let (ok, text) = mbpoll(port, &["-r", "2", "-c", "1", "127.0.0.1"]);
    assert!(ok && text.contains("250"), "{text}");
    let (ok, text) = mbpoll(port, &["-a", "9", "-r", "2", "-c", "1", "127.0.0.1"]);
    assert!(!ok, "a unit not on the line: {text}");
    let out = pymodbus.join().unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        report.contains("\"bad\": 0"),
        "{report}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(read_number(V7, 1, line, "frequency_reference"), Some(25.0));
    // On the line: the allowed reference write only; never the run, never the one above n011.
    assert_eq!(writes_to(&sim, "0002h"), 1, "{}", sim.output());
    assert_eq!(writes_to(&sim, "0001h"), 0, "{}", sim.output());
    let log = proxy.output();
    assert!(log.contains("is above"), "{log}");
    assert!(log.contains("not in --allow-commands"), "{log}");
}

/// A Modbus ASCII drive (the `quill-q2` fixture, 7E1) behind the proxy and the bridge: mbpoll
/// reads and writes it through `drivemap proxy --ascii` as Modbus TCP, and the bridge's
/// `command/run` runs it over `--ascii`.
#[test]
fn an_ascii_line_behind_the_proxy_and_the_bridge() {
    let dir = scratch("ascii");
    let maps = paths::fixture("quill-q2");
    let maps = maps.to_str().unwrap();
    let line = free_port();
    let line_addr = format!("127.0.0.1:{line}");
    let sim = Proc::spawn(
        "simulate quill-q2",
        drivemap(),
        &[
            "simulate",
            "--maps",
            maps,
            "--drive",
            "quill-q2@1",
            "--rtu-tcp",
            &line_addr,
            "--ascii",
            "--network-source",
            "--time-scale",
            "50",
        ],
        dir.join("sim.log"),
        &[],
    );
    wait_for(Duration::from_secs(20), "the simulator", &[&sim], || {
        listening(line).then_some(())
    });
    let port = free_port();
    let proxy = Proc::spawn(
        "proxy",
        drivemap(),
        &[
            "proxy",
            "--maps",
            maps,
            "--listen",
            &format!("127.0.0.1:{port}"),
            "--drive",
            "quill-q2@1",
            "--rtu-tcp",
            &line_addr,
            "--ascii",
            "--proxy-writes",
        ],
        dir.join("proxy.log"),
        &[],
    );
    wait_for(Duration::from_secs(20), "the proxy", &[&proxy], || {
        listening(port).then_some(())
    });
    // 0101h: the frequency command in 0.01 Hz.
    let (ok, text) = mbpoll(port, &["-r", "257", "127.0.0.1", "1234"]);
    assert!(ok, "{text}\n{}", proxy.output());
    let (ok, text) = mbpoll(port, &["-r", "257", "-c", "1", "127.0.0.1"]);
    assert!(ok && text.contains("1234"), "{text}");
    // Above the map's 60 Hz: refused before the line.
    let (ok, text) = mbpoll(port, &["-r", "257", "127.0.0.1", "6001"]);
    assert!(
        !ok && text.to_lowercase().contains("illegal data value"),
        "{text}"
    );
    drop(proxy);
    let (broker, mqtt) = mosquitto(&dir, "mosquitto", "allow_anonymous true");
    let b = Proc::spawn(
        "bridge",
        drivemap(),
        &[
            "bridge",
            "--maps",
            maps,
            "--drive",
            "quill-q2@1",
            "--rtu-tcp",
            &line_addr,
            "--ascii",
            "--period",
            "200ms",
            "--no-metrics",
            "--mqtt",
            &format!("mqtt://127.0.0.1:{mqtt}"),
            "--allow-writes",
            "run",
        ],
        dir.join("bridge.log"),
        &[],
    );
    wait_for(
        Duration::from_secs(30),
        "the drive online",
        &[&b, &broker, &sim],
        || {
            subscribe(mqtt, "drivemap/quill-q2-1/availability", 1, &[])
                .into_iter()
                .find(|(_, v)| v == "online")
        },
    );
    assert!(publish(mqtt, "drivemap/quill-q2-1/command/run", "PRESS", &[]).0);
    wait_for(
        Duration::from_secs(10),
        "the run over ASCII",
        &[&b, &sim],
        || {
            let out = run(&[
                "read",
                "--maps",
                maps,
                "--drive",
                "quill-q2",
                "--rtu-tcp",
                &line_addr,
                "--ascii",
                "--format",
                "json",
                "run_command",
            ]);
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).ok()?;
            (v.get(0)?.get("raw")?.as_u64()? & 1 == 1).then_some(())
        },
    );
}
