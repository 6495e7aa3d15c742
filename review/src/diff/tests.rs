//! The classifier over crafted before/after maps: `tests/fixtures/crafted/diff/<case>.yaml`
//! lists text edits to `tests/fixtures/crafted/cli/example-drive.yaml` (the map of the command line's
//! golden tests) and the change kinds they must produce, no more and no fewer.

use std::path::PathBuf;

use drivemap_test_support::paths;

use serde::Deserialize;

use super::registers::range_change;
use super::*;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    /// Labels of the expected change kinds (`scale changed`), with repetition.
    expect: Vec<String>,
    /// The edits give the "before" map and the base is "after".
    #[serde(default)]
    swap: bool,
    /// Edits made to both sides first (a part the base map lacks, such as roles).
    #[serde(default)]
    common: Vec<Edit>,
    edits: Vec<Edit>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Edit {
    from: String,
    to: String,
}

fn fixtures() -> PathBuf {
    paths::fixture("crafted")
}

fn base() -> String {
    std::fs::read_to_string(paths::fixture("crafted/cli/example-drive.yaml")).unwrap()
}

/// Why a case failed, said in the test's failure message.
#[derive(Debug, PartialEq)]
enum CaseError {
    /// An edit's `from` text does not occur exactly once in the map.
    NotOnce { from: String, count: usize },
    /// A side of the case (`before`, `after`) does not validate: its diagnostics.
    Invalid { side: String, diagnostics: String },
    /// An `expect` label names no change kind.
    NoKind(String),
    /// The change kinds found are not the expected ones (the changes, as debug text).
    Kinds {
        want: Vec<ChangeKind>,
        got: Vec<ChangeKind>,
        changes: String,
    },
    /// A change lacks the citation of a side that exists, or cites one that does not.
    Citations { what: &'static str, change: String },
    /// Comparing a map with itself found changes.
    SelfDiff,
}

impl std::fmt::Display for CaseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CaseError::NotOnce { from, count } => {
                write!(f, "`{from}` occurs {count} times, not once")
            }
            CaseError::Invalid { side, diagnostics } => {
                write!(f, "the {side} map does not validate:\n{diagnostics}")
            }
            CaseError::NoKind(label) => write!(f, "no change kind labelled `{label}`"),
            CaseError::Kinds { want, got, changes } => {
                write!(f, "expected {want:?}, got {got:?}:\n{changes}")
            }
            CaseError::Citations { what, change } => {
                write!(f, "{what} citations missing or extra: {change}")
            }
            CaseError::SelfDiff => f.write_str("a map differs from itself"),
        }
    }
}

/// Reads a version of the example map from memory (no temporary files).
fn read(name: &str, text: &str) -> Result<Map, CaseError> {
    drivemap_map::Loader::new()
        .load_str("example-drive.yaml", text)
        .map_err(|d| CaseError::Invalid {
            side: name.to_owned(),
            diagnostics: d.to_string(),
        })
}

fn kind_of(label: &str) -> Result<ChangeKind, CaseError> {
    ChangeKind::ALL
        .iter()
        .find(|k| k.label() == label)
        .copied()
        .ok_or_else(|| CaseError::NoKind(label.to_owned()))
}

/// `text` with `edit` made where its `from` occurs, exactly once.
fn edit_once(text: &str, edit: &Edit) -> Result<String, CaseError> {
    match text.matches(edit.from.as_str()).count() {
        1 => Ok(text.replace(edit.from.as_str(), &edit.to)),
        count => Err(CaseError::NotOnce {
            from: edit.from.clone(),
            count,
        }),
    }
}

/// Runs one case; returns the kinds it produced, or what went wrong.
fn run(case: &Case) -> Result<Vec<ChangeKind>, CaseError> {
    let mut base = base();
    for e in &case.common {
        base = edit_once(&base, e)?;
    }
    let mut edited = base.clone();
    for e in &case.edits {
        edited = edit_once(&edited, e)?;
    }
    let (before, after) = if case.swap {
        (edited, base)
    } else {
        (base, edited)
    };
    let old = read("before", &before)?;
    let new = read("after", &after)?;
    let diff = compare(&old, &new);
    let mut got: Vec<ChangeKind> = diff.changes.iter().map(|c| c.kind).collect();
    let mut want = case
        .expect
        .iter()
        .map(|l| kind_of(l))
        .collect::<Result<Vec<_>, _>>()?;
    got.sort_by_key(|k| k.label());
    want.sort_by_key(|k| k.label());
    if got != want {
        return Err(CaseError::Kinds {
            want,
            got,
            changes: format!("{:#?}", diff.changes),
        });
    }
    for c in &diff.changes {
        let register_change = !matches!(
            c.subject.as_str(),
            "protocol" | "variants" | "roles" | "example-drive"
        );
        // Role changes cite each side that exists, as register changes do.
        if c.subject == "roles"
            && c.kind != ChangeKind::DocumentationChanged
            && (c.old_source.is_some() != (c.kind != ChangeKind::RoleAdded)
                || c.new_source.is_some() != (c.kind != ChangeKind::RoleRemoved))
        {
            return Err(CaseError::Citations {
                what: "role",
                change: format!("{c:?}"),
            });
        }
        // Register changes cite each side that exists.
        let old_exists = c.kind != ChangeKind::RegisterAdded;
        let new_exists = c.kind != ChangeKind::RegisterRemoved;
        if register_change
            && (c.old_source.is_some() != old_exists || c.new_source.is_some() != new_exists)
        {
            return Err(CaseError::Citations {
                what: "register",
                change: format!("{c:?}"),
            });
        }
    }
    if !compare(&new, &new).changes.is_empty() {
        return Err(CaseError::SelfDiff);
    }
    Ok(got)
}

#[test]
fn each_case_yields_exactly_its_changes_and_every_kind_has_a_case() {
    let dir = fixtures().join("diff");
    let mut covered = std::collections::HashSet::new();
    let mut cases = 0;
    let mut entries: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    entries.sort();
    let mut failures = Vec::new();
    for path in entries {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let case: Case = serde_yaml::from_str(&std::fs::read_to_string(&path).unwrap())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        match run(&case) {
            Ok(kinds) => covered.extend(kinds),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
        cases += 1;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(cases > 50, "only {cases} cases");
    // Drive added/removed are whole-map changes, exercised by `drivemap diff --git`.
    let missing: Vec<&str> = ChangeKind::ALL
        .iter()
        .filter(|k| !matches!(k, ChangeKind::DriveAdded | ChangeKind::DriveRemoved))
        .filter(|k| !covered.contains(k))
        .map(|k| k.label())
        .collect();
    assert!(
        missing.is_empty(),
        "change kinds without a case: {missing:?}"
    );
}

#[test]
fn scale_change_carries_both_citations_and_the_values() {
    let case = Case {
        expect: vec!["scale changed".into()],
        swap: false,
        common: Vec::new(),
        edits: vec![Edit {
            from: "scale: 0.1, min: 50.0".into(),
            to: "scale: 0.01, min: 50.0".into(),
        }],
    };
    assert_eq!(run(&case), Ok(vec![ChangeKind::ScaleChanged]));
    let old = read("before", &base()).unwrap();
    let new = read(
        "after",
        &base().replace("scale: 0.1, min: 50.0", "scale: 0.01, min: 50.0"),
    )
    .unwrap();
    let d = compare(&old, &new);
    assert_eq!(d.breaking(), 1);
    assert_eq!(d.compatible(), 0);
    let c = &d.changes[0];
    assert_eq!(c.subject, "max_frequency (P-01)");
    assert_eq!(c.old.as_deref(), Some("0.1 Hz"));
    assert_eq!(c.new.as_deref(), Some("0.01 Hz"));
    assert_eq!(c.old_source.as_deref(), Some("manual.txt:40"));
    assert_eq!(c.new_source.as_deref(), Some("manual.txt:40"));
    assert_eq!(c.severity(), Severity::Breaking);
}

#[test]
fn drives_added_and_removed() {
    let d = read("x", &base()).unwrap();
    let a = added(&d);
    assert_eq!(a.changes[0].kind, ChangeKind::DriveAdded);
    assert_eq!(a.breaking(), 0);
    let r = removed(&d);
    assert_eq!(r.changes[0].kind, ChangeKind::DriveRemoved);
    assert_eq!(r.breaking(), 1);
}

#[test]
fn ranges_narrow_or_widen() {
    let r = |a: (Option<f64>, Option<f64>), b| range_change(a, b);
    assert_eq!(
        r((Some(0.0), Some(10.0)), (Some(0.0), Some(5.0))),
        (true, false)
    );
    assert_eq!(
        r((Some(0.0), Some(10.0)), (Some(-1.0), Some(10.0))),
        (false, true)
    );
    assert_eq!(
        r((Some(0.0), Some(10.0)), (Some(1.0), Some(20.0))),
        (true, true)
    );
    assert_eq!(r((None, None), (Some(0.0), None)), (true, false));
    assert_eq!(r((Some(0.0), Some(1.0)), (None, None)), (false, true));
    assert_eq!(
        r((Some(0.0), Some(1.0)), (Some(0.0), Some(1.0))),
        (false, false)
    );
}

#[test]
fn conflicts_and_gaps_are_compared_entry_by_entry_with_their_citations() {
    let before = read("before", &base()).unwrap();
    let text = base()
        .replace(
            "description: Page missing from the OCR text",
            "description: Page torn out",
        )
        .replace("chosen: \"1-31\"", "chosen: \"1-32\"");
    let after = read("after", &text).unwrap();
    let d = compare(&before, &after);
    type Shown<'a> = (&'a str, Option<&'a str>, Option<&'a str>, Option<&'a str>);
    let shown: Vec<Shown<'_>> = d
        .changes
        .iter()
        .map(|c| {
            (
                c.what.as_str(),
                c.old.as_deref(),
                c.new.as_deref(),
                c.new_source.as_deref(),
            )
        })
        .collect();
    assert_eq!(
        shown,
        [
            (
                "conflict \"Slave address range\"",
                Some("chosen: 1-31"),
                Some("chosen: 1-32"),
                Some("manual.txt:10")
            ),
            (
                "gap 0024h – 002Fh",
                Some("Page missing from the OCR text"),
                Some("Page torn out"),
                Some("manual.txt:34")
            ),
        ]
    );
    assert!(
        d.changes
            .iter()
            .all(|c| c.severity() == Severity::Compatible)
    );
    let removed = compare(&before, &read("after", &base().replace("gaps:\n  - {addresses: [0x0024, 0x002F], params: \"U-05 .. U-16\", description: Page missing from the OCR text, source: \"manual.txt:34\"}\n", "")).unwrap());
    assert_eq!(removed.changes.len(), 1);
    assert_eq!(removed.changes[0].what, "gap 0024h – 002Fh removed");
    assert_eq!(
        removed.changes[0].old_source.as_deref(),
        Some("manual.txt:34")
    );
}
