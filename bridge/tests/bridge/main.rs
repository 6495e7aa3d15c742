//! The integration tests of `drivemap-bridge` in one binary, a module per file
//! (`tests/bridge/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod bounded;
mod errors;
