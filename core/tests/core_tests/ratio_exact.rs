//! Exact ratio scales ("60.0 Hz = 3600"): every legal value round-trips exactly through the
//! register plan, and every value strictly between two counts is refused naming the two counts
//! around it. A float implementation (`round(value × counts / equals)` with a tolerance) accepts
//! the `f64` next to a count and fails `between_counts_is_refused`.

use drivemap_core::plan::{Conversion, Ranges, RegisterPlan};
use drivemap_core::ratio::{Fraction, Ratio, encode_ratio_with};
use drivemap_core::register::{Access, RegisterInfo, Table};
use drivemap_core::scale::{Decimal, RawRange, Rounding, ValueError};
use drivemap_core::width::Width;
use proptest::prelude::*;

/// The ratios of the fixtures and shipped maps, and a few more: 3600 = 60.0 Hz, 16383 = 100 %,
/// 20000 = 100 %, 8192 = 50.0 Hz, 3 = 1 (a third per count), 7 = 0.35.
const RATIOS: [Ratio; 6] = [
    Ratio::new(3600, Decimal::new(600, 1)),
    Ratio::new(16383, Decimal::new(100, 0)),
    Ratio::new(20000, Decimal::new(100, 0)),
    Ratio::new(8192, Decimal::new(500, 1)),
    Ratio::new(3, Decimal::new(1, 0)),
    Ratio::new(7, Decimal::new(35, 2)),
];

fn plan(ratio: Ratio, range: RawRange, signed: bool) -> RegisterPlan {
    RegisterPlan::new(
        RegisterInfo {
            id: "frequency",
            name: "Frequency",
            param: None,
            address: 1,
            access: Access::ReadWrite,
            table: Table::Holding,
            source: "m.txt:1",
            width: Width::Word,
            broadcast_only: false,
        },
        "Hz",
        Conversion::Ratio {
            signed,
            ratio,
            range: Ranges::fixed(range),
        },
        range,
    )
}

fn word(raw: i64, signed: bool) -> u32 {
    if signed {
        u32::from(raw as i16 as u16)
    } else {
        raw as u32
    }
}

fn next_up(x: f64) -> f64 {
    if x == 0.0 {
        return f64::from_bits(1);
    }
    let bits = x.to_bits();
    f64::from_bits(if x > 0.0 { bits + 1 } else { bits - 1 })
}

fn next_down(x: f64) -> f64 {
    -next_up(-x)
}

fn range_of(signed: bool) -> RawRange {
    if signed {
        RawRange::new(-16384, 16383)
    } else {
        RawRange::new(0, 65535)
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// decode(encode(v)) == v for every legal v, and the raw value is the count.
    #[test]
    fn every_count_round_trips(which in 0..RATIOS.len(), signed: bool, pick in 0.0..1.0f64) {
        let (ratio, range) = (RATIOS[which], range_of(signed));
        let p = plan(ratio, range, signed);
        let raw = range.min + ((range.max - range.min) as f64 * pick) as i64;
        let value = p.decode_number(word(raw, signed), &()).unwrap();
        prop_assert_eq!(p.encode_number(value, &()), Ok(word(raw, signed)));
        // The exact value, typed as its fraction, is the same count.
        let exact = p.decode_exact(word(raw, signed), &()).unwrap().unwrap();
        prop_assert_eq!(exact, ratio.exact(raw));
        prop_assert_eq!(exact.to_f64(), value);
        prop_assert_eq!(p.encode_exact(exact, &()), Ok(word(raw, signed)));
    }

    /// Every value strictly between two counts is refused, naming exactly those two counts;
    /// [`Rounding::Nearest`] sends one of them.
    #[test]
    fn between_counts_is_refused(which in 0..RATIOS.len(), signed: bool, pick in 0.0..1.0f64, at in 0.0..1.0f64) {
        let (ratio, range) = (RATIOS[which], range_of(signed));
        let p = plan(ratio, range, signed);
        let raw = range.min + ((range.max - 1 - range.min) as f64 * pick) as i64;
        let (lo, hi) = (ratio.decode(raw), ratio.decode(raw + 1));
        for value in [next_up(lo), next_down(hi), lo + (hi - lo) * at] {
            if value <= lo || value >= hi {
                continue;
            }
            match p.encode_number(value, &()) {
                Err(ValueError::NotACount { below, ratio: named, .. }) => {
                    prop_assert_eq!(below, raw);
                    prop_assert_eq!(named, ratio);
                }
                other => prop_assert!(false, "{value} between {lo} and {hi}: {other:?}"),
            }
            let rounded = encode_ratio_with("f", "Hz", value, ratio, range, Rounding::Nearest);
            prop_assert!(rounded == Ok(raw) || rounded == Ok(raw + 1), "{rounded:?}");
            // Exactly: a fraction just above a count is no count either.
            let just_above = Fraction::new(
                ratio.exact(raw).num * 2 * ratio.exact(raw + 1).den + 1,
                ratio.exact(raw).den * 2 * ratio.exact(raw + 1).den,
            ).unwrap();
            let e = p.encode_exact(just_above, &());
            prop_assert!(matches!(e, Err(ValueError::NotACount { .. })), "{:?}", e);
        }
    }

    /// Values outside the range are refused as out of range, never as "between counts".
    #[test]
    fn outside_the_range_is_out_of_range(which in 0..RATIOS.len(), by in 1i64..1000) {
        let ratio = RATIOS[which];
        let range = RawRange::new(100, 3600);
        let p = plan(ratio, range, false);
        for raw in [range.min - by, range.max + by] {
            let value = ratio.decode(raw);
            let e = p.encode_number(value, &());
            prop_assert!(matches!(e, Err(ValueError::OutOfRange { .. })), "{:?}", e);
            let e = p.encode_exact(ratio.exact(raw), &());
            prop_assert!(matches!(e, Err(ValueError::OutOfRange { .. })), "{:?}", e);
        }
    }
}

#[test]
fn sixty_hertz_is_3600_and_the_error_names_both_neighbours() {
    let p = plan(RATIOS[0], RawRange::new(0, 3600), false);
    assert_eq!(p.encode_number(60.0, &()), Ok(3600));
    assert_eq!(p.encode_number(59.9, &()), Ok(3594));
    assert_eq!(p.decode_number(3599, &()), Ok(3599.0 / 60.0));
    let e = p.encode_number(59.99, &()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "frequency: 59.99 Hz is not a whole number of counts (the register counts 1/60 (≈0.016667) Hz); \
         the nearest legal values are 3599/60 (≈59.983333) and 60 Hz"
    );
    assert!(matches!(
        p.encode_number(60.0 + 1.0 / 60.0, &()),
        Err(ValueError::OutOfRange { .. })
    ));
}
