//! The tests that run cargo themselves: `cargo build` of a copy of the workspace with a new map
//! and of an application built from the packaged crates, `cargo tree` and `cargo metadata` of the
//! workspace. Slow and holding cargo's locks, they are not in the default `cargo test` (`test =
//! false` in Cargo.toml): `scripts/test` runs them once, beside the other tests, with the same
//! binaries of the cli and custom-drive crates; alone:
//! `cargo nextest run --workspace --all-features --test nested_cargo` (`.config/nextest.toml`
//! runs the ones that build in the workspace's build directory one at a time; `cargo test`
//! with the same arguments runs them too).

mod crate_graph;
mod downstream_packages;
mod new_map_becomes_module;
mod workspace_lints;
mod yaml_is_enough;
