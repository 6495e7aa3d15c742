//! The integration tests of `drivemap-sim` in one binary, a module per file
//! (`tests/sim/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod coils;
mod example_frames;
mod indexed_faults;
mod indexed_sim;
mod limits;
mod line;
mod request_alloc;
mod rules;
mod server_limits;
