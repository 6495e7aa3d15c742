//! The tests that run cargo themselves: trybuild compiles the illegal accesses of
//! `compile-fail/`. Not in the default `cargo test` (`test = false` in Cargo.toml): `scripts/test`
//! runs them once, with the same binaries of the tests and cli crates:
//! `cargo test --workspace --all-features --test nested_cargo`.

mod compile_fail;
