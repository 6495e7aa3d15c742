//! A downstream crate's build script: its own map, generated into OUT_DIR.
//!
//! The map is the codegen's golden fixture, which uses every construct of the schema, so this
//! crate also proves that everything the generator can emit compiles. The second map selects
//! scales by a field of a status word (`selected_by: <register>.<field>`); the third, the
//! fictional drive of `tests/fixtures/acme-vf1`, has 32-bit values in two registers; the fourth,
//! `tests/fixtures/borealis-bf6`, scales its frequencies by a ratio (60.0 Hz = 3600).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A map with an error: `?` prints the report `drivemap check` prints, file:line:col.
    drivemap_codegen::Config::new()
        .map("../../tests/fixtures/crafted/maps/mini-drive.yaml")
        .map("../../tests/fixtures/crafted/maps/field-selector.yaml")
        .map("../../tests/fixtures/acme-vf1/acme-vf1.yaml")
        .map("../../tests/fixtures/borealis-bf6/borealis-bf6.yaml")
        .compile()?;
    Ok(())
}
