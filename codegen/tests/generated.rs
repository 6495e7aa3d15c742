//! Golden output: the generated module and the export of a small map using every construct.

use std::path::Path;

use drivemap_codegen::generate::{Options, drive_module};
use drivemap_codegen::validate::Context;

fn fixture() -> drivemap_codegen::Drive {
    drivemap_codegen::read_map(
        Path::new("tests/fixtures/mini-drive.yaml"),
        &Context::default(),
    )
    .unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn generated_module_snapshot() {
    let drive = fixture();
    let options = Options {
        runtime: "::drivemap_runtime".parse().unwrap(),
        source_name: "mini-drive.yaml".into(),
    };
    let code = drive_module(&drive, &options).unwrap();
    assert!(code.starts_with("// @generated"));
    insta::assert_snapshot!("mini_drive_module", code);
}

#[test]
fn export_snapshot() {
    let drive = fixture();
    let json = serde_json::to_string_pretty(&drivemap_codegen::export::export(&drive)).unwrap();
    insta::assert_snapshot!("mini_drive_export", json);
}

#[test]
fn config_writes_only_when_changed() {
    let out = std::env::temp_dir().join(format!("drivemap-config-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let mut config = drivemap_codegen::Config::new();
    config
        .map("tests/fixtures/mini-drive.yaml")
        .out_dir(&out)
        .cargo_directives(false);
    let first = config.compile().unwrap();
    assert_eq!(
        first.written.len(),
        2,
        "module and index written on the first run"
    );
    assert!(first.index.is_file());
    let index = std::fs::read_to_string(&first.index).unwrap();
    // The module is included by a path relative to the index, so the pair works from any
    // directory (OUT_DIR or a path of the user's choosing), and no absolute path is baked in.
    assert!(
        index.contains("pub mod mini_drive {\n    include!(\"mini_drive.rs\");\n}"),
        "{index}"
    );
    assert!(!index.contains(&*out.to_string_lossy()), "{index}");
    assert!(
        index.contains("#[doc = \" Example MD-1 — register map `mini-drive`.\"]"),
        "{index}"
    );
    let second = config.compile().unwrap();
    assert!(
        second.written.is_empty(),
        "nothing rewritten when nothing changed: {:?}",
        second.written
    );
    std::fs::remove_dir_all(&out).unwrap();
}

/// Rustdoc search finds a register by the manual's own words: `#[doc(alias)]` on its type for
/// its id, its parameter number and its address as the manual prints it (hex with its marker, or
/// the register number of a manual numbering registers in decimal).
#[test]
fn rustdoc_search_finds_a_register_by_the_manuals_words() {
    let module = |path: &str| {
        let drive = drivemap_codegen::read_map(Path::new(path), &Context::default())
            .unwrap_or_else(|d| panic!("{d}"));
        let options = Options {
            runtime: "::drivemap_runtime".parse().unwrap(),
            source_name: "x.yaml".into(),
        };
        drive_module(&drive, &options).unwrap()
    };
    let tds = module("../maps/ptlk-tds-v8.yaml");
    assert!(
        tds.contains(
            "#[doc(alias = \"max_output_frequency\")]\n#[doc(alias = \"Cn-02\")]\n#[doc(alias = \"0301H\")]\n#[doc(alias = \"0x0301\")]\npub type MaxOutputFrequency ="
        ),
        "{}",
        &tds[tds.find("pub type MaxOutputFrequency").unwrap_or(0).saturating_sub(400)..][..600]
    );
    let z3 = module("../tests/fixtures/zenith-z3/zenith-z3.yaml");
    assert!(
        z3.contains(
            "#[doc(alias = \"acceleration_time\")]\n#[doc(alias = \"P-01\")]\n#[doc(alias = \"45\")]\npub type AccelerationTime ="
        ),
        "{z3}"
    );
}
