//! `drivemap read`/`write` reach an entry of an indexed register by name (the fictional Tarrow
//! TM-44 of `tests/fixtures/tarrow-tm44/`: index in register 44, value in 45): `read
//! acceleration_time` writes index 1 to register 44 and reads register 45 (with 44 in the same
//! request, to check the drive still shows index 1), against a simulated drive that serves the
//! pair.

use drivemap_test_support::paths;

use crate::common;

use std::path::PathBuf;

use drivemap_sim::SimulatedSlave;

use common::{Framing, drivemap_fixture, serve};

fn fixture() -> PathBuf {
    paths::fixture("tarrow-tm44")
}

#[test]
fn read_and_write_name_an_entry_of_an_indexed_register() {
    let map = drivemap_map::Loader::new()
        .manuals(fixture().join("manuals"))
        .load(&fixture().join("tarrow-tm44.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let plan = map.plan().clone();
    let mut slave =
        SimulatedSlave::new(1, drivemap_live::leak_profile(&map)).with_indexed(plan.indexed);
    slave.indexed.set("parameter_value", 1, 125); // acceleration time 12.5 s
    slave.indexed.set("parameter_value", 2, 300); // deceleration time 30.0 s
    slave.set_holding(44, 2); // the keypad left deceleration time selected
    let (addr, slave) = serve(slave, Framing::RtuOverTcp);
    let run = |command: &str, names: &[&str]| {
        let mut args = vec![
            command,
            "--maps",
            ".",
            "--drive",
            "tarrow-tm44",
            "--rtu-tcp",
            &addr,
            "--timeout",
            "2s",
        ];
        args.extend_from_slice(names);
        drivemap_fixture(&fixture(), &args)
    };
    for name in ["acceleration_time", "Acceleration time"] {
        let (code, out, err) = run("read", &[name]);
        assert_eq!(code, 0, "{name}: {err}");
        assert_eq!(
            out,
            "acceleration_time  12.5 s  (entry 1 of parameter_value (index in parameter_index))\n"
        );
    }
    let (code, out, err) = run("write", &["maximum_frequency=55.5"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("maximum_frequency = 55.5"), "{out}");
    assert_eq!(
        slave.lock().unwrap().indexed.value("parameter_value", 3),
        Some(5550)
    );
    let (code, out, err) = run("read", &["maximum_frequency", "deceleration_time"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("maximum_frequency  55.5 Hz") && out.contains("deceleration_time  30 s"),
        "{out}"
    );
    // Refused before anything is sent: a read-only entry, a value outside the entry's range,
    // and registers named with entries.
    let (code, _, err) = run("write", &["total_running_hours=5"]);
    assert_ne!(code, 0);
    assert!(err.contains("total_running_hours is read-only"), "{err}");
    let (code, _, err) = run("write", &["maximum_frequency=75"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("maximum_frequency") && err.contains("nothing written"),
        "{err}"
    );
    let (code, _, err) = run("read", &["acceleration_time", "output_frequency"]);
    assert_ne!(code, 0);
    assert!(err.contains("separate commands"), "{err}");
    assert_eq!(
        slave.lock().unwrap().indexed.value("parameter_value", 3),
        Some(5550)
    );
}
