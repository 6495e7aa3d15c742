//! The integration tests of `drivemap-codegen` in one binary, a module per file
//! (`tests/codegen/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod field_selector;
mod generated;
mod line_width;
mod protocol;
mod roles_in_fields;
