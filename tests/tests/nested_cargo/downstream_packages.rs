//! A downstream application built only from the packaged crates: `cargo package --workspace`
//! (run by `scripts/test` before the tests) leaves `target/package/*.crate`; this test unpacks
//! them into a directory outside the workspace, writes an application whose `Cargo.toml` asks
//! for `drivemap-drives` (the V7 alone) and `drivemap-runtime` (tokio) by version from
//! crates.io, with `[patch.crates-io]` pointing at the unpacked packages, builds it offline and
//! runs it against a simulated V7: it writes the frequency reference and runs the drive through
//! the async drive trait (`AsyncVfd`), polls, stops, and reads the reference back. Then it
//! checks every package, libraries and binaries, as one workspace of the unpacked tarballs:
//! `scripts/test` packages with `--no-verify` and leaves that verification to this test (one
//! `cargo check`, in the workspace's target directory with its profiles, instead of one build
//! per package). A check runs every build script and reads every source and `include_str!`
//! file of the tarball, which is what a package can lack; the code generation and linking a
//! build adds cannot fail for what a tarball holds (and the application above is built and
//! run).
//!
//! The application's source is `examples/async-poll/src/main.rs`, copied: the example of the
//! repository is what a user would write. `drivemap-drives` generates its module from the
//! maps its package carries (`drives/maps` links to `maps/`), so this also proves the packaged
//! crate builds from its tarball alone.

use drivemap_test_support::paths;

use std::path::PathBuf;
use std::process::Command;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_sim::server::{TcpFraming, TcpServer};
use drivemap_sim::{SimOptions, Simulator};

fn root() -> PathBuf {
    paths::workspace().to_path_buf()
}

const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The packages the application needs, directly or through another.
const NEEDED: [&str; 5] = [
    "drivemap-core",
    "drivemap-map",
    "drivemap-codegen",
    "drivemap-runtime",
    "drivemap-drives",
];

/// Runs `cmd`, failing the test with its output unless it succeeds.
fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{stdout}{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn an_application_built_only_from_the_packages_drives_the_simulator() {
    let _nested = drivemap_tests::hold_nested_target();
    let packages = root().join("target").join("package");
    for name in NEEDED {
        let file = packages.join(format!("{name}-{VERSION}.crate"));
        assert!(
            file.is_file(),
            "{} is missing: run `cargo package --workspace` first (scripts/test does)",
            file.display()
        );
    }
    // Outside the workspace: nothing of the repository is reachable from there but the
    // unpacked packages.
    let dir = std::env::temp_dir().join(format!("drivemap-downstream-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("packages")).unwrap();
    std::fs::create_dir_all(dir.join("app").join("src")).unwrap();
    let mut patches = String::new();
    let mut members = Vec::new();
    for entry in std::fs::read_dir(&packages).unwrap() {
        let path = entry.unwrap().path();
        let Some(file) = path.file_name().and_then(|f| f.to_str()) else {
            continue;
        };
        let Some(stem) = file.strip_suffix(".crate") else {
            continue;
        };
        run(
            Command::new("tar")
                .arg("xzf")
                .arg(&path)
                .arg("-C")
                .arg(dir.join("packages")),
            &format!("unpacking {file}"),
        );
        let name = stem
            .strip_suffix(&format!("-{VERSION}"))
            .expect("a package of this version");
        patches += &format!("{name} = {{ path = \"../packages/{stem}\" }}\n");
        members.push(stem.to_owned());
    }
    members.sort();
    let missing: Vec<&str> = NEEDED
        .iter()
        .copied()
        .filter(|name| !members.contains(&format!("{name}-{VERSION}")))
        .collect();
    assert!(missing.is_empty(), "not packaged: {missing:?}");
    // The packaged drives crate carries the maps, the same as maps/.
    let packaged = dir
        .join("packages")
        .join(format!("drivemap-drives-{VERSION}"))
        .join("maps")
        .join("yaskawa-v7.yaml");
    assert_eq!(
        std::fs::read_to_string(&packaged).expect("drivemap-drives carries maps/yaskawa-v7.yaml"),
        std::fs::read_to_string(paths::maps().join("yaskawa-v7.yaml")).unwrap(),
        "the packaged map differs from maps/: run `cargo package --workspace` again"
    );
    let manifest = format!(
        r#"[package]
name = "plant-app"
version = "0.1.0"
edition = "2024"
publish = false

[dependencies]
drivemap-drives = {{ version = "{VERSION}", default-features = false, features = ["yaskawa-v7"] }}
drivemap-runtime = {{ version = "{VERSION}", features = ["tokio"] }}
tokio = {{ version = "1", features = ["rt", "macros", "time", "net"] }}

[patch.crates-io]
{patches}"#
    );
    std::fs::write(dir.join("app").join("Cargo.toml"), manifest).unwrap();
    std::fs::copy(
        root().join("examples/async-poll/src/main.rs"),
        dir.join("app").join("src").join("main.rs"),
    )
    .unwrap();
    // The example's crate docs are its README (`#![doc = include_str!("../README.md")]`).
    std::fs::copy(
        root().join("examples/async-poll/README.md"),
        dir.join("app").join("README.md"),
    )
    .unwrap();
    // The workspace's lock file: the same versions of the registry crates, all in the local
    // cache, so the build needs no network.
    std::fs::copy(
        root().join("Cargo.lock"),
        dir.join("app").join("Cargo.lock"),
    )
    .unwrap();
    // Where the nested builds put their programs (`nested_target`).
    let target = drivemap_test_support::cargo::nested_target();
    run(
        drivemap_tests::nested_cargo()
            .args(["build", "--offline", "--quiet"])
            .current_dir(dir.join("app")),
        "cargo build of the downstream application",
    );

    // Every published package compiles from its tarball alone, library and binaries (what
    // `cargo package`'s verification would find missing, which `scripts/test` leaves to this
    // test: `--no-verify`): the unpacked packages as one workspace, patched to each other.
    let quoted: Vec<String> = members.iter().map(|m| format!("\"{m}\"")).collect();
    std::fs::write(
        dir.join("packages").join("Cargo.toml"),
        format!(
            "[workspace]\nresolver = \"3\"\nmembers = [{}]\n\n[patch.crates-io]\n{}",
            quoted.join(", "),
            patches.replace("../packages/", "")
        ),
    )
    .unwrap();
    std::fs::copy(
        root().join("Cargo.lock"),
        dir.join("packages").join("Cargo.lock"),
    )
    .unwrap();
    run(
        drivemap_tests::nested_cargo()
            .args(["check", "--workspace", "--offline", "--quiet"])
            .current_dir(dir.join("packages")),
        "cargo check of every package from its tarball",
    );

    let path = paths::maps().join("yaskawa-v7.yaml");
    let v7 = drivemap_map::Loader::new()
        .load(&path)
        .expect("shipped map");
    let sim = Simulator::new(v7, SimOptions::new().network_source(TransportKind::Tcp)).unwrap();
    let sim = drivemap_sim::server::shared(sim);
    let server = TcpServer::spawn(sim.clone(), "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
    let addr = server.local_addr().to_string();
    let stdout = run(
        Command::new(target.join("debug").join("plant-app")).args([
            addr.as_str(),
            "1",
            "42.5",
            "3",
        ]),
        "the downstream application",
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 4, "{stdout}");
    assert!(lines[0].starts_with("poll 1: output "), "{stdout}");
    // Read back from the drive: the reference written.
    assert_eq!(lines[3], "stopped; reference 42.5 Hz", "{stdout}");
    let state = drivemap_sim::server::lock(&sim)
        .state()
        .expect("a drive model");
    assert_eq!(state.reference_hz, 42.5);
    assert!(!state.run_command, "the application stopped the drive");
    server.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
