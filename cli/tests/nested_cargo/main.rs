//! The tests that run cargo themselves: `cargo install` of the tool into an empty root, then the
//! bench tasks as a new user runs them. Not in the default `cargo test` (`test = false` in
//! Cargo.toml):
//! `scripts/test` runs them once, beside the other tests; alone:
//! `cargo nextest run --workspace --all-features --test nested_cargo` (`.config/nextest.toml`
//! runs the ones that build in the workspace's build directory one at a time; `cargo test` with
//! the same arguments runs them too).

mod bench;
