//! The run-time codec (`drivemap-live`, used by the CLI and the simulator) and the generated
//! code agree on every register kind of the fixture map, under every setting it depends on.

use drivemap_test_support::paths;

use custom_drive::mini_drive as md;
use drivemap_live::LiveSettings;
use drivemap_live::codec::Value;
use drivemap_runtime::core::register::{Bits, Code, Enumeration, Register, Writable};

fn drive() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&paths::fixture("crafted/maps/mini-drive.yaml"))
        .unwrap()
}

/// The generated settings and the live settings for one combination.
fn combos() -> Vec<(md::Settings, LiveSettings)> {
    let mut out = Vec::new();
    for (vc, vname) in [
        (md::VoltageClass::V200, "v200"),
        (md::VoltageClass::V400, "v400"),
    ] {
        for units in [None, Some(0u16), Some(1), Some(2), Some(9)] {
            for max in [None, Some(60.0)] {
                let g = md::Settings {
                    voltage_class: vc,
                    frequency_units: units.map(md::FrequencyUnitsValue::from_code),
                    max_frequency: max,
                    rated_current: Some(12.5),
                };
                let mut l = LiveSettings::default();
                l.variants.insert("voltage_class".into(), vname.into());
                if let Some(u) = units {
                    l.selectors.insert("frequency_units".into(), u);
                }
                if let Some(m) = max {
                    l.references.insert("max_frequency".into(), m);
                }
                l.references.insert("rated_current".into(), 12.5);
                out.push((g, l));
            }
        }
    }
    out
}

const RAWS: [u32; 9] = [0, 1, 2, 3, 600, 4000, 30000, 0x8000, 0xFFFF];
const VALUES: [f64; 10] = [-1.0, 0.0, 0.1, 1.0, 2.0, 50.0, 255.0, 300.0, 400.0, 600.5];

fn quantity<R: Register<Settings = md::Settings, Value = f64> + Writable<Input = f64>>(
    d: &drivemap_map::Map,
) {
    let r = d.register(R::ID).unwrap();
    for (g, l) in combos() {
        for raw in RAWS {
            let gen_v = R::decode(raw, &g);
            let live_v = drivemap_live::codec::decode(d, r, raw, &l);
            match (gen_v, live_v) {
                (Ok(a), Ok(Value::Quantity { value, .. })) => {
                    assert_eq!(a, value, "{} decode {raw}", R::ID)
                }
                (Err(a), Err(b)) => assert_eq!(a, b, "{} decode {raw}", R::ID),
                (a, b) => panic!("{} decode {raw}: generated {a:?}, live {b:?}", R::ID),
            }
        }
        for v in VALUES {
            assert_eq!(
                R::encode(&v, &g),
                drivemap_live::codec::encode(d, r, v, &l),
                "{} encode {v} under {g:?}",
                R::ID
            );
        }
    }
}

#[test]
fn quantities_agree() {
    let d = drive();
    quantity::<md::FrequencyReference>(&d);
    quantity::<md::MaxFrequency>(&d);
    quantity::<md::MaxVoltage>(&d);
    quantity::<md::Preset1>(&d);
    quantity::<md::ResponseDelay>(&d);
}

#[test]
fn read_only_quantities_decode_alike() {
    let d = drive();
    for (g, l) in combos() {
        for raw in RAWS {
            let a = md::OutputCurrent::decode(raw, &g).unwrap();
            let b =
                drivemap_live::codec::decode(&d, d.register("output_current").unwrap(), raw, &l)
                    .unwrap();
            assert_eq!(Some(a), b.as_f64());
            let a = md::Torque::decode(raw, &g).unwrap();
            let b =
                drivemap_live::codec::decode(&d, d.register("torque").unwrap(), raw, &l).unwrap();
            assert_eq!(Some(a), b.as_f64());
        }
    }
}

#[test]
fn codes_and_bits_agree() {
    let d = drive();
    let l = LiveSettings::default();
    let g = md::Settings::new();
    let units = d.register("frequency_units").unwrap();
    let command = d.register("command").unwrap();
    for raw in RAWS {
        let a = md::FrequencyUnits::decode(raw, &g).unwrap();
        match drivemap_live::codec::decode(&d, units, raw, &l).unwrap() {
            Value::Code { code, name, .. } => {
                assert_eq!(a.code(), code);
                assert_eq!(a.name().map(str::to_owned), name);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(
            md::FrequencyUnits::encode(&a, &g).ok(),
            drivemap_live::codec::encode(&d, units, f64::from(raw), &l).ok(),
            "code {raw}"
        );
        let bits = md::Command::decode(raw, &g).unwrap();
        match drivemap_live::codec::decode(&d, command, raw, &l).unwrap() {
            Value::Bits { raw: live_raw, .. } => assert_eq!(bits.bits(), live_raw),
            other => panic!("{other:?}"),
        }
    }
    // Reserved bits cannot be written through the live codec either.
    assert!(drivemap_live::codec::encode(&d, command, 0x0004 as f64, &l).is_err());
    assert_eq!(
        drivemap_live::codec::parse_value(&d, command, "run,mode=remote", &l),
        Ok(0x0021)
    );
}
