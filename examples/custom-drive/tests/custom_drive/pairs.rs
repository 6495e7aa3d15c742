//! 32-bit values in two registers (`pair:` in `tests/fixtures/acme-vf1/acme-vf1.yaml`): the
//! generated types are `f64` for scaled pairs and `u32` for a plain one, and the generated code
//! and the run-time interpreter decode and encode every raw value alike, in both word orders.

use drivemap_test_support::paths;

use custom_drive::acme_vf1 as acme;
use drivemap_live::LiveSettings;
use drivemap_live::codec::Value;
use drivemap_runtime::core::register::{Register, Writable};
use drivemap_runtime::core::width::{Width, WordOrder};

fn drive() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&paths::fixture("acme-vf1/acme-vf1.yaml"))
        .unwrap()
}

const RAWS: [u32; 8] = [
    0,
    1,
    0xFFFF,
    0x0001_0000,
    123_456,
    0x8000_0000,
    0xFFFE_1DC0,
    0xFFFF_FFFF,
];

fn live_number(d: &drivemap_map::Map, id: &str, raw: u32) -> Result<f64, String> {
    let r = d.register(id).unwrap();
    match drivemap_live::codec::decode(d, r, raw, &LiveSettings::default()) {
        Ok(Value::Quantity { value, .. }) => Ok(value),
        Ok(Value::Word(w)) => Ok(w as f64),
        Ok(other) => Err(format!("{other:?}")),
        Err(e) => Err(e.to_string()),
    }
}

fn agree<R: Register<Settings = acme::Settings, Value = f64>>(d: &drivemap_map::Map) {
    let s = acme::Settings::default();
    for raw in RAWS {
        assert_eq!(
            R::decode(raw, &s).map_err(|e| e.to_string()),
            live_number(d, R::ID, raw),
            "{} {raw:#010x}",
            R::ID
        );
    }
}

#[test]
fn generated_and_interpreted_pairs_agree() {
    let d = drive();
    assert_eq!(
        acme::EnergyCounter::WIDTH,
        Width::Pair(WordOrder::HighFirst)
    );
    assert_eq!(acme::MotorSpeed::WIDTH, Width::Pair(WordOrder::LowFirst));
    assert_eq!(acme::OutputFrequency::WIDTH, Width::Word);
    agree::<acme::EnergyCounter>(&d);
    agree::<acme::RunningHours>(&d);
    agree::<acme::MotorSpeed>(&d);
    agree::<acme::PositionSetpoint>(&d);
    let s = acme::Settings::default();
    assert_eq!(acme::EnergyCounter::decode(123_456, &s), Ok(12345.6));
    assert_eq!(acme::MotorSpeed::decode(0xFFFF_CFC7, &s), Ok(-1234.5));
    // The plain pair is a u32.
    let counter: u32 = acme::PulseCounter::decode(0xFFFF_FFFF, &s).unwrap();
    assert_eq!(counter, u32::MAX);
    // Encoding: the range is the 32-bit value's, the same refusals on both sides.
    let position = d.register("position_setpoint").unwrap();
    for v in [
        -1_000_001.0,
        -123_456.0,
        0.0,
        0.5,
        1_000_000.0,
        1e12,
        f64::NAN,
    ] {
        // Compared as text: NaN inside an error is not equal to itself.
        assert_eq!(
            format!("{:?}", acme::PositionSetpoint::encode(&v, &s)),
            format!(
                "{:?}",
                drivemap_live::codec::encode(&d, position, v, &LiveSettings::default())
            ),
            "{v}"
        );
    }
    assert_eq!(
        acme::PositionSetpoint::encode(&-123_456.0, &s),
        Ok(0xFFFE_1DC0)
    );
    assert_eq!(
        acme::PositionSetpoint::WIDTH.split(0xFFFE_1DC0),
        [0xFFFE, 0x1DC0]
    );
}
