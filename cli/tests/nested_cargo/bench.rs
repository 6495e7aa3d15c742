//! The bench tasks as a new user runs them, from a directory outside the repository:
//! `cargo install` into an empty root, then every command; `probe` against a simulator serving
//! a deliberately altered map; `scan` over a socat pseudo-terminal pair with a line of two
//! simulated drives; JSON and CSV outputs read back with Python's `json` and `csv`.

use drivemap_test_support::paths;

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use drivemap_map::Map;
use drivemap_runtime::transport::serial::{Parity, SerialOptions};
use drivemap_sim::{
    Line, SimOptions, Simulator, server::SerialServer, server::TcpFraming, server::TcpServer,
};

use drivemap_test_support::pty_pair;

fn repo() -> PathBuf {
    paths::workspace().to_path_buf()
}

/// An empty directory outside the repository, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        let p = std::env::temp_dir().join(format!("drivemap-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        assert!(
            !p.starts_with(repo()),
            "{} is inside the repository",
            p.display()
        );
        TempDir(p)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `bin args...` in `dir` with no map or manual directory from the environment.
fn run_in(bin: &Path, dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(bin)
        .args(args)
        .current_dir(dir)
        .env_remove("DRIVEMAP_MAPS")
        .env_remove("DRIVEMAP_MANUALS")
        .output()
        .expect("run drivemap");
    outcome(out)
}

fn outcome(out: Output) -> (i32, String, String) {
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs a Python script with `input` on standard input; returns its standard output.
fn python(script: &str, input: &str) -> String {
    let mut child = Command::new("python3")
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 is needed by this test");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let (code, out, err) = outcome(child.wait_with_output().unwrap());
    assert_eq!(code, 0, "python failed: {err}\ninput:\n{input}");
    out
}

fn shipped() -> Vec<String> {
    drivemap_map::find_maps(&paths::maps())
        .unwrap()
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect()
}

/// A `drivemap simulate` process; killed on drop.
struct SimProcess {
    child: Child,
    addr: String,
}

impl SimProcess {
    fn start(bin: &Path, dir: &Path, args: &[&str]) -> SimProcess {
        let mut child = Command::new(bin)
            .arg("simulate")
            .args(args)
            .args(["--quiet"])
            .current_dir(dir)
            .env_remove("DRIVEMAP_MAPS")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut first = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut first)
            .unwrap();
        // "simulating ptlk-tds-v8 at slave 1 on Modbus TCP 127.0.0.1:40123 (...)"
        let addr = first
            .split_whitespace()
            .find(|w| w.starts_with("127.0.0.1:"))
            .unwrap_or_else(|| panic!("no address in {first:?}"))
            .to_string();
        SimProcess { child, addr }
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn installed_anywhere_every_command_works_from_outside_the_repository() {
    let root = TempDir::new("install-root");
    let work = TempDir::new("install-work");
    // What the workspace's build compiled with the same features is reused; the installed
    // program's own build goes to `target/nested`, so it does not replace the workspace's
    // `target/debug/drivemap`, which other tests run meanwhile (`cargo::command`).
    let started = Instant::now();
    let out = drivemap_test_support::cargo::command()
        .args([
            "install",
            "--path",
            "cli",
            "--debug",
            "--offline",
            "--locked",
            "--root",
        ])
        .arg(&root.0)
        .current_dir(repo())
        .output()
        .unwrap();
    let (code, _, err) = outcome(out);
    assert_eq!(code, 0, "cargo install failed:\n{err}");
    eprintln!(
        "cargo install took {:.1} s",
        started.elapsed().as_secs_f64()
    );
    let bin = root.0.join("bin").join("drivemap");
    assert!(bin.is_file());
    let dir = &work.0;
    let run = |args: &[&str]| run_in(&bin, dir, args);

    // check: every built-in map.
    let (code, out, err) = run(&["check"]);
    assert_eq!(code, 0, "{err}");
    for id in shipped() {
        assert!(
            out.contains(&format!("ok   <built-in>/{id}.yaml ({id}:")),
            "{out}"
        );
    }
    // export and doc of every shipped drive (yaskawa-j7 extends yaskawa-v7).
    for id in shipped() {
        let (code, out, err) = run(&["export", "--drive", &id]);
        assert_eq!(code, 0, "export {id}: {err}");
        let parsed = python(
            "import json,sys; d=json.load(sys.stdin); print(d['drive']['id'])",
            &out,
        );
        assert_eq!(parsed.trim(), id);
        let md = format!("{id}.md");
        let (code, _, err) = run(&["doc", "--drive", &id, "-o", &md]);
        assert_eq!(code, 0, "doc {id}: {err}");
        assert!(
            std::fs::read_to_string(dir.join(&md))
                .unwrap()
                .contains(&id)
        );
    }
    // --maps and DRIVEMAP_MAPS add maps by id.
    let mine = dir.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    let v7 = std::fs::read_to_string(repo().join("maps/yaskawa-v7.yaml")).unwrap();
    std::fs::write(
        mine.join("bench-v7.yaml"),
        v7.replacen("id: yaskawa-v7", "id: bench-v7", 1),
    )
    .unwrap();
    let (code, out, err) = run(&["export", "--drive", "bench-v7", "--maps", "mine"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\"bench-v7\""));
    let out = Command::new(&bin)
        .args(["export", "--drive", "bench-v7"])
        .current_dir(dir)
        .env("DRIVEMAP_MAPS", &mine)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // diff of two files.
    std::fs::create_dir_all(dir.join("old")).unwrap();
    std::fs::create_dir_all(dir.join("new")).unwrap();
    std::fs::write(dir.join("old/yaskawa-v7.yaml"), &v7).unwrap();
    std::fs::write(
        dir.join("new/yaskawa-v7.yaml"),
        v7.replacen("max: 399.9", "max: 300.0", 1),
    )
    .unwrap();
    let (code, out, err) = run(&["diff", "old/yaskawa-v7.yaml", "new/yaskawa-v7.yaml"]);
    assert_eq!(code, 1, "a narrowed range breaks: {out}{err}");
    // completions.
    for shell in ["bash", "zsh", "fish"] {
        let (code, out, _) = run(&["completions", shell]);
        assert_eq!(code, 0);
        assert!(out.contains("probe") && out.contains("scan"), "{shell}");
    }
    // demo (compiled in).
    let (code, out, err) = run(&["demo", "--drive", "yaskawa-j7", "--time-scale", "50"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("done in"), "{out}");
    // The J7's source selections have no address: the demo sets them at the simulated drive,
    // where the status bits that report the source live, and says so.
    assert!(
        out.contains(
            "set at the simulated drive first (its factory setting ignores network commands): \
             status_signal_2.run_command_source = 0, status_signal_2.frequency_reference_source = 0"
        ),
        "{out}"
    );

    // The live commands against `drivemap simulate`.
    // The TDS-V8 speaks RTU only: served and reached as a drive behind a Modbus TCP gateway.
    let sim = SimProcess::start(&bin, dir, &["--drive", "ptlk-tds-v8", "--gateway", "0"]);
    let link = ["--drive", "ptlk-tds-v8", "--gateway", sim.addr.as_str()];
    let live = |cmd: &str, extra: &[&str]| {
        let mut all = vec![cmd];
        all.extend_from_slice(&link);
        all.extend_from_slice(extra);
        run(&all)
    };
    let (code, _, err) = live("write", &["accel_time_1=12.5"]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = live("read", &["--format", "json", "Bn-01", "inverter_status"]);
    assert_eq!(code, 0, "{err}");
    let got = python(
        "import json,sys\nfor r in json.load(sys.stdin): print(r['register'], r['value'], r['unit'], r['raw'], r['status'])",
        &out,
    );
    // Stopped in PRG mode: zero speed (bit 1) only; Ready is clear in PRG mode.
    assert_eq!(
        got,
        "accel_time_1 12.5 s 125 ok\ninverter_status 2.0 None 2 ok\n"
    );
    // poll to a file, as CSV, read back with Python's csv.
    let log = std::fs::File::create(dir.join("poll.csv")).unwrap();
    let status = Command::new(&bin)
        .arg("poll")
        .args(link)
        .args(["--format", "csv", "--count", "3", "--interval", "50ms"])
        .current_dir(dir)
        .stdout(log)
        .status()
        .unwrap();
    assert!(status.success());
    let csv_text = std::fs::read_to_string(dir.join("poll.csv")).unwrap();
    let got = python(
        "import csv,sys\nrows=list(csv.DictReader(sys.stdin))\n\
         print(len(rows), len({r['time'] for r in rows}), {r['status'] for r in rows})\n\
         print([r['text'] for r in rows if r['register']=='inverter_status'][0])",
        &csv_text,
    );
    let lines: Vec<&str> = got.lines().collect();
    let (n, times) = {
        let f: Vec<&str> = lines[0].split_whitespace().collect();
        (
            f[0].parse::<usize>().unwrap(),
            f[1].parse::<usize>().unwrap(),
        )
    };
    assert_eq!(times, 3, "{csv_text}");
    assert!(n >= 3 * 5 && n % 3 == 0, "{n} rows");
    assert!(lines[0].ends_with("{'ok'}"), "{got}");
    assert_eq!(lines[1], "0002h [zero_speed]");
    // poll as JSON lines.
    let (code, out, err) = live(
        "poll",
        &[
            "--format",
            "json",
            "--count",
            "2",
            "--interval",
            "10ms",
            "output_frequency",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let got = python(
        "import json,sys\nfor l in sys.stdin: r=json.loads(l); print(r['register'], r['parameter'], r['value'], r['unit'], r['raw'], r['status'])",
        &out,
    );
    assert_eq!(got, "output_frequency None 0.0 Hz 0 ok\n".repeat(2));
    // probe, with its JSON report in a file.
    let (code, out, err) = live("probe", &["--report", "report.json"]);
    assert!(code == 0 || code == 1, "{err}");
    // 186 readable registers; Cn-09's limit is 200 % of the inverter rated current, an
    // external quantity not given here, so it is read but not checked.
    assert!(out.contains("checked 185 readable register(s)"), "{out}");
    assert!(out.contains("inverter_rated_current"), "{out}");
    let report = std::fs::read_to_string(dir.join("report.json")).unwrap();
    let got = python(
        "import json,sys; r=json.load(sys.stdin); print(r['format'], r['drive'], r['checked'], r['agreed'] + len(r['disagreements']))",
        &report,
    );
    assert_eq!(got, "drivemap-probe/1 ptlk-tds-v8 185 185\n");
    // scan through the Modbus TCP gateway.
    let (code, out, err) = run(&[
        "scan",
        "--gateway",
        &sim.addr,
        "--slaves",
        "1-3",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let got = python(
        "import json,sys; r=json.load(sys.stdin)\nfor f in r['found']: print(f['slave'], f['maps'][0]['drive'])",
        &out,
    );
    assert_eq!(got, "1 ptlk-tds-v8\n");
}

/// A simulator holding, wherever its map gives no plain default, the least value the map
/// allows (or its first listed code), as a configured drive would rather than 0.
fn simulator(drive: Map, slave: u8) -> Simulator {
    // Each readable register's least value the map allows, by id: an enumeration's first code
    // where 0 is not one of them, else a lower limit above 0.
    let least: Vec<(String, Option<f64>)> = drive
        .registers()
        .filter(|r| r.readable() && !r.broadcast_only())
        .map(|r| {
            let codes = if r.fields().is_empty() {
                r.values()
            } else {
                &[]
            };
            let least = match (codes, r.limits().0) {
                (values, _) if !values.is_empty() && !values.iter().any(|v| v.value == 0) => {
                    values.first().map(|v| f64::from(v.value))
                }
                (_, Some(m)) if m > 0.0 => Some(m),
                _ => None,
            };
            (r.id().to_owned(), least)
        })
        .collect();
    let mut sim = Simulator::new(drive, SimOptions::new().slave(slave)).unwrap();
    for (id, least) in least {
        let Ok(raw) = sim.raw(&id) else {
            continue;
        };
        if raw != 0 {
            continue;
        }
        if let Some(v) = least {
            let _ = sim.set(&id, v);
        }
    }
    sim
}

fn map_text(id: &str) -> String {
    std::fs::read_to_string(paths::maps().join(format!("{id}.yaml"))).unwrap()
}

/// The yaskawa-v7 map with three deliberate differences: n001 removed; n002 with a code 3 the
/// shipped map lacks (and 3 as its default); n016's range replaced by a narrower band above
/// the shipped one (10.5..12.0 Hz instead of 0.1..10.0 Hz), so that the drive holds a value the
/// shipped map does not allow — a probe only reads, so a range is seen through the value held.
fn altered_v7() -> String {
    let mut map: serde_yaml::Value = serde_yaml::from_str(&map_text("yaskawa-v7")).unwrap();
    let groups = map["groups"].as_sequence_mut().unwrap();
    let mut hits = 0;
    for g in groups.iter_mut() {
        let Some(regs) = g.get_mut("registers").and_then(|r| r.as_sequence_mut()) else {
            continue;
        };
        let before = regs.len();
        regs.retain(|r| r["param"].as_str() != Some("n001"));
        hits += before - regs.len();
        for r in regs.iter_mut() {
            match r["param"].as_str() {
                Some("n002") => {
                    let values = r["values"].as_sequence_mut().unwrap();
                    let mut extra = values[0].clone();
                    extra["value"] = 3.into();
                    extra["id"] = "bench_only".into();
                    extra["name"] = "A code only the bench drive has".into();
                    values.push(extra);
                    r["default"] = 3.into();
                    hits += 1;
                }
                Some("n016") => {
                    r["min"] = 10.5.into();
                    r["max"] = 12.0.into();
                    hits += 1;
                }
                _ => {}
            }
        }
    }
    assert_eq!(hits, 3);
    write_hex(&mut map, false);
    serde_yaml::to_string(&map).unwrap()
}

/// Writes the numbers the manuals print in hex (addresses, exception and function codes) as
/// `XXXXH` strings again: serializing a parsed map prints them as decimals, which a map refuses.
fn write_hex(value: &mut serde_yaml::Value, hex: bool) {
    use serde_yaml::Value;
    match value {
        Value::Number(n) if hex => {
            if let Some(n) = n.as_u64() {
                *value = Value::String(format!("{n:02X}H"));
            }
        }
        Value::Sequence(items) => items.iter_mut().for_each(|v| write_hex(v, hex)),
        Value::Mapping(m) => {
            for (k, v) in m.iter_mut() {
                let key = k.as_str().unwrap_or("");
                // The keys `drivemap_map::hex::Slot` reads as hex.
                let hex = matches!(key, "address" | "code" | "exception")
                    || matches!(
                        (key, &*v),
                        (
                            "addresses" | "function_codes" | "codes" | "functions",
                            Value::Sequence(_)
                        )
                    );
                write_hex(v, hex);
            }
        }
        _ => {}
    }
}

/// Serves `sim` on Modbus TCP and runs `drivemap probe` with the shipped map against it.
fn probe(sim: Simulator, format: &str) -> (i32, String, String) {
    let server = TcpServer::spawn(
        drivemap_sim::server::shared(sim),
        "127.0.0.1:0",
        TcpFraming::ModbusTcp,
        None,
    )
    .unwrap();
    let addr = server.local_addr().to_string();
    let dir = TempDir::new(&format!("probe-{format}"));
    let r = run_in(
        Path::new(env!("CARGO_BIN_EXE_drivemap")),
        &dir.0,
        &[
            "probe",
            "--drive",
            "yaskawa-v7",
            "--tcp",
            &addr,
            "--format",
            format,
        ],
    );
    server.stop();
    r
}

const DISAGREEMENTS: &str = "import json,sys\nr=json.load(sys.stdin)\n\
    for d in r['disagreements']: print(d['kind'], d['register'], d['parameter'], d['address_text'], d['exception'], d['raw'])";

#[test]
fn probe_reports_exactly_what_an_altered_drive_does_differently() {
    // Control: the shipped map served as it is agrees with itself.
    let shipped = drivemap_map::Loader::new()
        .load(&repo().join("maps/yaskawa-v7.yaml"))
        .unwrap();
    let (code, out, err) = probe(simulator(shipped, 1), "json");
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(python(DISAGREEMENTS, &out), "");

    let altered = drivemap_map::Loader::new()
        .load_str("yaskawa-v7.yaml", &altered_v7())
        .unwrap();
    let (code, out, err) = probe(simulator(altered.clone(), 1), "json");
    assert_eq!(code, 1, "{err}");
    assert_eq!(
        python(DISAGREEMENTS, &out),
        "refused password_initialization_selection n001 0101h 2 None\n\
         unlisted_code control_method_selection n002 0102h None 3\n\
         out_of_range min_frequency n016 0110h None 105\n"
    );
    // The same as CSV, read with Python's csv; and the summary for eyes.
    let (code, out, _) = probe(simulator(altered.clone(), 1), "csv");
    assert_eq!(code, 1);
    let got = python(
        "import csv,sys\nfor r in csv.DictReader(sys.stdin):\n    if r['result']=='disagree': print(r['kind'], r['parameter'], r['exception'])",
        &out,
    );
    assert_eq!(
        got,
        "refused n001 02h\nunlisted_code n002 \nout_of_range n016 \n"
    );
    let (code, out, _) = probe(simulator(altered, 1), "table");
    assert_eq!(code, 1);
    assert_eq!(out.matches("\n  DISAGREE ").count(), 3, "{out}");
    assert!(out.contains("scale selector modbus_frequency_reference_unit_selection (n152) = 0 (read from the drive)"), "{out}");
}

#[test]
fn scan_finds_two_slaves_on_a_serial_line_and_names_their_maps() {
    let pty = pty_pair::PtyPair::new();
    let v7 = drivemap_map::Loader::new()
        .load(&repo().join("maps/yaskawa-v7.yaml"))
        .unwrap();
    let tds = drivemap_map::Loader::new()
        .load(&repo().join("maps/ptlk-tds-v8.yaml"))
        .unwrap();
    // Two simulated drives on one serial line (`drivemap_sim::Line`): the one addressed answers.
    let mut line = Line::new();
    line.add(Simulator::new(v7, SimOptions::new().slave(2)).unwrap())
        .unwrap();
    line.add(Simulator::new(tds, SimOptions::new().slave(7)).unwrap())
        .unwrap();
    let bus = SerialServer::spawn(
        line,
        SerialOptions::new(pty.paths[1].clone(), 9600).parity(Parity::Even),
        None,
    )
    .unwrap();
    let dir = TempDir::new("scan");
    let started = Instant::now();
    let (code, out, err) = run_in(
        Path::new(env!("CARGO_BIN_EXE_drivemap")),
        &dir.0,
        &[
            "scan",
            "--serial",
            &pty.paths[0],
            "--baud",
            "9600",
            "--parity",
            "even",
            "--slaves",
            "1-8",
            "--format",
            "json",
        ],
    );
    let took = started.elapsed();
    bus.stop();
    assert_eq!(code, 0, "{err}");
    eprintln!("scan of 8 addresses took {:.1} s", took.as_secs_f64());
    assert!(took < Duration::from_secs(60), "scan hung: {took:?}");
    let got = python(
        "import json,sys; r=json.load(sys.stdin)\n\
         print(r['lines'], r['slaves_tried'])\n\
         for f in r['found']: print(f['slave'], f['line'], f['maps'][0]['drive'], f['maps'][0]['score'])",
        &out,
    );
    assert_eq!(
        got, "['9600 8E1'] 8\n2 9600 8E1 yaskawa-v7 1.0\n7 9600 8E1 ptlk-tds-v8 1.0\n",
        "{out}"
    );
}
