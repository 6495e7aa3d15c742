//! The integration tests of `drivemap` in one binary, a module per file
//! (`tests/cli/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.
//! The tests that run cargo themselves are in `tests/nested_cargo/` (`test = false`), which
//! `scripts/test` runs once beside the other tests (alone: `cargo test --workspace --all-features
//! --test nested_cargo`).

mod support;
use support::{bridge_support, common, new_map};

mod arguments;
mod bico;
mod bridge;
mod build_errors;
mod decimal_manual;
mod diff;
mod doc;
mod example_frames;
mod export_facts;
mod export_formats;
mod export_node_red;
mod fail_fast;
mod gateway;
mod hostile_peer;
mod import;
mod indexed_entries;
mod line;
mod line_speed;
mod live;
mod machine_output;
mod modicon_column;
mod not_printed;
mod probe_sim;
mod ratio_scale;
mod review;
mod schema;
mod selected_range;
mod strings;
mod values;
mod write_gate;
