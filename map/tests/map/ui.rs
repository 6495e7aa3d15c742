//! Malformed maps and the errors they must produce: `tests/fixtures/crafted/errors/<name>.yaml`
//! beside `<name>.stderr`, the paths in it written from the workspace root. Run with `DRIVEMAP_BLESS=1` to rewrite the expected files after an
//! intended change, then review the diff.

use drivemap_test_support::paths;

#[test]
fn malformed_maps_report_their_errors() {
    let dir = &paths::fixture("crafted/errors");
    let maps = drivemap_map::find_maps(dir).expect("tests/fixtures/crafted/errors exists");
    assert!(
        maps.len() >= 20,
        "expected at least 20 malformed maps, found {}",
        maps.len()
    );
    let bless = std::env::var_os("DRIVEMAP_BLESS").is_some();
    let mut failures = Vec::new();
    for map in &maps {
        let expected_path = map.with_extension("stderr");
        let actual = match drivemap_map::Loader::new().load(map) {
            Ok(_) => format!("{} unexpectedly passed validation\n", map.display()),
            Err(diags) => format!("{diags}\n"),
        };
        // Where the repository is checked out is not part of the expected output.
        let actual = actual.replace(&format!("{}/", paths::workspace().display()), "");
        if bless {
            std::fs::write(&expected_path, &actual).unwrap();
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        if expected != actual {
            failures.push(format!(
                "--- {} expected:\n{expected}--- actual:\n{actual}",
                expected_path.display()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Addresses and codes are read in the manual's notations (`0x2001`, `2001H`, `2001h`, quoted or
/// not) as hexadecimal; a map whose manual numbers registers in decimal says so with
/// `address_format: decimal`, and then `address: 2001` is register 2001 (07D1H).
#[test]
fn addresses_are_read_in_the_manuals_notation() {
    let text = std::fs::read_to_string(paths::fixture("crafted/maps/mini-drive.yaml")).unwrap();
    let first = "        address: 0x0001\n";
    assert!(text.contains(first), "the fixture's first register moved");
    let read = |text: &str| {
        drivemap_map::Loader::new()
            .load_str("mini-drive.yaml", text)
            .map(|d| {
                let r = d.registers().find(|r| r.id() == "command").unwrap();
                (r.address(), d.protocol().exceptions[0].code)
            })
            .map_err(|e| e.to_string())
    };
    let hex_exception = text.replace("{code: 0x21,", "{code: 21h,");
    for written in ["2001H", "2001h", "\"0x2001\"", "'2001H'"] {
        let map = hex_exception.replace(first, &format!("        address: {written}\n"));
        assert_eq!(read(&map), Ok((0x2001, 0x21)), "{written}");
    }
    let decimal = text.replace(first, "        address: 2001\n");
    let e = read(&decimal).unwrap_err();
    assert!(e.contains("mini-drive.yaml:42:18"), "{e}");
    assert!(e.contains("address 2001 is decimal (07D1H)"), "{e}");
    let declared = format!("address_format: decimal\n{decimal}");
    assert_eq!(read(&declared), Ok((2001, 0x21)));
    // Hex notations stay hex in a decimal map; a wrong format value is refused by name.
    let both = declared.replace("address: 0x0900", "address: 900H");
    assert_eq!(read(&both), Ok((2001, 0x21)));
    let wrong = format!("address_format: octal\n{text}");
    let e = read(&wrong).unwrap_err();
    assert!(e.contains("unknown variant `octal`"), "{e}");
    // The export says how the manual numbers registers (the reference document's rendering is
    // checked in `review/tests/review/notation.rs`).
    let d = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &declared)
        .unwrap();
    let export = d.export();
    assert_eq!(export["drive"]["address_format"], "decimal");
    let hex = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap();
    assert_eq!(hex.export()["drive"]["address_format"], "hex");
}
