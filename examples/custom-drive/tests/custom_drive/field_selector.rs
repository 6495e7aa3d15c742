//! A scale selected by a field of a status word: the generated `Settings` and the run-time
//! interpreter's `LiveSettings` absorb the same status word and then decode the same monitor word
//! alike, and differently when the field changes.

use drivemap_test_support::paths;

use custom_drive::field_selector as fs;
use drivemap_live::LiveSettings;
use drivemap_live::codec::Value;
use drivemap_runtime::core::register::{DriveSettings, Register};

fn drive() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&paths::fixture("crafted/maps/field-selector.yaml"))
        .unwrap()
}

fn live_number(d: &drivemap_map::Map, id: &str, raw: u32, l: &LiveSettings) -> f64 {
    match drivemap_live::codec::decode(d, d.register(id).unwrap(), raw, l) {
        Ok(Value::Quantity { value, .. }) => value,
        other => panic!("{id} {raw}: {other:?}"),
    }
}

#[test]
fn generated_and_live_follow_the_high_byte_of_the_status_word() {
    let d = drive();
    assert_eq!(
        <fs::Settings as DriveSettings>::DEPENDENCIES,
        LiveSettings::dependencies(&d).as_slice()
    );
    let mut seen = Vec::new();
    for (status, current, speed) in [
        (0x0000u16, 1234.0, 15.0),
        (0x0101, 123.4, 15.0),
        (0x0203, 12.34, 1500.0),
    ] {
        let mut g = fs::Settings::new();
        assert!(g.absorb(0x0010, status));
        let mut l = LiveSettings::default();
        assert!(l.absorb(&d, 0x0010, status));
        assert_eq!(g.status_word_current_decimals, Some(status >> 8));
        let generated = fs::OutputCurrent::decode(1234, &g).unwrap();
        assert_eq!(generated, current, "generated, status {status:04X}h");
        assert_eq!(live_number(&d, "output_current", 1234, &l), current);
        assert_eq!(fs::SpeedMonitor::decode(1500, &g).unwrap(), speed);
        assert_eq!(live_number(&d, "speed_monitor", 1500, &l), speed);
        let torque = fs::TorqueCurrent::decode(0xFF38, &g).unwrap();
        assert_eq!(torque, live_number(&d, "torque_current", 0xFF38, &l));
        seen.push(generated);
    }
    assert_eq!(
        seen,
        [1234.0, 123.4, 12.34],
        "the field changes the decimals"
    );
    // A code no case lists: both refuse it alike.
    let mut g = fs::Settings::new();
    g.absorb(0x0010, 0x0900);
    let mut l = LiveSettings::default();
    l.absorb(&d, 0x0010, 0x0900);
    let generated = fs::OutputCurrent::decode(1234, &g).unwrap_err();
    let live = drivemap_live::codec::decode(&d, d.register("output_current").unwrap(), 1234, &l)
        .unwrap_err();
    assert_eq!(generated, live);
    assert!(
        generated
            .to_string()
            .contains("status_word.current_decimals"),
        "{generated}"
    );
}
