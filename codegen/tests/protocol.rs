//! Protocol figures a manual states in its own terms: a frame gap in milliseconds
//! (`timing.frame_gap: {ms: ..}`), carried through lowering into `core::profile::Timing` and
//! into the Markdown reference.

use drivemap_codegen::lower;
use drivemap_codegen::validate::Context;

fn fixture() -> String {
    std::fs::read_to_string("tests/fixtures/mini-drive.yaml").unwrap()
}

fn with_frame_gap(text: &str) -> String {
    let timing = "  timing:\n";
    assert!(text.contains(timing), "the fixture's timing moved");
    text.replace(
        timing,
        "  timing:\n    frame_gap: {ms: 10, source: \"manual.txt:17\"}\n",
    )
}

#[test]
fn a_frame_gap_in_ms_is_lowered_into_the_profile_timing() {
    let text = with_frame_gap(&fixture());
    let drive =
        drivemap_codegen::read_map_str("mini-drive.yaml", &text, &Context::default()).unwrap();
    let plan = lower::lower(&drive);
    assert_eq!(plan.profile.timing.frame_gap_us, Some(10_000));
    assert_eq!(plan.profile.timing.frame_gap_chars, 3.5);
    // Without it, none.
    let plain =
        drivemap_codegen::read_map_str("mini-drive.yaml", &fixture(), &Context::default()).unwrap();
    assert_eq!(lower::lower(&plain).profile.timing.frame_gap_us, None);
    // The reference's timing row states it with its citation.
    let md = drivemap_codegen::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains("frame gap 3.5 characters, at least 10 ms (`manual.txt:17`)"),
        "{md}"
    );
    // The export carries it as written.
    let json = drivemap_codegen::export::export(&drive);
    assert_eq!(json["protocol"]["timing"]["frame_gap"]["ms"], 10.0);
    assert_eq!(
        json["protocol"]["timing"]["frame_gap"]["source"],
        "manual.txt:17"
    );
}
