//! The integration tests of `drivemap-runtime` in one binary, a module per file
//! (`tests/runtime/<module>.rs`), as cargo and ripgrep do: the dependency tree is linked
//! once, not once per test file.

mod support;
use support::common;

mod async_client;
mod client;
mod coils;
mod faults;
mod gate;
mod guarantees_tcp;
mod hostile_peer;
mod indexed_async;
mod late_replies;
mod links;
mod manual_frames;
mod planner_alloc;
mod planner_exhaustive;
mod planner_functions;
mod planner_poller;
mod roundtrip;
mod serial_pty;
