//! A limit through another parameter holds in the simulated drive too: a master that does not
//! use drivemap and writes a V7 reference above n011 gets the drive's data setting error (21h,
//! "a simple upper/lower limit error occurred with control data", 003_8bcf5d50afb8e230.txt:739),
//! and the reference is not taken.

use drivemap_test_support::paths;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::pdu::Request;
use drivemap_runtime::{rtu, tcp};
use drivemap_sim::{SimOptions, Simulator};

fn v7() -> Simulator {
    let path = paths::shipped_map("yaskawa-v7");
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    Simulator::new(drive, SimOptions::new()).unwrap()
}

/// Writes one word with 06h over RTU framing; the exception code, if the drive answered one.
fn write(sim: &mut Simulator, address: u16, value: u16) -> Option<u8> {
    let mut buf = [0u8; rtu::MAX_FRAME];
    let slave = sim.slave();
    let n = rtu::encode_request(slave, &Request::WriteSingle { address, value }, &mut buf).unwrap();
    let mut out = [0u8; tcp::MAX_FRAME];
    let reply = sim
        .handle(TransportKind::Rtu, &buf[..n], &mut out)
        .reply
        .expect("reply");
    (out[1] & 0x80 != 0)
        .then_some(out[2])
        .filter(|_| reply >= 3)
}

#[test]
fn a_reference_above_n011_is_refused_by_the_simulated_drive() {
    let mut sim = v7();
    assert_eq!(
        sim.value("max_output_frequency").unwrap().as_f64(),
        Some(60.0)
    );
    // n152 = 0: 0.1 Hz. 500.0 Hz = 5000 = 1388h, above n011 = 60.0 Hz.
    assert_eq!(write(&mut sim, 0x0002, 5000), Some(0x21));
    assert_eq!(sim.raw("frequency_reference").unwrap(), 0);
    // 60.0 Hz, n011 itself, is taken.
    assert_eq!(write(&mut sim, 0x0002, 600), None);
    assert_eq!(sim.raw("frequency_reference").unwrap(), 600);
    // n011 lowered: the limit follows.
    sim.set("max_output_frequency", 50.0).unwrap();
    assert_eq!(write(&mut sim, 0x0002, 550), Some(0x21));
    assert_eq!(write(&mut sim, 0x0002, 500), None);
}
