//! The integration tests of `custom-drive` in one binary, a module per file
//! (`tests/custom_drive/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.
//! The tests that run cargo themselves are in `tests/nested_cargo/` (`test = false`), which
//! `scripts/test` runs once beside the other tests (alone: `cargo test --workspace --all-features
//! --test nested_cargo`).

mod field_selector;
mod generated_api;
mod live_agrees;
mod pairs;
mod ratio_drive;
