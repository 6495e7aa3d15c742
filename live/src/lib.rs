//! A drive map at run time, for tools that load YAML instead of compiling it: the simulator and
//! the `drivemap read/write/poll` commands.
//!
//! The generated modules and this crate agree by construction: both read the same validated IR
//! ([`drivemap_codegen::ir`]) and convert with the same functions of
//! [`drivemap_runtime::scale`]; a test in `tests/` compares them register by register.

pub mod codec;
pub mod intern;
pub mod lookup;
pub mod profile;
pub mod settings;

pub use codec::{Value, decode, encode, parse_value};
pub use lookup::{NotFound, find};
pub use profile::leak_profile;
pub use settings::LiveSettings;
