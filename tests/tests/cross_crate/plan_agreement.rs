//! The generated drive modules and the run-time interpreter (`drivemap-live`, used by the CLI and
//! the simulator) mean the same thing by every register of every shipped map.
//!
//! Both sides convert with the one implementation in `drivemap-core` (`RegisterPlan`), so what
//! can drift is the data and the settings: this test checks that
//! 1. the plan the generator printed (`<module>::REGISTERS`, `PROFILE`) equals, row by row, the
//!    plan the interpreter lowers from the YAML at run time;
//! 2. the generated `Settings` (typed fields filled by `DriveSettings::absorb`) and the
//!    interpreter's `LiveSettings` (keyed by name) answer every conversion alike: for random
//!    variants, selector codes, reference words and external quantities, every register decodes
//!    random words to the same values and encodes random values (and the values it decoded) to
//!    the same words, or refuses them with the same error.
//!
//! The drives come from the generated `for_each_drive!` list, and every `maps/*.yaml` must be in
//! it, so a new map is covered with no edit here.

use drivemap_test_support::paths;

use std::cell::RefCell;
use std::path::PathBuf;

use drivemap_drives::runtime::core::plan::SettingsView;
use drivemap_drives::runtime::core::plan::{Conversion, RegisterPlan};
use drivemap_drives::runtime::core::profile::Profile;
use drivemap_drives::runtime::core::register::DriveSettings;
use drivemap_live::LiveSettings;
use drivemap_live::codec::Value;
use drivemap_map::RegisterRef;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// The maps the drives crate is generated from: `maps/`.
fn maps_dir() -> PathBuf {
    paths::maps()
}

/// The generated settings seen with the variants and external quantities this case chose
/// (typed fields the test cannot name generically); codes and register quantities come from
/// the generated `absorb` and `SettingsView` themselves.
struct Typed<'a, S> {
    settings: &'a S,
    variants: &'a [u8],
    externals: &'a [Option<f64>],
}

impl<S: SettingsView> SettingsView for Typed<'_, S> {
    fn code(&self, slot: u8) -> Option<u16> {
        self.settings.code(slot)
    }
    fn quantity(&self, slot: u8) -> Option<f64> {
        match self.externals.get(usize::from(slot)) {
            Some(Some(v)) => Some(*v),
            _ => self.settings.quantity(slot),
        }
    }
    fn variant(&self, axis: u8) -> u8 {
        self.variants[usize::from(axis)]
    }
}

fn same_number(a: &Result<f64, String>, b: &Result<f64, String>) -> bool {
    match (a, b) {
        (Ok(x), Ok(y)) => x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
        (Err(x), Err(y)) => x == y,
        _ => false,
    }
}

/// What the interpreter decoded, as the number the generated code gives for the same word.
fn live_number(plan: &RegisterPlan, value: Result<Value, String>) -> Result<f64, String> {
    Ok(match value? {
        Value::Word(i) => i as f64,
        Value::Quantity { value, .. } => value,
        Value::Code { code, .. } => f64::from(code),
        Value::Bit(on) => f64::from(u8::from(on)),
        // `codec::decode` of one raw value refuses a string, so this is never reached.
        Value::Text(_) => return Err(format!("{}: text from one raw value", plan.info.id)),
        Value::Bits { raw, .. } => match plan.conversion {
            Conversion::Bits { mask, .. } => f64::from(raw & mask),
            _ => {
                return Err(format!(
                    "{}: bits value of a non-bit register",
                    plan.info.id
                ));
            }
        },
    })
}

/// What the generated code reads from a word: a number, a code, or the bits the map defines.
fn generated_number(
    plan: &RegisterPlan,
    raw: u32,
    settings: &impl SettingsView,
) -> Result<f64, String> {
    if plan.info.table.is_bits() {
        // A coil or discrete input: the generated `bool` is `raw != 0`.
        return Ok(f64::from(u8::from(raw != 0)));
    }
    match plan.conversion {
        Conversion::Enum { .. } => Ok(f64::from(raw as u16)),
        Conversion::Bits { mask, .. } => Ok(f64::from(raw as u16 & mask)),
        _ => plan.decode_number(raw, settings).map_err(|e| e.to_string()),
    }
}

#[derive(Debug, Clone)]
struct Case {
    variants: Vec<u8>,
    dependencies: Vec<u16>,
    externals: Vec<Option<f64>>,
    /// Raw values: words, or a 32-bit pair's joined words (a one-word register reads the low
    /// word, on both sides).
    raws: Vec<u32>,
    values: Vec<f64>,
}

fn case_strategy(axes: &[usize], dependencies: usize, quantities: usize) -> BoxedStrategy<Case> {
    let variants = axes
        .iter()
        .map(|&n| (0..n as u8).boxed())
        .collect::<Vec<_>>();
    let value = prop_oneof![
        -1000.0f64..70000.0,
        (-10i64..70000).prop_map(|v| v as f64),
        (-5_000_000_000i64..5_000_000_000).prop_map(|v| v as f64),
        Just(f64::NAN),
        Just(f64::INFINITY),
        (0u16..16).prop_map(f64::from),
    ];
    (
        variants,
        prop::collection::vec(
            prop_oneof![0u16..8, any::<u16>(), 100u16..30000],
            dependencies,
        ),
        prop::collection::vec(prop::option::of(0.1f64..1000.0), quantities),
        prop::collection::vec(
            prop_oneof![any::<u16>().prop_map(u32::from), any::<u32>()],
            3,
        ),
        prop::collection::vec(value, 3),
    )
        .prop_map(|(variants, dependencies, externals, raws, values)| Case {
            variants,
            dependencies,
            externals,
            raws,
            values,
        })
        .boxed()
}

fn agree<S: DriveSettings + SettingsView + Default>(
    id: &str,
    registers: &'static [RegisterPlan],
    profile: &Profile,
) {
    let path = maps_dir().join(format!("{id}.yaml"));
    let live = drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let plan = live.plan();

    // 1. The printed plan is the lowered plan.
    assert_eq!(
        registers.len(),
        plan.registers.len(),
        "{id}: register count"
    );
    for (i, (generated, lowered)) in registers.iter().zip(plan.registers).enumerate() {
        assert_eq!(
            generated, lowered,
            "{id}: row {i} ({}) differs",
            lowered.info.id
        );
    }
    assert_eq!(*profile, *plan.profile, "{id}: profile differs");
    assert_eq!(
        S::DEPENDENCIES,
        LiveSettings::dependencies(&live).as_slice(),
        "{id}: settings dependencies"
    );

    // 2. Settings and conversions agree on random settings, words and values.
    let by_row: Vec<RegisterRef<'_>> = (0..plan.registers.len())
        .map(|row| {
            live.register_of_row(row)
                .expect("every row is a register's")
        })
        .collect();
    let axes: Vec<usize> = plan.settings.axes.iter().map(|(_, o)| o.len()).collect();
    let externals: Vec<Option<&str>> = plan
        .settings
        .quantities
        .iter()
        .map(|q| match q {
            drivemap_map::Quantity::External { id, .. } => Some(id.as_str()),
            drivemap_map::Quantity::Register(_) => None,
        })
        .collect();
    let strategy = case_strategy(&axes, S::DEPENDENCIES.len(), externals.len());
    let checked = RefCell::new(0usize);
    let mut runner = TestRunner::new(Config {
        cases: 48,
        failure_persistence: None,
        ..Config::default()
    });
    let result = runner.run(&strategy, |case| {
        let mut typed = S::default();
        let mut named = LiveSettings::default();
        for ((axis, options), &chosen) in plan.settings.axes.iter().zip(&case.variants) {
            named
                .variants
                .insert(axis.clone(), options[usize::from(chosen)].clone());
        }
        for (&address, &raw) in S::DEPENDENCIES.iter().zip(&case.dependencies) {
            let a = typed.absorb(address, raw);
            let b = named.absorb(&live, address, raw);
            prop_assert_eq!(a, b, "{}: absorb({:#06x}, {})", id, address, raw);
        }
        let external_values: Vec<Option<f64>> = externals
            .iter()
            .zip(&case.externals)
            .map(|(id, v)| id.and(*v))
            .collect();
        for (id, v) in externals.iter().zip(&external_values) {
            if let (Some(id), Some(v)) = (id, v) {
                named.references.insert((*id).to_owned(), *v);
            }
        }
        let view = Typed {
            settings: &typed,
            variants: &case.variants,
            externals: &external_values,
        };
        for (row, (generated, r)) in registers.iter().zip(&by_row).enumerate() {
            let mut values = case.values.clone();
            for &raw in &case.raws {
                let g = generated_number(generated, raw, &view);
                let l = live_number(
                    generated,
                    drivemap_live::codec::decode(&live, *r, raw, &named).map_err(|e| e.to_string()),
                );
                prop_assert!(
                    same_number(&g, &l),
                    "{}: row {} ({}) decodes {:#06x}: generated {:?}, interpreted {:?}",
                    id,
                    row,
                    generated.info.id,
                    raw,
                    g,
                    l
                );
                if let Ok(v) = g {
                    values.push(v);
                }
            }
            for &v in &values {
                let g = generated.encode_number(v, &view).map_err(|e| e.to_string());
                let l =
                    drivemap_live::codec::encode(&live, *r, v, &named).map_err(|e| e.to_string());
                prop_assert_eq!(
                    &g,
                    &l,
                    "{}: row {} ({}) encodes {}",
                    id,
                    row,
                    generated.info.id,
                    v
                );
                *checked.borrow_mut() += 1;
            }
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{id}: {e}");
    }
    assert!(
        *checked.borrow() >= 48 * registers.len(),
        "{id}: too few encodings compared"
    );
}

#[test]
fn generated_modules_and_the_interpreter_agree_on_every_shipped_map() {
    let mut covered = Vec::new();
    macro_rules! check {
        ($module:ident, $id:literal) => {
            agree::<drivemap_drives::$module::Settings>(
                $id,
                drivemap_drives::$module::REGISTERS,
                &drivemap_drives::$module::PROFILE,
            );
            covered.push($id.to_owned());
        };
    }
    drivemap_drives::for_each_drive!(check);

    let mut shipped: Vec<String> = std::fs::read_dir(maps_dir())
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "yaml").then(|| p.file_stem().unwrap().to_string_lossy().into())
        })
        .collect();
    shipped.sort();
    covered.sort();
    assert_eq!(
        covered, shipped,
        "every map of maps/ is generated and compared"
    );
}
