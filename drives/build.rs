//! Generates one module per `maps/*.yaml` (or `$DRIVEMAP_MAPS_DIR/*.yaml`).

fn main() {
    let dir = std::env::var("DRIVEMAP_MAPS_DIR").unwrap_or_else(|_| {
        let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
        format!("{manifest}/../maps")
    });
    println!("cargo:rerun-if-env-changed=DRIVEMAP_MAPS_DIR");
    if let Err(e) = drivemap_codegen::Config::new().maps_dir(&dir).compile() {
        eprintln!("{e}");
        std::process::exit(1);
    }
}
