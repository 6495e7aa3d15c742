//! Any text as a map: load → validate → export must return an error or a value, never panic,
//! overflow the stack or run away (libFuzzer's -rss_limit_mb and -timeout catch the latter).
#![no_main]

use drivemap_map::Loader;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(drive) = Loader::new().load_str("fuzz.yaml", text) {
        let json = drive.export();
        serde_json::to_string(&json).expect("export serializes");
        // A map that validates has only finite timing: serde_json writes a non-finite f64 as
        // null, which is how `frame_gap_chars: .inf` used to leave `export`.
        let timing = &json["protocol"]["timing"];
        assert!(
            timing.is_null() || timing["frame_gap_chars"].is_number(),
            "timing exported with a non-finite frame gap: {timing}"
        );
    }
});
