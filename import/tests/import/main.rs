//! The integration tests of `drivemap-import` in one binary, a module per file
//! (`tests/import/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod fixtures;
mod seed_manuals;
