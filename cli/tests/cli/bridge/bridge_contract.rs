//! The drive contract on the path people expose to their network: `drivemap bridge` with a real
//! mosquitto (persistence, retained messages) and simulated drives, each case asserting what
//! reached the simulator (its request log: `slave   1  06h  0001h x1    ok`) and what the drive
//! holds (`drivemap read`).
//!
//! - retained, empty and non-`PRESS` messages on command topics write nothing, at start, after
//!   a broker restart and after a bridge restart;
//! - a stop gets through a flood of runs at any rate, and the drive ends stopped;
//! - `run` keeps the direction of a drive turning in reverse, and a `set/` of the command word
//!   is kept by run and stop;
//! - a random interleaving of runs, stops, references and resets (retained or not, pressed or
//!   not) against a line with a drive that never answers: the drive ends as the last pressed,
//!   unretained run or stop says, within the bound, and never changes direction;
//! - untrusted text in logs is escaped and shortened; credentials in `--mqtt`, wildcard topic
//!   roots and a rate of `inf` are refused.

use drivemap_test_support::paths;

use std::time::{Duration, Instant};

use crate::bridge_support::*;
use drivemap_test_support::rng::SplitMix;

const V7: &str = "yaskawa-v7";
const RUN: &str = "drivemap/yaskawa-v7-1/command/run";
const STOP: &str = "drivemap/yaskawa-v7-1/command/stop";

/// The V7's command word as the simulator holds it (`drivemap read`).
fn command_word(port: u16) -> Option<u16> {
    let out = run(&[
        "read",
        "--drive",
        V7,
        "--rtu-tcp",
        &format!("127.0.0.1:{port}"),
        "--format",
        "json",
        "digital_input_command",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).ok()?;
    Some(v.get(0)?.get("raw")?.as_u64()? as u16)
}

/// Writes to the V7's command register (06h or 10h to 0001h) in a simulator's request log.
fn command_writes(sim: &Proc) -> usize {
    sim.output()
        .lines()
        .filter(|l| {
            l.contains("slave   1") && (l.contains("06h  0001h") || l.contains("10h  0001h"))
        })
        .count()
}

/// The bridge on the V7 of `line` (and, with `silent`, a V7 at slave 9 that never answers),
/// on the broker at `broker`, `extra` arguments after the usual ones.
fn bridge_on(dir: &std::path::Path, line: u16, broker: u16, silent: bool, extra: &[&str]) -> Proc {
    let mut args: Vec<String> = ["bridge", "--drive", "yaskawa-v7@1"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    if silent {
        args.extend(["--drive".into(), "yaskawa-v7@9".into()]);
    }
    for a in [
        "--rtu-tcp",
        &format!("127.0.0.1:{line}"),
        "--period",
        "200ms",
        "--timeout",
        "300ms",
        "--mqtt",
        &format!("mqtt://127.0.0.1:{broker}"),
        "--mqtt-client-id",
        "drivemap-test",
    ] {
        args.push(a.to_owned());
    }
    if !extra.contains(&"--metrics") {
        args.push("--no-metrics".into());
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    Proc::spawn("bridge", drivemap(), &refs, dir.join("bridge.log"), &[])
}

fn online(port: u16, logs: &[&Proc]) {
    wait_for(Duration::from_secs(30), "the drive online", logs, || {
        subscribe(port, "drivemap/yaskawa-v7-1/availability", 1, &[])
            .into_iter()
            .find(|(_, v)| v == "online")
    });
}

fn connections(b: &Proc) -> usize {
    b.output().matches("MQTT connected").count()
}

/// Retained, empty and non-`PRESS` messages on `command/run` start nothing: a retained run
/// published before the bridge starts, the same after a broker restart (persistence keeps it)
/// and after a bridge restart; `OFF`, `0`, `false`, `stop`, `{"state":"off"}` and the empty
/// payload, each refused on the error topic. A `PRESS` then runs the drive. (The bridge used to
/// start the drive on each of them.)
#[test]
fn retained_and_unpressed_commands_start_nothing() {
    let dir = scratch("retained");
    let conf = format!(
        "allow_anonymous true\npersistence true\npersistence_location {}/\n",
        dir.display()
    );
    let (broker, port) = mosquitto(&dir, "mosquitto", &conf);
    let (sim, line) = simulated_line_with(&dir, &[(V7, 1)], false);
    assert!(publish(port, RUN, "PRESS", &["-r", "-q", "1"]).0);
    assert!(
        publish(
            port,
            "drivemap/yaskawa-v7-1/command/reference",
            "30",
            &["-r"]
        )
        .0
    );
    let allow = ["--allow-writes", "run,frequency_reference,fault_reset"];
    let mut b = bridge_on(&dir, line, port, false, &allow);
    online(port, &[&b, &broker, &sim]);
    let errors = std::thread::spawn(move || {
        subscribe(port, "drivemap/yaskawa-v7-1/error", 12, &["-C", "6"])
    });
    std::thread::sleep(Duration::from_millis(800));
    for payload in ["OFF", "0", "false", "stop", "{\"state\":\"off\"}", ""] {
        std::thread::sleep(Duration::from_millis(600));
        publish(port, RUN, payload, &[]);
    }
    let errors = errors.join().unwrap();
    assert_eq!(errors.len(), 6, "{errors:?}\n{}", b.output());
    for (_, e) in &errors {
        let e: serde_json::Value = serde_json::from_str(e).unwrap();
        assert_eq!(e["written"], false);
        assert!(e["error"].as_str().unwrap().contains("PRESS"), "{e}");
    }
    // The broker goes away and comes back with its retained messages.
    drop(broker);
    let (broker, _) = mosquitto_on(&dir, "mosquitto", &conf, port);
    wait_for(
        Duration::from_secs(30),
        "the bridge reconnected",
        &[&b],
        || (connections(&b) >= 2).then_some(()),
    );
    std::thread::sleep(Duration::from_secs(2));
    // The bridge goes away and comes back.
    assert_eq!(b.terminate(Duration::from_secs(10)), Some(0));
    let again = dir.join("again");
    std::fs::create_dir_all(&again).unwrap();
    let b = bridge_on(&again, line, port, false, &allow);
    online(port, &[&b, &broker, &sim]);
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(command_writes(&sim), 0, "{}", sim.output());
    assert_eq!(command_word(line), Some(0));
    assert_eq!(read_number(V7, 1, line, "frequency_reference"), Some(0.0));
    // A press runs it.
    assert!(publish(port, RUN, "PRESS", &[]).0);
    wait_for(Duration::from_secs(10), "the run", &[&b, &sim], || {
        (command_word(line)? & 1 == 1).then_some(())
    });
    assert_eq!(command_writes(&sim), 1, "{}", sim.output());
}

/// `--command-rate 1` and a client pressing `run` 20 times a second: the operator's stops are
/// never refused (each is carried out, or superseded by a run that came after it), and after
/// the last stop the drive stays stopped. The bridge used to refuse stops over the rate and
/// carry queued runs out after them. The stops' latency (arrival to the write's reply, from the
/// bridge's own histogram) is printed.
#[test]
fn a_stop_gets_through_a_flood_of_runs() {
    let dir = scratch("flood");
    let (broker, port) = mosquitto(&dir, "mosquitto", "allow_anonymous true");
    let (sim, line) = simulated_line_with(&dir, &[(V7, 1)], true);
    let metrics = free_port();
    let b = bridge_on(
        &dir,
        line,
        port,
        false,
        &[
            "--allow-writes",
            "run",
            "--command-rate",
            "1",
            "--metrics",
            &format!("127.0.0.1:{metrics}"),
        ],
    );
    online(port, &[&b, &broker, &sim]);
    let flood = std::thread::spawn(move || {
        let presses: String = (0..60).map(|_| "PRESS\n").collect();
        // ~20 per second from one client (mosquitto_pub -l sends a line each as it reads it).
        for chunk in presses.as_bytes().chunks(6 * 5) {
            publish_lines(port, RUN, std::str::from_utf8(chunk).unwrap());
            std::thread::sleep(Duration::from_millis(250));
        }
    });
    for _ in 0..5 {
        std::thread::sleep(Duration::from_millis(400));
        assert!(publish(port, STOP, "PRESS", &[]).0);
    }
    flood.join().unwrap();
    assert!(publish(port, STOP, "PRESS", &[]).0);
    let t0 = Instant::now();
    wait_for(Duration::from_secs(5), "the last stop", &[&b, &sim], || {
        (command_word(line)? & 1 == 0).then_some(())
    });
    let last = t0.elapsed();
    std::thread::sleep(Duration::from_secs(3));
    assert_eq!(command_word(line).map(|w| w & 1), Some(0), "{}", b.output());
    let log = b.output();
    let stops: Vec<&str> = log.lines().filter(|l| l.contains("command/stop")).collect();
    assert_eq!(stops.len(), 6, "{log}");
    assert!(
        stops
            .iter()
            .all(|l| l.ends_with(": stopped") || l.contains("superseded by a later run")),
        "{stops:#?}"
    );
    assert!(log.contains("rate limit"), "{log}");
    let (_, text) = http_get(metrics, "/metrics").unwrap();
    let stat = |what: &str| -> f64 {
        text.lines()
            .filter(|l| {
                l.starts_with(&format!("drivemap_bridge_command_latency_seconds_{what}"))
                    && l.contains("command=\"stop\"")
            })
            .filter_map(|l| l.rsplit(' ').next()?.parse::<f64>().ok())
            .sum()
    };
    let (sum, count) = (stat("sum"), stat("count"));
    assert!(count >= 1.0, "{text}");
    eprintln!(
        "stop latency under a 20/s run flood: {count} stops carried out, mean {:.1} ms from arrival to the write's reply; the last one read stopped by a separate process {last:?} after publishing",
        1000.0 * sum / count
    );
}

/// A random interleaving of MQTT messages (run, stop, reference, fault reset; retained or not;
/// `PRESS` or another payload) with broker restarts (persistence on), against a line with a
/// drive that never answers: after each sequence the drive is running exactly when the last
/// pressed, unretained run or stop was a run, it never changes direction (it turns in reverse
/// from the start, as another master set it), and retained or unpressed messages alone never
/// start it. On the bridge before this change, seed 7 fails on its first sequence (an `OFF` or
/// a retained run starts the drive, a run reverses it).
#[test]
fn random_interleavings_keep_the_contract() {
    let dir = scratch("interleavings");
    let conf = format!(
        "allow_anonymous true\npersistence true\npersistence_location {}/\n",
        dir.display()
    );
    let (mut broker, port) = mosquitto(&dir, "mosquitto", &conf);
    let (sim, line) = simulated_line_with(&dir, &[(V7, 1)], true);
    // Reverse selected before the bridge starts, by another master.
    let out = run(&[
        "write",
        "--drive",
        V7,
        "--rtu-tcp",
        &format!("127.0.0.1:{line}"),
        "digital_input_command=reverse=1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b = bridge_on(
        &dir,
        line,
        port,
        true,
        &[
            "--allow-writes",
            "run,frequency_reference,fault_reset",
            "--command-rate",
            "50",
        ],
    );
    online(port, &[&b, &broker, &sim]);
    for seed in [7u64, 11, 23, 42] {
        let mut rng = SplitMix(seed);
        let mut expect_running = command_word(line).unwrap() & 1 == 1;
        for _ in 0..10 {
            if rng.chance(12) {
                // The broker restarts; the bridge reconnects before the next message.
                let before = connections(&b);
                drop(broker);
                broker = mosquitto_on(&dir, "mosquitto", &conf, port).0;
                wait_for(
                    Duration::from_secs(30),
                    "the bridge reconnected",
                    &[&b],
                    || (connections(&b) > before).then_some(()),
                );
                std::thread::sleep(Duration::from_millis(500));
            }
            let what = rng.below(4);
            let retained = rng.chance(25);
            let pressed = rng.chance(70);
            let (topic, payload) = match what {
                0 => (RUN, if pressed { "PRESS" } else { "OFF" }),
                1 => (STOP, if pressed { "PRESS" } else { "" }),
                2 => ("drivemap/yaskawa-v7-1/command/reference", "20"),
                _ => (
                    "drivemap/yaskawa-v7-1/command/fault_reset",
                    if pressed { "PRESS" } else { "1" },
                ),
            };
            let mut extra = vec![];
            if retained {
                extra.push("-r");
            }
            assert!(publish(port, topic, payload, &extra).0);
            if retained && rng.chance(50) {
                // Cleared, as MQTT does: an empty retained message (or left for the restart).
                publish(port, topic, "", &["-r"]);
            }
            if !retained && pressed && what <= 1 {
                expect_running = what == 0;
            }
            std::thread::sleep(Duration::from_millis(rng.below(300)));
        }
        // Two request times of the silent drive (600 ms each), the V7's, and `drivemap read`.
        std::thread::sleep(Duration::from_millis(1800));
        let word = command_word(line).unwrap();
        assert_eq!(
            word & 1 == 1,
            expect_running,
            "seed {seed}: command word {word:04X}h\n{}",
            b.output()
        );
        assert_eq!(
            word & 2,
            2,
            "seed {seed}: the direction changed ({word:04X}h)"
        );
        // Leave no retained command behind for the next seed.
        for t in [RUN, STOP, "drivemap/yaskawa-v7-1/command/fault_reset"] {
            publish(port, t, "", &["-r"]);
        }
    }
}

/// Untrusted text is escaped and shortened in the log, so a payload cannot forge a line; the
/// options that would leak a password or silently break the connection are refused at start;
/// a `--config` nested 100,000 deep is refused at once with the map loader's depth limit (it
/// took 36.7 s, quadratic).
#[test]
fn untrusted_text_and_unsafe_options() {
    let dir = scratch("hygiene");
    let (broker, port) = mosquitto(&dir, "mosquitto", "allow_anonymous true");
    let (sim, line) = simulated_line_with(&dir, &[(V7, 1)], true);
    let b = bridge_on(&dir, line, port, false, &["--allow-writes", "run"]);
    online(port, &[&b, &broker, &sim]);
    let forged = "x\nbridge: command on drivemap/yaskawa-v7-1/command/stop (PRESS): stopped";
    publish(port, RUN, forged, &[]);
    // Larger than the bridge takes: the broker drops it for this client, the connection stays.
    let big = dir.join("big");
    std::fs::write(&big, "A".repeat(200 * 1024)).unwrap();
    let sent = std::process::Command::new(require("mosquitto_pub"))
        .args(["-h", "127.0.0.1", "-p", &port.to_string(), "-t", RUN, "-f"])
        .arg(&big)
        .status()
        .unwrap();
    assert!(sent.success());
    std::thread::sleep(Duration::from_secs(3));
    let log = b.output();
    assert!(
        !log.lines()
            .any(|l| l.starts_with("bridge: command on drivemap/yaskawa-v7-1/command/stop")),
        "{log}"
    );
    assert!(log.contains("\\nbridge: command on"), "{log}");
    assert_eq!(connections(&b), 1, "{log}");
    assert!(log.len() < 20_000, "{} bytes of log", log.len());
    // A stop still gets through.
    assert!(publish(port, STOP, "PRESS", &["-q", "1"]).0);
    let deep = dir.join("deep.yaml");
    std::fs::write(&deep, "[".repeat(100_000)).unwrap();
    let began = Instant::now();
    let out = run(&[
        "bridge",
        "--config",
        deep.to_str().unwrap(),
        "--no-metrics",
        "--mqtt",
        "mqtt://127.0.0.1:1",
    ]);
    let text = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{text}");
    assert!(text.contains("deep.yaml:1:"), "{text}");
    assert!(
        began.elapsed() < Duration::from_secs(5),
        "{:?}",
        began.elapsed()
    );
    let allowed = ["--allow-writes", "run"];
    for (args, says, never) in [
        (
            vec!["--mqtt", "mqtt://user:s3cret@127.0.0.1:1883"],
            "credentials in the URL are refused",
            "s3cret",
        ),
        (vec!["--mqtt-topic", "plant/+"], "wildcards", ""),
        (vec!["--discovery-prefix", "ha/#"], "wildcards", ""),
        (vec!["--command-rate", "inf"], "--command-rate", ""),
        (vec!["--command-rate", "0"], "--command-rate", ""),
        // n011 is read from the drive every cycle: an assumed value would replace it.
        (
            vec!["--set", "n011=400"],
            "reads max_output_frequency (n011)",
            "",
        ),
    ] {
        let mut all = vec![
            "bridge",
            "--drive",
            "yaskawa-v7@1",
            "--rtu-tcp",
            "127.0.0.1:1",
            "--no-metrics",
        ];
        if !args.contains(&"--mqtt") {
            all.extend(["--mqtt", "mqtt://127.0.0.1:1"]);
        }
        all.extend(allowed);
        all.extend(args.iter().copied());
        let out = run(&all);
        let text = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(!out.status.success(), "{args:?}: {text}");
        assert!(text.contains(says), "{args:?}: {text}");
        if !never.is_empty() {
            assert!(!text.contains(never), "{args:?}: {text}");
        }
    }
}

/// A map marked `draft:` (not reviewed against its manual) is read by the bridge, with a note,
/// and nothing is written through it, not even a stop: its run register's address is what a
/// reader made of the text. With `--draft` the same commands are carried out and say they went
/// through a draft.
#[test]
fn a_draft_map_is_read_and_never_written_without_draft() {
    let dir = scratch("draft");
    let maps = dir.join("maps");
    std::fs::create_dir_all(&maps).unwrap();
    let v7 = std::fs::read_to_string(paths::shipped_map("yaskawa-v7")).unwrap();
    let draft = v7.replacen(
        "\nschema: 2\n",
        "\nschema: 2\ndraft:\n  by: a test (the V7 map marked as a draft)\n",
        1,
    );
    assert_ne!(draft, v7, "no `schema: 2` line to mark");
    std::fs::write(maps.join("yaskawa-v7.yaml"), draft).unwrap();
    let (broker, port) = mosquitto(&dir, "mosquitto", "allow_anonymous true");
    let (sim, line) = simulated_line_with(&dir, &[(V7, 1)], false);
    let maps_arg = maps.to_str().unwrap();
    let b = bridge_on(
        &dir,
        line,
        port,
        false,
        &["--maps", maps_arg, "--allow-writes", "run"],
    );
    online(port, &[&b, &broker, &sim]);
    let errors =
        std::thread::spawn(move || subscribe(port, "drivemap/yaskawa-v7-1/error", 6, &["-C", "2"]));
    std::thread::sleep(Duration::from_millis(800));
    assert!(publish(port, RUN, "PRESS", &[]).0);
    std::thread::sleep(Duration::from_millis(300));
    assert!(publish(port, STOP, "PRESS", &[]).0);
    let errors = errors.join().unwrap();
    assert_eq!(errors.len(), 2, "{errors:?}\n{}", b.output());
    assert!(
        errors.iter().all(|(_, e)| e.contains("draft")),
        "{errors:?}"
    );
    assert!(b.output().contains("is a draft map"), "{}", b.output());
    assert_eq!(command_writes(&sim), 0, "{}", sim.output());
    drop(b);
    let again = dir.join("again");
    std::fs::create_dir_all(&again).unwrap();
    let b = bridge_on(
        &again,
        line,
        port,
        false,
        &["--maps", maps_arg, "--allow-writes", "run", "--draft"],
    );
    // The first bridge's retained `online` is still on the broker: wait for this one's.
    wait_for(
        Duration::from_secs(30),
        "the bridge connected",
        &[&b],
        || (connections(&b) >= 1).then_some(()),
    );
    std::thread::sleep(Duration::from_millis(1500));
    assert!(publish(port, RUN, "PRESS", &[]).0);
    wait_for(Duration::from_secs(10), "the run", &[&b, &sim], || {
        (command_word(line)? & 1 == 1).then_some(())
    });
    assert!(b.output().contains("through draft map"), "{}", b.output());
}
