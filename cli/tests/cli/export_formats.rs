//! `drivemap export --format home-assistant | telegraf | node-red` checked against the tools'
//! own rules and against a running simulator:
//!
//! - the Home Assistant YAML of every shipped map on every link passes Home Assistant's own
//!   modbus configuration schema (2024.3.3, the last release for this Python, in target/ha-venv;
//!   the test fails when it is missing) with no entity dropped and no warning;
//! - the Telegraf TOML follows the request style of Telegraf's documented `inputs.modbus` schema
//!   (`plugins/inputs/modbus/sample_request.conf`; Telegraf itself is not in Debian bookworm):
//!   known keys and values only, one request per planned read whose fields tile it exactly;
//! - read as Home Assistant and Telegraf read them (addresses, data types, word order, scale,
//!   precision), the exported registers of a `drivemap simulate` drive give the values
//!   `drivemap read` gives;
//! - nothing is left out silently: every register asked for is an entity, a field, a decoded
//!   message, or named in a "left out" comment with its reason.

use drivemap_test_support::paths;

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;
use std::time::Duration;

use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::transport::tcp::TcpTransport;
use serde_json::Value;

use common::{Sim, command, drivemap_builtin, repo};

/// `drivemap export ARGS` of the built-in maps, in-process (`drivemap_cli::export_in_process`:
/// the binary's parser and export code, each map loaded once): the sweeps below export every map
/// on every link in every format. `the_in_process_export_is_the_binarys` compares it with the
/// binary's output.
fn export(args: &[&str]) -> String {
    drivemap_cli::export_in_process(&[&["drivemap", "export"][..], args].concat())
        .unwrap_or_else(|e| panic!("drivemap export {args:?}: {e}"))
}

/// The in-process export is the binary's, byte for byte: every format, a map with every kind of
/// register left out (a scale another parameter selects, registers of another link) and with
/// `--set`, and the largest map.
#[test]
fn the_in_process_export_is_the_binarys() {
    let cases: [&[&str]; 7] = [
        &["--drive", "yaskawa-v7"],
        &["--drive", "yaskawa-v7", "--format", "facts"],
        &[
            "--drive",
            "yaskawa-v7",
            "--all",
            "--tcp",
            "192.0.2.12:502",
            "--format",
            "home-assistant",
        ],
        &[
            "--drive",
            "yaskawa-v7",
            "--all",
            "--rtu-tcp",
            "192.0.2.11:4001",
            "--format",
            "telegraf",
        ],
        &[
            "--drive",
            "yaskawa-v7",
            "--set",
            "n152=1",
            "--gateway",
            "192.0.2.10:502",
            "--format",
            "node-red",
        ],
        &[
            "--drive",
            "automationdirect-acn",
            "--all",
            "--serial",
            "/dev/ttyUSB0",
            "--format",
            "home-assistant",
        ],
        &[
            "--drive",
            "automationdirect-acn",
            "--all",
            "--gateway",
            "192.0.2.10:502",
            "--format",
            "node-red",
        ],
    ];
    for args in cases {
        let (code, out, err) = drivemap_builtin(&[&["export"][..], args].concat());
        assert_eq!(code, 0, "drivemap export {args:?}: {err}");
        assert!(!out.is_empty(), "{args:?}");
        assert_eq!(export(args), out, "drivemap export {args:?}");
    }
    // A refusal is the binary's too.
    let args = ["--drive", "yaskawa-v7", "--format", "telegraf"];
    let (code, _, err) = drivemap_builtin(&[&["export"][..], &args[..]].concat());
    let e = drivemap_cli::export_in_process(&[&["drivemap", "export"][..], &args[..]].concat())
        .unwrap_err();
    assert_eq!(
        (code, err.trim_end()),
        (2, format!("drivemap: {e}").as_str())
    );
}

/// The shipped maps.
fn maps() -> Vec<String> {
    let mut ids: Vec<String> = std::fs::read_dir(paths::maps())
        .unwrap()
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            Some(name.strip_suffix(".yaml")?.to_owned())
        })
        .collect();
    ids.sort();
    assert!(ids.len() >= 5, "{ids:?}");
    ids
}

/// The links a map can be reached on.
fn links(id: &str) -> Vec<[&'static str; 2]> {
    let mut l = vec![
        ["--gateway", "192.0.2.10:502"],
        ["--rtu-tcp", "192.0.2.11:4001"],
        ["--serial", "/dev/ttyUSB0"],
    ];
    let json = export(&["--drive", id]);
    let map: Value = serde_json::from_str(&json).unwrap();
    if map["protocol"]["transports"]
        .as_array()
        .is_some_and(|t| t.iter().any(|x| x == "tcp"))
    {
        l.push(["--tcp", "192.0.2.12:502"]);
    }
    l
}

#[test]
fn home_assistant_export_passes_home_assistants_own_modbus_schema() {
    let python = repo().join("target/ha-venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run tests/interop/install.sh (Home Assistant's modbus schema)",
        python.display()
    );
    let dir = std::env::temp_dir().join(format!("drivemap-ha-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut files = Vec::new();
    for id in maps() {
        for link in links(&id) {
            for which in [&["--all"][..], &[][..]] {
                let yaml = export(
                    &[
                        &["--drive", &id, "--format", "home-assistant"][..],
                        &link,
                        which,
                    ]
                    .concat(),
                );
                let f = dir.join(format!(
                    "{id}{}{}.yaml",
                    link[0].replace('-', "_"),
                    if which.is_empty() { "" } else { "_all" }
                ));
                std::fs::write(&f, yaml).unwrap();
                files.push(f);
            }
        }
    }
    let out = Command::new(&python)
        .arg(repo().join("tests/interop/ha_check_modbus.py"))
        .args(&files)
        .output()
        .expect("run Home Assistant's schema check");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "Home Assistant refused an export:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        text.lines().filter(|l| l.contains(": ok: ")).count(),
        files.len(),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Telegraf's request-style schema as its documentation gives it (sample_general_begin.conf,
/// sample_request.conf, sample_general_end.conf).
fn check_telegraf(text: &str, what: &str, max_read: i64) -> Vec<String> {
    check_telegraf_with_bits(text, what, max_read, 2000)
}

/// [`check_telegraf`] where coil and discrete-input requests (`register = "coil"` or
/// `"discrete"`: no byte order, fields of one bit with no type or scale) read at most
/// `max_bits`.
fn check_telegraf_with_bits(text: &str, what: &str, max_read: i64, max_bits: i64) -> Vec<String> {
    let doc: toml::Table = text
        .parse()
        .unwrap_or_else(|e| panic!("{what}: {e}\n{text}"));
    assert_eq!(doc.len(), 1, "{what}: only [[inputs.modbus]]");
    let plugins = doc["inputs"]["modbus"]
        .as_array()
        .expect("[[inputs.modbus]]");
    assert_eq!(plugins.len(), 1, "{what}");
    let p = plugins[0].as_table().unwrap();
    let general = [
        "name",
        "interval",
        "timeout",
        "controller",
        "transmission_mode",
        "baud_rate",
        "data_bits",
        "parity",
        "stop_bits",
        "configuration_type",
        "request",
        "workarounds",
    ];
    for k in p.keys() {
        assert!(general.contains(&k.as_str()), "{what}: unknown key {k}");
    }
    assert_eq!(p["configuration_type"].as_str(), Some("request"), "{what}");
    let controller = p["controller"].as_str().unwrap();
    let mode = p["transmission_mode"].as_str().unwrap();
    if controller.starts_with("tcp://") {
        assert!(["TCP", "RTUoverTCP"].contains(&mode), "{what}: {mode}");
    } else {
        assert!(controller.starts_with("file://"), "{what}: {controller}");
        assert_eq!(mode, "RTU", "{what}");
        assert!(
            ["N", "E", "O"].contains(&p["parity"].as_str().unwrap()),
            "{what}"
        );
        assert!(
            [1, 2].contains(&p["stop_bits"].as_integer().unwrap()),
            "{what}"
        );
    }
    for k in ["interval", "timeout"] {
        let v = p[k].as_str().unwrap();
        assert!(
            v.strip_suffix("ms")
                .is_some_and(|n| n.parse::<u64>().is_ok()),
            "{what}: {k} = {v}"
        );
    }
    let w = p["workarounds"].as_table().unwrap();
    for k in w.keys() {
        assert!(
            ["pause_between_requests", "max_word_registers_per_request"].contains(&k.as_str()),
            "{what}: workarounds.{k}"
        );
    }
    let mut names = Vec::new();
    let requests = p
        .get("request")
        .and_then(|r| r.as_array())
        .cloned()
        .unwrap_or_default();
    for r in &requests {
        let r = r.as_table().unwrap();
        for k in r.keys() {
            assert!(
                [
                    "slave_id",
                    "byte_order",
                    "register",
                    "measurement",
                    "optimization",
                    "fields",
                    "tags"
                ]
                .contains(&k.as_str()),
                "{what}: request key {k}"
            );
        }
        let register = r["register"].as_str().unwrap();
        assert!(
            ["holding", "input", "coil", "discrete"].contains(&register),
            "{what}"
        );
        let bits = ["coil", "discrete"].contains(&register);
        if bits {
            assert!(
                r.get("byte_order").is_none(),
                "{what}: a byte order on {register}"
            );
        } else {
            assert!(
                ["ABCD", "CDAB"].contains(&r["byte_order"].as_str().unwrap()),
                "{what}"
            );
        }
        assert_eq!(r["optimization"].as_str(), Some("none"), "{what}");
        let fields = r["fields"].as_array().unwrap();
        // The fields tile one contiguous request: each starts where the previous one ends.
        let mut next: Option<i64> = None;
        let mut first = 0;
        for f in fields {
            let f = f.as_table().unwrap();
            let keys: &[&str] = if bits {
                &["address", "name", "omit"]
            } else {
                &["address", "name", "type", "scale", "omit"]
            };
            for k in f.keys() {
                assert!(keys.contains(&k.as_str()), "{what}: field key {k}");
            }
            let address = f["address"].as_integer().unwrap();
            let ty = if bits {
                "UINT16"
            } else {
                f["type"].as_str().unwrap()
            };
            let width = match ty {
                "INT16" | "UINT16" => 1,
                "INT32" | "UINT32" => 2,
                other => panic!("{what}: type {other}"),
            };
            match next {
                Some(n) => assert_eq!(address, n, "{what}: a gap or an overlap in {r:?}"),
                None => first = address,
            }
            next = Some(address + width);
            if f.get("omit").and_then(|o| o.as_bool()) != Some(true) {
                names.push(f["name"].as_str().unwrap().to_owned());
            } else {
                assert_eq!(ty, "UINT16", "{what}");
            }
        }
        let span = next.unwrap() - first;
        let max = if bits { max_bits } else { max_read };
        assert!(
            span >= 1 && span <= max,
            "{what}: {span} registers in one request"
        );
    }
    names
}

#[test]
fn telegraf_export_follows_the_documented_request_schema_one_request_per_planned_read() {
    for id in maps() {
        let json = export(&["--drive", &id]);
        let map: Value = serde_json::from_str(&json).unwrap();
        let max_read = map["protocol"]["max_read"].as_i64().unwrap_or(125).min(125);
        for link in links(&id) {
            let args = [&["--drive", &id, "--all"][..], &link].concat();
            let toml = export(&[&args[..], &["--format", "telegraf"]].concat());
            let what = format!("{id} {}", link[0]);
            let names = check_telegraf(&toml, &what, max_read);
            let mut unique = names.clone();
            unique.sort();
            unique.dedup();
            assert_eq!(unique.len(), names.len(), "{what}: a field twice");
            // As many requests as the planner's reads, which the header gives.
            let planned: usize = toml
                .lines()
                .next()
                .and(toml.lines().nth(1))
                .and_then(|l| l.split(" in ").nth(1))
                .and_then(|l| l.split_whitespace().next())
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("{what}: no plan in the header"));
            assert_eq!(
                toml.lines()
                    .filter(|l| l.trim() == "[[inputs.modbus.request]]")
                    .count(),
                planned,
                "{what}"
            );
        }
    }
}

/// Every readable register of `--all`, in each format: exported, or left out with its reason.
#[test]
fn every_register_asked_for_is_exported_or_named_with_the_reason() {
    for id in maps() {
        let json = export(&["--drive", &id]);
        let map: Value = serde_json::from_str(&json).unwrap();
        let readable: Vec<String> = map["registers"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["access"] != "w")
            .map(|r| r["id"].as_str().unwrap().to_owned())
            .collect();
        for link in links(&id) {
            let args = [&["--drive", &id, "--all"][..], &link].concat();
            let ha = export(&[&args[..], &["--format", "home-assistant"]].concat());
            let tg = export(&[&args[..], &["--format", "telegraf"]].concat());
            let nr = export(&[&args[..], &["--format", "node-red"]].concat());
            let nr: Vec<Value> = serde_json::from_str(&nr).unwrap();
            let comment = nr
                .iter()
                .find(|n| n["type"] == "comment")
                .expect("a comment node")["info"]
                .as_str()
                .unwrap()
                .to_owned();
            let code: String = nr
                .iter()
                .filter(|n| n["type"] == "function")
                .map(|n| n["func"].as_str().unwrap())
                .collect();
            let slave = link_slave(&ha);
            // What each text exports and leaves out, read once (a text is searched for every
            // register of the map): the quoted names after `open` up to `close`, and the lines
            // (`# ` stripped) that say `left out ...: <reason>`.
            let quoted = |text: &str, open: &str, close: &str| -> BTreeSet<String> {
                text.split(open)
                    .skip(1)
                    .filter_map(|rest| {
                        let (name, _) = rest.split_once('"')?;
                        rest[name.len()..]
                            .starts_with(close)
                            .then(|| name.to_owned())
                    })
                    .collect()
            };
            let left_out = |text: &str| -> Vec<String> {
                text.lines()
                    .filter(|l| l.contains(": "))
                    .filter_map(|l| l.trim_start_matches("# ").strip_prefix("left out "))
                    .map(str::to_owned)
                    .collect()
            };
            let (ha_ids, ha_left) = (quoted(&ha, "unique_id: \"", "\""), left_out(&ha));
            let (tg_names, tg_left) = (quoted(&tg, "name = \"", "\", type"), left_out(&tg));
            let (nr_puts, nr_left) = (quoted(&code, "put(\"", "\","), left_out(&comment));
            let why = |left: &[String], r: &str| left.iter().any(|l| l.starts_with(r));
            let mut left = 0;
            for r in &readable {
                let in_ha = ha_ids.contains(&format!("{}_{slave}_{r}", id.replace('-', "_")));
                assert!(
                    in_ha ^ why(&ha_left, r),
                    "{id} {}: {r} in Home Assistant",
                    link[0]
                );
                let in_tg = tg_names.contains(r);
                assert!(
                    in_tg ^ why(&tg_left, r),
                    "{id} {}: {r} in Telegraf",
                    link[0]
                );
                let in_nr = nr_puts.contains(r);
                assert!(
                    in_nr ^ why(&nr_left, r),
                    "{id} {}: {r} in Node-RED",
                    link[0]
                );
                left += usize::from(!in_nr);
            }
            // The reasons are real ones: a map-wide sweep leaves out only what a tool cannot
            // read as the map means it.
            assert!(
                left < readable.len(),
                "{id} {}: everything left out",
                link[0]
            );
        }
    }
    // A scale another parameter selects is left out until --set gives it, then exported.
    let v7 = |extra: &[&str]| {
        export(
            &[
                &[
                    "--drive",
                    "yaskawa-v7",
                    "--format",
                    "telegraf",
                    "--tcp",
                    "127.0.0.1:502",
                    "--register",
                    "output_frequency",
                ][..],
                extra,
            ]
            .concat(),
        )
    };
    let without = v7(&[]);
    assert!(
        without.contains("# left out output_frequency: its scale depends on another parameter")
            && without.contains("--set n152=<value>")
            && !without.contains("name = \"output_frequency\""),
        "{without}"
    );
    let with = v7(&["--set", "n152=1"]);
    assert!(
        with.contains(
            "{ address = 36, name = \"output_frequency\", type = \"UINT16\", scale = 0.01 }"
        ) && with.contains("output_frequency: its scale holds for n152 as given with --set"),
        "{with}"
    );
    let with = v7(&["--set", "n152=0"]);
    assert!(with.contains("scale = 0.1 }"), "{with}");
}

fn link_slave(ha: &str) -> String {
    ha.lines()
        .find_map(|l| l.trim().strip_prefix("slave: "))
        .unwrap_or("1")
        .to_owned()
}

/// Starts `drivemap simulate ARGS` on a loopback listener; returns it and its address.
fn simulate(args: &[&str]) -> (Sim, String) {
    let sim = Sim::listening(command().arg("simulate").args(args));
    let addr = sim.addr.clone();
    (sim, addr)
}

/// A raw Modbus client: PDU addresses as given, no map.
fn raw_client(addr: &str) -> Client<TcpTransport> {
    static GENERIC: Profile = Profile::GENERIC;
    Client::new(
        TcpTransport::connect(addr, Duration::from_secs(2)).expect("connect"),
        &GENERIC,
    )
}

fn read_words(c: &mut Client<TcpTransport>, input: bool, pdu: u16, n: u16) -> Vec<u16> {
    let mut w = vec![0u16; usize::from(n)];
    let r = if input {
        c.read_input(1, pdu, &mut w)
    } else {
        c.read_holding(1, pdu, &mut w)
    };
    r.unwrap_or_else(|e| panic!("read {pdu} x{n}: {e}"));
    w
}

fn int(words: &[u16], signed: bool, low_first: bool) -> f64 {
    match (words.len(), signed) {
        (1, false) => f64::from(words[0]),
        (1, true) => f64::from(words[0] as i16),
        _ => {
            let (hi, lo) = if low_first {
                (words[1], words[0])
            } else {
                (words[0], words[1])
            };
            let raw = (u32::from(hi) << 16) | u32::from(lo);
            if signed {
                f64::from(raw as i32)
            } else {
                f64::from(raw)
            }
        }
    }
}

/// The values Home Assistant and Telegraf read with the exports of `drive` on `link` equal
/// those `drivemap read` gives, for every register exported.
fn values_agree(drive: &str, sim_link: &str, link: &str, sets: &[&str]) {
    let (_sim, addr) = simulate(
        &[
            &[
                "--drive",
                drive,
                sim_link,
                "0",
                "--quiet",
                "--network-source",
            ][..],
            sets,
        ]
        .concat(),
    );
    let base = [&["--drive", drive, link, &addr][..], sets].concat();
    let ha = export(&[&base[..], &["--format", "home-assistant"]].concat());
    let tg = export(&[&base[..], &["--format", "telegraf"]].concat());

    // What drivemap reads, by register id.
    let ha_doc: serde_json::Value = {
        let y: serde_yaml::Value = serde_yaml::from_str(&ha).expect("YAML");
        serde_json::to_value(y).unwrap()
    };
    let prefix = format!("{}_1_", drive.replace('-', "_"));
    let sensors = ha_doc["modbus"][0]["sensors"].as_array().unwrap().clone();
    let ids: Vec<String> = sensors
        .iter()
        .map(|s| {
            s["unique_id"]
                .as_str()
                .unwrap()
                .strip_prefix(&prefix)
                .unwrap()
                .to_owned()
        })
        .collect();
    assert!(ids.len() >= 5, "{drive}: {ids:?}");
    let (code, read, err) = drivemap_builtin(
        &[
            &["read", "--drive", drive, link, &addr, "--format", "json"][..],
            sets,
            &ids.iter().map(String::as_str).collect::<Vec<_>>(),
        ]
        .concat(),
    );
    assert_eq!(code, 0, "{drive}: drivemap read: {err}");
    let read: Vec<Value> = serde_json::from_str(&read).unwrap();
    let expected: BTreeMap<String, f64> = read
        .iter()
        .map(|r| {
            (
                r["register"].as_str().unwrap().to_owned(),
                r["value"].as_f64().unwrap_or_else(|| panic!("{r}")),
            )
        })
        .collect();
    let nonzero = expected.values().filter(|v| **v != 0.0).count();
    assert!(
        nonzero >= 3,
        "{drive}: too few non-zero values to tell: {expected:?}"
    );

    let mut c = raw_client(&addr);
    // Home Assistant: one read per sensor; value = raw * scale + offset, rounded to precision.
    for (s, id) in sensors.iter().zip(&ids) {
        let ty = s["data_type"].as_str().unwrap();
        let n = if ty.ends_with("32") { 2 } else { 1 };
        let words = read_words(
            &mut c,
            s["input_type"] == "input",
            s["address"].as_u64().unwrap() as u16,
            n,
        );
        let raw = int(&words, !ty.starts_with('u'), s["swap"] == "word");
        let mut v = raw * s["scale"].as_f64().unwrap_or(1.0) + s["offset"].as_f64().unwrap_or(0.0);
        if let Some(p) = s["precision"].as_u64() {
            let k = 10f64.powi(p as i32);
            v = (v * k).round() / k;
        }
        let want = expected[id];
        assert!(
            (v - want).abs() < 1e-6,
            "{drive} Home Assistant {id}: {v}, drivemap read {want}"
        );
    }

    // Telegraf: one read per request, each field decoded from its words.
    let doc: toml::Table = tg.parse().unwrap();
    let mut seen = 0;
    for r in doc["inputs"]["modbus"][0]["request"].as_array().unwrap() {
        let fields = r["fields"].as_array().unwrap();
        let first = fields[0]["address"].as_integer().unwrap();
        let last = fields.last().unwrap();
        let width = |f: &toml::Value| {
            if f["type"].as_str().unwrap().ends_with("32") {
                2
            } else {
                1
            }
        };
        let end = last["address"].as_integer().unwrap() + width(last);
        let words = read_words(
            &mut c,
            r["register"].as_str() == Some("input"),
            first as u16,
            (end - first) as u16,
        );
        for f in fields {
            if f.get("omit").is_some() {
                continue;
            }
            let o = (f["address"].as_integer().unwrap() - first) as usize;
            let ty = f["type"].as_str().unwrap();
            let raw = int(
                &words[o..o + width(f) as usize],
                !ty.starts_with('U'),
                r["byte_order"].as_str() == Some("CDAB"),
            );
            let v = raw * f.get("scale").and_then(|s| s.as_float()).unwrap_or(1.0);
            let id = f["name"].as_str().unwrap();
            let want = expected[id];
            assert!(
                (v - want).abs() < 1e-6,
                "{drive} Telegraf {id}: {v}, drivemap read {want}"
            );
            seen += 1;
        }
    }
    assert_eq!(
        seen,
        ids.len(),
        "{drive}: Telegraf reads what Home Assistant reads"
    );
}

#[test]
fn values_read_as_home_assistant_and_telegraf_read_them_equal_drivemap_reads() {
    // The V7 on its Modbus TCP card (TCP addresses), with the scales set by n152 and n018.
    values_agree(
        "yaskawa-v7",
        "--tcp",
        "--tcp",
        &[
            "--set",
            "n152=1",
            "--set",
            "n018=0",
            "--set",
            "n011=55.5",
            "--set",
            "n019=2.5",
        ],
    );
    // The ACN behind a Modbus TCP gateway: RTU addressing, one below the printed addresses.
    values_agree("automationdirect-acn", "--gateway", "--gateway", &[]);
}

/// The coil fixture (`tests/fixtures/tindra-tc4`) in every format: Home Assistant binary
/// sensors of `input_type: coil` and `discrete_input` (checked by Home Assistant's own schema,
/// none dropped), Telegraf `coil` and `discrete` requests of the planned reads (one bit per
/// field, within the map's 32 per read), Node-RED `Coil` and `Input` reads, each table in reads
/// of its own.
#[test]
fn the_coil_fixture_exports_coils_and_discrete_inputs_in_every_format() {
    let dir = paths::fixture("tindra-tc4");
    let export = |format: &str, link: [&str; 2]| {
        let (code, out, err) = common::drivemap_fixture(
            &dir,
            &[
                "export",
                "--drive",
                "tindra-tc4",
                "--all",
                link[0],
                link[1],
                "--format",
                format,
            ],
        );
        assert_eq!(code, 0, "{format}: {err}");
        out
    };
    let python = repo().join("target/ha-venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run tests/interop/install.sh (Home Assistant's modbus schema)",
        python.display()
    );
    let tmp = std::env::temp_dir().join(format!("drivemap-ha-coils-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut files = Vec::new();
    for link in [["--tcp", "192.0.2.10:502"], ["--serial", "/dev/ttyUSB0"]] {
        let ha = export("home-assistant", link);
        assert!(ha.contains("    binary_sensors:"), "{ha}");
        let entry = |id: &str| {
            let start = ha
                .find(&format!("unique_id: \"tindra_tc4_1_{id}\""))
                .unwrap_or_else(|| panic!("{id}: {ha}"));
            ha[start..]
                .split("      - name:")
                .next()
                .unwrap()
                .to_owned()
        };
        let run = entry("operation_command");
        assert!(
            run.contains("address: 0\n") && run.contains("input_type: coil"),
            "{run}"
        );
        let running = entry("operation_status");
        assert!(
            running.contains("address: 0\n")
                && running.contains("input_type: discrete_input")
                && running.contains("device_class: running"),
            "{running}"
        );
        assert!(
            entry("alarm_signal").contains("device_class: problem"),
            "{ha}"
        );
        // The registers stay sensors.
        let sensors = ha.split("    binary_sensors:").next().unwrap();
        assert!(
            sensors.contains("tindra_tc4_1_output_frequency_monitor"),
            "{ha}"
        );
        let f = tmp.join(format!("tindra_{}.yaml", link[0].trim_start_matches('-')));
        std::fs::write(&f, &ha).unwrap();
        files.push(f);

        let toml = export("telegraf", link);
        let names = check_telegraf_with_bits(&toml, "tindra-tc4", 8, 32);
        assert!(
            names.iter().any(|n| n == "operation_command")
                && names.iter().any(|n| n == "operation_status")
                && names.iter().any(|n| n == "output_frequency_monitor"),
            "{names:?}"
        );
        assert!(toml.contains("register = \"coil\""), "{toml}");
        assert!(toml.contains("register = \"discrete\""), "{toml}");
        assert!(
            toml.contains("{ address = 0, name = \"operation_command\" },  # Operation command"),
            "{toml}"
        );

        let nr: Vec<Value> = serde_json::from_str(&export("node-red", link)).unwrap();
        let reads: Vec<(&str, &str)> = nr
            .iter()
            .filter(|n| n["type"] == "modbus-read")
            .map(|n| {
                (
                    n["dataType"].as_str().unwrap(),
                    n["quantity"].as_str().unwrap(),
                )
            })
            .collect();
        // The coils in two reads (the reserved 0005h is not bridged: the drive answers 02h
        // for it), the seven inputs in one, the registers in theirs.
        assert_eq!(
            reads.iter().filter(|r| **r == ("Coil", "4")).count(),
            2,
            "{reads:?}"
        );
        assert!(reads.contains(&("Input", "7")), "{reads:?}");
        assert!(reads.iter().any(|r| r.0 == "HoldingRegister"), "{reads:?}");
        let code: String = nr
            .iter()
            .filter(|n| n["type"] == "function")
            .map(|n| n["func"].as_str().unwrap())
            .collect();
        assert!(
            code.contains("put(\"operation_status\", (w[0] ? 1 : 0)"),
            "{code}"
        );
    }
    let out = Command::new(&python)
        .arg(repo().join("tests/interop/ha_check_modbus.py"))
        .args(&files)
        .output()
        .expect("run Home Assistant's schema check");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "Home Assistant refused the coil export:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        text.lines().filter(|l| l.contains(": ok: ")).count(),
        files.len(),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}
