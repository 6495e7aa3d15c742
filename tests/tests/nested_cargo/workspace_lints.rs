//! The workspace's lints hold everywhere: every member inherits them (`[lints] workspace = true`),
//! neither the workspace nor the two crates outside it (`fuzz/`, `tests/no-std-drive/`) allows
//! a lint wholesale, and every `allow` attribute left in the sources says why, in a comment on
//! its line or right above it.

use drivemap_test_support::paths;

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    paths::workspace().to_path_buf()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The lines of the TOML tables whose header satisfies `wanted`, with their line numbers
/// (comments and blank lines left out).
fn table_lines(text: &str, wanted: impl Fn(&str) -> bool) -> Vec<(usize, String)> {
    let mut inside = false;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.starts_with('[') {
            inside = wanted(line);
        } else if inside && !line.is_empty() && !line.starts_with('#') {
            out.push((i + 1, line.to_owned()));
        }
    }
    out
}

#[test]
fn every_member_inherits_the_workspace_lints() {
    let out = Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--no-deps",
            "--offline",
            "--format-version",
            "1",
        ])
        .arg("--manifest-path")
        .arg(root().join("Cargo.toml"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo prints JSON");
    let packages = meta["packages"].as_array().expect("a package list");
    assert!(packages.len() > 10, "{} members", packages.len());
    let mut wrong = Vec::new();
    for p in packages {
        let manifest = PathBuf::from(p["manifest_path"].as_str().expect("a manifest path"));
        let lints = table_lines(&read(&manifest), |h| h.starts_with("[lints"));
        let inherits = lints
            .iter()
            .map(|(_, l)| l.replace(' ', ""))
            .collect::<Vec<_>>()
            == ["workspace=true"];
        if !inherits {
            wrong.push(format!("{}: [lints] is {lints:?}", manifest.display()));
        }
    }
    assert!(
        wrong.is_empty(),
        "members whose lints are not exactly `[lints] workspace = true`:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn no_lint_is_allowed_wholesale() {
    let mut found = Vec::new();
    for (manifest, header) in [
        ("Cargo.toml", "[workspace.lints"),
        ("fuzz/Cargo.toml", "[lints"),
        ("tests/no-std-drive/Cargo.toml", "[lints"),
    ] {
        let text = read(&root().join(manifest));
        let lints = table_lines(&text, |h| h.starts_with(header));
        assert!(
            lints
                .iter()
                .any(|(_, l)| l.replace(' ', "") == "unsafe_code=\"deny\""),
            "{manifest}: no `unsafe_code = \"deny\"` among {lints:?}"
        );
        for (n, line) in lints {
            if line.contains("allow") {
                found.push(format!("{manifest}:{n}: {line}"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "lints allowed for a whole crate or workspace:\n{}",
        found.join("\n")
    );
}

/// Every `.rs` file under `dir`, build output and dependencies left out.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.expect("a directory entry").path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if path.is_dir() {
            if !matches!(name.as_ref(), "target" | ".git" | "node_modules") {
                sources(&path, out);
            }
        } else if name.ends_with(".rs") {
            out.push(path);
        }
    }
}

/// Whether line `i` (an attribute allowing a lint) has a plain `//` comment after it on the same
/// line, or in the run of comment and attribute lines right above it.
fn says_why(lines: &[&str], i: usize) -> bool {
    let plain = |l: &str| l.starts_with("//") && !l.starts_with("///") && !l.starts_with("//!");
    if let Some(after) = lines[i].split_once(")]").map(|(_, rest)| rest.trim())
        && plain(after)
    {
        return true;
    }
    for line in lines[..i].iter().rev().map(|l| l.trim()) {
        if plain(line) {
            return true;
        }
        if !(line.starts_with("//") || line.starts_with("#[") || line.starts_with("#![")) {
            return false;
        }
    }
    false
}

#[test]
fn every_allow_attribute_says_why() {
    let mut files = Vec::new();
    sources(&root(), &mut files);
    assert!(files.len() > 100, "{} source files", files.len());
    let mut seen = 0;
    let mut silent = Vec::new();
    for file in &files {
        let text = read(file);
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            // The needles are built, so that this file does not find itself.
            let attribute = ["allow", "expect"].iter().any(|kind| {
                let call = format!("{kind}(");
                line.contains(&format!("#[{call}"))
                    || line.contains(&format!("#![{call}"))
                    || (line.contains("#[cfg_attr(") && line.contains(&call))
            });
            if !attribute {
                continue;
            }
            seen += 1;
            if !says_why(&lines, i) {
                let name = file.strip_prefix(root()).unwrap_or(file).display();
                silent.push(format!("{name}:{}: {}", i + 1, line.trim()));
            }
        }
    }
    assert!(
        seen > 10,
        "only {seen} allow attributes found: is the walk right?"
    );
    assert!(
        silent.is_empty(),
        "allow attributes without a `//` comment saying why (on the line or right above):\n{}",
        silent.join("\n")
    );
}
