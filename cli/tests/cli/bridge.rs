//! `drivemap bridge` with the real tools: Debian's Prometheus scraping it, Debian's mosquitto
//! carrying its state, discovery and commands (plain and with a password file and TLS). Each
//! test starts simulated drives (`drivemap simulate`), the bridge and the tool on loopback, and
//! fails, never skips, when a tool is missing (`tests/interop/install.sh` installs them).

use drivemap_test_support::paths;

mod bridge_contract;
mod bridge_proxy;
use crate::bridge_support;

use std::time::Duration;

use bridge_support::*;
use serde_json::Value as Json;

const V7: &str = "yaskawa-v7";
const V8: &str = "ptlk-tds-v8";

/// The bridge polling the V7 (slave 1) on a simulated line, and the TDS-V8 (slave 2) on the
/// same line when `v8` is given, with `extra` arguments.
fn bridge(
    dir: &std::path::Path,
    port: u16,
    v8: bool,
    extra: &[&str],
    env: &[(&str, &str)],
) -> Proc {
    let mut args: Vec<String> = vec!["bridge".into(), "--drive".into(), format!("{V7}@1")];
    if v8 {
        args.push("--drive".into());
        args.push(format!("{V8}@2"));
    }
    for a in [
        "--rtu-tcp",
        &format!("127.0.0.1:{port}"),
        "--period",
        "200ms",
    ] {
        args.push(a.into());
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    Proc::spawn("bridge", drivemap(), &refs, dir.join("bridge.log"), env)
}

/// Prometheus scrapes the bridge, which polls two simulated drives on one simulated line; after `drivemap write`
/// changed their references and ran them and the simulated drives ramped, Prometheus' query
/// API holds each drive's output frequency series (named and labelled per the conventions)
/// with the value the simulator holds. The bridge's health series are there too.
#[test]
fn prometheus_scrapes_the_drives_output_frequency_after_a_write() {
    let prometheus = require("prometheus");
    let dir = scratch("prometheus");
    let (sim, line) = simulated_line(&dir, &[(V7, 1), (V8, 2)]);
    let metrics = free_port();
    let maddr = format!("127.0.0.1:{metrics}");
    let b = bridge(&dir, line, true, &["--metrics", &maddr], &[]);
    wait_for(Duration::from_secs(30), "/metrics", &[&b], || {
        http_get(metrics, "/metrics").filter(|(s, body)| *s == 200 && body.contains("drivemap_up"))
    });
    let web = free_port();
    let config = dir.join("prometheus.yml");
    std::fs::write(
        &config,
        format!(
            "global:\n  scrape_interval: 1s\n  scrape_timeout: 900ms\nscrape_configs:\n  - job_name: drivemap\n    static_configs:\n      - targets: ['{maddr}']\n"
        ),
    )
    .unwrap();
    let data = dir.join("tsdb");
    let prom = Proc::spawn(
        "prometheus",
        &prometheus,
        &[
            &format!("--config.file={}", config.display()),
            &format!("--storage.tsdb.path={}", data.display()),
            &format!("--web.listen-address=127.0.0.1:{web}"),
        ],
        dir.join("prometheus.log"),
        &[],
    );
    // The references written and the drives run, as an operator would with `drivemap write`.
    for (drive, slave, reference, run) in [
        (
            V7,
            1u8,
            "frequency_reference=30",
            "digital_input_command=run_command",
        ),
        (V8, 2, "frequency_command=20", "operation_command=run"),
    ] {
        let out = bridge_support::run(&[
            "write",
            "--drive",
            drive,
            "--slave",
            &slave.to_string(),
            "--rtu-tcp",
            &format!("127.0.0.1:{line}"),
            reference,
            run,
        ]);
        assert!(
            out.status.success(),
            "{drive}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // The simulated drives ramp to their references.
    let held: Vec<f64> = [(V7, 1u8, 30.0), (V8, 2, 20.0)]
        .iter()
        .map(|&(drive, slave, target)| {
            wait_for(
                Duration::from_secs(30),
                "the drive to ramp",
                &[&sim],
                || {
                    read_number(drive, slave, line, "output_frequency")
                        .filter(|v| (v - target).abs() < 1e-6)
                },
            )
        })
        .collect();
    let query = encode("drivemap_output_frequency_hertz");
    let series = wait_for(
        Duration::from_secs(60),
        "Prometheus to hold both drives' output frequency at the simulator's values",
        &[&b, &prom],
        || {
            let (status, body) = http_get(web, &format!("/api/v1/query?query={query}"))?;
            if status != 200 {
                return None;
            }
            let v: Json = serde_json::from_str(&body).ok()?;
            let result = v["data"]["result"].as_array()?.clone();
            let value = |drive: &str| {
                result
                    .iter()
                    .find(|s| s["metric"]["drive"] == drive)
                    .and_then(|s| s["value"][1].as_str()?.parse::<f64>().ok())
            };
            (value(V7) == Some(held[0]) && value(V8) == Some(held[1])).then_some(result)
        },
    );
    let v7 = series.iter().find(|s| s["metric"]["drive"] == V7).unwrap();
    assert_eq!(v7["metric"]["slave"], "1");
    assert_eq!(v7["metric"]["register"], "output_frequency");
    assert_eq!(v7["metric"]["job"], "drivemap");
    let v8 = series.iter().find(|s| s["metric"]["drive"] == V8).unwrap();
    assert_eq!(v8["metric"]["slave"], "2");
    // Health: the cycle time against the bus-time model per link, and every drive up.
    for q in [
        ("drivemap_bridge_cycle_duration_seconds > 0", 1),
        ("drivemap_bridge_cycle_bus_model_seconds > 0", 1),
        ("drivemap_up == 1", 2),
        ("drivemap_running == 1", 2),
    ] {
        let (_, body) = http_get(web, &format!("/api/v1/query?query={}", encode(q.0))).unwrap();
        let v: Json = serde_json::from_str(&body).unwrap();
        let n = v["data"]["result"].as_array().map_or(0, Vec::len);
        assert!(n >= q.1, "{}: {n} series in {body}", q.0);
    }
    // The scrape endpoint only answers GET /metrics.
    assert_eq!(http_get(metrics, "/nothing").unwrap().0, 404);
    drop(prom);
}

/// The discovery message on `topic`.
fn config(discovery: &[(String, String)], topic: &str) -> Json {
    let (_, payload) = discovery
        .iter()
        .find(|(t, _)| t == topic)
        .unwrap_or_else(|| {
            let topics: Vec<&str> = discovery.iter().map(|(t, _)| t.as_str()).collect();
            panic!("no discovery message on {topic}; topics: {topics:#?}")
        });
    serde_json::from_str(payload).unwrap()
}

/// Home Assistant's MQTT discovery, as documented (integrations/mqtt, "Discovery messages"
/// and each platform's page): the fields every entity needs, and those of its platform.
fn check_ha_entity(component: &str, c: &Json) {
    for field in ["name", "unique_id", "availability", "device"] {
        assert!(c.get(field).is_some(), "{component} without {field}: {c}");
    }
    assert!(
        c["device"]["identifiers"]
            .as_array()
            .is_some_and(|a| !a.is_empty())
    );
    for a in c["availability"].as_array().unwrap() {
        assert!(
            a["topic"]
                .as_str()
                .is_some_and(|t| t.starts_with("drivemap/"))
        );
    }
    let sensor_classes = [
        "frequency",
        "current",
        "voltage",
        "duration",
        "power",
        "energy",
        "temperature",
        "enum",
    ];
    match component {
        "sensor" => {
            assert!(c["state_topic"].is_string(), "{c}");
            if let Some(dc) = c["device_class"].as_str() {
                assert!(sensor_classes.contains(&dc), "{dc}");
            }
        }
        "binary_sensor" => {
            assert!(c["state_topic"].is_string());
            assert_eq!(
                (c["payload_on"].as_str(), c["payload_off"].as_str()),
                (Some("1"), Some("0"))
            );
            if let Some(dc) = c["device_class"].as_str() {
                assert!(["problem", "running"].contains(&dc), "{dc}");
            }
        }
        "number" => {
            assert!(c["command_topic"].is_string(), "{c}");
            assert!(
                c["min"].is_number() && c["max"].is_number() && c["step"].is_number(),
                "{c}"
            );
        }
        "select" => {
            assert!(
                c["command_topic"].is_string() && c["options"].is_array(),
                "{c}"
            );
        }
        "button" => {
            assert!(
                c["command_topic"].is_string() && c["payload_press"].is_string(),
                "{c}"
            );
        }
        "switch" => {
            // A coil: on and off as the bridge publishes and takes them.
            assert!(c["command_topic"].is_string(), "{c}");
            assert_eq!(
                (c["payload_on"].as_str(), c["payload_off"].as_str()),
                (Some("1"), Some("0")),
                "{c}"
            );
            assert!(
                c["state_topic"].is_string() || c["optimistic"] == true,
                "{c}"
            );
        }
        other => panic!("unexpected component {other}"),
    }
}

/// The bridge on mosquitto: Home Assistant discovery with the documented fields, state values
/// equal to the simulator's, a command that changes the simulated drive, and refused ones (out
/// of range, read-only, not in --allow-writes, over the rate limit) that change nothing and are
/// published on the error topic. SIGTERM: the bridge stops within the cycle, says so, and the
/// broker shows it offline.
#[test]
fn mqtt_discovery_state_and_commands_through_the_gate() {
    let dir = scratch("mqtt");
    let (broker, port) = mosquitto(&dir, "mosquitto", "allow_anonymous true");
    let (sim, p7) = simulator(&dir, V7, 1);
    let url = format!("mqtt://127.0.0.1:{port}");
    let mut b = bridge(
        &dir,
        p7,
        false,
        &[
            "--no-metrics",
            "--mqtt",
            &url,
            "--allow-writes",
            "frequency_reference,run,output_frequency",
            "--command-rate",
            "1",
        ],
        &[],
    );
    let logs = [&b, &broker, &sim];
    // State: the maximum frequency the simulator holds, in the map's unit.
    let max = read_number(V7, 1, p7, "max_output_frequency").unwrap();
    wait_for(Duration::from_secs(30), "the state topic", &logs, || {
        subscribe(port, "drivemap/yaskawa-v7-1/max_output_frequency", 1, &[])
            .into_iter()
            .find(|(_, v)| v.parse::<f64>().ok() == Some(max))
    });
    let discovery = subscribe(port, "homeassistant/#", 2, &[]);
    let node = "drivemap_yaskawa_v7_1";
    for (topic, payload) in &discovery {
        let component = topic.split('/').nth(1).unwrap();
        check_ha_entity(component, &serde_json::from_str(payload).unwrap());
    }
    let out_f = config(
        &discovery,
        &format!("homeassistant/sensor/{node}/output_frequency/config"),
    );
    assert_eq!(out_f["unit_of_measurement"], "Hz");
    assert_eq!(out_f["device_class"], "frequency");
    assert_eq!(out_f["state_class"], "measurement");
    assert_eq!(
        out_f["state_topic"],
        "drivemap/yaskawa-v7-1/output_frequency"
    );
    let running = config(
        &discovery,
        &format!("homeassistant/binary_sensor/{node}/status_signal_1_during_run/config"),
    );
    assert_eq!(running["device_class"], "running");
    let reference = config(
        &discovery,
        &format!("homeassistant/number/{node}/frequency_reference/config"),
    );
    assert_eq!(
        reference["command_topic"],
        "drivemap/yaskawa-v7-1/set/frequency_reference"
    );
    assert_eq!(reference["unit_of_measurement"], "Hz");
    // The box spans the manual's widest bounds (at most 100 % of n011, whose maximum is the
    // manual's); the bridge checks the limit in force when a value comes.
    assert_eq!(
        (reference["min"].as_f64(), reference["step"].as_f64()),
        (Some(0.0), Some(0.01))
    );
    assert!(reference["max"].as_f64().unwrap() >= 60.0, "{reference}");
    let run = config(
        &discovery,
        &format!("homeassistant/button/{node}/command_run/config"),
    );
    assert_eq!(run["command_topic"], "drivemap/yaskawa-v7-1/command/run");
    // Not allowed, so not offered as a number: the acceleration time is a sensor.
    assert!(
        discovery
            .iter()
            .all(|(t, _)| !t.contains("/number/") || !t.contains("accel_time"))
    );
    let accel = read_number(V7, 1, p7, "accel_time_1").unwrap();

    // An allowed command changes the simulated drive.
    let (ok, text) = publish(
        port,
        "drivemap/yaskawa-v7-1/set/frequency_reference",
        "25",
        &[],
    );
    assert!(ok, "{text}");
    wait_for(
        Duration::from_secs(10),
        "the reference written",
        &logs,
        || (read_number(V7, 1, p7, "frequency_reference") == Some(25.0)).then_some(()),
    );
    // Refusals: each changes nothing and is published with its topic.
    let errors =
        std::thread::spawn(move || subscribe(port, "drivemap/yaskawa-v7-1/error", 8, &["-C", "3"]));
    std::thread::sleep(Duration::from_millis(1500)); // the bucket refills (1 per second)
    for (topic, payload) in [
        ("set/frequency_reference", "500"),
        ("set/output_frequency", "3"),
        ("set/accel_time_1", "5"),
    ] {
        std::thread::sleep(Duration::from_millis(1100));
        publish(
            port,
            &format!("drivemap/yaskawa-v7-1/{topic}"),
            payload,
            &[],
        );
    }
    let errors = errors.join().unwrap();
    let find = |topic: &str| -> Json {
        let e = errors
            .iter()
            .map(|(_, p)| serde_json::from_str::<Json>(p).unwrap())
            .find(|e| e["topic"] == format!("drivemap/yaskawa-v7-1/{topic}"))
            .unwrap_or_else(|| panic!("no refusal of {topic} in {errors:?}\n{}", b.output()));
        assert_eq!(e["written"], false);
        e
    };
    assert!(
        find("set/frequency_reference")["error"]
            .as_str()
            .unwrap()
            .contains("above")
    );
    assert!(
        find("set/output_frequency")["error"]
            .as_str()
            .unwrap()
            .contains("read")
    );
    assert!(
        find("set/accel_time_1")["error"]
            .as_str()
            .unwrap()
            .contains("--allow-writes")
    );
    assert_eq!(read_number(V7, 1, p7, "frequency_reference"), Some(25.0));
    assert_eq!(read_number(V7, 1, p7, "accel_time_1"), Some(accel));
    // A flood: over the rate limit (1 per second) the commands are refused, and at most the
    // bucket's worth is carried out.
    let flood =
        std::thread::spawn(move || subscribe(port, "drivemap/yaskawa-v7-1/error", 5, &["-C", "3"]));
    std::thread::sleep(Duration::from_millis(1500));
    assert!(publish_lines(
        port,
        "drivemap/yaskawa-v7-1/set/frequency_reference",
        "11\n12\n13\n14\n"
    ));
    let flood = flood.join().unwrap();
    assert_eq!(flood.len(), 3, "{flood:?}");
    assert!(
        flood.iter().all(|(_, p)| p.contains("rate limit")),
        "{flood:?}"
    );
    wait_for(
        Duration::from_secs(10),
        "the first of the flood written",
        &logs,
        || (read_number(V7, 1, p7, "frequency_reference") == Some(11.0)).then_some(()),
    );
    // The drive trait's run: the simulated drive ramps, and the state follows.
    std::thread::sleep(Duration::from_millis(1100));
    let (ok, _) = publish(port, "drivemap/yaskawa-v7-1/command/run", "PRESS", &[]);
    assert!(ok);
    wait_for(
        Duration::from_secs(20),
        "output frequency 11 Hz on the state topic",
        &logs,
        || {
            subscribe(port, "drivemap/yaskawa-v7-1/output_frequency", 1, &[])
                .into_iter()
                .find(|(_, v)| v == "11.0")
        },
    );
    let log = b.output();
    assert!(
        log.contains("command on \"drivemap/yaskawa-v7-1/command/run\" (\"PRESS\"): running"),
        "{log}"
    );
    assert!(
        log.contains("set/accel_time_1\" (\"5\") refused, nothing written"),
        "{log}"
    );
    // SIGTERM: stops after the cycle in flight, marks the bridge offline.
    assert_eq!(
        b.terminate(Duration::from_secs(10)),
        Some(0),
        "{}",
        b.output()
    );
    assert!(b.output().contains("bridge: stopped"));
    let availability = subscribe(port, "drivemap/+/availability", 1, &[]);
    for topic in [
        "drivemap/bridge/availability",
        "drivemap/yaskawa-v7-1/availability",
    ] {
        let last = availability.iter().rev().find(|(t, _)| t == topic);
        assert_eq!(
            last.map(|(_, v)| v.as_str()),
            Some("offline"),
            "{topic}: {availability:?}"
        );
    }
}

fn openssl(dir: &std::path::Path, args: &[&str]) {
    let out = std::process::Command::new(require("openssl"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "openssl {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A test CA and a server certificate for 127.0.0.1 signed by it, made with openssl.
fn test_ca(dir: &std::path::Path) {
    openssl(
        dir,
        &[
            "req",
            "-x509",
            "-newkey",
            "rsa:2048",
            "-nodes",
            "-keyout",
            "ca.key",
            "-out",
            "ca.pem",
            "-days",
            "2",
            "-subj",
            "/CN=drivemap test CA",
        ],
    );
    openssl(
        dir,
        &[
            "req",
            "-newkey",
            "rsa:2048",
            "-nodes",
            "-keyout",
            "server.key",
            "-out",
            "server.csr",
            "-subj",
            "/CN=localhost",
        ],
    );
    std::fs::write(
        dir.join("ext.cnf"),
        "subjectAltName=IP:127.0.0.1,DNS:localhost\nbasicConstraints=CA:FALSE\nkeyUsage=digitalSignature,keyEncipherment\nextendedKeyUsage=serverAuth\n",
    )
    .unwrap();
    openssl(
        dir,
        &[
            "x509",
            "-req",
            "-in",
            "server.csr",
            "-CA",
            "ca.pem",
            "-CAkey",
            "ca.key",
            "-CAcreateserial",
            "-out",
            "server.pem",
            "-days",
            "2",
            "-extfile",
            "ext.cnf",
        ],
    );
    // mosquitto drops root's privileges before reading them.
    for f in ["server.key", "ca.pem", "server.pem"] {
        let _ = std::process::Command::new("chmod")
            .args(["0644", dir.join(f).to_str().unwrap()])
            .status();
    }
}

/// mosquitto with a password file and TLS (a CA made by the test): the bridge connects with
/// the right credentials (from the environment) and publishes; with wrong ones (from a file)
/// the broker refuses it and the bridge says so; a client without credentials cannot publish
/// a command, and nothing changes on the drive, while the same command with credentials is
/// carried out.
#[test]
fn mqtt_with_password_and_tls() {
    let dir = scratch("tls");
    test_ca(&dir);
    let passwd = dir.join("passwd");
    let out = std::process::Command::new(require("mosquitto_passwd"))
        .args(["-b", "-c", passwd.to_str().unwrap(), "bridge", "s3cret"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::process::Command::new("chmod")
        .args(["0644", passwd.to_str().unwrap()])
        .status();
    let conf = format!(
        "allow_anonymous false\npassword_file {}\ncafile {}\ncertfile {}\nkeyfile {}\n",
        passwd.display(),
        dir.join("ca.pem").display(),
        dir.join("server.pem").display(),
        dir.join("server.key").display()
    );
    let (broker, port) = mosquitto(&dir, "mosquitto-tls", &conf);
    let (sim, p7) = simulator(&dir, V7, 1);
    let url = format!("mqtts://127.0.0.1:{port}");
    let ca = dir.join("ca.pem");
    let ca = ca.to_str().unwrap();
    let common = [
        "--no-metrics",
        "--mqtt",
        &url,
        "--mqtt-ca",
        ca,
        "--allow-writes",
        "frequency_reference",
    ];
    let good = bridge(
        &dir,
        p7,
        false,
        &common,
        &[
            ("DRIVEMAP_MQTT_USERNAME", "bridge"),
            ("DRIVEMAP_MQTT_PASSWORD", "s3cret"),
        ],
    );
    let tls = ["--cafile", ca, "-u", "bridge", "-P", "s3cret"];
    wait_for(
        Duration::from_secs(30),
        "the bridge connected and publishing over TLS",
        &[&good, &broker, &sim],
        || {
            subscribe(port, "drivemap/yaskawa-v7-1/availability", 1, &tls)
                .into_iter()
                .find(|(_, v)| v == "online")
        },
    );
    assert!(
        good.output().contains("MQTT connected to mqtts://"),
        "{}",
        good.output()
    );

    // Wrong credentials, from a file: refused, and the bridge says so.
    let wrong = dir.join("wrong");
    std::fs::write(&wrong, "bridge:not-the-password\n").unwrap();
    let bad_dir = dir.join("bad");
    std::fs::create_dir_all(&bad_dir).unwrap();
    let mut args = common.to_vec();
    args.extend([
        "--mqtt-credentials",
        wrong.to_str().unwrap(),
        "--mqtt-client-id",
        "wrong",
    ]);
    let bad = bridge(&bad_dir, p7, false, &args, &[]);
    let said = wait_for(
        Duration::from_secs(30),
        "the refusal reported",
        &[&bad, &broker],
        || {
            let log = bad.output();
            log.contains("refused the connection").then_some(log)
        },
    );
    assert!(said.contains("user name and password"), "{said}");
    assert!(!said.contains("MQTT connected"), "{said}");

    // No credentials: the broker refuses the client; nothing reaches the drive.
    let before = read_number(V7, 1, p7, "frequency_reference").unwrap();
    let (ok, text) = publish(
        port,
        "drivemap/yaskawa-v7-1/set/frequency_reference",
        "42",
        &["--cafile", ca],
    );
    assert!(!ok, "an anonymous client could publish: {text}");
    // Without TLS either: the listener speaks only TLS.
    let (ok, _) = publish(
        port,
        "drivemap/yaskawa-v7-1/set/frequency_reference",
        "42",
        &["-u", "bridge", "-P", "s3cret"],
    );
    assert!(!ok);
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(read_number(V7, 1, p7, "frequency_reference"), Some(before));
    assert!(!good.output().contains("(42)"), "{}", good.output());
    // With credentials the same command is carried out.
    let (ok, text) = publish(
        port,
        "drivemap/yaskawa-v7-1/set/frequency_reference",
        "42",
        &tls,
    );
    assert!(ok, "{text}");
    wait_for(
        Duration::from_secs(10),
        "the reference written",
        &[&good, &broker],
        || (read_number(V7, 1, p7, "frequency_reference") == Some(42.0)).then_some(()),
    );
}

/// A drive run through coils and read through discrete inputs (`tests/fixtures/tindra-tc4`)
/// behind the bridge: Home Assistant discovery makes its discrete inputs and coils binary
/// sensors (a coil allowed to be set a switch), their states are `1`/`0`, a coil is set through
/// MQTT, the drive trait's run and stop go through the run coil, and the metrics endpoint gives
/// each coil and input in its role's family (`drivemap_running`, `drivemap_run`), 0 or 1.
#[test]
fn a_coil_drive_on_mqtt_and_the_metrics_endpoint() {
    let dir = scratch("coils");
    let fixture = paths::fixture("tindra-tc4").canonicalize().unwrap();
    let maps = fixture.to_string_lossy().into_owned();
    let env = [("DRIVEMAP_MAPS", maps.as_str())];
    let line = free_port();
    let addr = format!("127.0.0.1:{line}");
    let sim = Proc::spawn(
        "simulate",
        drivemap(),
        &[
            "simulate",
            "--drive",
            "tindra-tc4@1",
            "--rtu-tcp",
            &addr,
            "--network-source",
            "--time-scale",
            "50",
            "--quiet",
        ],
        dir.join("simulate.log"),
        &env,
    );
    wait_for(Duration::from_secs(30), "the simulator", &[&sim], || {
        listening(line).then_some(())
    });
    let (broker, port) = mosquitto(&dir, "mosquitto", "allow_anonymous true");
    let metrics = free_port();
    let url = format!("mqtt://127.0.0.1:{port}");
    let maddr = format!("127.0.0.1:{metrics}");
    let b = Proc::spawn(
        "bridge",
        drivemap(),
        &[
            "bridge",
            "--drive",
            "tindra-tc4@1",
            "--rtu-tcp",
            &addr,
            "--period",
            "200ms",
            "--mqtt",
            &url,
            "--metrics",
            &maddr,
            "--allow-writes",
            "multi_speed_1,run,stop,frequency_reference",
        ],
        dir.join("bridge.log"),
        &env,
    );
    let logs = [&b, &broker, &sim];
    let root = "drivemap/tindra-tc4-1";
    let state = |object: &str| {
        subscribe(port, &format!("{root}/{object}"), 1, &[])
            .into_iter()
            .map(|(_, v)| v)
            .next_back()
    };
    wait_for(
        Duration::from_secs(30),
        "the ready input's state",
        &logs,
        || (state("inverter_ready").as_deref() == Some("1")).then_some(()),
    );
    let discovery = subscribe(port, "homeassistant/#", 2, &[]);
    for (topic, payload) in &discovery {
        let component = topic.split('/').nth(1).unwrap();
        check_ha_entity(component, &serde_json::from_str(payload).unwrap());
    }
    let node = "drivemap_tindra_tc4_1";
    let running = config(
        &discovery,
        &format!("homeassistant/binary_sensor/{node}/operation_status/config"),
    );
    assert_eq!(running["device_class"], "running");
    assert_eq!(running["state_topic"], format!("{root}/operation_status"));
    let fault = config(
        &discovery,
        &format!("homeassistant/binary_sensor/{node}/alarm_signal/config"),
    );
    assert_eq!(fault["device_class"], "problem");
    // The run coil is polled (its role) and not allowed to be set: a binary sensor.
    config(
        &discovery,
        &format!("homeassistant/binary_sensor/{node}/operation_command/config"),
    );
    let speed = config(
        &discovery,
        &format!("homeassistant/switch/{node}/multi_speed_1/config"),
    );
    assert_eq!(speed["command_topic"], format!("{root}/set/multi_speed_1"));
    // A coil set through MQTT.
    let (ok, text) = publish(port, &format!("{root}/set/multi_speed_1"), "1", &[]);
    assert!(ok, "{text}");
    let coil = |id: &str| {
        let out = std::process::Command::new(drivemap())
            .args(["read", "--drive", "tindra-tc4", "--rtu-tcp", &addr, id])
            .args(["--format", "json"])
            .env("DRIVEMAP_MAPS", &maps)
            .output()
            .unwrap();
        let v: Json = serde_json::from_slice(&out.stdout).ok()?;
        v[0]["value"].as_f64()
    };
    wait_for(Duration::from_secs(10), "the coil set", &logs, || {
        (coil("multi_speed_1") == Some(1.0)).then_some(())
    });
    // The trait's run through the run coil; the operation status input follows.
    let (ok, _) = publish(port, &format!("{root}/set/frequency_reference"), "20", &[]);
    assert!(ok);
    std::thread::sleep(Duration::from_millis(500));
    let (ok, _) = publish(port, &format!("{root}/command/run"), "PRESS", &[]);
    assert!(ok);
    wait_for(Duration::from_secs(20), "the drive to run", &logs, || {
        (state("operation_status").as_deref() == Some("1")).then_some(())
    });
    assert_eq!(coil("operation_command"), Some(1.0));
    let body = wait_for(Duration::from_secs(10), "/metrics", &logs, || {
        http_get(metrics, "/metrics")
            .filter(|(s, body)| *s == 200 && body.contains("drivemap_running{"))
            .map(|(_, body)| body)
    });
    let sample = |family: &str, register: &str| {
        body.lines()
            .find(|l| {
                l.starts_with(&format!("{family}{{"))
                    && l.contains(&format!("register=\"{register}\""))
            })
            .and_then(|l| l.rsplit(' ').next())
            .map(str::to_owned)
    };
    assert_eq!(
        sample("drivemap_running", "operation_status").as_deref(),
        Some("1.0"),
        "{body}"
    );
    assert_eq!(
        sample("drivemap_ready", "inverter_ready").as_deref(),
        Some("1.0"),
        "{body}"
    );
    // The run coil is the run role's family: 1 while running.
    assert_eq!(
        sample("drivemap_run", "operation_command").as_deref(),
        Some("1.0"),
        "{body}"
    );
    std::thread::sleep(Duration::from_millis(1100));
    let (ok, _) = publish(port, &format!("{root}/command/stop"), "PRESS", &[]);
    assert!(ok);
    wait_for(Duration::from_secs(20), "the drive to stop", &logs, || {
        (coil("operation_command") == Some(0.0)).then_some(())
    });
}
