//! The integration tests of `drivemap-review` in one binary, a module per file
//! (`tests/review/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod coils_diff;
mod diff_roles_in_fields;
mod diff_sees_every_change;
mod indexed_diff;
mod not_printed_diff;
mod notation;
mod ratio_diff;
mod read_and_repeat;
