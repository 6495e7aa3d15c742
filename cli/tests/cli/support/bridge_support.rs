//! Processes for the bridge tests: simulated drives, the bridge, the real tools (Prometheus,
//! mosquitto), each killed when dropped; loopback ports; a tiny HTTP GET.

// Each test binary compiles this module and uses only the helpers it needs.
#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The drivemap binary: this build's, or the one `DRIVEMAP_TEST_BIN` names (an older build,
/// to show which of these tests fail on it).
pub fn drivemap() -> &'static str {
    static BIN: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    BIN.get_or_init(|| {
        std::env::var("DRIVEMAP_TEST_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_drivemap").into())
    })
}

/// A tool the test needs; the test fails (never skips) when it is missing.
pub fn require(tool: &str) -> String {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .chain([PathBuf::from("/usr/sbin"), PathBuf::from("/sbin")])
            .map(|d| d.join(tool))
            .find(|p| p.is_file())
    });
    match found {
        Some(p) => p.to_string_lossy().into_owned(),
        None => panic!(
            "{tool} is missing: run tests/interop/install.sh (as root it installs the Debian packages prometheus, mosquitto, mosquitto-clients)"
        ),
    }
}

/// A free loopback port (bound and released).
pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A fresh directory for one test's files.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("bridge-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A child process killed when dropped; its output goes to a log file.
pub struct Proc {
    pub child: Child,
    pub log: PathBuf,
    pub what: String,
}

impl Proc {
    pub fn spawn(
        what: &str,
        program: &str,
        args: &[&str],
        log: PathBuf,
        env: &[(&str, &str)],
    ) -> Proc {
        let file = std::fs::File::create(&log).unwrap();
        let mut cmd = Command::new(program);
        cmd.args(args)
            .stdin(Stdio::null())
            .stdout(file.try_clone().unwrap())
            .stderr(file);
        for (k, v) in env {
            cmd.env(k, v);
        }
        let child = cmd
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {program}: {e}"));
        Proc {
            child,
            log,
            what: what.to_owned(),
        }
    }

    /// What it printed so far.
    pub fn output(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// Sends SIGTERM and waits at most `limit` for it to exit; its exit code.
    pub fn terminate(&mut self, limit: Duration) -> Option<i32> {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let until = Instant::now() + limit;
        while Instant::now() < until {
            if let Ok(Some(status)) = self.child.try_wait() {
                return status.code();
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        None
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Waits until `f` gives a value, at most `limit`; panics with `what` and the logs.
pub fn wait_for<T>(
    limit: Duration,
    what: &str,
    logs: &[&Proc],
    mut f: impl FnMut() -> Option<T>,
) -> T {
    let until = Instant::now() + limit;
    loop {
        if let Some(v) = f() {
            return v;
        }
        if Instant::now() > until {
            let mut text = String::new();
            for p in logs {
                text += &format!("\n--- {} ---\n{}", p.what, tail(&p.output(), 3000));
            }
            panic!("timed out after {limit:?} waiting for {what}{text}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn tail(s: &str, n: usize) -> &str {
    let start = s.len().saturating_sub(n);
    let mut i = start;
    while !s.is_char_boundary(i) {
        i += 1;
    }
    &s[i..]
}

/// Whether something listens on the loopback port.
pub fn listening(port: u16) -> bool {
    TcpStream::connect(("127.0.0.1", port)).is_ok()
}

/// A simulated drive on an RTU-over-TCP port, network selected as its source, time 50× faster.
pub fn simulator(dir: &Path, drive: &str, slave: u8) -> (Proc, u16) {
    simulated_line(dir, &[(drive, slave)])
}

/// Simulated drives on one line (one RTU-over-TCP port), each at its slave address, network
/// selected as their source, time 50× faster.
pub fn simulated_line(dir: &Path, drives: &[(&str, u8)]) -> (Proc, u16) {
    simulated_line_with(dir, drives, true)
}

/// [`simulated_line`], logging every request it serves (`quiet: false`): the log shows what
/// reached the drives (`slave   1  06h  0001h x1    ok`).
pub fn simulated_line_with(dir: &Path, drives: &[(&str, u8)], quiet: bool) -> (Proc, u16) {
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let mut args: Vec<String> = vec!["simulate".into()];
    for (drive, slave) in drives {
        args.push("--drive".into());
        args.push(format!("{drive}@{slave}"));
    }
    for a in ["--rtu-tcp", &addr, "--network-source", "--time-scale", "50"] {
        args.push(a.into());
    }
    if quiet {
        args.push("--quiet".into());
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let name = drives
        .iter()
        .map(|(d, s)| format!("{d}@{s}"))
        .collect::<Vec<_>>()
        .join(" ");
    let p = Proc::spawn(
        &format!("simulate {name}"),
        drivemap(),
        &refs,
        dir.join(format!("sim-{port}.log")),
        &[],
    );
    wait_for(
        Duration::from_secs(20),
        "the simulator to listen",
        &[&p],
        || listening(port).then_some(()),
    );
    (p, port)
}

/// Runs `drivemap <args>` to completion.
pub fn run(args: &[&str]) -> Output {
    Command::new(drivemap()).args(args).output().unwrap()
}

/// A register's engineering value as `drivemap read --format json` gives it, on a simulator.
pub fn read_number(drive: &str, slave: u8, port: u16, register: &str) -> Option<f64> {
    let out = run(&[
        "read",
        "--drive",
        drive,
        "--slave",
        &slave.to_string(),
        "--rtu-tcp",
        &format!("127.0.0.1:{port}"),
        "--format",
        "json",
        register,
    ]);
    if !out.status.success() {
        return None;
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).ok()?;
    v.get(0)?.get("value")?.as_f64()
}

/// `GET path` over HTTP/1.1 on loopback: status and body.
pub fn http_get(port: u16, path: &str) -> Option<(u16, String)> {
    let mut s = TcpStream::connect(("127.0.0.1", port)).ok()?;
    s.set_read_timeout(Some(Duration::from_secs(10))).ok()?;
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"
    )
    .ok()?;
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).ok()?;
    let text = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = text.split_once("\r\n\r\n")?;
    let status = head.split_whitespace().nth(1)?.parse().ok()?;
    let body = if head
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        dechunk(body)
    } else {
        body.to_owned()
    };
    Some((status, body))
}

fn dechunk(mut body: &str) -> String {
    let mut out = String::new();
    while let Some((size, rest)) = body.split_once("\r\n") {
        let Ok(n) = usize::from_str_radix(size.trim(), 16) else {
            break;
        };
        if n == 0 || rest.len() < n {
            break;
        }
        out.push_str(&rest[..n]);
        body = rest[n..].trim_start_matches("\r\n");
    }
    out
}

/// Percent-encodes a query value.
pub fn encode(q: &str) -> String {
    q.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The retained and live messages on `topic` for `seconds`: `(topic, payload)` lines as
/// `mosquitto_sub -v` prints them.
pub fn subscribe(port: u16, topic: &str, seconds: u32, extra: &[&str]) -> Vec<(String, String)> {
    let sub = require("mosquitto_sub");
    let out = Command::new(sub)
        .args([
            "-h",
            "127.0.0.1",
            "-p",
            &port.to_string(),
            "-t",
            topic,
            "-v",
            "-W",
        ])
        .arg(seconds.to_string())
        .args(extra)
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_once(' '))
        .map(|(t, p)| (t.to_owned(), p.to_owned()))
        .collect()
}

/// Publishes one message; whether mosquitto_pub succeeded, and what it printed.
pub fn publish(port: u16, topic: &str, payload: &str, extra: &[&str]) -> (bool, String) {
    let out = Command::new(require("mosquitto_pub"))
        .args([
            "-h",
            "127.0.0.1",
            "-p",
            &port.to_string(),
            "-t",
            topic,
            "-m",
            payload,
        ])
        .args(extra)
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

/// The user the tests run as (`id -un`).
fn user() -> String {
    let out = Command::new("id").arg("-un").output().unwrap();
    String::from_utf8_lossy(&out.stdout).trim().to_owned()
}

/// A mosquitto broker on loopback with `config` (its `listener` line is added). It runs as the
/// user the tests run as (`user` line: started as root, mosquitto would otherwise drop to its
/// own user, which cannot read the test's files where the clone is in a directory only root
/// may enter).
pub fn mosquitto(dir: &Path, name: &str, config: &str) -> (Proc, u16) {
    mosquitto_on(dir, name, config, free_port())
}

/// [`mosquitto`] on `port` (a broker started again where the last one listened).
pub fn mosquitto_on(dir: &Path, name: &str, config: &str, port: u16) -> (Proc, u16) {
    let broker = require("mosquitto");
    let conf = dir.join(format!("{name}.conf"));
    std::fs::write(
        &conf,
        format!("listener {port} 127.0.0.1\nuser {}\n{config}\n", user()),
    )
    .unwrap();
    let p = Proc::spawn(
        name,
        &broker,
        &["-c", conf.to_str().unwrap()],
        dir.join(format!("{name}.log")),
        &[],
    );
    wait_for(
        Duration::from_secs(20),
        "mosquitto to listen",
        &[&p],
        || listening(port).then_some(()),
    );
    (p, port)
}

/// Publishes each line of `lines` as one message from one client (as fast as it can).
pub fn publish_lines(port: u16, topic: &str, lines: &str) -> bool {
    let mut child = Command::new(require("mosquitto_pub"))
        .args([
            "-h",
            "127.0.0.1",
            "-p",
            &port.to_string(),
            "-t",
            topic,
            "-l",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    if let Some(mut stdin) = child.stdin.take() {
        let _ = stdin.write_all(lines.as_bytes());
    }
    child.wait().is_ok_and(|s| s.success())
}
