//! The map-driven simulator serves indexed access (`indexed:`) as the drive does: the index
//! register selects which entry the value register shows and accepts, each entry keeps its own
//! value, and an entry's access and range are enforced by the simulated drive itself. The drive
//! is the fictional Tarrow TM-44 (`tests/fixtures/tarrow-tm44`).

use drivemap_test_support::paths;

use std::time::Duration;

use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::indexed::EntryRef;
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_sim::{SimOptions, Simulator};
use drivemap_test_support::sim_link::{LinkFault, SimLink};

fn drive() -> drivemap_map::Map {
    let dir = paths::fixture("tarrow-tm44");
    drivemap_map::Loader::new()
        .manuals(dir.join("manuals"))
        .load(&dir.join("tarrow-tm44.yaml"))
        .unwrap_or_else(|d| panic!("{d}"))
}

fn options() -> ClientOptions {
    ClientOptions {
        timeout: Duration::from_millis(20),
        retries: 0,
        request_gap: Duration::ZERO,
        ..ClientOptions::default()
    }
}

fn entry(drive: &drivemap_map::Map, id: &str) -> EntryRef {
    drivemap_runtime::core::indexed::find(drive.plan().indexed, id).unwrap()
}

#[test]
fn the_index_register_selects_what_the_value_register_shows_and_takes() {
    let drive = drive();
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let profile = drive.plan().profile;
    let mut c = Client::with_options(SimLink::new(TransportKind::Rtu, sim), profile, options());
    c.write_entry(1, entry(&drive, "acceleration_time"), 12.5)
        .unwrap();
    c.write_entry(1, entry(&drive, "maximum_frequency"), 50.0)
        .unwrap();
    let bank = c.transport().sim.indexed();
    assert_eq!(bank.value("parameter_value", 1), Some(125));
    assert_eq!(bank.value("parameter_value", 3), Some(5000));
    assert_eq!(
        c.read_entry(1, entry(&drive, "acceleration_time")).unwrap(),
        12.5
    );
    assert_eq!(
        c.read_entry(1, entry(&drive, "maximum_frequency")).unwrap(),
        50.0
    );
    // Entries the map lists power on inside their range (0.1 s, the range's lowest).
    assert_eq!(
        c.read_entry(1, entry(&drive, "deceleration_time")).unwrap(),
        0.1
    );
    // The keypad changes an entry; the next read shows it.
    c.transport()
        .sim
        .indexed_mut()
        .set("parameter_value", 12, 4321);
    assert_eq!(
        c.read_entry(1, entry(&drive, "total_running_hours"))
            .unwrap(),
        4321.0
    );
}

/// A lost request (the index write never reached the drive) and a lost reply (it did): the
/// next reads still give each entry its own value.
#[test]
fn a_lost_index_write_never_mixes_entries() {
    let drive = drive();
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let profile = drive.plan().profile;
    let mut c = Client::with_options(SimLink::new(TransportKind::Rtu, sim), profile, options());
    c.write_entry(1, entry(&drive, "acceleration_time"), 5.0)
        .unwrap();
    c.write_entry(1, entry(&drive, "deceleration_time"), 7.0)
        .unwrap();
    for fault in [
        LinkFault::LoseRequest,
        LinkFault::LoseReply,
        LinkFault::LateReply,
    ] {
        c.transport().inject(fault);
        assert!(
            c.read_entry(1, entry(&drive, "acceleration_time")).is_err(),
            "{fault:?}"
        );
        assert_eq!(
            c.read_entry(1, entry(&drive, "deceleration_time")).unwrap(),
            7.0
        );
        c.transport().inject(fault);
        assert!(
            c.read_entry(1, entry(&drive, "deceleration_time")).is_err(),
            "{fault:?}"
        );
        assert_eq!(
            c.read_entry(1, entry(&drive, "acceleration_time")).unwrap(),
            5.0
        );
    }
}

/// Past the client's gate (a client with no map), the simulated drive itself refuses a write to
/// a read-only entry and a value outside the selected entry's range, with the map's exception
/// codes, and takes any word for an index the manual does not list.
#[test]
fn the_simulated_drive_enforces_each_entrys_access_and_range() {
    let drive = drive();
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let mut c = Client::with_options(
        SimLink::new(TransportKind::Rtu, sim),
        &Profile::GENERIC,
        options(),
    );
    c.write_register(1, 44, 12).unwrap();
    let e = c.write_register(1, 45, 5).unwrap_err();
    assert!(e.exception().is_some(), "{e}");
    c.write_register(1, 44, 3).unwrap();
    let e = c.write_register(1, 45, 7000).unwrap_err();
    assert!(e.exception().is_some(), "{e}");
    c.write_register(1, 45, 6000).unwrap();
    c.write_register(1, 44, 5).unwrap();
    c.write_register(1, 45, 7000).unwrap();
    let bank = c.transport().sim.indexed();
    assert_eq!(bank.value("parameter_value", 3), Some(6000));
    assert_eq!(bank.value("parameter_value", 5), Some(7000));
    assert_eq!(bank.value("parameter_value", 12), Some(0));
}
