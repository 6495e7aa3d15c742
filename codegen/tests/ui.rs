//! Malformed maps and the errors they must produce: `tests/ui/<name>.yaml` beside
//! `tests/ui/<name>.stderr`. Run with `DRIVEMAP_BLESS=1` to rewrite the expected files after an
//! intended change, then review the diff.

use std::path::Path;

use drivemap_codegen::validate::Context;

#[test]
fn malformed_maps_report_their_errors() {
    let dir = Path::new("tests/ui");
    let maps = drivemap_codegen::find_maps(dir).expect("tests/ui exists");
    assert!(
        maps.len() >= 20,
        "expected at least 20 malformed maps, found {}",
        maps.len()
    );
    let bless = std::env::var_os("DRIVEMAP_BLESS").is_some();
    let mut failures = Vec::new();
    for map in &maps {
        let expected_path = map.with_extension("stderr");
        let actual = match drivemap_codegen::read_map(map, &Context::default()) {
            Ok(_) => format!("{} unexpectedly passed validation\n", map.display()),
            Err(diags) => format!("{diags}\n"),
        };
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

/// The slave range is the manual's: 01H-FEH is recorded as printed (not refused for exceeding the
/// serial-line specification's 247); a range starting at 0, the broadcast address, is refused.
#[test]
fn slave_ranges_are_recorded_as_the_manual_prints_them() {
    let text = std::fs::read_to_string("tests/fixtures/mini-drive.yaml").unwrap();
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("slave_address:"))
        .expect("the fixture has a slave range");
    let indent = &line[..line.len() - line.trim_start().len()];
    let with = |range: &str| text.replace(line, &format!("{indent}slave_address: {range}"));
    let drive = drivemap_codegen::read_map_str(
        "mini-drive.yaml",
        &with("{min: 1, max: 254}"),
        &Context::default(),
    )
    .expect("01H-FEH is valid");
    assert_eq!(drive.protocol.slave_address.max, 254);
    let e = drivemap_codegen::read_map_str(
        "mini-drive.yaml",
        &with("{min: 0, max: 31}"),
        &Context::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("0 is broadcast"), "{e}");
}
