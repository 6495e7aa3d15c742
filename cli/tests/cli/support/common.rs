//! Shared by the CLI's integration tests (`use crate::common;` in each): the built `drivemap` binary run
//! as a user runs it, with its exit code and output; bounded runs that kill a hang; a
//! `drivemap simulate` process killed on drop.

// Each test binary compiles this module and uses only the helpers it needs.
#![allow(dead_code)]

use drivemap_test_support::paths;
use std::io::{BufRead, BufReader, Read};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex, mpsc};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_sim::SimulatedSlave;

/// The workspace root.
pub fn repo() -> PathBuf {
    paths::workspace().to_path_buf()
}

/// The shipped maps (`maps/`).
pub fn shipped_maps() -> PathBuf {
    paths::maps()
}

/// The built `drivemap`, not inheriting `DRIVEMAP_MAPS` or `DRIVEMAP_MANUALS` from the test's
/// environment (a test that wants them sets them).
pub fn command() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_drivemap"));
    cmd.env_remove("DRIVEMAP_MAPS")
        .env_remove("DRIVEMAP_MANUALS");
    cmd
}

/// Exit code (-1 when ended by a signal), stdout and stderr of a finished run.
pub fn outcome(out: Output) -> (i32, String, String) {
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `cmd` to its end: exit code, stdout, stderr.
pub fn run(cmd: &mut Command) -> (i32, String, String) {
    outcome(cmd.output().expect("run drivemap"))
}

/// `drivemap ARGS --maps <repo>/maps`.
pub fn drivemap(args: &[&str]) -> (i32, String, String) {
    run(command().args(args).arg("--maps").arg(shipped_maps()))
}

/// `drivemap ARGS`, with the maps built into the binary unless `ARGS` say otherwise.
pub fn drivemap_builtin(args: &[&str]) -> (i32, String, String) {
    run(command().args(args))
}

/// `drivemap ARGS` run in `dir` (relative paths in `ARGS` are read from there).
pub fn drivemap_in(dir: &Path, args: &[&str]) -> (i32, String, String) {
    run(command().args(args).current_dir(dir))
}

/// `drivemap ARGS` run in a fixture directory (`tests/fixtures/<vendor-model>`): its maps
/// (`DRIVEMAP_MAPS`) and its manuals (`DRIVEMAP_MANUALS`, the fixture's `manuals/`).
pub fn drivemap_fixture(fixture: &Path, args: &[&str]) -> (i32, String, String) {
    run(command()
        .args(args)
        .current_dir(fixture)
        .env("DRIVEMAP_MAPS", fixture)
        .env("DRIVEMAP_MANUALS", fixture.join("manuals")))
}

/// Runs `cmd`, killing it and failing the test (with what it printed so far) when it is still
/// running after `limit`: exit code, stdout, stderr and how long it took.
pub fn run_bounded(cmd: &mut Command, limit: Duration) -> (i32, String, String, Duration) {
    let started = Instant::now();
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run drivemap");
    let out = drain(child.stdout.take().unwrap());
    let err = drain(child.stderr.take().unwrap());
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code().unwrap_or(-1);
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "{cmd:?}: still running after {:?} (limit {limit:?}); killed\nstdout: {}",
                started.elapsed(),
                out.join().unwrap()
            );
        }
        thread::sleep(Duration::from_millis(10));
    };
    let took = started.elapsed();
    (code, out.join().unwrap(), err.join().unwrap(), took)
}

/// `drivemap ARGS --maps <repo>/maps` bounded as [`run_bounded`].
pub fn drivemap_bounded(args: &[&str], limit: Duration) -> (i32, String, String, Duration) {
    run_bounded(
        command().args(args).arg("--maps").arg(shipped_maps()),
        limit,
    )
}

/// Reads a pipe to its end on a thread of its own (so neither pipe of a child fills up).
fn drain(mut pipe: impl Read + Send + 'static) -> thread::JoinHandle<String> {
    thread::spawn(move || {
        let mut s = String::new();
        let _ = pipe.read_to_string(&mut s);
        s
    })
}

/// A `drivemap simulate` child process; killed on drop.
pub struct Sim {
    child: Child,
    /// The loopback address it listens on, from its first line (empty on a serial link).
    pub addr: String,
    /// Its first line ("simulating <drive> at slave N on ...").
    pub first: String,
}

impl Sim {
    /// `drivemap simulate ARGS --quiet --maps <repo>/maps` on a loopback listener (`--tcp 0`,
    /// `--rtu-tcp 0`, `--gateway 127.0.0.1:0`): fails the test when its first line names no
    /// address.
    pub fn start(args: &[&str]) -> Sim {
        Sim::listening(&mut Sim::quiet(args))
    }

    /// As [`Sim::start`] on any link; `addr` is empty when the first line names no loopback
    /// address.
    pub fn start_any(args: &[&str]) -> Sim {
        Sim::spawn(&mut Sim::quiet(args))
    }

    fn quiet(args: &[&str]) -> Command {
        let mut cmd = command();
        cmd.arg("simulate")
            .args(args)
            .arg("--quiet")
            .arg("--maps")
            .arg(shipped_maps());
        cmd
    }

    /// [`Sim::spawn`], failing the test when the first line names no loopback address.
    pub fn listening(cmd: &mut Command) -> Sim {
        let sim = Sim::spawn(cmd);
        assert!(!sim.addr.is_empty(), "no address in {:?}", sim.first);
        sim
    }

    /// Starts `cmd` (a `drivemap simulate` command line as given) and waits up to 20 s for its
    /// first line; the rest of its output (the request log without `--quiet`) is read and
    /// dropped, so the simulator never blocks on a full pipe.
    pub fn spawn(cmd: &mut Command) -> Sim {
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start drivemap simulate");
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = mpsc::channel();
        thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        let first = match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(line) => line,
            Err(e) => {
                let _ = child.kill();
                let _ = child.wait();
                panic!("{cmd:?}: no first line ({e})");
            }
        };
        thread::spawn(move || while rx.recv().is_ok() {});
        let addr = first
            .split_whitespace()
            .find(|w| w.starts_with("127.0.0.1:"))
            .map(|w| w.trim_end_matches([',', ')']).to_owned())
            .unwrap_or_default();
        Sim { child, addr, first }
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A directory of its own under the system's temporary directory, removed on drop.
pub struct Scratch(pub PathBuf);

impl Scratch {
    /// `drivemap-<name>-<pid>` under the temporary directory, emptied.
    pub fn new(name: &str) -> Scratch {
        let p = std::env::temp_dir().join(format!("drivemap-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        Scratch(p)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// How a [`serve`]d slave frames its link, and the `drivemap` flag that reaches it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Framing {
    /// Modbus TCP (`--tcp`).
    Tcp,
    /// Modbus TCP to a gateway with the drive on its serial line (`--gateway`).
    Gateway,
    /// RTU frames over TCP (`--rtu-tcp`).
    RtuOverTcp,
}

impl Framing {
    /// The `drivemap` link flag for this framing.
    pub fn flag(self) -> &'static str {
        match self {
            Framing::Tcp => "--tcp",
            Framing::Gateway => "--gateway",
            Framing::RtuOverTcp => "--rtu-tcp",
        }
    }
}

/// Serves `slave` on a loopback listener in a thread of the test (each connection for up to
/// 30 s): its address and the slave, shared with the test to set and inspect.
pub fn serve(slave: SimulatedSlave, framing: Framing) -> (String, Arc<Mutex<SimulatedSlave>>) {
    let slave = Arc::new(Mutex::new(slave));
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let shared = Arc::clone(&slave);
    thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(stream) = stream else { continue };
            let until = Instant::now() + Duration::from_secs(30);
            let mut s = shared.lock().unwrap();
            let _ = match framing {
                Framing::Tcp => s.serve(&mut TcpTransport::from_stream(stream).unwrap(), until),
                Framing::Gateway => s.serve(
                    &mut TcpTransport::from_gateway_stream(stream).unwrap(),
                    until,
                ),
                Framing::RtuOverTcp => s.serve(
                    &mut RtuOverTcpTransport::from_stream(stream).unwrap(),
                    until,
                ),
            };
        }
    });
    (addr, slave)
}
