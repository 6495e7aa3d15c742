//! The generated code of every shipped map reads as code: no line of it is longer than the
//! printer's width (100 characters, `generate::plan::WIDTH`), but for a comment (the manual's
//! prose in rustdoc) or a line holding one string literal and nothing that could go on another
//! line (`name: "…",`). Plan rows used to be single lines of up to 3,231 characters.

use drivemap_test_support::paths;

/// Whether a long line is one the printer cannot break: a comment or doc attribute, or one
/// `key: "literal"` (with at most a closing `}`, `)` or `,` after it).
fn unbreakable(line: &str) -> bool {
    let t = line.trim_start();
    if t.starts_with("//") || t.starts_with("#[doc") {
        return true;
    }
    let value = match t.split_once(": ") {
        Some((key, value)) if key.chars().all(|c| c.is_ascii_lowercase() || c == '_') => value,
        _ => t,
    };
    let Some(body) = value.strip_prefix('"') else {
        return false;
    };
    // The literal's end (its first unescaped quote); after it only closing punctuation.
    let mut escaped = false;
    let Some(end) = body.char_indices().find_map(|(i, c)| match c {
        _ if escaped => {
            escaped = false;
            None
        }
        '\\' => {
            escaped = true;
            None
        }
        '"' => Some(i),
        _ => None,
    }) else {
        return false;
    };
    body[end + 1..]
        .chars()
        .all(|c| matches!(c, ',' | ')' | '}' | ' ' | ';'))
}

#[test]
fn no_generated_line_is_longer_than_the_width_but_a_string_or_a_comment() {
    let mut config = drivemap_codegen::Config::new();
    let maps = drivemap_map::find_maps(&paths::maps()).unwrap();
    assert!(maps.len() >= 5, "{maps:?}");
    for map in &maps {
        config.map(map);
    }
    config.cargo_directives(false);
    let code = config.generate().unwrap();
    let width = drivemap_codegen::generate::LINE_WIDTH;
    assert_eq!(width, 100);
    let mut checked = 0;
    for m in &code.modules {
        for (n, line) in m.source.lines().enumerate() {
            checked += 1;
            assert!(
                line.chars().count() <= width || unbreakable(line),
                "{}:{}: {} characters:\n{line}",
                m.file_name,
                n + 1,
                line.chars().count()
            );
        }
    }
    assert!(checked > 20_000, "{checked} lines");
}

#[test]
fn the_check_tells_a_long_row_from_a_long_string() {
    assert!(unbreakable(
        "            name: \"a name longer than anything, the manual's own words\","
    ));
    assert!(unbreakable("    /// prose of the manual"));
    assert!(!unbreakable(
        "        /* 0 */ RegisterPlan::word(RegisterInfo { id: \"a\", name: \"b\", address: 0x0001 }),"
    ));
    assert!(!unbreakable("            name: \"x\", lsb: 0, width: 1,"));
    assert!(!unbreakable(
        "            \"Hz\", Conversion::Decimal { signed: false }, source: \"m.txt:1\" },"
    ));
}
