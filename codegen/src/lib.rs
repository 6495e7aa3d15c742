//! drivemap code generator: prints the drive plan of a validated map (`drivemap-map`) as typed
//! Rust.
//!
//! [`generate`] prints one module per drive (tokens built with `quote`, parsed by `syn`, printed
//! by `prettyplease`; the plan rows as text); [`Config`] drives it from a `build.rs` in the style of
//! `prost-build`, or returns the code without writing files ([`Config::generate`]).
//!
//! The map front end (model, loading, validation, lowering) is `drivemap-map`; this crate only
//! prints.
#![doc = include_str!("../README.md")]
#![warn(unreachable_pub, missing_docs, unnameable_types)]

mod config;
pub mod generate;

pub(crate) use drivemap_map::{Diagnostic, describe, facts};
pub(crate) use drivemap_map::{default_manuals_dir, find_maps};

// The build-script API, one path per item: `config` is private and its five items are the
// crate's (as `prost_build::Config` is).
pub use config::{Code, Config, Error, Generated, Module};
