//! The generated code of a drive with indexed access (the fictional Tarrow TM-44,
//! `tests/fixtures/tarrow-tm44`: index in register 44, value in 45) gives each listed entry a
//! typed handle (`entries::ACCELERATION_TIME`, a `const EntryRef`) that the client reads and
//! writes in one call against the simulated drive. The module is generated into
//! `tests/generated/tarrow_tm44.rs` and compiled here; `generated_module_is_current` fails when
//! it is stale (`DRIVEMAP_BLESS=1` rewrites it).

use std::path::Path;
use std::time::Duration;

use drivemap_map::validate::Context;
use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::profile::TransportKind;
use drivemap_sim::{SimOptions, Simulator};
use drivemap_test_support::sim_link::SimLink;

#[allow(dead_code)]
mod tarrow_tm44 {
    include!("generated/tarrow_tm44.rs");
}

fn fixture() -> std::path::PathBuf {
    drivemap_tests::workspace().join("tests/fixtures/tarrow-tm44")
}

#[test]
fn generated_module_is_current() {
    let code = drivemap_codegen::Config::new()
        .map(fixture().join("tarrow-tm44.yaml"))
        .generate()
        .unwrap_or_else(|e| panic!("{e}"))
        .modules
        .remove(0)
        .source;
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/generated/tarrow_tm44.rs");
    if std::env::var_os("DRIVEMAP_BLESS").is_some() {
        std::fs::write(&file, &code).unwrap();
    }
    let current = std::fs::read_to_string(&file).unwrap_or_default();
    assert!(
        current == code,
        "{} is stale: regenerate with DRIVEMAP_BLESS=1 cargo test -p drivemap-tests --test indexed_generated",
        file.display()
    );
    // Every listed entry has its handle, documented with its index, pair and citation.
    assert!(
        code.contains("pub const ACCELERATION_TIME: rt::core::indexed::EntryRef"),
        "{code}"
    );
    assert!(code.contains("Acceleration time (index 1 of `parameter_value` through `parameter_index`, s; read/write)"), "{code}");
}

#[test]
fn a_typed_entry_handle_reads_and_writes_through_the_client() {
    use tarrow_tm44::entries;
    assert_eq!(entries::MAXIMUM_FREQUENCY.entry.index, 3);
    assert_eq!(entries::MAXIMUM_FREQUENCY.pair.index_address, 44);
    assert_eq!(tarrow_tm44::INDEXED.len(), 1);
    let drive = drivemap_map::read_map(
        &fixture().join("tarrow-tm44.yaml"),
        &Context::with_manuals(&fixture().join("manuals")),
    )
    .unwrap_or_else(|d| panic!("{d}"));
    // The generated data is the plan the map lowers to.
    assert_eq!(tarrow_tm44::INDEXED, drive.plan().indexed);
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let options = ClientOptions {
        timeout: Duration::from_millis(50),
        retries: 0,
        ..ClientOptions::default()
    };
    let mut c = Client::with_options(
        SimLink::new(TransportKind::Rtu, sim),
        &tarrow_tm44::PROFILE,
        options,
    );
    c.write_entry(1, entries::MAXIMUM_FREQUENCY, 55.5).unwrap();
    c.write_entry(1, entries::ACCELERATION_TIME, 3.5).unwrap();
    assert_eq!(c.read_entry(1, entries::MAXIMUM_FREQUENCY).unwrap(), 55.5);
    assert_eq!(c.read_entry(1, entries::ACCELERATION_TIME).unwrap(), 3.5);
    let e = c
        .write_entry(1, entries::TOTAL_RUNNING_HOURS, 1.0)
        .unwrap_err();
    assert!(e.is_refusal(), "{e}");
}
