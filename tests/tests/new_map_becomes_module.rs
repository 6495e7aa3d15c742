//! Dropping a YAML file into the maps directory adds a module to `drivemap-drives` with no other
//! edit: a throwaway application depends on the drives crate, built against a copy of `maps/`
//! plus one new map, and uses the new module by name. With one drive's feature, the crate has that
//! drive's module alone; with `DRIVEMAP_DRIVES=<id>`, the new drive's module alone.

use std::path::Path;
use std::process::Command;

use drivemap_tests::workspace;

/// Builds and runs the application in `app` whose `drivemap-drives` dependency has `features`
/// (Cargo's `default-features = false` when given) and whose `main` prints the module `module`'s
/// drive id and `DRIVES`; returns what it printed.
fn run_app(
    app: &Path,
    maps: &Path,
    features: Option<&str>,
    selected: Option<&str>,
    module: &str,
) -> String {
    let root = workspace();
    let drives = root.join("drives").display().to_string();
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
    let mut cargo = Command::new(env!("CARGO"));
    match selected {
        Some(ids) => cargo.env("DRIVEMAP_DRIVES", ids),
        None => cargo.env_remove("DRIVEMAP_DRIVES"),
    };
    let out = cargo
        .args(["run", "--quiet", "--offline", "--manifest-path"])
        .arg(app.join("Cargo.toml"))
        .env("DRIVEMAP_MAPS", maps)
        .env("CARGO_TARGET_DIR", root.join("target/new-map-probe"))
        .env(
            "DRIVEMAP_MANUALS",
            root.join("target/new-map-probe/no-manuals"),
        )
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "build failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_owned()
}

#[test]
fn a_new_yaml_file_becomes_a_module() {
    let root = workspace();
    let tmp = std::env::temp_dir().join(format!("drivemap-new-map-{}", std::process::id()));
    // The new drive: nothing else in the repository mentions it.
    let (maps, app) =
        drivemap_tests::maps_and_app(&tmp, &root.join("map/tests/fixtures/mini-drive.yaml"));

    let stdout = run_app(&app, &maps, None, None, "mini_drive");
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

    // An application that enables one drive's feature gets that module alone.
    assert_eq!(
        run_app(&app, &maps, Some("yaskawa-v7"), None, "yaskawa_v7"),
        "yaskawa-v7 yaskawa-v7",
        "only the V7 module is generated"
    );
    // The new map has no feature (Cargo features are declared in Cargo.toml), but an
    // application selects it alone by id, with no edit of the drives crate.
    assert_eq!(
        run_app(&app, &maps, Some(""), Some("mini-drive"), "mini_drive"),
        "mini-drive mini-drive",
        "only the new module is generated"
    );
    std::fs::remove_dir_all(&tmp).unwrap();
}

/// A broken map in the maps directory fails the drives build with the diagnostics
/// `drivemap check` prints for it, every one of them at once (`file:line:col`, the register, the
/// message), not a panic or the first error alone.
#[test]
fn a_broken_map_fails_the_build_with_every_error_as_check_prints_it() {
    let root = workspace();
    let tmp = std::env::temp_dir().join(format!("drivemap-broken-map-{}", std::process::id()));
    // Four errors in one file: decimal addresses in a register, an alternative, a command, a gap.
    let broken = root.join("map/tests/ui/e41-decimal-address.yaml");
    let (maps, _) = drivemap_tests::maps_and_app(&tmp, &broken);
    let map = maps.join("e41-decimal-address.yaml");
    let expected = drivemap_map::Loader::new()
        .load(&map)
        .expect_err("the map is broken")
        .to_string();
    assert!(expected.ends_with("4 errors"), "{expected}");
    let out = Command::new(env!("CARGO"))
        .args(["build", "--quiet", "--offline", "-p", "drivemap-drives"])
        .current_dir(&root)
        .env("DRIVEMAP_MAPS", &maps)
        .env_remove("DRIVEMAP_DRIVES")
        .env("CARGO_TARGET_DIR", root.join("target/new-map-probe"))
        .env(
            "DRIVEMAP_MANUALS",
            root.join("target/new-map-probe/no-manuals"),
        )
        .output()
        .expect("cargo runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    for line in expected.lines() {
        assert!(stderr.contains(line), "missing `{line}` in:\n{stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    std::fs::remove_dir_all(&tmp).unwrap();
}
