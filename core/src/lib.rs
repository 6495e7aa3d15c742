//! The vocabulary of drivemap, shared by the generator, the generated drive modules, the
//! run-time interpreter and the clients: what a register is ([`register`]), how its word converts
//! ([`scale`], [`plan`]), what may be written to it ([`rule`]) and what a drive accepts on the
//! wire ([`profile`]), which registers play the standard parts of a drive ([`roles`]) and which
//! parameters are reached through an index/value register pair ([`indexed`]).
//!
//! `#![no_std]` and free of allocation: a generated drive module and the protocol layer built on
//! this crate can run on a microcontroller. Data flows one way: the generator's lowering pass
//! (`drivemap_map::lower`) decides a [`plan::RegisterPlan`] per register; generated code
//! prints it as `const` data, the interpreter builds it at run time, and both convert with
//! [`plan::RegisterPlan::decode_number`] and its siblings.
#![doc = include_str!("../README.md")]
#![no_std]
#![deny(missing_docs, unreachable_pub)]

#[cfg(test)]
extern crate std;

pub mod bit_fields;
pub mod command_profile;
pub mod functions;
pub mod indexed;
pub mod kind;
pub mod plan;
pub mod profile;
pub mod ratio;
pub mod register;
pub mod roles;
pub mod rule;
pub mod scale;
pub mod stated;
pub mod width;

// Second paths to the items most code names, not documented: each item has one documented
// path, in its module. They stay for the code that names them (the generated drive modules, whose
// text is kept byte for byte, and most crates of the workspace).
#[doc(hidden)]
pub use command_profile::CommandProfile;
#[doc(hidden)]
pub use functions::Functions;
#[doc(hidden)]
pub use kind::ConversionKind;
#[doc(hidden)]
pub use plan::{RegisterPlan, SettingsView, Value};
#[doc(hidden)]
pub use profile::Profile;
#[doc(hidden)]
pub use register::{
    Access, BitRegister, Bits, Code, DrivePlan, DriveSettings, Enumeration, ReadOnly, ReadWrite,
    ReadWriteAs, Readable, Reg, Register, RegisterInfo, Table, Writable, WriteOnly,
    WriteRestriction,
};
#[doc(hidden)]
pub use roles::{Role, Roles};
#[doc(hidden)]
pub use rule::{Broadcast, Transports, WriteRule};
#[doc(hidden)]
pub use scale::{Rounding, ValueError};
#[doc(hidden)]
pub use stated::{NotPrinted, ProtocolFact, Stated};
#[doc(hidden)]
pub use width::{Width, WordOrder};
