//! The tests that run cargo themselves: `cargo install` of the tool into an empty root, then the
//! bench tasks as a new user runs them. Not in the default `cargo test` (`test = false` in
//! Cargo.toml): `scripts/test` runs them once, with the same binaries of the tests and
//! custom-drive crates: `cargo test --workspace --all-features --test nested_cargo`.

mod bench;
