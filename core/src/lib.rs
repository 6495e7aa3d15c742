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
#![deny(missing_docs, unreachable_pub, unnameable_types)]

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
pub mod text;
pub mod width;
