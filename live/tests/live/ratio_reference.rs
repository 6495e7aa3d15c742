//! A register with a ratio scale as the reference of another register (the fictional Borealis
//! BF6's maximum frequency, "60.0 Hz = 3600"): a scale relative to it and a limit through it
//! (`max_relative`) take its exact value once the settings hold the word read from the drive.

use drivemap_test_support::paths;

use drivemap_live::LiveSettings;
use drivemap_live::codec::Value;
use drivemap_runtime::core::scale::ValueError;

fn drive() -> drivemap_map::Map {
    let text = std::fs::read_to_string(paths::fixture("borealis-bf6/borealis-bf6.yaml")).unwrap();
    let reference = "min: 0.0, max: 400.0, source: \"borealis-bf6.txt:11\"}";
    assert!(
        text.contains(reference),
        "the fixture's frequency reference moved"
    );
    let text = text
        .replace(
            reference,
            "min: 0.0, max: 400.0, max_relative: {relative_to: maximum_frequency, percent: 100, source: \"borealis-bf6.txt:18\"}, source: \"borealis-bf6.txt:11\"}",
        )
        .replace(
            "      - {id: output_current,",
            "      - {id: speed_percent, name: Speed, address: 0x0014, access: r, unit: Hz, scale: {relative_to: maximum_frequency, full_scale: 10000}, source: \"borealis-bf6.txt:13\"}\n      - {id: output_current,",
        );
    drivemap_map::Loader::new()
        .load_str("borealis-bf6.yaml", &text)
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_ratio_register_is_a_reference() {
    let d = drive();
    let mut s = LiveSettings::default();
    // Maximum frequency 0022h reads 3599 counts: 3599/60 Hz.
    assert!(s.absorb(&d, 0x0022, 3599));
    let speed = d.register("speed_percent").unwrap();
    match drivemap_live::codec::decode(&d, speed, 5000, &s) {
        Ok(Value::Quantity { value, .. }) => assert_eq!(value, 3599.0 / 120.0),
        other => panic!("{other:?}"),
    }
    let reference = d.register("frequency_reference").unwrap();
    assert_eq!(
        drivemap_live::codec::encode(&d, reference, 3599.0 / 60.0, &s),
        Ok(3599)
    );
    assert!(matches!(
        drivemap_live::codec::encode(&d, reference, 60.0, &s),
        Err(ValueError::AboveLimit { .. })
    ));
}
