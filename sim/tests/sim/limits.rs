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

/// A range a mode parameter selects (`limits: {selected_by: P1300}`, the fictional
/// `tests/fixtures/lindgren-lg7`): the simulated drive refuses, with 03h "the value is outside
/// the range in force", a word outside the range of the case its own P1300 selects, and keeps
/// the value; a master that does not use drivemap meets the same rule as `drivemap write`.
#[test]
fn a_range_selected_by_the_control_mode_is_kept_by_the_simulated_drive() {
    let path = paths::fixture("lindgren-lg7/lindgren-lg7.yaml");
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    let mut sim = Simulator::new(drive, SimOptions::new()).unwrap();
    // P1300 = 0 (V/f): P0640 10.0 ..= 400.0 % (0.1 %: 100 ..= 4000).
    assert_eq!(sim.raw("control_mode").unwrap(), 0);
    assert_eq!(write(&mut sim, 0x0101, 2000), None);
    assert_eq!(write(&mut sim, 0x0101, 4001), Some(0x03));
    assert_eq!(sim.raw("motor_overload_factor").unwrap(), 2000);
    // P1300 = 20 (vector): 10.0 ..= 150.0 %, the scale unchanged.
    assert_eq!(write(&mut sim, 0x0100, 20), None);
    assert_eq!(write(&mut sim, 0x0101, 1501), Some(0x03));
    assert_eq!(write(&mut sim, 0x0101, 2000), Some(0x03));
    assert_eq!(write(&mut sim, 0x0101, 1500), None);
    assert_eq!(
        sim.value("motor_overload_factor").unwrap().as_f64(),
        Some(150.0)
    );
    // Back to V/f: the wider range again.
    assert_eq!(write(&mut sim, 0x0100, 1), None);
    assert_eq!(write(&mut sim, 0x0101, 4000), None);
    // A code P1300 does not list is refused: no case without a range is reached by a write.
    assert_eq!(write(&mut sim, 0x0100, 7), Some(0x03));
}
