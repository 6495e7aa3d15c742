//! Dropping a YAML file into `maps/` adds a module to `drivemap-drives` with no other edit: a
//! throwaway application depends on the drives crate of a copy of the workspace with one new map
//! in `maps/`, and uses the new module by name. With one drive's feature, the crate has that
//! drive's module alone; the new map has no feature until a line in the drives crate's
//! `Cargo.toml` declares it (rustc warns until then), and then it is selected alone.

use drivemap_test_support::paths;

use std::path::Path;

use drivemap_tests::{workspace, workspace_with_map};

/// Builds and runs the application in `app` whose `drivemap-drives` dependency is `drives` with
/// `features` (Cargo's `default-features = false` when given) and whose `main` prints the module
/// `module`'s drive id and `DRIVES`; returns what it printed and what the build said.
fn run_app(app: &Path, drives: &Path, features: Option<&str>, module: &str) -> (String, String) {
    let drives = drives.display().to_string();
    let dependency = match features {
        None => format!("{{ path = {drives:?} }}"),
        Some("") => format!("{{ path = {drives:?}, default-features = false }}"),
        Some(f) => format!("{{ path = {drives:?}, default-features = false, features = [{f:?}] }}"),
    };
    std::fs::write(
        app.join("Cargo.toml"),
        format!(
            "[package]\nname = \"new-map-app\"\nversion = \"0.0.0\"\nedition = \"2024\"\n\n[workspace]\n\n[dependencies]\ndrivemap-drives = {dependency}\n"
        ),
    )
    .unwrap();
    std::fs::write(
        app.join("src/main.rs"),
        format!(
            "fn main() {{\n    let ids: Vec<&str> = drivemap_drives::DRIVES.iter().map(|(id, _)| *id).collect();\n    println!(\"{{}} {{}}\", drivemap_drives::{module}::PROFILE.drive_id, ids.join(\",\"));\n}}\n"
        ),
    )
    .unwrap();
    let out = drivemap_tests::nested_cargo()
        .args(["run", "--quiet", "--offline", "--manifest-path"])
        .arg(app.join("Cargo.toml"))
        .env(
            "DRIVEMAP_MANUALS",
            drivemap_test_support::cargo::nested_target().join("no-manuals"),
        )
        .output()
        .expect("cargo runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "build failed:\n{stderr}");
    (
        String::from_utf8_lossy(&out.stdout).trim().to_owned(),
        stderr,
    )
}

#[test]
fn a_new_yaml_file_becomes_a_module() {
    let root = workspace();
    let tmp = std::env::temp_dir().join(format!("drivemap-new-map-{}", std::process::id()));
    let app = drivemap_tests::app_dir(&tmp.join("app"));
    // The new drive: nothing else in the repository mentions it.
    let (_copy, copy) = workspace_with_map(&paths::fixture("crafted/maps/mini-drive.yaml"));
    let drives = copy.join("drives");

    let (stdout, said) = run_app(&app, &drives, None, "mini_drive");
    let mut words = stdout.split_whitespace();
    assert_eq!(words.next(), Some("mini-drive"));
    let ids: Vec<&str> = words.next().unwrap_or_default().split(',').collect();
    assert!(
        ids.contains(&"mini-drive") && ids.contains(&"ptlk-tds-v8"),
        "{ids:?}"
    );
    assert_eq!(
        ids.len(),
        drivemap_map::find_maps(&root.join("maps")).unwrap().len() + 1
    );
    // The new map has no feature (Cargo features are declared in Cargo.toml, never generated):
    // rustc says so, naming it.
    assert!(
        said.contains("unexpected `cfg` condition value: `mini-drive`")
            && said.contains("consider adding `mini-drive` as a feature in `Cargo.toml`"),
        "{said}"
    );

    // An application that enables one drive's feature gets that module alone.
    assert_eq!(
        run_app(&app, &drives, Some("yaskawa-v7"), "yaskawa_v7").0,
        "yaskawa-v7 yaskawa-v7",
        "only the V7 module is generated"
    );
    // With the line the warning asks for, an application selects the new map alone.
    let manifest = drives.join("Cargo.toml");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let declared = text.replace(
        "\nyaskawa-v7 = []\n",
        "\nyaskawa-v7 = []\nmini-drive = []\n",
    );
    assert_ne!(
        text, declared,
        "drives/Cargo.toml declares `yaskawa-v7 = []`"
    );
    std::fs::write(&manifest, declared).unwrap();
    let (stdout, said) = run_app(&app, &drives, Some("mini-drive"), "mini_drive");
    assert_eq!(
        stdout, "mini-drive mini-drive",
        "only the new module is generated"
    );
    assert!(!said.contains("unexpected `cfg`"), "{said}");
    std::fs::remove_dir_all(&tmp).unwrap();
}

/// A broken map in `maps/` fails the drives build with the diagnostics `drivemap check` prints
/// for it, every one of them at once (`file:line:col`, the register, the message), not a panic
/// or the first error alone.
#[test]
fn a_broken_map_fails_the_build_with_every_error_as_check_prints_it() {
    // Four errors in one file: decimal addresses in a register, an alternative, a command, a gap.
    let broken = paths::fixture("crafted/errors/e41-decimal-address.yaml");
    let (_copy, copy) = workspace_with_map(&broken);
    // As the build names it: through `drives/maps`, resolved.
    let map = copy
        .join("maps")
        .canonicalize()
        .unwrap()
        .join("e41-decimal-address.yaml");
    let expected = drivemap_map::Loader::new()
        .load(&map)
        .expect_err("the map is broken")
        .to_string();
    assert!(expected.ends_with("4 errors"), "{expected}");
    let out = drivemap_tests::nested_cargo()
        .args(["build", "--quiet", "--offline", "-p", "drivemap-drives"])
        .current_dir(&copy)
        .env(
            "DRIVEMAP_MANUALS",
            drivemap_test_support::cargo::nested_target().join("no-manuals"),
        )
        .output()
        .expect("cargo runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    for line in expected.lines() {
        assert!(stderr.contains(line), "missing `{line}` in:\n{stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
}
