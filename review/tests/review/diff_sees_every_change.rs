//! `drivemap diff` cannot miss a part of a map: every map of `maps/` (the directory is read, so a
//! new map is covered with no edit here) and every fixture map is mutated value by value — each
//! scalar changed (a number moved by one, a flag flipped, a citation moved one line, an enumerated
//! word replaced by another of its kind, an identifier or a text extended), each mapping entry
//! and list item deleted — and every mutation that validation accepts and that changes what the
//! map says must show in the diff, in both directions.
//!
//! "What the map says" is the map as it writes it (`Map::written`: the expanded map, every key
//! named) with each register's effective access, table, write restriction, transports, repeat
//! rule and function codes: deleting `access: rw` from a register whose group gives `rw`, or a
//! variant's `min` equal to the base's, says nothing new, and is counted apart as a no-op.
//!
//! Every key path is mutated: each path with its list indices taken out (`groups[].registers[]
//! .scale`, `roles.run[].field`, `protocol.exceptions[].code`) at its first occurrence, and
//! outside `groups` also at its last, so the run stays short on a map of 1,300 registers (each
//! mutation reads and validates the whole map).

use drivemap_test_support::paths;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use drivemap_map::Map;
use drivemap_map::facts::parse_citation;
use drivemap_map::{Tree as Node, TreeKind as NodeKind};
use drivemap_review::diff::compare;
use serde_yaml::Value;

/// One step of a path into the map's tree: a key of a mapping or an item of a list.
#[derive(Debug, Clone)]
enum Seg {
    Key(String),
    Index(usize),
}

/// The tree's own path for `path`.
fn tree_path(path: &[Seg]) -> drivemap_map::TreePath {
    path.iter()
        .fold(drivemap_map::TreePath::root(), |p, s| match s {
            Seg::Key(k) => p.key(k),
            Seg::Index(i) => p.index(*i),
        })
}

fn root() -> PathBuf {
    paths::workspace().to_path_buf()
}

/// The maps mutated: every map of `maps/`, then the fixture maps.
fn maps() -> Vec<PathBuf> {
    let mut out = drivemap_map::find_maps(&paths::maps()).unwrap();
    assert!(out.len() >= 5, "maps/ holds {} maps", out.len());
    for dir in [
        "tests/fixtures/acme-vf1",
        "tests/fixtures/tarrow-tm44",
        "tests/fixtures/orbis-q5",
        "tests/fixtures/halvard-hx2",
        "tests/fixtures/brenner-fx4",
        "tests/fixtures/halden-h1",
        "tests/fixtures/borealis-bf6",
        "tests/fixtures/crafted/maps",
        "tests/fixtures/crafted/maps/variants",
        "tests/fixtures/crafted/cli",
    ] {
        out.extend(drivemap_map::find_maps(&root().join(dir)).unwrap());
    }
    out
}

/// What a map says, as one comparable value: every part and every register key as the map
/// writes it ([`Map::written`], which names every field of the expanded map and of the
/// schema's register), registers with the keys they take from their group applied, and a
/// variant's limit or default that restates the base's left out.
fn meaning(d: &Map) -> serde_json::Value {
    let mut written = serde_json::to_value(d.written()).expect("the written map as JSON");
    for r in written["registers"].as_array_mut().expect("registers") {
        let r = r.as_object_mut().expect("a register");
        let Some(by_variant) = r.get("by_variant").and_then(|v| v.as_object()) else {
            continue;
        };
        // A variant's limit or default that restates the base's says nothing new.
        let restated: Vec<(String, &str)> = by_variant
            .iter()
            .flat_map(|(variant, o)| {
                let o = o.as_object().expect("a variant override");
                ["min", "max", "default"]
                    .into_iter()
                    .filter(|key| o.get(*key).is_some_and(|v| Some(v) == r.get(*key)))
                    .map(move |key| (variant.clone(), key))
            })
            .collect();
        let by_variant = r["by_variant"].as_object_mut().expect("by_variant");
        for (variant, key) in restated {
            by_variant[&variant]
                .as_object_mut()
                .expect("a variant override")
                .remove(key);
        }
    }
    written
}

/// Whether two meanings are the same text: the values equal (quick to refuse, the common
/// case) and written the same (the text also tells key order and `-0.0` from `0.0` apart).
fn same_meaning(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    let text = |v| serde_json::to_string(v).expect("a meaning as text");
    a == b && text(a) == text(b)
}

/// One edit of a tree.
#[derive(Debug, Clone)]
enum Mutation {
    /// Replace the scalar at the path.
    Set(Value),
    /// Delete the mapping entry or list item at the path.
    Delete,
}

/// Words a key takes from a closed list: a mutation picks another of the list.
fn domain(key: &str) -> Option<&'static [&'static str]> {
    Some(match key {
        "access" => &["r", "w", "rw"],
        "modbus_table" => &["holding", "input"],
        "write_restriction" => &["none", "stopped", "prg_mode"],
        "parities" | "parity" | "default_parity" => &["none", "even", "odd"],
        "transports" => &["rtu", "tcp"],
        "kind" => &["accept", "persist"],
        "order" => &["high_first", "low_first"],
        "address_format" => &["hex", "decimal"],
        "direction" => &["request", "response"],
        "depends_on" => &[
            "capacity",
            "control_method",
            "variant",
            "setting",
            "unknown",
        ],
        "what" => &[
            "range", "default", "unit", "scale", "signed", "values", "fields", "access",
        ],
        _ => return None,
    })
}

fn is_identifier(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_lowercase())
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

/// The changed value of a scalar written under `key`.
fn changed(key: &str, v: &Value) -> Option<Value> {
    Some(match v {
        Value::Bool(b) => Value::Bool(!b),
        Value::Number(n) => {
            if let Some(u) = n.as_u64() {
                Value::from(u + 1)
            } else if let Some(i) = n.as_i64() {
                Value::from(i + 1)
            } else {
                let f = n.as_f64()?;
                // A scale of 0.1 becomes 1 (limits stay whole increments); others move by one.
                Value::from(if f != 0.0 && f.abs() < 1.0 {
                    f * 10.0
                } else {
                    f + 1.0
                })
            }
        }
        Value::String(s) => {
            if let Some(words) = domain(key) {
                let i = words.iter().position(|w| w == s).unwrap_or(0);
                Value::from(words[(i + 1) % words.len()])
            } else if let Some((file, line)) = parse_citation(s) {
                Value::from(format!("{file}:{}", line + 1))
            } else if let Some((id, page)) = s
                .rsplit_once(":p")
                .and_then(|(id, p)| Some((id, p.parse::<u32>().ok()?)))
            {
                Value::from(format!("{id}:p{}", page + 1))
            } else if is_identifier(s) {
                Value::from(format!("{s}_x"))
            } else {
                Value::from(format!("{s} (x)"))
            }
        }
        Value::Null => Value::from(1),
        _ => return None,
    })
}

/// Every path of the tree with the key its value is written under (a list item's key is its
/// list's), in document order.
fn paths(node: &Node, at: &mut Vec<Seg>, key: &str, out: &mut Vec<(Vec<Seg>, String, bool)>) {
    match &node.kind {
        NodeKind::Scalar(_) => out.push((at.clone(), key.to_owned(), true)),
        NodeKind::Seq(items) => {
            for (i, item) in items.iter().enumerate() {
                at.push(Seg::Index(i));
                out.push((at.clone(), key.to_owned(), false));
                paths(item, at, key, out);
                at.pop();
            }
        }
        NodeKind::Map(entries) => {
            for (k, _, v) in entries {
                at.push(Seg::Key(k.clone()));
                out.push((at.clone(), k.clone(), false));
                paths(v, at, k, out);
                at.pop();
            }
        }
    }
}

/// The path with list indices taken out: `groups[].registers[].scale`.
fn abstract_path(path: &[Seg]) -> String {
    path.iter()
        .map(|s| match s {
            Seg::Key(k) => format!(".{k}"),
            Seg::Index(_) => "[]".to_owned(),
        })
        .collect()
}

fn show(path: &[Seg]) -> String {
    tree_path(path).to_string()
}

/// `tree` with `m` applied at `path`; `None` when the path is not there.
fn mutate(tree: &Node, path: &[Seg], m: &Mutation) -> Option<Node> {
    let mut tree = tree.clone();
    let (last, parent) = path.split_last()?;
    let mut node = &mut tree;
    for seg in parent {
        node = match (seg, &mut node.kind) {
            (Seg::Key(k), NodeKind::Map(entries)) => {
                &mut entries.iter_mut().find(|(key, _, _)| key == k)?.2
            }
            (Seg::Index(i), NodeKind::Seq(items)) => items.get_mut(*i)?,
            _ => return None,
        };
    }
    match (last, &mut node.kind, m) {
        (Seg::Key(k), NodeKind::Map(entries), Mutation::Delete) => {
            entries.retain(|(key, _, _)| key != k)
        }
        (Seg::Index(i), NodeKind::Seq(items), Mutation::Delete) => {
            items.remove(*i);
        }
        (Seg::Key(k), NodeKind::Map(entries), Mutation::Set(v)) => {
            entries.iter_mut().find(|(key, _, _)| key == k)?.2.kind = NodeKind::Scalar(v.clone())
        }
        (Seg::Index(i), NodeKind::Seq(items), Mutation::Set(v)) => {
            items.get_mut(*i)?.kind = NodeKind::Scalar(v.clone())
        }
        _ => return None,
    }
    Some(tree)
}

#[derive(Default, Debug)]
struct Counts {
    tried: usize,
    rejected: usize,
    no_op: usize,
    accepted: usize,
    shown: usize,
}

/// Mutates one map; returns its counts and the mutations the diff did not show.
fn mutate_map(map: &Path) -> (Counts, Vec<String>) {
    let mut missed = Vec::new();
    let dir = map.parent().unwrap().to_path_buf();
    let base = move |id: &str| {
        let path = dir.join(format!("{id}.yaml"));
        let text = std::fs::read_to_string(&path).ok()?;
        Some((path.display().to_string(), text))
    };
    let name = map.file_name().unwrap().to_string_lossy().into_owned();
    let text = std::fs::read_to_string(map).unwrap();
    let file: Arc<str> = Arc::from(name.as_str());
    let tree = drivemap_map::parse_map(&file, &text).unwrap();
    // One loader for every edit of the map: a variant's base is parsed once.
    let loader = drivemap_map::Loader::new().cached().bases(&base);
    let read = |tree: Node| loader.load_tree(&name, tree);
    let original = read(tree.clone()).unwrap_or_else(|e| panic!("{name}: {e}"));
    let original_meaning = meaning(&original);
    assert!(
        compare(&original, &original).changes.is_empty(),
        "{name} differs from itself"
    );

    let mut all = Vec::new();
    paths(&tree, &mut Vec::new(), "", &mut all);
    // The first occurrence of each path in the registers, the first and the last elsewhere.
    let mut by_path: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, (p, _, _)) in all.iter().enumerate() {
        by_path.entry(abstract_path(p)).or_default().push(i);
    }
    let mut chosen: Vec<usize> = Vec::new();
    for (ap, list) in &by_path {
        chosen.push(list[0]);
        if !ap.starts_with(".groups[]") {
            chosen.push(list[list.len() - 1]);
        }
    }
    chosen.sort_unstable();
    chosen.dedup();

    let mut counts = Counts::default();
    for i in chosen {
        let (path, key, scalar) = &all[i];
        let mut mutations = vec![Mutation::Delete];
        if *scalar {
            let NodeKind::Scalar(v) = &tree.at(&tree_path(path)).unwrap().kind else {
                unreachable!()
            };
            if let Some(v) = changed(key, v) {
                mutations.push(Mutation::Set(v));
            }
        }
        for m in mutations {
            let Some(edited) = mutate(&tree, path, &m) else {
                continue;
            };
            counts.tried += 1;
            let Ok(drive) = read(edited) else {
                counts.rejected += 1;
                continue;
            };
            if same_meaning(&meaning(&drive), &original_meaning) {
                counts.no_op += 1;
                continue;
            }
            counts.accepted += 1;
            let forward = compare(&original, &drive);
            let backward = compare(&drive, &original);
            if !forward.changes.is_empty() && !backward.changes.is_empty() {
                counts.shown += 1;
            } else {
                missed.push(format!(
                    "{name}: {} {m:?}: no change shown ({} forward, {} backward)",
                    show(path),
                    forward.changes.len(),
                    backward.changes.len()
                ));
            }
        }
    }
    (counts, missed)
}

#[test]
fn every_mutation_check_accepts_shows_in_the_diff() {
    let started = std::time::Instant::now();
    // `MUTATE_ONLY=<part of a path>` mutates the maps it names (then the total check fails).
    let only = std::env::var("MUTATE_ONLY").ok();
    let maps: Vec<PathBuf> = maps()
        .into_iter()
        .filter(|m| {
            only.as_ref()
                .is_none_or(|o| m.to_string_lossy().contains(o.as_str()))
        })
        .collect();
    // The maps share out among the cores (each mutation reads and validates a whole map).
    let next = std::sync::atomic::AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(maps.len().max(1));
    let mut results: Vec<(usize, Counts, Vec<String>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(map) = maps.get(i) else { break };
                        let (counts, missed) = mutate_map(map);
                        done.push((i, counts, missed));
                    }
                    done
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
    results.sort_by_key(|r| r.0);
    let mut total = Counts::default();
    let mut missed = Vec::new();
    let mut report = Vec::new();
    for (i, counts, m) in results {
        let name = maps[i].file_name().unwrap().to_string_lossy().into_owned();
        report.push(format!(
            "{name}: {} tried, {} rejected by check, {} no-op, {} accepted, {} shown",
            counts.tried, counts.rejected, counts.no_op, counts.accepted, counts.shown
        ));
        total.tried += counts.tried;
        total.rejected += counts.rejected;
        total.no_op += counts.no_op;
        total.accepted += counts.accepted;
        total.shown += counts.shown;
        missed.extend(m);
    }
    report.push(format!(
        "all maps: {} mutations tried, {} rejected by check, {} no-op, {} accepted, {} shown by diff ({:.1} s, {threads} threads)",
        total.tried,
        total.rejected,
        total.no_op,
        total.accepted,
        total.shown,
        started.elapsed().as_secs_f64()
    ));
    println!("{}", report.join("\n"));
    assert!(
        missed.is_empty(),
        "{} accepted mutation(s) the diff does not show:\n{}\n\n{}",
        missed.len(),
        missed.join("\n"),
        report.join("\n")
    );
    assert_eq!(total.accepted, total.shown);
    assert!(total.accepted > 1000, "{}", report.join("\n"));
}
