//! Generates the modules of the fictional Tarrow TM-44 (`fixtures/tarrow-tm44`, a drive with
//! indexed access), Kestrel KD4 (`fixtures/kestrel-kd4`, a CiA 402 command profile) and Tindra
//! TC4 (`fixtures/tindra-tc4`, coils and discrete inputs) and Lumen LX2 (`fixtures/lumen-lx2`,
//! strings) into `OUT_DIR`, for `tests/cross_crate/indexed_generated.rs`,
//! `tests/cross_crate/drive_contract/command_profiles.rs`, `tests/cross_crate/coils.rs` and
//! `tests/cross_crate/strings.rs` to compile and use: the generated code of a fixture construct
//! is compiled with the current generator and runtime.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));
    for (id, module) in [
        ("tarrow-tm44", "tarrow_tm44"),
        ("kestrel-kd4", "kestrel_kd4"),
        ("tindra-tc4", "tindra_tc4"),
        ("lumen-lx2", "lumen_lx2"),
    ] {
        let dir = manifest.join("fixtures").join(id);
        println!("cargo:rerun-if-changed={}", dir.display());
        let code = drivemap_codegen::Config::new()
            .map(dir.join(format!("{id}.yaml")))
            .generate()
            .unwrap_or_else(|e| {
                eprintln!("generating {}: {e}", dir.display());
                std::process::exit(1);
            });
        let source = &code.modules[0].source;
        std::fs::write(out.join(format!("{module}.rs")), source).expect("OUT_DIR is writable");
    }
}
