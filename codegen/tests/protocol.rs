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

/// `max_read`/`max_write` take a plain number, `{value, source}` or `{value, unknown: <why>}`;
/// the runtime uses the value, the reference and the export say which is not printed and why.
#[test]
fn a_limit_not_printed_keeps_its_value_and_says_why() {
    let text = fixture().replace(
        "  max_read: 8\n  max_write: 8\n",
        "  max_read: {value: 8, unknown: \"no limit printed; 8 is its own frame\", source: \"manual.txt:18\"}\n  max_write: {value: 4, source: \"manual.txt:19\"}\n",
    );
    assert_ne!(text, fixture(), "the fixture's limits moved");
    let drive =
        drivemap_codegen::read_map_str("mini-drive.yaml", &text, &Context::default()).unwrap();
    let plan = lower::lower(&drive);
    assert_eq!((plan.profile.max_read, plan.profile.max_write), (8, 4));
    let md = drivemap_codegen::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains(
            "at most 8 per read, 4 per write. max_read 8 not printed: no limit printed; 8 is its own frame (`manual.txt:18`). max_write (`manual.txt:19`)"
        ),
        "{md}"
    );
    let json = drivemap_codegen::export::export(&drive);
    assert_eq!(json["protocol"]["max_read"], 8);
    let l = &json["protocol"]["limits"]["max_read"];
    assert_eq!(l["not_printed"], "no limit printed; 8 is its own frame");
    assert_eq!(l["source"], "manual.txt:18");
    assert_eq!(
        json["protocol"]["limits"]["max_write"]["source"],
        "manual.txt:19"
    );
    // A plain number: no `limits` in the export.
    let plain =
        drivemap_codegen::read_map_str("mini-drive.yaml", &fixture(), &Context::default()).unwrap();
    assert!(
        drivemap_codegen::export::export(&plain)["protocol"]
            .get("limits")
            .is_none()
    );
    // The value is required: an unknown limit still needs a working number.
    let e = drivemap_codegen::read_map_str(
        "mini-drive.yaml",
        &fixture().replace(
            "  max_read: 8\n",
            "  max_read: {unknown: \"not printed\"}\n",
        ),
        &Context::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("missing field `value`"), "{e}");
}
