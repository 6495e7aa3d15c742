//! A drive map at run time, for tools that load YAML instead of compiling it: the simulator,
//! the `drivemap read/write/poll` commands, and any program that talks to a drive by register
//! name ([`session::Session`] over a [`link::Link`]; `examples/read_by_name.rs`).
//!
//! The generated modules and this crate agree by construction: both read the same plan of a
//! validated map ([`drivemap_map::Map::plan`]) and convert with the same functions of
//! [`drivemap_runtime::core::scale`]; a test in `tests/` compares them register by register.
#![doc = include_str!("../README.md")]
#![warn(missing_docs, unreachable_pub, unnameable_types)]

pub mod codec;
pub mod draft;
pub mod duration;
pub mod examples;
pub mod indexed;
pub mod intern;
pub mod link;
pub mod lookup;
pub mod paramset;
mod profile;
pub mod session;
mod settings;
pub mod silence;
pub mod unprinted;

pub use profile::leak_profile;
pub use settings::{LiveSettings, View};
