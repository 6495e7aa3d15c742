// The crate's documentation is its README (module contents, examples, features), so the page on
// crates.io and the one on docs.rs are one text and its examples are compiled as doctests.
#![doc = include_str!("../README.md")]
// Without the `std` feature: the registers over the runtime's protocol core, for a target
// without an operating system (`scripts/test` builds `tests/no-std-drive`, a `#![no_std]` crate
// on one drive).
#![cfg_attr(not(feature = "std"), no_std)]
#![warn(missing_docs)]

/// The runtime the generated modules are written against (`drivemap-runtime`), re-exported so
/// that an application needs one dependency: its traits (`Register`, `Readable`, `Writable`),
/// its clients and transports (with `std`) and its drive API.
pub use drivemap_runtime as runtime;

// The generated index: one `pub mod` per map selected by the features, `DRIVES` and
// `for_each_drive!` (`build.rs`).
include!(concat!(env!("OUT_DIR"), "/drivemap.rs"));

// A `#[cfg(feature = "<id>")]` per map of `maps/`, so that rustc warns about a map whose feature
// `Cargo.toml` does not declare (`build.rs`).
include!(concat!(env!("OUT_DIR"), "/features.rs"));
