//! A bad map in a downstream `build.rs`: `drivemap_codegen::Config`'s error is the report
//! `drivemap check` prints for the same map, as its `Display` and as its `Debug` (what `?` in a
//! `main` that returns it prints), with no debug dump of its structure.

use crate::common;

use std::path::Path;

use common::command;
use drivemap_test_support::paths;

/// `drivemap check`'s error lines for `map` (stderr, without its closing summary).
fn check_lines(map: &Path) -> Vec<String> {
    let out = command()
        .arg("check")
        .arg(map)
        .output()
        .expect("run drivemap");
    assert!(!out.status.success(), "check accepted {}", map.display());
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| l.contains(": error"))
        .map(str::to_owned)
        .collect()
}

#[test]
fn a_bad_map_fails_the_build_with_checks_report() {
    let dir = paths::fixture("crafted/errors");
    let out = std::env::temp_dir().join(format!("drivemap-build-errors-{}", std::process::id()));
    let mut seen = 0;
    for name in [
        "e05-overlapping-addresses.yaml",
        "e02-unknown-key.yaml",
        "e01-yaml-syntax.yaml",
    ] {
        let map = dir.join(name);
        // A missing file would compare two "cannot read" reports.
        assert!(map.is_file(), "{} is missing", map.display());
        let expected = check_lines(&map);
        assert!(!expected.is_empty(), "{name}: check printed no error line");
        let e = drivemap_codegen::Config::new()
            .map(&map)
            .out_dir(&out)
            .cargo_directives(false)
            .compile()
            .expect_err(name);
        let shown = e.to_string();
        let lines: Vec<&str> = shown.lines().collect();
        let (count, findings) = lines.split_last().expect("a report");
        assert_eq!(findings, expected, "{name}: the build's report is check's");
        let n = expected.len();
        assert_eq!(
            *count,
            format!("{n} error{}", if n == 1 { "" } else { "s" })
        );
        // file:line:col first.
        let place = findings[0].split(": error").next().unwrap_or_default();
        let mut parts = place.rsplitn(3, ':');
        let (col, line, file) = (parts.next(), parts.next(), parts.next());
        assert!(
            file.is_some_and(|f| f.ends_with(name))
                && [line, col]
                    .iter()
                    .all(|n| n.is_some_and(|n| n.parse::<u32>().is_ok())),
            "{name}: file:line:col first: {}",
            findings[0]
        );
        // What `fn main() -> Result<(), Box<dyn Error>>` prints after `Error: `.
        let boxed: Box<dyn std::error::Error> = Box::new(e);
        assert_eq!(format!("{boxed:?}"), shown, "{name}: Debug is the report");
        seen += 1;
    }
    assert_eq!(seen, 3);
    let _ = std::fs::remove_dir_all(&out);
}
