//! The run-time crates read maps through the map front end (`drivemap-map`) alone: none of them
//! links the code generator (`drivemap-codegen`) or its printing libraries (`syn`, `quote`,
//! `proc-macro2`, `prettyplease`). `serde` and `thiserror` derive through `syn` at compile
//! time, as procedural macros; what a crate links is its tree without proc-macro edges.

use drivemap_test_support::paths;

use std::process::Command;

/// Crate names in `cargo tree -p <package> -e <edges>` of the workspace, one per line.
fn tree(package: &str, edges: &str) -> Vec<String> {
    let manifest = paths::workspace().join("Cargo.toml");
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "--offline",
            "--locked",
            "--prefix",
            "none",
            "--format",
            "{p}",
        ])
        .args(["-e", edges, "-p", package, "--manifest-path"])
        .arg(&manifest)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .expect("cargo tree prints UTF-8")
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_owned))
        .collect()
}

const RUN_TIME: &[&str] = &[
    "drivemap-runtime",
    "drivemap-live",
    "drivemap-sim",
    "drivemap-drives",
    "drivemap-bridge",
    "drivemap-import",
    "drivemap",
];

#[test]
fn run_time_crates_do_not_link_the_generator() {
    let mut found = Vec::new();
    for package in RUN_TIME {
        let linked = tree(package, "normal,no-proc-macro");
        assert!(
            linked.iter().any(|c| c == package),
            "cargo tree -p {package} does not list the package itself: {linked:?}"
        );
        for c in &linked {
            if [
                "syn",
                "quote",
                "proc-macro2",
                "prettyplease",
                "drivemap-codegen",
            ]
            .contains(&c.as_str())
            {
                found.push(format!("{package} links {c}"));
            }
        }
        // With procedural macros counted, the generator and its printer are still absent.
        for c in tree(package, "normal") {
            if c == "prettyplease" || c == "drivemap-codegen" {
                found.push(format!("{package} depends on {c}"));
            }
        }
    }
    assert!(found.is_empty(), "{found:#?}");
}

/// The map front end itself has no generator in it; the generator does (the check above is not
/// vacuous).
#[test]
fn the_front_end_has_no_generator_and_the_generator_has() {
    let front = tree("drivemap-map", "normal,no-proc-macro");
    for c in ["syn", "quote", "prettyplease", "drivemap-codegen"] {
        assert!(!front.iter().any(|x| x == c), "drivemap-map links {c}");
    }
    let generator = tree("drivemap-codegen", "normal,no-proc-macro");
    for c in ["syn", "quote", "prettyplease", "drivemap-map"] {
        assert!(
            generator.iter().any(|x| x == c),
            "drivemap-codegen lacks {c}"
        );
    }
}
