//! `drivemap save`, `compare` and `restore` end to end against `drivemap simulate`: a line of two
//! simulated drives of one map, settings changed on the first, saved, restored to the second,
//! compared; for every map in `maps/`, over RTU frames over TCP and, where the map has it,
//! Modbus TCP.

use std::collections::BTreeMap;

use drivemap_live::codec::{self, Value};
use drivemap_live::paramset;
use drivemap_map::Map;
use drivemap_runtime::core::plan::Conversion;
use drivemap_sim::{SimOptions, Simulator};

use crate::common::{Scratch, Sim, drivemap, repo, shipped_maps};

/// Validates each set file (YAML, as parsed) against `docs/schema/parameter-set.schema.json`
/// with the interop venv's `jsonschema` (`tests/interop/install.sh`).
fn validate_schema(files: &[String]) {
    use std::io::Write;
    use std::process::{Command, Stdio};
    const SCRIPT: &str = "import json, sys, jsonschema
schema = json.load(open(sys.argv[1]))
jsonschema.Draft202012Validator.check_schema(schema)
v = jsonschema.Draft202012Validator(schema)
bad = 0
for i, doc in enumerate(json.load(sys.stdin)):
    for e in v.iter_errors(doc):
        bad += 1
        print(f'set {i}: at /{\"/\".join(map(str, e.absolute_path))}: {e.message}')
sys.exit(1 if bad else 0)
";
    let python = repo().join("target/interop-venv/bin/python");
    let docs: Vec<serde_json::Value> = files
        .iter()
        .map(|f| serde_yaml::from_str(&std::fs::read_to_string(f).unwrap()).unwrap())
        .collect();
    let mut child = Command::new(&python)
        .args(["-c", SCRIPT])
        .arg(repo().join("docs/schema/parameter-set.schema.json"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{}: {e}: run tests/interop/install.sh", python.display()));
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::to_string(&docs).unwrap().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "parameter-set.schema.json rejects a set:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn maps() -> Vec<(String, Map)> {
    let mut out: Vec<(String, Map)> = drivemap_map::find_maps(&shipped_maps())
        .expect("maps/ lists")
        .into_iter()
        .map(|p| {
            let d = drivemap_map::Loader::new().load(&p).expect("shipped map");
            (d.id().to_owned(), d)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(out.len() >= 5, "maps/ has the shipped maps");
    out
}

/// `--set NAME=100` for every external quantity of the map: the simulator and the commands are
/// told the same.
fn externals(drive: &Map) -> Vec<String> {
    drive
        .externals()
        .iter()
        .map(|q| format!("{}=100", q.external))
        .collect()
}

/// Words that name the link's own settings (address, speed, format, timeouts) or a lock:
/// changing them on a simulator would change the link or the drive's other answers.
const LINK_WORDS: &[&str] = &[
    "slave",
    "address",
    "baud",
    "parity",
    "bps",
    "transmission",
    "communication",
    "modbus",
    "memobus",
    "rts",
    "time_out",
    "timeout",
    "password",
    "initial",
    "stop_bit",
    "protocol",
    "station",
    "response",
];

/// Up to `n` settings of the map (spread over it) that depend on no other and that no other
/// depends on, each with a value other than the simulator's that the map accepts, as the
/// manual's value text.
fn changes(drive: &Map, sim: &Simulator, n: usize) -> Vec<(String, String)> {
    let settings = sim.settings();
    let regs = paramset::settings_of(drive);
    let depended: Vec<String> = regs
        .iter()
        .flat_map(|r| paramset::depends_on(drive, *r))
        .map(|d| d.id().to_owned())
        .collect();
    let mut candidates = Vec::new();
    for r in &regs {
        let id = r.id();
        let name = r.name().to_ascii_lowercase();
        if LINK_WORDS
            .iter()
            .any(|w| id.contains(w) || name.contains(&w.replace('_', " ")))
            || depended.iter().any(|d| d == id)
            || !paramset::depends_on(drive, *r).is_empty()
        {
            continue;
        }
        let plan = r.plan();
        let current = sim.raw(id).expect("a register of the simulator");
        let raws: Vec<i64> = match plan.conversion {
            Conversion::Enum { values, .. } => values.iter().map(|v| i64::from(v.code)).collect(),
            Conversion::Bits { .. } => continue,
            _ => {
                let e = plan.envelope;
                vec![e.max, e.min, e.min + 1, (e.min + e.max) / 2]
            }
        };
        let pick = raws.into_iter().find_map(|raw| {
            let raw = u32::try_from(raw & 0xFFFF_FFFF).ok()?;
            if raw == current {
                return None;
            }
            let text = match codec::decode(drive, *r, raw, &settings).ok()? {
                Value::Quantity {
                    value,
                    decimals,
                    exact: None,
                    ..
                } => format!("{value:.decimals$}"),
                Value::Word(w) => w.to_string(),
                Value::Code { code, .. } => code.to_string(),
                _ => return None,
            };
            (codec::parse_value(drive, *r, &text, &settings).ok()? == raw).then_some(text)
        });
        if let Some(text) = pick {
            candidates.push((id.to_owned(), text));
        }
    }
    if candidates.len() <= n {
        return candidates;
    }
    let step = candidates.len() / n;
    (0..n).map(|i| candidates[i * step].clone()).collect()
}

/// The links a map's drive is simulated on: RTU frames over TCP always, Modbus TCP where the
/// map lists it.
fn links(drive: &Map) -> Vec<(&'static str, &'static str)> {
    let mut out = vec![("--rtu-tcp", "0")];
    let tcp = drive
        .protocol()
        .transports
        .iter()
        .any(|t| format!("{t:?}").eq_ignore_ascii_case("tcp"));
    if tcp {
        out.push(("--tcp", "0"));
    }
    out
}

/// Runs `drivemap <args> <link> <extra>`; exit code, stdout, stderr.
fn run(args: &[&str], link: (&str, &str), extra: &[String]) -> (i32, String, String) {
    let mut all: Vec<&str> = args.to_vec();
    all.extend([link.0, link.1, "--timeout", "2s"]);
    for e in extra {
        all.extend(["--set", e.as_str()]);
    }
    drivemap(&all)
}

/// A line of two drives of `id`, the first with `sets` (`NAME=VALUE`, slave 1 only) and every
/// external quantity given to both.
fn line(id: &str, flag: &str, sets: &[(String, String)], ext: &[String]) -> Sim {
    let one = format!("{id}@1");
    let two = format!("{id}@2");
    let mut args: Vec<String> = vec![
        "--drive".into(),
        one,
        "--drive".into(),
        two,
        flag.into(),
        if flag == "--tcp" || flag == "--rtu-tcp" {
            "0".into()
        } else {
            "127.0.0.1:0".into()
        },
    ];
    for (k, v) in sets {
        args.extend(["--set".into(), format!("1:{k}={v}")]);
    }
    for e in ext {
        args.extend(["--set".into(), e.clone()]);
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    Sim::start(&refs)
}

#[test]
fn a_drive_saved_and_restored_to_another_slave_compares_equal_for_every_map() {
    let scratch = Scratch::new("paramset-clone");
    let mut saved = Vec::new();
    for (id, drive) in maps() {
        let sim = Simulator::new(drive.clone(), SimOptions::new()).expect("simulator");
        let changed = changes(&drive, &sim, 4);
        if !paramset::settings_of(&drive).is_empty() {
            assert!(!changed.is_empty(), "{id}: no setting to change");
        }
        let ext = externals(&drive);
        for (flag, _) in links(&drive) {
            let line = line(&id, flag, &changed, &ext);
            let link = (flag, line.addr.as_str());
            let file = scratch.0.join(format!("{id}{flag}.yaml"));
            let file = file.to_str().unwrap();
            let (code, _, err) = run(
                &["save", "--drive", &id, "--slave", "1", "-o", file],
                link,
                &ext,
            );
            assert_eq!(code, 0, "{id} {flag}: save: {err}");
            saved.push(file.to_owned());
            let text = std::fs::read_to_string(file).unwrap();
            for (k, _) in &changed {
                assert!(text.contains(&format!("id: \"{k}\"")), "{id}: {k} saved");
            }
            // Before: the two drives differ in exactly the settings changed on the first.
            let (code, out, err) = run(
                &[
                    "compare", "drive@1", "drive@2", "--drive", &id, "--format", "json",
                ],
                link,
                &ext,
            );
            let json: serde_json::Value = serde_json::from_str(&out)
                .unwrap_or_else(|e| panic!("{id}: compare json: {e}: {out}{err}"));
            let differ: Vec<&str> = json["differences"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d["id"].as_str().unwrap())
                .collect();
            let mut expected: Vec<&str> = changed.iter().map(|(k, _)| k.as_str()).collect();
            let mut found = differ.clone();
            expected.sort();
            found.sort();
            assert_eq!(
                found, expected,
                "{id} {flag}: differences before the restore"
            );
            assert_eq!(
                code,
                i32::from(!changed.is_empty()),
                "{id}: exit 1 when different"
            );

            let (code, out, err) = run(
                &["restore", file, "--drive", &id, "--slave", "2"],
                link,
                &ext,
            );
            assert_eq!(code, 0, "{id} {flag}: restore: {out}{err}");
            assert!(
                out.contains(&format!(
                    "{} written and verified, 0 written but not verified, 0 not written",
                    changed.len()
                )),
                "{id} {flag}: {out}"
            );
            let (code, out, err) = run(
                &["compare", "drive@1", "drive@2", "--drive", &id],
                link,
                &ext,
            );
            assert_eq!(code, 0, "{id} {flag}: compare after restore: {out}{err}");
            assert!(out.contains(": 0 differ,"), "{id}: {out}");
            let (code, out, _) = run(
                &["compare", file, "--drive", &id, "--slave", "2"],
                link,
                &ext,
            );
            assert_eq!(code, 0, "{id} {flag}: the set against the clone: {out}");
            // A restore of an unchanged set writes nothing.
            let (code, out, err) = run(
                &["restore", file, "--drive", &id, "--slave", "2"],
                link,
                &ext,
            );
            assert_eq!(code, 0, "{id} {flag}: second restore: {out}{err}");
            assert!(out.starts_with("0 of "), "{id}: {out}");
            assert!(
                out.contains("0 written and verified, 0 written but not verified, 0 not written"),
                "{id}: {out}"
            );
            assert!(
                !out.contains("stored"),
                "{id}: no store without a write: {out}"
            );
        }
    }
    validate_schema(&saved);
}

/// The V7 with the maximum frequency, a frequency reference and an accel time changed.
fn v7_changed() -> Vec<(String, String)> {
    pairs(&[("n011", "50"), ("n024", "45"), ("n019", "12.5")])
}

fn pairs(list: &[(&str, &str)]) -> Vec<(String, String)> {
    list.iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn compare_defaults_lists_exactly_the_settings_changed() {
    let line = line("yaskawa-v7", "--tcp", &v7_changed(), &[]);
    let link = ("--tcp", line.addr.as_str());
    let (code, out, err) = run(&["compare", "defaults", "--drive", "yaskawa-v7"], link, &[]);
    assert_eq!(code, 1, "{out}{err}");
    let params: Vec<&str> = out
        .lines()
        .skip(1)
        .filter(|l| !l.ends_with("no printed default"))
        .map(|l| {
            l.split_once(" (")
                .and_then(|(_, rest)| rest.split_once(')'))
                .map(|(p, _)| p)
                .unwrap()
        })
        .collect();
    assert_eq!(params, ["n011", "n019", "n024"], "{out}");
    assert!(out.contains("(n011): 60.0 Hz -> 50.0 Hz"), "{out}");
    assert!(
        out.contains("[000_032dced3a1e91a75.txt:1061]"),
        "the citation: {out}"
    );
    assert!(out.contains("(n014): no printed default"), "{out}");
    // The untouched slave 2 holds the defaults.
    let (code, out, _) = run(
        &[
            "compare",
            "defaults",
            "--drive",
            "yaskawa-v7",
            "--slave",
            "2",
        ],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}");
    let (code, out, _) = run(
        &[
            "compare",
            "defaults",
            "--drive",
            "yaskawa-v7",
            "--format",
            "md",
        ],
        link,
        &[],
    );
    assert_eq!(code, 1);
    assert!(
        out.contains(
            "| max_output_frequency (n011) | 60.0 Hz | 50.0 Hz | 000_032dced3a1e91a75.txt:1061 |"
        ),
        "{out}"
    );
}

/// The GPD515's C1-10 selects the unit of C1-01 to C1-09, which the map lists before it: the
/// plan writes C1-10 first.
#[test]
fn the_plan_writes_what_selects_a_scale_before_what_it_scales() {
    let changed = pairs(&[("C1-10", "0"), ("C1-01", "50")]);
    let line = line("yaskawa-gpd515", "--rtu-tcp", &changed, &[]);
    let link = ("--rtu-tcp", line.addr.as_str());
    let scratch = Scratch::new("paramset-order");
    let file = scratch.0.join("gpd.yaml");
    let file = file.to_str().unwrap();
    let (code, _, err) = run(
        &[
            "save",
            "--drive",
            "yaskawa-gpd515",
            "--slave",
            "1",
            "-o",
            file,
        ],
        link,
        &[],
    );
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = run(
        &[
            "restore",
            file,
            "--drive",
            "yaskawa-gpd515",
            "--slave",
            "2",
            "--dry-run",
        ],
        link,
        &[],
    );
    assert_eq!(code, 0, "{err}");
    let at = |p: &str| {
        out.find(&format!("({p})"))
            .unwrap_or_else(|| panic!("{p} in {out}"))
    };
    assert!(out.starts_with("2 of "), "{out}");
    assert!(at("C1-10") < at("C1-01"), "{out}");
    assert!(out.contains("then enter"), "{out}");
    // A dry run wrote nothing; the restore then makes the two drives alike.
    let (code, _, _) = run(
        &[
            "compare",
            "defaults",
            "--drive",
            "yaskawa-gpd515",
            "--slave",
            "2",
        ],
        link,
        &[],
    );
    assert_eq!(code, 0);
    let (code, out, err) = run(
        &["restore", file, "--drive", "yaskawa-gpd515", "--slave", "2"],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("2 written and verified"), "{out}");
    let (code, out, _) = run(
        &["compare", "drive@1", "drive@2", "--drive", "yaskawa-gpd515"],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}");
}

/// The TDS-V8's Cn-09 is at most 200 % of the inverter rated current (an external quantity).
#[test]
fn a_value_above_its_relative_limit_is_refused_before_anything_is_written() {
    let ext = vec!["inverter_rated_current=10".to_owned()];
    let changed = pairs(&[("Cn-09", "15"), ("Bn-01", "20")]);
    let line = line("ptlk-tds-v8", "--gateway", &changed, &ext);
    let link = ("--gateway", line.addr.as_str());
    let scratch = Scratch::new("paramset-limit");
    let file = scratch.0.join("tds.yaml");
    let file = file.to_str().unwrap();
    let before = scratch.0.join("before.yaml");
    let before = before.to_str().unwrap();
    let (code, _, err) = run(&["save", "--drive", "ptlk-tds-v8", "-o", file], link, &ext);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(
        &[
            "save",
            "--drive",
            "ptlk-tds-v8",
            "--slave",
            "2",
            "-o",
            before,
        ],
        link,
        &ext,
    );
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(file).unwrap();
    assert!(text.contains("param: \"Cn-09\", value: 15.0}"), "{text}");
    // Cn-09 = 25 A, above 200 % of 10 A; and a code that is not one of the first code setting's.
    let mut coded = false;
    let bad: String = text
        .lines()
        .map(|l| {
            if l.contains("param: \"Cn-09\"") {
                l.replace("value: 15.0", "value: 25.0")
            } else if !coded && l.contains(", code: ") {
                coded = true;
                let (head, _) = l.split_once(", value:").unwrap();
                format!("{head}, value: 999}}")
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(file, bad).unwrap();
    let (code, out, err) = run(
        &["restore", file, "--drive", "ptlk-tds-v8", "--slave", "2"],
        link,
        &ext,
    );
    assert_eq!(code, 2, "{out}{err}");
    assert!(err.contains("motor_rated_current (Cn-09)"), "{err}");
    assert!(err.contains("inverter_rated_current"), "{err}");
    assert!(err.contains("999"), "every reason listed: {err}");
    assert!(err.ends_with("nothing written\n"), "{err}");
    // Slave 2 is as it was, though the set's Bn-01 differs from it.
    let (code, out, _) = run(
        &["compare", before, "--drive", "ptlk-tds-v8", "--slave", "2"],
        link,
        &ext,
    );
    assert_eq!(code, 0, "{out}");
    let (code, out, _) = run(
        &["compare", file, before, "--drive", "ptlk-tds-v8"],
        link,
        &ext,
    );
    assert_eq!(code, 1, "the refused set is still a set to compare: {out}");
}

#[test]
fn a_set_of_another_map_or_a_broken_file_is_refused_naming_where() {
    let scratch = Scratch::new("paramset-files");
    let file = scratch.0.join("bad.yaml");
    std::fs::write(
        &file,
        "format: \"drivemap-parameter-set/1\"\ndrive: yaskawa-v7\nfingerprint: x\nslave: 1\nsaved: now\nsettings:\n  - {id: max_output_frequency, value: [1]}\n",
    )
    .unwrap();
    let (code, _, err) = drivemap(&["compare", file.to_str().unwrap(), "defaults"]);
    assert_eq!(code, 2);
    assert!(err.contains("bad.yaml") && err.contains("line 7"), "{err}");
    let set = paramset::ParameterSet {
        format: paramset::FORMAT.into(),
        drive: "ptlk-tds-v8".into(),
        variant: BTreeMap::new(),
        fingerprint: "x".into(),
        slave: 1,
        saved: String::new(),
        settings: Vec::new(),
        unread: Vec::new(),
    };
    let tds = scratch.0.join("tds.yaml");
    let v7 = drivemap_map::Loader::new()
        .load(&shipped_maps().join("yaskawa-v7.yaml"))
        .unwrap();
    std::fs::write(&tds, set.to_yaml(&v7)).unwrap();
    let (code, _, err) = drivemap(&[
        "compare",
        tds.to_str().unwrap(),
        "defaults",
        "--drive",
        "yaskawa-v7",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("ptlk-tds-v8") && err.contains("--other"),
        "{err}"
    );
    // Text printed in messages is one short line: a value with a line break, or a long one, is
    // refused naming where it is, shortened and escaped.
    let long = "9".repeat(5000);
    for (value, shown) in [("\"1\\n2\"", "`1\\n2`"), (long.as_str(), "99999…")] {
        std::fs::write(
            &file,
            format!(
                "format: \"drivemap-parameter-set/1\"\ndrive: yaskawa-v7\nfingerprint: x\nslave: 1\nsaved: now\nsettings:\n  - {{id: max_output_frequency, value: {value}}}\n"
            ),
        )
        .unwrap();
        let (code, _, err) = drivemap(&["compare", file.to_str().unwrap(), "defaults"]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("settings[0].value") && err.contains(shown),
            "{err}"
        );
        assert!(err.len() < 400, "{err}");
    }
}

/// `simulate --restore set.yaml` powers on with the set: the drive compares equal to it.
#[test]
fn simulate_restore_powers_on_with_a_set() {
    let changed = pairs(&[("C1-10", "0"), ("C1-01", "50"), ("b1-01", "0")]);
    let line = line("yaskawa-gpd515", "--rtu-tcp", &changed, &[]);
    let link = ("--rtu-tcp", line.addr.as_str());
    let scratch = Scratch::new("paramset-simulate");
    let file = scratch.0.join("gpd.yaml");
    let file = file.to_str().unwrap();
    let (code, _, err) = run(
        &[
            "save",
            "--drive",
            "yaskawa-gpd515",
            "--slave",
            "1",
            "-o",
            file,
        ],
        link,
        &[],
    );
    assert_eq!(code, 0, "{err}");
    drop(line);
    let sim = Sim::start(&[
        "--drive",
        "yaskawa-gpd515",
        "--slave",
        "1",
        "--rtu-tcp",
        "0",
        "--restore",
        file,
    ]);
    let link = ("--rtu-tcp", sim.addr.as_str());
    let (code, out, err) = run(
        &["compare", file, "--drive", "yaskawa-gpd515", "--slave", "1"],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, _) = run(
        &[
            "compare",
            "defaults",
            "--drive",
            "yaskawa-gpd515",
            "--slave",
            "1",
        ],
        link,
        &[],
    );
    assert_eq!(code, 1, "{out}");
    // A set of another map is refused naming both.
    let (code, _, err) = drivemap(&[
        "simulate",
        "--drive",
        "yaskawa-v7",
        "--rtu-tcp",
        "0",
        "--restore",
        file,
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("yaskawa-gpd515") && err.contains("yaskawa-v7"),
        "{err}"
    );
}

/// The V7's parameters may be written only while it is stopped: a restore to a running drive
/// is refused, naming the settings, and nothing is written.
#[test]
fn a_running_drive_is_not_restored() {
    let scratch = Scratch::new("paramset-running");
    let file = scratch.0.join("v7.yaml");
    let file = file.to_str().unwrap();
    let sim = Sim::start(&[
        "--drive",
        "yaskawa-v7@1",
        "--drive",
        "yaskawa-v7@2",
        "--rtu-tcp",
        "0",
        "--network-source",
        "--set",
        "1:n019=12.5",
        "--set",
        "2:n024=30",
    ]);
    let link = ("--rtu-tcp", sim.addr.as_str());
    let (code, _, err) = run(&["save", "--drive", "yaskawa-v7", "-o", file], link, &[]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = run(
        &[
            "write",
            "--drive",
            "yaskawa-v7",
            "--slave",
            "2",
            "digital_input_command=run_command",
        ],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = run(
        &["restore", file, "--drive", "yaskawa-v7", "--slave", "2"],
        link,
        &[],
    );
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("the drive shows running") && err.contains("accel_time_1 (n019)"),
        "{err}"
    );
    assert!(err.contains("nothing written"), "{err}");
    // Stopped, it is restored.
    let (code, out, err) = run(
        &[
            "write",
            "--drive",
            "yaskawa-v7",
            "--slave",
            "2",
            "digital_input_command=0",
        ],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = run(
        &["restore", file, "--drive", "yaskawa-v7", "--slave", "2"],
        link,
        &[],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("2 written and verified"), "{out}");
}
