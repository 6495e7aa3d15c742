//! Generates the module of the fictional Tarrow TM-44 (`fixtures/tarrow-tm44`, a drive with
//! indexed access) into `OUT_DIR`, for `tests/indexed_generated.rs` to compile and use: the
//! generated code of a fixture construct is compiled with the current generator and runtime.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));
    let dir = manifest.join("fixtures/tarrow-tm44");
    println!("cargo:rerun-if-changed={}", dir.display());
    let code = drivemap_codegen::Config::new()
        .map(dir.join("tarrow-tm44.yaml"))
        .generate()
        .unwrap_or_else(|e| {
            eprintln!("generating {}: {e}", dir.display());
            std::process::exit(1);
        });
    let source = &code.modules[0].source;
    std::fs::write(out.join("tarrow_tm44.rs"), source).expect("OUT_DIR is writable");
}
