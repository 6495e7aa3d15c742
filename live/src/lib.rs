//! A drive map at run time, for tools that load YAML instead of compiling it: the simulator,
//! the `drivemap read/write/poll` commands, and any program that talks to a drive by register
//! name ([`Session`] over a [`Link`]; `examples/read_by_name.rs`).
//!
//! The generated modules and this crate agree by construction: both read the same validated IR
//! ([`drivemap_map::ir`]) and convert with the same functions of
//! [`drivemap_runtime::scale`]; a test in `tests/` compares them register by register.
#![doc = include_str!("../README.md")]

pub mod codec;
pub mod draft;
pub mod duration;
pub mod examples;
pub mod indexed;
pub mod intern;
pub mod link;
pub mod lookup;
pub mod paramset;
pub mod profile;
pub mod session;
pub mod settings;
pub mod silence;
pub mod unprinted;

pub use codec::{Value, decode, encode, parse_value};
pub use link::{Link, LinkError, Parity};
pub use lookup::{NotFound, find};
pub use paramset::ParameterSet;
pub use profile::leak_profile;
pub use session::{ReadError, Session, SessionError, find_all};
pub use settings::LiveSettings;
