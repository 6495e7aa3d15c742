//! The integration tests of `drivemap-map` in one binary, a module per file
//! (`tests/map/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod citation_places;
mod facts;
mod facts_data;
mod indexed;
mod not_printed;
mod read_param;
mod register_index;
mod roles;
mod selected_limits;
mod serial_defaults;
mod ui;
mod untrusted;
mod variants;
