//! A value is sent as given or refused: any value a decimal or relative scale accepts (without
//! rounding) decodes back to exactly that value, a value between two steps is refused naming
//! the two steps around it, and rounding to the nearest step is an explicit choice that still
//! checks the range on the value given.

use drivemap_core::scale::{
    Decimal, RawRange, Rounding, ValueError, decode_relative, encode_decimal_with,
    encode_relative_with,
};
use proptest::prelude::*;

/// Every decimal factor the shipped maps use, and a few more.
const SCALES: [Decimal; 7] = [
    Decimal::new(1, 0),
    Decimal::new(1, 1),
    Decimal::new(1, 2),
    Decimal::new(1, 3),
    Decimal::new(5, 1),
    Decimal::new(10, 0),
    Decimal::new(25, 2),
];

fn exact(value: f64, scale: Decimal, range: RawRange) -> Result<i64, ValueError> {
    encode_decimal_with("r", "u", value, scale, range, Rounding::Exact)
}

fn nearest(value: f64, scale: Decimal, range: RawRange) -> Result<i64, ValueError> {
    encode_decimal_with("r", "u", value, scale, range, Rounding::Nearest)
}

/// Checks one candidate value against one scale and range.
fn check_decimal(value: f64, scale: Decimal, range: RawRange) -> Result<(), TestCaseError> {
    let (min, max) = (scale.decode(range.min), scale.decode(range.max));
    let in_range = value >= min && value <= max;
    match exact(value, scale, range) {
        Ok(raw) => {
            prop_assert_eq!(scale.decode(raw), value);
            prop_assert!(range.contains(raw));
        }
        Err(ValueError::NotAStep {
            below, above, step, ..
        }) => {
            prop_assert!(in_range, "{value} out of range yet called between steps");
            prop_assert!(
                below < value && value < above,
                "{below} < {value} < {above}"
            );
            prop_assert_eq!(step, scale.as_f64());
            // The two values named are sendable as given.
            prop_assert!(exact(below, scale, range).is_ok(), "{below} sendable");
            prop_assert!(exact(above, scale, range).is_ok(), "{above} sendable");
        }
        Err(ValueError::OutOfRange { .. } | ValueError::WordOverflow { .. }) => {
            prop_assert!(!in_range, "{value} in range {min} ..= {max} yet refused")
        }
        Err(ValueError::NotFinite { .. }) => prop_assert!(!value.is_finite()),
        Err(e) => prop_assert!(false, "unexpected {e}"),
    }
    // Rounding: the range applies to the value given; in range, the nearest step.
    match nearest(value, scale, range) {
        Ok(raw) => {
            prop_assert!(
                in_range,
                "{} outside {} ..= {} rounded into range",
                value,
                min,
                max
            );
            let sent = scale.decode(raw);
            prop_assert!(
                (sent - value).abs() <= scale.as_f64() / 2.0 * (1.0 + 1e-9),
                "{value} rounded to {sent}"
            );
        }
        Err(_) => prop_assert!(!in_range, "{value} in range but not rounded"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn a_decimal_value_is_sent_as_given_or_refused(
        s in 0..SCALES.len(),
        lo in -40000i64..=0,
        span in 0i64..70000,
        raw in -70000i64..70000,
        fraction in -1.5f64..1.5,
        arbitrary in proptest::num::f64::ANY,
        typed in -700.0f64..700.0,
    ) {
        let scale = SCALES[s];
        let range = RawRange::new(lo, lo + span);
        let step_value = scale.decode(raw);
        // What users type: a number with at most three decimals.
        let typed = (typed * 1000.0).round() / 1000.0;
        for value in [
            step_value,
            step_value + fraction * scale.as_f64(),
            arbitrary,
            typed,
        ] {
            check_decimal(value, scale, range)?;
        }
    }

    #[test]
    fn a_relative_value_is_sent_as_given_or_refused(
        full in prop::sample::select(vec![1000.0f64, 8192.0, 30000.0]),
        reference in 500u32..4000,
        raw in 0i64..=65535,
        fraction in -1.5f64..1.5,
        typed in 0.0f64..500.0,
    ) {
        // A maximum frequency as the drive holds it: 50.0 .. 400.0 Hz in 0.1 Hz.
        let reference = f64::from(reference) / 10.0;
        let range = RawRange::word(false);
        let step = reference / full;
        let typed = (typed * 100.0).round() / 100.0;
        let on_step = decode_relative(raw, full, reference);
        for value in [on_step, on_step + fraction * step, typed] {
            let max = range.max as f64 * reference / full;
            let in_range = (0.0..=max).contains(&value);
            let got = encode_relative_with("r", "n011", "Hz", value, full, reference, range, Rounding::Exact);
            match got {
                Ok(r) => prop_assert_eq!(decode_relative(r, full, reference), value),
                Err(ValueError::NotAStep { below, above, .. }) => {
                    prop_assert!(in_range);
                    prop_assert!(below < value && value < above, "{below} < {value} < {above}");
                }
                Err(ValueError::OutOfRange { .. } | ValueError::WordOverflow { .. }) => {
                    prop_assert!(!in_range)
                }
                Err(e) => prop_assert!(false, "unexpected {e}"),
            }
            let rounded = encode_relative_with("r", "n011", "Hz", value, full, reference, range, Rounding::Nearest);
            prop_assert_eq!(rounded.is_ok(), in_range, "{} in 0 ..= {}", value, max);
        }
    }
}

/// The issue's cases, by name.
#[test]
fn the_reported_values() {
    let tenth = Decimal::new(1, 1);
    let hz = RawRange::new(0, 4000);
    // 35.75 Hz to a register that counts 0.1 Hz.
    let e = exact(35.75, tenth, hz).unwrap_err();
    assert_eq!(
        e.to_string(),
        "r: 35.75 u is between 35.7 and 35.8 u; the register counts 0.1 u"
    );
    assert_eq!(nearest(35.75, tenth, hz), Ok(358));
    // n019 = 0.04 s (0.1 s steps, 0.0 ..= 6000.0 s): refused; rounded it is 0.
    let s = RawRange::new(0, 60000);
    assert!(matches!(
        exact(0.04, tenth, s),
        Err(ValueError::NotAStep { below, above, .. }) if below == 0.0 && above == 0.1
    ));
    assert_eq!(nearest(0.04, tenth, s), Ok(0));
    // -0.04 s is below the range: refused whether rounded or not.
    assert!(matches!(
        exact(-0.04, tenth, s),
        Err(ValueError::OutOfRange { .. })
    ));
    assert!(matches!(
        nearest(-0.04, tenth, s),
        Err(ValueError::OutOfRange { .. })
    ));
    // 6000.04 s is above it, though it rounds to the maximum.
    assert!(matches!(
        nearest(6000.04, tenth, s),
        Err(ValueError::OutOfRange { .. })
    ));
    // A ramp of 0.005 s to a register of 0.01 s: refused, not sent as 0.01 s.
    assert!(matches!(
        exact(0.005, Decimal::new(1, 2), s),
        Err(ValueError::NotAStep { .. })
    ));
}
