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

//! Talking to a V7 on a serial line (compiled, not run: it needs the port):
//!
//! ```no_run
//! use std::time::Duration;
//! use drivemap_drives::runtime::{Client, ClientOptions, Rounding};
//! use drivemap_drives::runtime::transport::serial::{Parity, SerialOptions, SerialTransport};
//! use drivemap_drives::yaskawa_v7::{self as v7, Settings};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let link = SerialTransport::open(
//!     SerialOptions::new("/dev/ttyUSB0", 9600).parity(Parity::Even).with_profile(&v7::PROFILE),
//! )?;
//! // The map's timing (V7/J7: 24 bits + 10 ms after each reply), with a shorter timeout.
//! let mut drive = Client::with_options(link, &v7::PROFILE, ClientOptions {
//!     timeout: Duration::from_millis(200),
//!     ..ClientOptions::for_profile(&v7::PROFILE)
//! });
//! let mut settings = Settings::default();
//! drive.load_settings(1, &mut settings)?; // reads n152 (frequency units) and n011
//! let hz: f64 = drive.read::<v7::OutputFrequency>(1, &settings)?;
//! // Refused above n011, out of range, or between two steps (35.75 Hz at 0.1 Hz): as given or not at all.
//! drive.write::<v7::FrequencyReference>(1, &35.7, &settings)?;
//! // The nearest step, asked for: 35.8 Hz.
//! drive.write_rounded::<v7::FrequencyReference>(1, &35.75, &settings, Rounding::Nearest)?;
//! drive.modify_bits::<v7::DigitalInputCommand>(1, &settings, 0x0001, 0)?; // run
//! let (reference, output) =
//!     drive.read_many::<(v7::FrequencyReferenceMonitor, v7::OutputFrequency)>(1, &settings)?;
//! drive.write::<v7::BroadcastFrequencyReference>(0, &50.0, &settings)?; // slave 0, no reply
//! drive.persist(1, "enter")?; // counted EEPROM write
//! # let _ = (hz, reference, output);
//! # Ok(())
//! # }
//! ```

// Without the `std` feature: the registers over the runtime's protocol core, for a target
// without an operating system (`scripts/test` builds `tests/no-std-drive`, a `#![no_std]` crate
// on one drive).
#![cfg_attr(not(feature = "std"), no_std)]

pub use drivemap_runtime as runtime;

include!(concat!(env!("OUT_DIR"), "/drivemap.rs"));
