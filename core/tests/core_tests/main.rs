//! The integration tests of `drivemap-core` in one binary, a module per file
//! (`tests/core_tests/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod exact_values;
mod generated_shapes;
mod ratio_exact;
mod text;
mod value_shape;
