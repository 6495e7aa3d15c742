//! The integration tests of `drivemap-tests` in one binary, a module per file
//! (`tests/cross_crate/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.
//! The tests that run cargo themselves are in `tests/nested_cargo/` (`test = false`), which
//! `scripts/test` runs once: `cargo test --workspace --all-features --test nested_cargo`.

mod support;
use support::interop_support;

mod acn_address_columns;
mod automationdirect_acn;
mod coils;
mod drive_contract;
mod drive_trait;
mod every_construct;
mod function_codes;
mod generated_enumerations;
mod generated_examples;
mod indexed_generated;
mod interop_client;
mod interop_masters;
mod interop_typed;
mod line_poll;
mod line_timing;
mod not_printed;
mod plan_agreement;
mod roles_in_fields;
mod scale_kinds;
mod strings;
mod tds_v8;
mod transports;
mod yaskawa_gpd515;
mod yaskawa_v7;
