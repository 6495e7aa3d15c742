//! The semantic diff (`drivemap diff`, `drivemap_review::diff`) of two maps: the input is two
//! maps separated by a line `#---8<---`; when both validate, they are compared both ways and
//! rendered as text, Markdown and annotations. It must never panic.
#![no_main]

use drivemap_review::diff;
use drivemap_map::Loader;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Some((old, new)) = text.split_once("#---8<---\n") else {
        return;
    };
    let loader = Loader::new();
    let (Ok(old), Ok(new)) = (
        loader.load_str("old.yaml", old),
        loader.load_str("new.yaml", new),
    ) else {
        return;
    };
    let diffs = [diff::compare(&old, &new), diff::compare(&new, &old)];
    let _ = diff::render::text(&diffs, false);
    let _ = diff::render::markdown(&diffs, None);
    let _ = diff::render::github(&diffs, None);
    let _ = diff::render::json(&diffs, None);
    let same = diff::compare(&old, &old);
    assert_eq!(same.breaking() + same.compatible(), 0, "a map differs from itself");
});
