//! Review's word on a map's notations: the protocol warnings of `drivemap check` and the Markdown
//! reference's rendering of a decimal manual's addresses.

use drivemap_test_support::paths;

fn mini_drive() -> String {
    std::fs::read_to_string(paths::fixture("crafted/maps/mini-drive.yaml")).unwrap()
}

/// The slave range is the manual's: 01H-FEH is recorded as printed (not refused for exceeding the
/// serial-line specification's 247); a range starting at 0, the broadcast address, is refused.
#[test]
fn slave_ranges_are_recorded_as_the_manual_prints_them() {
    let text = mini_drive();
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("slave_address:"))
        .expect("the fixture has a slave range");
    let indent = &line[..line.len() - line.trim_start().len()];
    let with = |range: &str| text.replace(line, &format!("{indent}slave_address: {range}"));
    let drive = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &with("{min: 1, max: 254}"))
        .expect("01H-FEH is valid");
    assert_eq!(drive.protocol().slave_address.max, Some(254));
    // Not refused, but a word about the serial-line specification's 247, at the range.
    // (The fixture's uncited protocol numbers have warnings of their own: `protocol_stated`.)
    let about_247 = |d: &drivemap_map::Map| {
        drivemap_review::review::protocol_warnings(d)
            .into_iter()
            .filter(|w| w.message.contains("serial-line specification"))
            .collect::<Vec<_>>()
    };
    let warnings = about_247(&drive);
    assert_eq!(warnings.len(), 1);
    let w = warnings[0].to_string();
    assert!(w.starts_with("mini-drive.yaml:19:"), "{w}");
    assert!(
        w.contains("warning: slave addresses 248..=254 are the manual's, but the Modbus serial-line specification reserves 248-255"),
        "{w}"
    );
    let standard = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &with("{min: 1, max: 247}"))
        .unwrap();
    assert!(about_247(&standard).is_empty());
    let e = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &with("{min: 0, max: 31}"))
        .unwrap_err();
    assert!(e.to_string().contains("0 is broadcast"), "{e}");
}

/// The reference document shows a decimal manual's numbers as printed, with their hex, and a hex
/// manual's as hex.
#[test]
fn the_reference_prints_addresses_in_the_manuals_notation() {
    let text = mini_drive();
    let first = "        address: 0x0001\n";
    assert!(text.contains(first), "the fixture's first register moved");
    let declared = format!(
        "address_format: decimal\n{}",
        text.replace(first, "        address: 2001\n")
    );
    let d = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &declared)
        .unwrap();
    let doc = drivemap_review::reference::render(&d, "mini-drive.yaml");
    assert!(doc.contains("| 2001 (07D1h) |"), "{doc}");
    let hex = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap();
    assert!(drivemap_review::reference::render(&hex, "mini-drive.yaml").contains("| 0001h |"));
}
