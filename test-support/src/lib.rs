//! What the workspace's tests and benches share, from one place instead of `#[path]` includes:
//!
//! - [`line::EmulatedLine`]: a serial line at its baud rate between two pseudo-terminals,
//!   recording each character's time on the wire, and [`line::analyse`], the timing rules
//!   read from that record;
//! - [`pty_pair::PtyPair`]: two linked pseudo-terminals made by `socat`, a real serial line;
//! - [`hostile_peer::HostilePeer`]: a Modbus TCP server that misbehaves on purpose;
//! - [`late_slave::serve_late`]: a slave on any transport (a pseudo-terminal) that answers
//!   some requests just after the client's timeout;
//! - [`sim_link::SimLink`]: an in-memory link to a simulated drive that loses, delays and refuses
//!   frames on request and records what reached the wire;
//! - [`alloc_count::Counting`]: a global allocator that counts heap allocations, per thread and
//!   in all, for the tests and benches that promise none per request;
//! - [`instant_link::InstantLink`]: an in-memory RTU link on which a simulated slave answers
//!   inside `send` (no thread, no clock), for those benches and tests;
//! - [`rng::SplitMix`]: SplitMix64, to draw test cases and reproducible subsets;
//! - [`cargo`]: cargo for a build inside a test, which leaves the workspace's build fresh;
//! - [`paths`]: where the workspace's files are (the fixtures of `tests/fixtures/`, the shipped
//!   maps of `maps/`, the docs), the one place a test learns the repository's layout.
//!
//! The links and peers need the runtime and the simulator: they are behind the `links` feature,
//! so that a crate whose tests only need [`paths`] builds nothing else for them.
#![doc = include_str!("../README.md")]

pub mod alloc_count;
pub mod cargo;
#[cfg(feature = "links")]
pub mod hostile_peer;
#[cfg(feature = "links")]
pub mod instant_link;
#[cfg(feature = "links")]
pub mod late_slave;
#[cfg(all(unix, feature = "links"))]
pub mod line;
pub mod paths;
pub mod pty_pair;
pub mod rng;
#[cfg(feature = "links")]
pub mod sim_link;
