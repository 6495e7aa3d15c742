//! Every kind of conversion (`drivemap_core::kind::ConversionKind::ALL`; the scale kinds among them)
//! is used by a map of `maps/` or a fixture, and every printer shows it: the JSON export, the
//! Markdown reference of `drivemap doc`, the semantic diff, the wording of `describe` (through
//! the facts view) and the generated code (its rustdoc and its plan rows).
//!
//! A new kind of scale (a `Conversion` variant) needs a `ConversionKind` (`core/src/kind.rs`,
//! forced by `ConversionKind::of`), an arm in [`expected`] here (forced by the exhaustive match)
//! saying what each printer must show of it, and a register using it in a fixture map under
//! `tests/fixtures/` (else [`every_kind_is_used_by_a_map`] fails). See `core/README.md`,
//! "Adding a new kind of scale".

use drivemap_test_support::paths;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use drivemap_map::facts::{FactKey, RegisterFacts};
use drivemap_map::{Map, RegisterRef, describe};
use drivemap_runtime::core::kind::ConversionKind;

/// Every map of `maps/` and of each fixture directory `tests/fixtures/<drive>/` (read, so a new
/// fixture counts with no edit here).
fn maps() -> Vec<PathBuf> {
    let mut out = drivemap_map::find_maps(&paths::maps()).unwrap();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(paths::fixtures())
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    for d in dirs {
        out.extend(drivemap_map::find_maps(&d).unwrap());
    }
    out
}

fn read(path: &Path) -> Map {
    drivemap_map::Loader::new()
        .load(path)
        .unwrap_or_else(|d| panic!("{}: {d}", path.display()))
}

/// What the printers must show of a register of each kind: `export` checks its JSON entry;
/// `text` is words the Markdown reference and the rustdoc must contain; `diff` words the diff's
/// one-line summary of the register must contain.
struct Expected {
    export: fn(&serde_json::Value) -> bool,
    text: String,
    diff: Vec<String>,
}

fn expected(kind: ConversionKind, r: RegisterRef<'_>, f: &RegisterFacts) -> Expected {
    let plan = r.plan();
    let named = describe::kind(plan).to_owned();
    let scale_row = |key| {
        f.get(key)
            .unwrap_or_else(|| panic!("{}: {kind:?} without a {key:?} row", f.id))
            .value
            .clone()
    };
    // The diff's summary prints the map's scale, so a unit without one shows only the kind.
    let with_scale = |text: &String| {
        let mut d = vec![named.clone()];
        if r.scale().is_some() {
            d.push(text.clone());
        }
        d
    };
    match kind {
        ConversionKind::Word => Expected {
            export: |e| e["scale"] == 1.0 && e["values"] == serde_json::json!([]),
            text: describe::address(r.address()),
            diff: vec![named.clone()],
        },
        ConversionKind::Decimal => {
            let text = scale_row(FactKey::Scale);
            Expected {
                export: |e| e["scale"].is_number(),
                diff: with_scale(&text),
                text,
            }
        }
        ConversionKind::Relative => {
            let text = scale_row(FactKey::Scale);
            assert!(text.contains("= 100 % of"), "{}: {text}", f.id);
            Expected {
                export: |e| e["scale_relative_to"]["full_scale"].is_number(),
                diff: with_scale(&text),
                text,
            }
        }
        ConversionKind::Ratio => {
            let text = scale_row(FactKey::Scale);
            assert!(text.contains("per count, exact"), "{}: {text}", f.id);
            Expected {
                export: |e| {
                    e["scale"]["counts"].is_u64()
                        && e["scale"]["equals"].is_number()
                        && e["scale"]["step"].is_string()
                },
                diff: with_scale(&text),
                text,
            }
        }
        ConversionKind::Selected => {
            let text = scale_row(FactKey::SelectedBy);
            assert!(!f.cases.is_empty(), "{}: selected without cases", f.id);
            Expected {
                export: |e| {
                    e["scale_selected_by"].is_string()
                        && e["scale_cases"].as_array().is_some_and(|c| !c.is_empty())
                },
                diff: with_scale(&text),
                text,
            }
        }
        ConversionKind::Enum => Expected {
            export: |e| e["values"].as_array().is_some_and(|v| !v.is_empty()),
            text: r.values()[0].id.clone(),
            diff: vec![named.clone()],
        },
        ConversionKind::Bits => Expected {
            export: |e| e["fields"].as_array().is_some_and(|v| !v.is_empty()),
            text: r.fields()[0].id.clone(),
            diff: vec![named.clone()],
        },
        ConversionKind::Text => {
            let text = scale_row(FactKey::Width);
            assert!(text.starts_with("text in "), "{}: {text}", f.id);
            Expected {
                export: |e| {
                    e["string"]["registers"].as_u64() == e["words"].as_u64()
                        && e["string"]["byte_order"].is_string()
                        && e["scale"].is_null()
                },
                text,
                diff: vec![named.clone()],
            }
        }
    }
}

/// The registers of each kind in a drive, a few of each (the first three), with their facts.
fn by_kind(drive: &Map) -> BTreeMap<ConversionKind, Vec<(usize, RegisterFacts)>> {
    let mut out: BTreeMap<ConversionKind, Vec<(usize, RegisterFacts)>> = BTreeMap::new();
    for (i, r) in drive.registers().enumerate() {
        let f = r.facts();
        let list = out.entry(f.kind).or_default();
        if list.len() < 3 {
            list.push((i, f));
        }
    }
    out
}

#[test]
fn every_kind_is_used_by_a_map() {
    let mut seen = BTreeMap::new();
    for path in maps() {
        for kind in by_kind(&read(&path)).into_keys() {
            seen.entry(kind)
                .or_insert_with(|| path.display().to_string());
        }
    }
    let missing: Vec<_> = ConversionKind::ALL
        .iter()
        .filter(|k| !seen.contains_key(k))
        .collect();
    assert!(
        missing.is_empty(),
        "no map of maps/ or tests/fixtures/ uses {missing:?}: add a register of that kind to a fixture"
    );
}

#[test]
fn export_doc_and_generated_code_show_every_kind() {
    let mut checked = BTreeMap::<ConversionKind, usize>::new();
    for path in maps() {
        let drive = read(&path);
        let export = drive.export();
        let doc = drivemap_review::reference::render(&drive, "map.yaml");
        let code = drivemap_codegen::Config::new()
            .map(&path)
            .generate()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .modules
            .remove(0)
            .source;
        for (kind, list) in by_kind(&drive) {
            // A plain unsigned word without unit is generated as the shorthand
            // `RegisterPlan::word(..)` (Conversion::WORD), not a `Conversion::Word { .. }`.
            assert!(
                code.contains(&format!("Conversion::{} {{", kind.variant()))
                    || (kind == ConversionKind::Word && code.contains("RegisterPlan::word(")),
                "{}: generated plan has no Conversion::{}",
                drive.id(),
                kind.variant()
            );
            for (i, f) in list {
                let r = drive.register_at(i).expect("an index of the map");
                let e = expected(kind, r, &f);
                let entry = export["registers"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .find(|x| x["id"] == f.id.as_str())
                    .unwrap_or_else(|| panic!("{}: {} not exported", drive.id(), f.id));
                assert!(
                    (e.export)(entry),
                    "{}: export of {kind:?} register {} does not show it: {entry}",
                    drive.id(),
                    f.id
                );
                let shown = |text: &str, what: &str| {
                    let escaped = text
                        .replace('|', "\\|")
                        .replace('[', "\\[")
                        .replace(']', "\\]");
                    assert!(
                        what.contains(text) || what.contains(&escaped),
                        "{}: {kind:?} register {}: `{text}` missing",
                        drive.id(),
                        f.id
                    );
                };
                shown(&e.text, &doc);
                shown(&e.text, &code);
                *checked.entry(kind).or_default() += 1;
            }
        }
    }
    assert_eq!(
        checked.keys().copied().collect::<Vec<_>>(),
        ConversionKind::ALL,
        "every kind checked"
    );
}

/// A map with no registers: compared with it, every register of a map is removed.
fn no_registers() -> Map {
    let text = "schema: 2
drive:
  id: no-registers
  vendor: Example
  models: [NR-1]
  manuals:
    - {file: manual.txt, title: Example manual}
protocol:
  transports: [rtu]
  function_codes: [0x03, 0x06, 0x10]
  max_read: 8
  max_write: 8
  slave_address: {min: 1, max: 31}
groups: []
";
    let map = drivemap_map::Loader::new()
        .load_str("no-registers.yaml", text)
        .unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(map.registers().len(), 0);
    map
}

#[test]
fn the_diff_shows_every_kind() {
    let mut checked = BTreeMap::<ConversionKind, usize>::new();
    for path in maps() {
        let drive = read(&path);
        // Every register taken away: the diff sums each removed register up in one line.
        let diff = drivemap_review::diff::compare(&drive, &no_registers());
        for (kind, list) in by_kind(&drive) {
            for (i, f) in list {
                let r = drive.register_at(i).expect("an index of the map");
                let e = expected(kind, r, &f);
                let subject = r.label();
                let removed = diff
                    .changes
                    .iter()
                    .find(|c| {
                        c.kind == drivemap_review::diff::ChangeKind::RegisterRemoved
                            && c.subject == subject
                    })
                    .unwrap_or_else(|| {
                        panic!("{}: removing {} is not in the diff", drive.id(), f.id)
                    });
                let text = removed.old.as_deref().unwrap_or_default();
                for words in &e.diff {
                    assert!(
                        text.contains(words.as_str()),
                        "{}: the diff of {kind:?} register {} does not say `{words}`: {text}",
                        drive.id(),
                        f.id
                    );
                }
                *checked.entry(kind).or_default() += 1;
            }
        }
    }
    assert_eq!(
        checked.keys().copied().collect::<Vec<_>>(),
        ConversionKind::ALL,
        "every kind checked"
    );
}
