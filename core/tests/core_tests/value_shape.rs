//! What the plan decides per kind of conversion, for the front ends that read it instead of
//! matching on the kind: the value's shape (`Conversion::shape`), the settings a conversion
//! reads (`Conversion::depends_on`), one count of a scale in force (`Scale::step`) and its
//! exact value (`Scale::exact`), each checked against what the conversion does: a wrong arm
//! for a kind fails here.

use drivemap_core::kind::ConversionKind;
use drivemap_core::plan::{
    Case, CaseScale, Conversion, Dependency, Field, Label, Ranges, RegisterPlan, Relative, Setting,
    SettingsView, ValueShape,
};
use drivemap_core::ratio::Ratio;
use drivemap_core::register::{Access, RegisterInfo};
use drivemap_core::scale::{Decimal, RawRange};
use drivemap_core::text::ByteOrder;
use proptest::prelude::*;

const SELECTOR: Setting = Setting {
    slot: 0,
    label: "n152",
};
const REFERENCE: Setting = Setting {
    slot: 1,
    label: "n011",
};
const LABELS: &[Label] = &[Label {
    code: 0,
    id: "stop",
    name: "Stop",
}];
const FIELDS: &[Field] = &[Field {
    id: "run",
    name: "Run",
    lsb: 0,
    width: 1,
    values: &[],
    source: "m.txt:3",
}];
const CASES: &[Case] = &[
    Case {
        codes: &[0],
        scale: CaseScale::Decimal {
            scale: Decimal::new(1, 2),
            range: RawRange::new(0, 40000),
        },
    },
    Case {
        codes: &[1, 2],
        scale: CaseScale::Relative(Relative {
            full_scale: 30000.0,
            reference: REFERENCE,
        }),
    },
];

/// One conversion of each kind there is today (a fixed list, not a match on the kinds: a new
/// kind's own arms are checked by `tests/tests/cross_crate/scale_kinds.rs` through the maps).
fn conversions(signed: bool) -> [Conversion; 8] {
    let range = Ranges::fixed(RawRange::word(signed));
    [
        Conversion::Word { signed, range },
        Conversion::Decimal {
            signed,
            scale: Decimal::new(1, 1),
            range,
        },
        Conversion::Relative {
            signed,
            relative: Relative {
                full_scale: 16384.0,
                reference: REFERENCE,
            },
        },
        Conversion::Ratio {
            signed,
            ratio: Ratio::new(3600, Decimal::new(600, 1)),
            range,
        },
        Conversion::Selected {
            signed,
            selector: SELECTOR,
            cases: CASES,
        },
        Conversion::Enum {
            values: LABELS,
            unlisted: None,
        },
        Conversion::Bits {
            mask: 1,
            fields: FIELDS,
        },
        Conversion::Text {
            order: ByteOrder::LowFirst,
        },
    ]
}

fn plan(conversion: Conversion) -> RegisterPlan {
    RegisterPlan::new(
        RegisterInfo {
            id: "value",
            name: "Value",
            address: 1,
            access: Access::ReadWrite,
            source: "m.txt:1",
            ..RegisterInfo::DEFAULT
        },
        "Hz",
        conversion,
        RawRange::word(false),
    )
}

/// The selector's code and the reference quantity, each known or not.
struct Settings {
    code: Option<u16>,
    quantity: Option<f64>,
}

impl SettingsView for Settings {
    fn code(&self, slot: u8) -> Option<u16> {
        (slot == SELECTOR.slot).then_some(self.code).flatten()
    }
    fn quantity(&self, slot: u8) -> Option<f64> {
        (slot == REFERENCE.slot).then_some(self.quantity).flatten()
    }
    fn variant(&self, _: u8) -> u8 {
        0
    }
}

#[test]
fn every_kind_has_the_shape_its_conversion_has() {
    for signed in [false, true] {
        for c in conversions(signed) {
            let kind = ConversionKind::of(&c);
            let p = plan(c);
            let known = Settings {
                code: Some(0),
                quantity: Some(60.0),
            };
            match c.shape() {
                ValueShape::Number => {
                    assert!(kind.is_scale(), "{kind:?}");
                    assert!(p.scale(&known).is_some(), "{kind:?}: a number has a scale");
                    assert_eq!(p.signed(), signed, "{kind:?}");
                }
                ValueShape::Word { signed: s } => {
                    assert_eq!(kind, ConversionKind::Word);
                    assert_eq!(s, signed);
                    assert!(p.scale(&known).is_none());
                }
                ValueShape::Codes(values) => {
                    assert_eq!(kind, ConversionKind::Enum);
                    assert_eq!(values, p.labels());
                    assert!(p.scale(&known).is_none());
                }
                ValueShape::Text { order } => {
                    assert_eq!(kind, ConversionKind::Text);
                    assert_eq!(order, ByteOrder::LowFirst);
                    assert!(p.scale(&known).is_none());
                    assert!(!p.signed());
                    // Text is not a number either way.
                    assert!(p.decode_number(0x4142, &known).is_err());
                    assert!(p.encode_word(0x4142, &known).is_err());
                }
                ValueShape::Bits { mask, fields } => {
                    assert_eq!(kind, ConversionKind::Bits);
                    assert_eq!((mask, fields), (1, FIELDS));
                    assert_eq!(p.write_rule().reserved, !mask);
                    assert!(p.scale(&known).is_none());
                }
            }
        }
    }
}

#[test]
fn a_conversion_reads_the_settings_its_scale_in_force_needs() {
    let all = |c: &Conversion, code: Option<u16>| {
        let mut out = Vec::new();
        c.depends_on(
            &Settings {
                code,
                quantity: None,
            },
            |d| out.push(d),
        );
        out
    };
    for c in conversions(false) {
        let kind = ConversionKind::of(&c);
        let (decimal_case, relative_case, unknown) =
            (all(&c, Some(0)), all(&c, Some(2)), all(&c, None));
        match c {
            Conversion::Selected { .. } => {
                assert_eq!(decimal_case, [Dependency::Code(SELECTOR)]);
                let both = [Dependency::Code(SELECTOR), Dependency::Quantity(REFERENCE)];
                assert_eq!(relative_case, both);
                assert_eq!(unknown, both);
            }
            Conversion::Relative { .. } => {
                assert_eq!(decimal_case, [Dependency::Quantity(REFERENCE)]);
            }
            _ => assert!(decimal_case.is_empty(), "{kind:?} reads {decimal_case:?}"),
        }
        // What it reports is what converting needs: without those settings the scale is
        // refused, with them it is in force.
        let p = plan(c);
        let none = Settings {
            code: None,
            quantity: None,
        };
        assert_eq!(
            unknown.is_empty(),
            !matches!(p.scale(&none), Some(Err(_))),
            "{kind:?}"
        );
        let labels: Vec<&str> = unknown.iter().map(|d| d.setting().label).collect();
        match c {
            Conversion::Selected { .. } => assert_eq!(labels, ["n152", "n011"]),
            Conversion::Relative { .. } => assert_eq!(labels, ["n011"]),
            _ => assert!(labels.is_empty(), "{kind:?}"),
        }
    }
}

proptest! {
    /// `Scale::step` is what one count adds in the scale in force, and `Scale::exact` the exact
    /// value of a ratio's count (none for the others).
    #[test]
    fn a_step_is_one_count_and_exact_only_for_a_ratio(
        raw in 0u32..30000,
        code in 0u16..3,
        reference in 1.0f64..1000.0,
    ) {
        let settings = Settings { code: Some(code), quantity: Some(reference) };
        for c in conversions(false) {
            let p = plan(c);
            let Some(Ok(scale)) = p.scale(&settings) else { continue };
            let one = p.decode_number(raw + 1, &settings).unwrap()
                - p.decode_number(raw, &settings).unwrap();
            let step = scale.step();
            prop_assert!(
                (one - step).abs() <= 1e-9 * step.abs().max(1.0),
                "{c:?}: one count {one}, step {step}"
            );
            let exact = scale.exact(p.int(raw));
            match c {
                Conversion::Ratio { .. } => {
                    prop_assert_eq!(exact, p.decode_exact(raw, &settings).unwrap());
                    prop_assert!(exact.is_some());
                }
                _ => prop_assert_eq!(exact, None),
            }
        }
    }
}
