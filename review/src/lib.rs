//! drivemap review tools on the map front end (`drivemap-map`): the semantic [`diff`] of two maps
//! (`drivemap diff`), the manual [`review`] of a map's citations and coverage (`drivemap check
//! --manuals`, `drivemap coverage`) and the Markdown [`reference`](mod@reference) of a drive
//! (`drivemap doc`, `docs/drives/`).
//!
//! All text about a map comes from `drivemap_map::describe`.
#![doc = include_str!("../README.md")]
#![warn(missing_docs, unreachable_pub, unnameable_types)]

pub mod diff;
pub mod reference;
pub mod review;
