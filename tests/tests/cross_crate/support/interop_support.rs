//! Shared by the interop tests: the third-party peers (found or the test fails naming the
//! install step), a socat pseudo-terminal pair, simulators served in-process with a request log.

// Each test binary compiles this module and uses only the helpers it needs.
#![allow(dead_code)]

use drivemap_test_support::paths;

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_sim::server::Logger;
use drivemap_sim::{RequestRecord, SimOptions, Simulator, clock::ManualClock, server::SharedSim};

/// How to install every peer; printed when one is missing.
pub const INSTALL: &str = "run tests/interop/install.sh (as root it does: apt-get install -y mbpoll socat; \
     python3 -m venv target/interop-venv && target/interop-venv/bin/pip install pymodbus minimalmodbus pyserial jsonschema)";

/// The workspace root.
pub fn root() -> PathBuf {
    paths::workspace().to_path_buf()
}

/// A script under tests/interop/.
pub fn script(name: &str) -> PathBuf {
    root().join("tests").join("interop").join(name)
}

/// Fails the test unless `tool` runs.
pub fn require_tool(tool: &str, probe: &[&str]) {
    let ok = Command::new(tool)
        .args(probe)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok();
    assert!(
        ok,
        "`{tool}` is required by this interop test and is not installed: {INSTALL}"
    );
}

/// The venv's Python with `modules` importable, or the test fails naming the install step.
pub fn python(modules: &[&str]) -> PathBuf {
    let python = root()
        .join("target")
        .join("interop-venv")
        .join("bin")
        .join("python");
    assert!(
        python.is_file(),
        "the interop venv {} is missing: {INSTALL}",
        python.display()
    );
    let import = format!("import {}", modules.join(", "));
    let out = Command::new(&python)
        .args(["-c", &import])
        .output()
        .expect("running the venv's python");
    assert!(
        out.status.success(),
        "`{import}` fails in {}: {INSTALL}\n{}",
        python.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    python
}

#[allow(unused_imports)] // not every test binary that includes this module uses it
pub use drivemap_test_support::pty_pair::PtyPair;

/// A child process killed on drop (a Python server, say).
pub struct Peer(pub Child);

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `cmd` and waits (at most 30 s) until it prints `ready` on stdout.
pub fn start_ready(mut cmd: Command) -> Peer {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {cmd:?}: {e}"));
    let stdout = child.stdout.take().expect("stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    thread::spawn(move || {
        let mut lines = BufReader::new(stdout).lines();
        for line in lines.by_ref().map_while(Result::ok) {
            if line.trim() == "ready" {
                let _ = tx.send(());
                break;
            }
        }
        for _ in lines {}
    });
    let peer = Peer(child);
    rx.recv_timeout(Duration::from_secs(30))
        .unwrap_or_else(|_| panic!("{cmd:?} did not print `ready` within 30 s"));
    peer
}

/// A free TCP port on loopback (bound and released).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// A map by drive id.
pub fn drive(id: &str) -> drivemap_map::Map {
    let path = paths::maps().join(format!("{id}.yaml"));
    drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A simulator on a manual clock, shared for serving, with every request recorded.
pub struct Sim {
    pub sim: SharedSim,
    pub clock: ManualClock,
    pub records: Arc<Mutex<Vec<RequestRecord>>>,
}

impl Sim {
    pub fn new(id: &str, options: SimOptions) -> Sim {
        Sim::of(drive(id), options)
    }

    /// A simulator of `map` (a fixture's, say) on a manual clock.
    pub fn of(map: drivemap_map::Map, options: SimOptions) -> Sim {
        let clock = ManualClock::new();
        let id = map.id().to_owned();
        let sim = Simulator::new(map, options.clock(Arc::new(clock.clone())))
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        Sim {
            sim: drivemap_sim::server::shared(sim),
            clock,
            records: Arc::new(Mutex::new(Vec::new())),
        }
    }

    pub fn logger(&self) -> Logger {
        let records = self.records.clone();
        Arc::new(move |r: &RequestRecord| records.lock().unwrap().push(*r))
    }

    pub fn records(&self) -> Vec<RequestRecord> {
        self.records.lock().unwrap().clone()
    }

    pub fn with<R>(&self, f: impl FnOnce(&mut Simulator) -> R) -> R {
        f(&mut drivemap_sim::server::lock(&self.sim))
    }

    /// Waits (at most 5 s) until `n` broadcasts have been handled: a broadcast gets no reply, so
    /// a master cannot know by itself when the drive has executed it.
    pub fn wait_broadcasts(&self, n: usize) {
        let until = Instant::now() + Duration::from_secs(5);
        let count = || {
            self.records
                .lock()
                .unwrap()
                .iter()
                .filter(|r| r.slave == 0)
                .count()
        };
        while count() < n && Instant::now() < until {
            thread::sleep(Duration::from_millis(2));
        }
        assert_eq!(count(), n, "broadcasts handled");
    }
}

/// Runs a command to completion with a time limit; returns its output.
pub fn run_with_limit(mut cmd: Command, limit: Duration) -> Output {
    let child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {cmd:?}: {e}"));
    let pid = child.id();
    let (tx, rx) = std::sync::mpsc::channel();
    thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(limit) {
        Ok(out) => out.expect("collecting output"),
        Err(_) => {
            let _ = Command::new("kill").arg(pid.to_string()).status();
            panic!("{cmd:?} did not finish within {limit:?}");
        }
    }
}
