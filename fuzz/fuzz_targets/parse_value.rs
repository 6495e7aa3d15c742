//! The CLI's value parser (`drivemap write reg=<text>`) over every register of a shipped map:
//! the first byte picks the register, the second the variant and selector codes, the rest is
//! the text typed. It must return a word or an error, never panic.
#![no_main]

use std::sync::LazyLock;

use drivemap_map::{Loader, Map};
use drivemap_live::LiveSettings;
use libfuzzer_sys::fuzz_target;

static DRIVES: LazyLock<Vec<Map>> = LazyLock::new(|| {
    [
        ("ptlk-tds-v8.yaml", include_str!("../../maps/ptlk-tds-v8.yaml")),
        ("yaskawa-v7.yaml", include_str!("../../maps/yaskawa-v7.yaml")),
    ]
    .iter()
    .map(|(name, text)| {
        Loader::new().load_str(name, text).expect("shipped map")
    })
    .collect()
});

fuzz_target!(|data: &[u8]| {
    let [pick, knobs, rest @ ..] = data else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let drive = &DRIVES[usize::from(*knobs & 1)];
    let Some(r) = drive.register_at(usize::from(*pick) * drive.registers().len() / 256) else {
        return;
    };
    let mut settings = LiveSettings::default();
    if knobs & 2 != 0 {
        for axis in drive.variants() {
            let option = &axis.options[usize::from(*knobs >> 4) % axis.options.len()];
            settings.variants.insert(axis.id.clone(), option.id.clone());
        }
        for s in drive.selectors() {
            settings.selectors.insert(s.id().to_owned(), u16::from(*knobs >> 2));
        }
        for q in drive.references() {
            settings.references.insert(q.id().to_owned(), f64::from(*pick) * 0.5);
        }
    }
    let _ = drivemap_live::codec::parse_value(drive, r, text, &settings);
});
