//! An application crate with its own drive maps (`mini-drive`, `field-selector` for scales
//! selected by a field of a status word, `acme-vf1` with 32-bit values in two registers, and
//! `borealis-bf6` with ratio scales), generated at build time.
//!
//! ```
//! use custom_drive::mini_drive as md;
//! use drivemap_runtime::core::register::{Register, Writable};
//!
//! let settings = md::Settings { frequency_units: Some(md::FrequencyUnitsValue::HundredthHz), ..Default::default() };
//! assert_eq!(md::FrequencyReference::encode(&50.0, &settings), Ok(5000));
//! ```
#![doc = include_str!("../README.md")]

include!(concat!(env!("OUT_DIR"), "/drivemap.rs"));
