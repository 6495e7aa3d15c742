//! The integration tests of `drivemap-live` in one binary, a module per file
//! (`tests/live/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod example_frames;
mod ratio_reference;
mod read_by_name;
mod selected_limits;
