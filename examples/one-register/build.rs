//! One map, generated into OUT_DIR.

// As in `src/main.rs`: every `unused` lint an error.
#![deny(unused)]

fn main() -> Result<(), Box<dyn std::error::Error>> {
    drivemap_codegen::Config::new()
        .map("../../maps/yaskawa-v7.yaml")
        .compile()?;
    Ok(())
}
