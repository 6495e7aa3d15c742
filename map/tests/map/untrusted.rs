//! Maps come from pull requests: loading one must not exhaust memory, overflow the stack or take
//! quadratic time, whatever its text. Huge inputs are generated here rather than committed.
//! Time bounds are generous "does not hang" limits for a debug build, not performance figures.

use drivemap_test_support::paths;

use std::time::{Duration, Instant};

use drivemap_map::{
    MAX_YAML_ALIAS_NODES as MAX_ALIAS_NODES, MAX_YAML_BYTES as MAX_MAP_BYTES,
    MAX_YAML_DEPTH as MAX_DEPTH,
};

fn load_str(name: &str, text: &str) -> Result<drivemap_map::Map, Vec<drivemap_map::Diagnostic>> {
    drivemap_map::Loader::new()
        .load_str(name, text)
        .map_err(|d| d.0)
}

/// Runs `f` on a thread with a 256 KiB stack: a recursion proportional to the input would
/// overflow it long before 100,000 levels.
fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(f)
        .unwrap()
        .join()
        .expect("no stack overflow or panic")
}

fn first_error(text: &str) -> String {
    let errs = load_str("m.yaml", text).expect_err("must be refused");
    errs[0].to_string()
}

#[test]
fn billion_laughs_is_refused_quickly() {
    // 9 levels of 9 aliases: 387 million scalars if expanded, 1.2 KB of text.
    let mut text = String::from(
        "a0: &a0 [\"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\"]\n",
    );
    for i in 1..10 {
        let refs = vec![format!("*a{}", i - 1); 9].join(", ");
        text.push_str(&format!("a{i}: &a{i} [{refs}]\n"));
    }
    assert!(text.len() < 1300, "{}", text.len());
    let started = Instant::now();
    let err = first_error(&text);
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "took {:?}",
        started.elapsed()
    );
    assert!(
        err.contains("YAML alias `*a")
            && err.contains("anchor at m.yaml:")
            && err.contains(&MAX_ALIAS_NODES.to_string()),
        "{err}"
    );
}

#[test]
fn many_small_aliases_are_refused() {
    let mut text = String::from("a: &x 1\nb: [");
    text.push_str(&vec!["*x"; 2000].join(", "));
    text.push_str("]\n");
    let err = first_error(&text);
    assert!(
        err.contains("`*x`") && err.contains("at most 1000 aliases"),
        "{err}"
    );
}

#[test]
fn deep_flow_nesting_cannot_overflow_the_stack() {
    for (open, close) in [("[", "]"), ("{a: ", "}")] {
        let text = format!("{}{}", open.repeat(100_000), close.repeat(100_000));
        let started = Instant::now();
        let err = on_small_stack(move || first_error(&text));
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "took {:?}",
            started.elapsed()
        );
        // Either bound may trip first: ours, or the parser's own limit on flow keys.
        assert!(
            err.contains(&format!("deeper than {MAX_DEPTH} levels"))
                || err.contains("recursion limit exceeded"),
            "{err}"
        );
    }
}

#[test]
fn deep_block_nesting_cannot_overflow_the_stack() {
    let mut text = String::new();
    for i in 0..100_000 {
        text.push_str(&" ".repeat(i % 2));
        text.push_str("- ");
    }
    text.push_str("x\n");
    let err = on_small_stack(move || first_error(&text));
    assert!(err.contains("deeper than"), "{err}");
}

#[test]
fn unterminated_deep_nesting_reports_without_reparsing() {
    // A syntax error after 100,000 open brackets (500 KB): the error path used to re-parse the
    // whole text with a second parser (118 s).
    let text = "[".repeat(500_000);
    let started = Instant::now();
    let err = on_small_stack(move || first_error(&text));
    assert!(
        started.elapsed() < Duration::from_secs(20),
        "took {:?}",
        started.elapsed()
    );
    assert!(err.contains("m.yaml:1:"), "{err}");
}

#[test]
fn two_hundred_thousand_keys_load_in_linear_time() {
    let mut text = String::from("drive:\n");
    for i in 0..200_000 {
        text.push_str(&format!("  k{i}: 1\n"));
    }
    text.push_str("  k17: 2\n");
    let started = Instant::now();
    let err = first_error(&text);
    let took = started.elapsed();
    eprintln!("200k keys: {took:?}");
    assert!(took < Duration::from_secs(20), "took {took:?}");
    assert!(
        err.contains("m.yaml:200002:3") && err.contains("duplicate key `k17`"),
        "{err}"
    );
}

#[test]
fn a_file_over_the_size_limit_is_refused_before_parsing() {
    let text = format!("drive: {}\n", "x".repeat(MAX_MAP_BYTES));
    let err = first_error(&text);
    assert!(
        err.contains("m.yaml:1:1") && err.contains("at most 4194304 bytes"),
        "{err}"
    );
    let dir = std::env::temp_dir().join(format!("drivemap-untrusted-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.yaml");
    std::fs::write(&path, &text).unwrap();
    let err = drivemap_map::Loader::new()
        .load(&path)
        .expect_err("refused")
        .0[0]
        .to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        err.contains("huge.yaml:1:1") && err.contains("at most 4194304 bytes"),
        "{err}"
    );
}

#[test]
fn a_second_document_is_an_error_at_its_line() {
    let err = first_error("drive: {id: a}\n---\ndrive: {id: b}\n");
    assert!(
        err.starts_with("m.yaml:2:1: error: a second YAML document"),
        "{err}"
    );
}

#[test]
fn every_shipped_map_is_within_the_limits() {
    for map in drivemap_map::find_maps(&paths::maps()).unwrap() {
        let len = std::fs::metadata(&map).unwrap().len() as usize;
        assert!(len * 4 < MAX_MAP_BYTES, "{} is {len} bytes", map.display());
        drivemap_map::Loader::new()
            .load(&map)
            .unwrap_or_else(|e| panic!("{e:?}"));
    }
}

/// Addresses and codes are decided from their raw text (`crate::hex`): a megabyte of digits, an
/// address anchored and aliased ten thousand times, or a hex string that overflows are refused
/// with short messages, without a panic.
#[test]
fn hostile_addresses_are_refused_briefly() {
    let long = format!("address: {}\n", "9".repeat(1 << 20));
    let err = on_small_stack(move || first_error(&long));
    assert!(
        err.len() < 200 && err.contains("digits"),
        "{}",
        &err[..err.len().min(300)]
    );
    // An alias would carry a decimal resolved elsewhere into an address: refused where it stands
    // in schema 2 (schema 1, where a bare number is decimal anyway, read the anchored value:
    // `drivemap_map::schema`).
    for (text, at) in [
        ("x: &a 2001\ny: {address: *a}\n", "m.yaml:3:14"),
        ("x: &p [0x10, 20]\ngaps: [{addresses: *p}]\n", "m.yaml:3:20"),
        (
            "x: &c 16\nprotocol: {function_codes: [0x03, *c]}\n",
            "m.yaml:3:35",
        ),
    ] {
        let err = first_error(&format!("schema: 2\n{text}"));
        assert!(err.starts_with(at), "{err}");
        assert!(err.contains("where an address or code goes"), "{err}");
    }
    let huge_hex = "address: 0x1FFFFFFFFFFFFFFFFFFFFFFFF\n";
    assert!(!first_error(huge_hex).is_empty());
}
