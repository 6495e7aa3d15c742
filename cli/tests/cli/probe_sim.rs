//! A simulator powers on like the drive (issue 25, item 7): every register starts at its
//! factory default where the map gives one, else at the nearest value its own map allows. So
//! `drivemap probe` of every map in `maps/` against its own simulator, as it powers on, agrees:
//! 0 disagreements, on every transport the map offers and under every variant option. The maps
//! are read from the directory, not from a list.

use drivemap_test_support::paths;

use std::path::{Path, PathBuf};

use drivemap_map::facts::TransportName;
use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};

use crate::common;
use crate::new_map;

#[test]
fn probe_of_every_shipped_map_against_its_own_simulator_agrees() {
    let ids = every_map_agrees_with_its_simulator(&paths::maps());
    assert!(ids.len() >= 5, "{ids:?}");
}

/// A map added to `maps/` (the fixture drive of another vendor) is probed against its own
/// simulator by the same test, with no test edit.
#[test]
fn a_new_map_agrees_with_its_own_simulator_with_no_test_edit() {
    let n = new_map::NewMap::new("probe-sim");
    let ids = every_map_agrees_with_its_simulator(&n.root.join("maps"));
    assert!(ids.iter().any(|i| i == n.id), "{ids:?}");
}

/// Probes every map of `dir` against its own simulator, on every transport and variant
/// option; panics listing every disagreement. The drive ids probed.
pub(crate) fn every_map_agrees_with_its_simulator(dir: &Path) -> Vec<String> {
    let mut maps: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    maps.sort();
    let mut ids = Vec::new();
    let mut failures = Vec::new();
    let mut summary = Vec::new();
    for path in &maps {
        let drive = drivemap_map::Loader::new().load(path).unwrap();
        let id = drive.id().to_owned();
        ids.push(id.clone());
        let mut links: Vec<(&str, TcpFraming)> = vec![];
        if drive.protocol().transports.contains(&TransportName::Rtu) {
            links.push(("--rtu-tcp", TcpFraming::RtuOverTcp));
        }
        if drive.protocol().transports.contains(&TransportName::Tcp) {
            links.push(("--tcp", TcpFraming::ModbusTcp));
        }
        assert!(!links.is_empty(), "{id}: no transport");
        // The base variant, and each other option of every axis on its own: its own ranges
        // and defaults (V7 460 V class: n012 0.2-510.0 V, default 460.0).
        let mut variants: Vec<Option<(String, String)>> = vec![None];
        for axis in drive.variants() {
            for option in axis.options.iter().skip(1) {
                variants.push(Some((axis.id.clone(), option.id.clone())));
            }
        }
        for (variant, (flag, framing)) in variants
            .iter()
            .flat_map(|v| links.iter().map(move |l| (v, *l)))
        {
            let mut options = SimOptions::new();
            let mut variant_args = vec![];
            if let Some((axis, option)) = variant {
                options = options.variant(axis, option);
                variant_args = vec!["--variant".to_owned(), format!("{axis}={option}")];
            }
            let sim = Simulator::new(drive.clone(), options).unwrap();
            assert_eq!(sim.warnings(), [] as [String; 0], "{id} {variant:?}");
            let slave = sim.slave().to_string();
            let server = TcpServer::spawn(sim, "127.0.0.1:0", framing, None).unwrap();
            let addr = server.local_addr().to_string();
            let flag_shown = format!("{flag} {}", variant_args.join(" "));
            let flag_shown = flag_shown.trim_end();
            let out = common::command()
                .args(["probe", "--drive", &id, flag, &addr, "--slave", &slave])
                .args(&variant_args)
                .args(["--format", "json", "--maps"])
                .arg(dir)
                .output()
                .unwrap();
            let stdout = String::from_utf8_lossy(&out.stdout);
            let report: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
                panic!(
                    "{id} {flag_shown}: {e}: {stdout}{}",
                    String::from_utf8_lossy(&out.stderr)
                )
            });
            let disagreements = report["disagreements"].as_array().unwrap();
            summary.push(format!(
                "{id} {flag_shown}: checked {}, {} disagreement(s)",
                report["checked"],
                disagreements.len()
            ));
            if !disagreements.is_empty() || out.status.code() != Some(0) {
                failures.push(format!(
                    "{id} {flag_shown}: exit {:?}, {} disagreement(s):\n{}",
                    out.status.code(),
                    disagreements.len(),
                    disagreements
                        .iter()
                        .map(|d| format!("  {d}"))
                        .collect::<Vec<_>>()
                        .join("\n")
                ));
            }
        }
    }
    eprintln!("{}", summary.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    ids
}

/// The fixtures run through a command profile (CiA 402, PROFIdrive, ABB Drives, Danfoss FC),
/// each in its own directory with its manual.
const PROFILE_FIXTURES: &[&str] = &["kestrel-kd4", "norrland-nv20", "oskar-ax3", "solvik-sf7"];

/// Each profile fixture agrees with its own simulator (`probe`, every link it lists), passes
/// `check --strict` against its own manual, and `demo` runs and stops it through its state
/// machine; `export` carries its profile and `diff` against itself reports nothing.
#[test]
fn every_profile_fixture_is_probed_checked_demoed_exported_and_diffed() {
    for id in PROFILE_FIXTURES {
        let dir = paths::fixtures().join(id);
        let ids = every_map_agrees_with_its_simulator(&dir);
        assert_eq!(ids, [id.to_string()]);
        let file = format!("{id}.yaml");
        let (code, out, err) = common::drivemap_fixture(&dir, &["check", "--strict", &file]);
        assert_eq!(code, 0, "{id}: {out}{err}");
        assert!(out.contains("0 unverified"), "{id}: {out}");
        let (code, out, err) = common::drivemap_fixture(
            &dir,
            &["demo", "--drive", id, "--time-scale", "50", "--step", "1"],
        );
        assert_eq!(code, 0, "{id}: {out}{err}");
        assert!(
            out.contains("then run forward") && out.contains("stop"),
            "{id}: {out}"
        );
        // The last row of the table: the output back at 0 Hz after the stop.
        let last = out
            .lines()
            .rev()
            .find(|l| l.split_whitespace().nth(1) == Some("s"))
            .unwrap_or_default();
        let numbers: Vec<f64> = last
            .split_whitespace()
            .skip(2)
            .filter_map(|t| t.parse().ok())
            .collect();
        assert_eq!(numbers.get(1), Some(&0.0), "{id}: {last}\n{out}");
        assert!(out.contains("done in"), "{id}: {out}");
        // The table shows the state of the machine: where the run path ends while running.
        let drive = drivemap_map::Loader::new().load(&dir.join(&file)).unwrap();
        let profile = drive.plan().roles.profile.unwrap();
        let run = profile
            .path(drivemap_runtime::core::command_profile::PathKind::Run)
            .unwrap();
        let running = profile.state_id(run.to[0]);
        assert!(out.contains(&format!("[{running}]")), "{id}: {out}");
        let (code, out, err) = common::drivemap_fixture(&dir, &["export", &file]);
        assert_eq!(code, 0, "{id}: {err}");
        let json: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(json["profile"]["standard"].is_string(), "{id}: {out}");
        let (code, out, err) = common::drivemap_fixture(&dir, &["diff", &file, &file]);
        assert_eq!(code, 0, "{id}: {out}{err}");
    }
}

/// The coil fixture (`tests/fixtures/tindra-tc4`: run, direction and trip reset as coils, the
/// state as discrete inputs) agrees with its own simulator (`probe` reads every coil, input and
/// register, on RTU framing and Modbus TCP), passes `check --strict` against its own manual,
/// `demo` runs and stops it through its run coil, `export` gives each register's table, and
/// `diff` against itself reports nothing.
#[test]
fn the_coil_fixture_is_probed_checked_demoed_exported_and_diffed() {
    let id = "tindra-tc4";
    let dir = paths::fixtures().join(id);
    let ids = every_map_agrees_with_its_simulator(&dir);
    assert_eq!(ids, [id.to_string()]);
    let file = format!("{id}.yaml");
    let (code, out, err) = common::drivemap_fixture(&dir, &["check", "--strict", &file]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("0 unverified"), "{out}");
    let (code, out, err) = common::drivemap_fixture(
        &dir,
        &["demo", "--drive", id, "--time-scale", "50", "--step", "1"],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("then run forward") && out.contains("stop"),
        "{out}"
    );
    // Running (the operation status input) while it runs, back at 0 Hz after the stop.
    assert!(out.contains("running"), "{out}");
    let last = out
        .lines()
        .rev()
        .find(|l| l.split_whitespace().nth(1) == Some("s"))
        .unwrap_or_default();
    let numbers: Vec<f64> = last
        .split_whitespace()
        .skip(2)
        .filter_map(|t| t.parse().ok())
        .collect();
    assert_eq!(numbers.get(1), Some(&0.0), "{last}\n{out}");
    let (code, out, err) = common::drivemap_fixture(&dir, &["export", &file]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    let table = |id: &str| {
        json["registers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["id"] == id)
            .map(|r| r["table"].clone())
    };
    assert_eq!(table("operation_command"), Some("coil".into()));
    assert_eq!(table("operation_status"), Some("discrete_input".into()));
    assert_eq!(table("output_frequency_setting"), Some("holding".into()));
    assert_eq!(json["protocol"]["max_read_bits"], 32, "{out}");
    assert_eq!(json["protocol"]["max_write_bits"], 16, "{out}");
    assert_eq!(
        json["protocol"]["limits"]["max_read_bits"]["source"],
        "tindra-tc4.txt:15"
    );
    let (code, out, err) = common::drivemap_fixture(&dir, &["diff", &file, &file]);
    assert_eq!(code, 0, "{out}{err}");
}
