//! Typed register maps of industrial AC drives, generated at build time from `maps/*.yaml`.
//!
//! One module per drive (`ptlk_tds_v8`, `yaskawa_v7`, …). Each has a zero-sized type per
//! register implementing [`drivemap_runtime::Register`] (and `Readable` / `Writable` as the
//! manual allows), value types (bit fields, enumerations with `Unknown(u16)`, `f64` engineering
//! values), a `Settings` type for the parameters conversions depend on, the drive's
//! `PROFILE` and its `REGISTERS` table. [`DRIVES`] lists them all.
//!
//! ```
//! use drivemap_drives::ptlk_tds_v8 as tds;
//! use drivemap_drives::runtime::{Register, Writable};
//!
//! // 5DC0h = 80 % of Cn-02 (max output frequency): 48 Hz when Cn-02 = 60 Hz.
//! let settings = tds::Settings { max_output_frequency: Some(60.0), ..Default::default() };
//! assert_eq!(tds::FrequencyCommand::decode(0x5DC0, &settings), Ok(48.0));
//! assert_eq!(tds::FrequencyCommand::encode(&48.0, &settings), Ok(0x5DC0));
//! ```

pub use drivemap_runtime as runtime;

include!(concat!(env!("OUT_DIR"), "/drivemap.rs"));
