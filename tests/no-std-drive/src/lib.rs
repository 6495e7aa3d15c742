//! A `#![no_std]` crate on the V7's generated module: the frame that writes a frequency
//! reference, typed and range-checked, encoded by the runtime's protocol core, with no standard
//! library and no allocator.
//!
//! Proof that nothing in the dependency graph links `std`: this crate defines the panic handler,
//! a lang item `std` defines too. Were `std` anywhere among the crates it depends on (a `use
//! std::..` in the generated code or the runtime's core, a dependency with its default features
//! on), rustc would stop with "found duplicate lang item `panic_impl`" (E0152).
#![no_std]

use drivemap_drives::runtime::core::profile::TransportKind;
use drivemap_drives::runtime::core::register::{Register, Writable};
use drivemap_drives::runtime::core::scale::ValueError;
use drivemap_drives::runtime::pdu::Request;
use drivemap_drives::runtime::rtu;
use drivemap_drives::yaskawa_v7 as v7;

/// Why no frame was made.
#[derive(Debug)]
pub enum FrameError {
    /// The value is not one the register takes (its range, its steps, a setting it needs).
    Value(ValueError),
    /// The register's address depends on a setting not known.
    Address,
    /// The buffer is too short.
    Buffer,
}

/// The RTU frame that writes `hz` to the V7's frequency reference on `slave` into `out`, with
/// the settings its conversion needs (n152, n011); its length.
pub fn write_reference(
    slave: u8,
    hz: f64,
    settings: &v7::Settings,
    out: &mut [u8],
) -> Result<usize, FrameError> {
    let raw = v7::FrequencyReference::encode(&hz, settings).map_err(FrameError::Value)?;
    let address = v7::FrequencyReference::address(settings, TransportKind::Rtu)
        .map_err(|_| FrameError::Address)?;
    let request = Request::WriteSingle {
        address,
        value: raw as u16,
    };
    rtu::encode_request(slave, &request, out).map_err(|_| FrameError::Buffer)
}

/// The output frequency (Hz) of a word read from the V7.
pub fn output_frequency(word: u16, settings: &v7::Settings) -> Result<f64, ValueError> {
    v7::OutputFrequency::decode(word.into(), settings)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {}
}
