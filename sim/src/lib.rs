//! A Modbus drive simulator driven by any drivemap map, with no code per drive.
//!
//! [`Simulator`] holds one word per register of the map, starting from the map's defaults
//! (encoded through the live codec; a register without a numeric default starts at 0 where its
//! map allows 0, else at the allowed value nearest 0, never at one its map refuses), laid out
//! per transport with address alternatives resolved by the drive's own settings. It answers only
//! the functions the drive's profile lists and enforces the manual's rules with the drive's own
//! exception codes ([`ExceptionPlan`]): unknown function, unknown or write-only register,
//! quantity 0 or above the drive's maximum, a value the generated `encode` would refuse, a write
//! to a read-only register or to a parameter the drive's state forbids (stopped-only while
//! running, TDS-V8 PRG-only in DRV mode). It stays silent on broadcasts, damaged frames and
//! other slaves' addresses, executes broadcasts only on the registers the profile allows, and
//! counts the persist commands of the map (ENTER, save). What a persist command stores is what
//! the drive powers on with after [`Simulator::power_cycle`]: values written and not stored
//! are lost.
//!
//! A map that gives `roles:` also gets a drive model ([`roles`]): the run and direction fields of
//! its command registers make the status fields show running and the output frequency ramp
//! towards the reference at the accel/decel time's rate, converted through
//! the map's scales (including relative and selected scales, whose settings come from the
//! simulator's own registers). Time comes from a [`clock::Clock`], so tests are deterministic.
//!
//! Every reply any drive of this crate sends is framed by [`framing`] (the runtime's
//! `encode_response`), and every link is read by one serve loop ([`server`]).
//!
//! For the runtime's own tests, benches and doctests, [`slave::SimulatedSlave`] is a bare drive
//! built from a [`Profile`](drivemap_runtime::core::profile::Profile) alone (plain register memory, no map),
//! and [`fault::FaultyLink`] an in-memory link to one that damages replies on request.
//!
//! ```
//! use std::sync::Arc;
//! use std::time::Duration;
//! use drivemap_sim::{clock::ManualClock, SimOptions, Simulator};
//!
//! let maps = concat!(env!("CARGO_MANIFEST_DIR"), "/../maps/ptlk-tds-v8.yaml");
//! let drive = drivemap_map::Loader::new().load(maps.as_ref()).unwrap();
//! let clock = ManualClock::new();
//! let mut sim = Simulator::new(drive, SimOptions::new().clock(Arc::new(clock.clone()))).unwrap();
//! sim.set("frequency_command", 30.0).unwrap(); // Hz, 50 % of Cn-02 = 60 Hz
//! sim.set_raw("operation_command", 0x0001).unwrap(); // run forward
//! clock.advance(Duration::from_secs(2)); // Bn-01 10 s to 60 Hz: 6 Hz/s
//! sim.tick();
//! assert_eq!(sim.value("output_frequency").unwrap().as_f64(), Some(12.0));
//! ```
#![doc = include_str!("../README.md")]
#![warn(unreachable_pub, missing_docs, unnameable_types)]

// One path per item: a module of one or two items is private and its items are the crate's
// (documented where they are defined); a module of more keeps its path, with no second one.
pub mod clock;
mod exceptions;
mod fault;
pub mod framing;
pub mod indexed;
mod line;
mod model;
pub mod roles;
pub mod server;
mod simulator;
mod slave;
#[cfg(feature = "serial")]
pub mod timed;

pub use exceptions::ExceptionPlan;
pub use fault::{Fault, FaultyLink};
pub use line::{Line, SlaveTaken};
pub use model::DriveState;
pub use simulator::{
    Handled, Outcome, RequestRecord, RolesChoice, SimError, SimOptions, Simulator, Stats,
};
pub use slave::{SERVE_LIMITS, SimulatedSlave};
