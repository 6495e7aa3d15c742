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
