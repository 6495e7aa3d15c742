//! `repeat_needs_change` and `read_values` (issue 13, ACN requests 4 and 5) from the map through
//! lowering into the plan, the Markdown reference and the export, on the fixture map (its
//! `memory` group gives the rule to both of its registers; `password` reads as codes).

use drivemap_test_support::paths;

use drivemap_core::plan::{Label, RepeatNeedsChange};

fn fixture() -> String {
    std::fs::read_to_string(paths::fixture("crafted/maps/mini-drive.yaml")).unwrap()
}

fn read(text: &str) -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn both_are_lowered_into_the_plan() {
    let drive = read(&fixture());
    let plan = drive.plan();
    let row = |id: &str| plan.register(id).unwrap_or_else(|| panic!("{id}"));
    let rule = Some(RepeatNeedsChange {
        between: 0,
        source: "manual.txt:50",
    });
    // The group's rule reaches both of its registers, and no other.
    assert_eq!(row("password").repeat_needs_change, rule);
    assert_eq!(row("clear_history").repeat_needs_change, rule);
    assert_eq!(row("max_frequency").repeat_needs_change, None);
    assert_eq!(
        row("password").read_values,
        &[
            Label {
                code: 0,
                id: "unlocked",
                name: "Unlocked"
            },
            Label {
                code: 1,
                id: "locked",
                name: "Locked"
            }
        ]
    );
    assert_eq!(
        row("password").read_label(1).map(|l| l.name),
        Some("Locked")
    );
    assert!(row("clear_history").read_values.is_empty());
    // The read meaning does not change how a write encodes: the word, 0-9999.
    assert_eq!(row("password").encode_word(1234, &()), Ok(1234));
    assert!(row("password").encode_word(10000, &()).is_err());
}

/// `between` is in engineering units: a scaled register's intermediate is lowered to its raw
/// word, a signed one's to two's complement.
#[test]
fn the_intermediate_is_lowered_to_its_raw_word() {
    let text = fixture()
        .replace(
            "        default: 60.0\n        source: \"manual.txt:40\"",
            "        default: 60.0\n        repeat_needs_change: {between: 50.5, source: \"manual.txt:40\"}\n        source: \"manual.txt:40\"",
        );
    assert_ne!(text, fixture(), "the fixture's max_frequency moved");
    let drive = read(&text);
    let plan = drive.plan();
    assert_eq!(
        plan.register("max_frequency").unwrap().repeat_needs_change,
        Some(RepeatNeedsChange {
            between: 505,
            source: "manual.txt:40"
        })
    );
}

#[test]
fn the_reference_and_the_export_show_both() {
    let drive = read(&fixture());
    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains("| 0200h |  | Lock password | `password` | read/write<br>repeat needs a change: 0 between |  | written as a word, read as codes (below) | 0 ..= 9999 |"),
        "{md}"
    );
    assert!(
        md.contains("Read and written with different meanings: a write takes the word (range in the table above); a read means:\n\n| Code | Id | Meaning | Source |\n|---|---|---|---|\n| 0 | `unlocked` | Unlocked | `manual.txt:51` |\n| 1 | `locked` | Locked | `manual.txt:51` |"),
        "{md}"
    );
    assert!(
        md.contains("Repeat needs a change: a value is executed only when it differs from the previous write, so 0 is written before any other value (`manual.txt:50`)."),
        "{md}"
    );
    let json = drive.export();
    let regs = json["registers"].as_array().unwrap();
    let password = regs.iter().find(|r| r["id"] == "password").unwrap();
    assert_eq!(password["read_values"][1]["name"], "Locked");
    assert_eq!(password["repeat_needs_change"]["between"], 0.0);
    assert_eq!(password["repeat_needs_change"]["between_raw"], 0);
    assert_eq!(password["repeat_needs_change"]["source"], "manual.txt:50");
    let max = regs.iter().find(|r| r["id"] == "max_frequency").unwrap();
    assert!(max["repeat_needs_change"].is_null());
    assert_eq!(max["read_values"], serde_json::json!([]));
}
