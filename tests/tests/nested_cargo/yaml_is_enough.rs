//! A new drive is a YAML file and nothing else. With a copy of the workspace whose `maps/` holds
//! the map of a fictional drive (`tests/fixtures/acme-vf1/`: a 2-bit run/stop code, a 2-bit direction code, an operating
//! state reported as codes, an edge-triggered reset, a drive-specific exception code) and no
//! other edit:
//!
//! - `drivemap check --require-manuals` passes on the new map;
//! - the `drivemap` tool built with it has the generated module and its drive trait, and
//!   `drivemap demo --drive acme-vf1` completes through them;
//! - `drivemap simulate` runs its drive model, and an application written once against the drive
//!   trait (`tests/fixtures/any-drive-app/main.rs`, which names no register and no drive) ramps
//!   it to the reference and stops it.
//!
//! Builds share the workspace's target directory and the copy of the workspace with
//! `new_map_becomes_module.rs` (`drivemap_tests::workspace_with_map`, `nested_cargo`).

use drivemap_test_support::paths;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use drivemap_tests::workspace;

fn fixture() -> PathBuf {
    paths::fixture("acme-vf1")
}

fn target() -> PathBuf {
    drivemap_test_support::cargo::nested_target()
}

fn cargo(args: &[&str], workspace: &Path) -> std::process::Output {
    drivemap_tests::nested_cargo()
        .args(args)
        .current_dir(workspace)
        .env("DRIVEMAP_MANUALS", fixture().join("manuals"))
        .output()
        .expect("cargo runs")
}

fn ok(out: &std::process::Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Stops the child process when dropped, so a failing assertion leaves no simulator behind.
struct Child(std::process::Child);

impl Drop for Child {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn a_drive_of_another_vendor_needs_only_its_yaml() {
    let root = workspace();
    let tmp = target().join(format!("yaml-is-enough-{}", std::process::id()));
    let app = drivemap_tests::app_dir(&tmp.join("app"));
    let (_copy, copy) = drivemap_tests::workspace_with_map(&fixture().join("acme-vf1.yaml"));
    // The maps of the copy: the shipped ones and the new one.
    let maps = copy.join("maps");

    // The workspace's own tool, which other tests run while this one builds: the copy's build
    // leaves it alone (its programs go to `target/nested`).
    let ours = drivemap_test_support::cargo::workspace_build_dir().join("debug/drivemap");
    let stamp = |p: &Path| {
        std::fs::metadata(p)
            .ok()
            .map(|m| (m.len(), m.modified().ok()))
    };
    let ours_before = stamp(&ours);

    // The tool, built with the new map among its drives.
    ok(
        &cargo(
            &[
                "build",
                "--quiet",
                "--offline",
                "-p",
                "drivemap",
                "--bin",
                "drivemap",
            ],
            &copy,
        ),
        "building drivemap with the new map",
    );
    let drivemap = target().join("debug/drivemap");
    assert_ne!(drivemap, ours);
    assert_eq!(
        stamp(&ours),
        ours_before,
        "building the copy's tool rewrote {}",
        ours.display()
    );
    let tool = |args: &[&str]| {
        Command::new(&drivemap)
            .args(args)
            .env("DRIVEMAP_MAPS", &maps)
            .env("DRIVEMAP_MANUALS", fixture().join("manuals"))
            .output()
            .expect("drivemap runs")
    };

    let checked = ok(
        &tool(&[
            "check",
            "--require-manuals",
            maps.join("acme-vf1.yaml").to_str().unwrap(),
        ]),
        "drivemap check",
    );
    assert!(
        checked.contains("ok") && checked.contains("acme-vf1"),
        "{checked}"
    );

    let demo = ok(
        &tool(&[
            "demo",
            "--drive",
            "acme-vf1",
            "--time-scale",
            "50",
            "--reverse",
        ]),
        "drivemap demo",
    );
    assert!(
        demo.contains("drivemap_drives::acme_vf1 (the generated module)"),
        "{demo}"
    );
    // The simulated drive starts at its factory setting (run source: keypad), where it would
    // ignore the demo's run: the demo selects the network first and says so.
    assert!(
        demo.contains(
            "set at the simulated drive first (its factory setting ignores network commands): \
             run_command_source = 2 (\"RS-485 (Modbus RTU)\"), frequency_reference_source = 2 (\"RS-485 (Modbus RTU)\")"
        ),
        "{demo}"
    );
    assert!(
        demo.contains("running reversing ready accelerating"),
        "{demo}"
    );
    assert!(demo.contains("stopping"), "{demo}");
    let last = demo
        .lines()
        .rev()
        .find(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .unwrap();
    assert!(
        last.contains(" 0.00 "),
        "the demo ends at 0 Hz: {last}\n{demo}"
    );

    // The simulator of the new drive, and the generic application against it.
    let mut sim = Child(
        Command::new(&drivemap)
            .args([
                "simulate",
                "--drive",
                "acme-vf1",
                "--tcp",
                "127.0.0.1:0",
                "--time-scale",
                "10",
                "--quiet",
                // Installed for network control: the Ethernet option selected as the source.
                "--network-source",
            ])
            .env("DRIVEMAP_MAPS", &maps)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("drivemap simulate starts"),
    );
    let mut line = String::new();
    BufReader::new(sim.0.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(line.contains("drive model on"), "{line}");
    let addr = line
        .split_whitespace()
        .find(|w| w.starts_with("127.0.0.1:"))
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_owned();

    std::fs::copy(
        root.join("tests/fixtures/any-drive-app/main.rs"),
        app.join("src/main.rs"),
    )
    .unwrap();
    std::fs::write(
        app.join("Cargo.toml"),
        format!(
            "[package]\nname = \"any-drive-app\"\nversion = \"0.0.0\"\nedition = \"2024\"\n\n[workspace]\n\n\
             [dependencies]\ndrivemap-drives = {{ path = {:?} }}\ndrivemap-runtime = {{ path = {:?} }}\n",
            copy.join("drives").display().to_string(),
            copy.join("runtime").display().to_string()
        ),
    )
    .unwrap();
    let out = cargo(
        &[
            "run",
            "--quiet",
            "--offline",
            "--manifest-path",
            app.join("Cargo.toml").to_str().unwrap(),
            "--",
            "acme-vf1",
            &addr,
        ],
        &copy,
    );
    let said = ok(&out, "the generic application");
    assert!(said.contains("at reference 30.00 Hz"), "{said}");
    assert!(said.contains("stopped, status ready"), "{said}");
    let _ = std::fs::remove_dir_all(&tmp);
}
