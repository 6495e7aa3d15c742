//! `drivemap simulate --serial PATH --line-speed BAUD`: the simulated drive keeps its timing on
//! a line of that speed over a pseudo-terminal pair (which delivers bytes at once). A V7 read
//! of one register at 9600 baud 8N1 takes the request's 8 characters (8.3 ms), the V7's 24 bits
//! and n156 (2.5 + 10 ms) and the reply's 7 characters (7.3 ms): 28.1 ms, where the bare pty
//! answers within a frame gap.

#![cfg(unix)]

use crate::common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::transport::serial::{SerialOptions, SerialTransport};
use drivemap_runtime::{client::Client, client::ClientOptions};
use drivemap_test_support::pty_pair::PtyPair;

use common::command;

struct Sim(Child);

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `drivemap simulate` of the V7 on `path`, with `extra` flags, once it says it serves.
fn simulate(path: &str, extra: &[&str]) -> Sim {
    let mut child = command()
        .args([
            "simulate",
            "--drive",
            "yaskawa-v7",
            "--slave",
            "1",
            "--quiet",
            "--serial",
            path,
        ])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("drivemap simulate");
    let mut first = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("its first line");
    assert!(first.starts_with("simulating"), "{first}");
    Sim(child)
}

/// The fastest of five reads of one V7 register through `path`, from the call to the reply.
fn fastest_read(path: &str) -> Duration {
    let profile = &drivemap_drives::yaskawa_v7::PROFILE;
    let link = SerialTransport::open(SerialOptions::new(path, 9600).with_profile(profile))
        .expect("the master's end");
    let mut client = Client::with_options(
        link,
        profile,
        ClientOptions::for_line(profile, SerialConfig::new(9600)),
    );
    let slave = 1;
    let mut out = [0u16; 1];
    (0..5)
        .map(|_| {
            // Past the request gap, so that the call's time is the line's.
            std::thread::sleep(Duration::from_millis(20));
            let t = Instant::now();
            client
                .read_holding(slave, 0x0020, &mut out)
                .expect("the simulated V7 answers");
            t.elapsed()
        })
        .min()
        .expect("five reads")
}

#[test]
fn the_simulated_drive_keeps_its_timing_at_the_line_speed() {
    let model = BusModel::new(
        &drivemap_drives::yaskawa_v7::PROFILE,
        SerialConfig::new(9600),
    );
    let b = model.exchange(0x03, 1).expect("a read");
    let on_wire = Duration::from_nanos(b.request_ns + b.latency_ns + b.response_ns);
    assert!(on_wire > Duration::from_millis(28), "{on_wire:?}");

    let pty = PtyPair::new();
    let _sim = simulate(&pty.paths[0], &["--baud", "9600", "--line-speed", "9600"]);
    let timed = fastest_read(&pty.paths[1]);
    assert!(timed >= on_wire, "{timed:?} < {on_wire:?}");
    assert!(timed < on_wire + Duration::from_millis(10), "{timed:?}");
    drop(_sim);

    // Without the flag the pty answers as fast as the simulator: within a frame gap or so.
    let pty = PtyPair::new();
    let _sim = simulate(&pty.paths[0], &["--baud", "9600"]);
    let bare = fastest_read(&pty.paths[1]);
    assert!(bare < Duration::from_millis(15), "{bare:?}");
}

#[test]
fn line_speed_needs_a_serial_port() {
    let out = command()
        .args([
            "simulate",
            "--drive",
            "yaskawa-v7",
            "--tcp",
            "5999",
            "--line-speed",
            "9600",
        ])
        .output()
        .expect("drivemap");
    assert_ne!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--serial"), "{err}");
}
