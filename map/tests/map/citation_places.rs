//! The one list of citation places (`Map::citation_places`) holds every `source:` key a map
//! writes: for every shipped map and every fixture, the `source` keys of the merged YAML tree
//! are exactly the places of the list that carry a citation, at the same path and with the same
//! text. A `source` key the list leaves out (a new construct, a forgotten place) fails here, and
//! so would every check that reads the list instead of walking the model.

use drivemap_test_support::paths;

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use drivemap_map::facts::PlaceKind;
use drivemap_map::{Tree as Node, TreeKind as NodeKind, TreePath as YamlPath};

/// Every scalar under a `source` key of the tree, by path.
fn tree_sources(node: &Node, at: &YamlPath, out: &mut BTreeMap<String, String>) {
    match &node.kind {
        NodeKind::Scalar(_) => {}
        NodeKind::Seq(items) => {
            for (i, item) in items.iter().enumerate() {
                tree_sources(item, &at.index(i), out);
            }
        }
        NodeKind::Map(entries) => {
            for (k, _, v) in entries {
                let here = at.key(k);
                if let (true, NodeKind::Scalar(value)) = (k == "source", &v.kind) {
                    let text = match value {
                        serde_yaml::Value::String(s) => s.clone(),
                        other => format!("{other:?}"),
                    };
                    out.insert(format!("{here:?}"), text);
                }
                tree_sources(v, &here, out);
            }
        }
    }
}

fn corpus() -> Vec<PathBuf> {
    let mut files = drivemap_map::find_maps(&paths::maps()).unwrap();
    for dir in std::fs::read_dir(paths::fixtures()).unwrap() {
        let dir = dir.unwrap().path();
        if dir.is_dir() {
            files.extend(drivemap_map::find_maps(&dir).unwrap());
            let schema1 = dir.join("schema-1");
            if schema1.is_dir() {
                files.extend(drivemap_map::find_maps(&schema1).unwrap());
            }
        }
    }
    let variants = paths::fixture("crafted/maps/variants");
    files.extend(drivemap_map::find_maps(&variants).unwrap());
    files.sort();
    files
}

#[test]
fn every_source_key_of_every_map_and_fixture_is_a_citation_place() {
    let files = corpus();
    assert!(files.len() >= 15, "{files:?}");
    let mut kinds_seen = BTreeSet::new();
    for file in &files {
        let drive = drivemap_map::Loader::new()
            .load(file)
            .unwrap_or_else(|d| panic!("{}: {d}", file.display()));
        let mut written = BTreeMap::new();
        tree_sources(drive.tree(), &YamlPath::root(), &mut written);
        let places = drive.citation_places();
        let mut listed: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for p in &places {
            kinds_seen.insert(p.kind.name());
            if let Some(s) = p.source {
                // A block's registers share their template's `source` key, each with its
                // own line.
                listed
                    .entry(format!("{:?}", p.path))
                    .or_default()
                    .insert(s.to_owned());
            }
            assert!(
                p.register.is_some() || !p.required,
                "{}: a required place outside a register",
                file.display()
            );
        }
        let missing: Vec<_> = written
            .iter()
            .filter(|(k, _)| !listed.contains_key(*k))
            .collect();
        assert!(
            missing.is_empty(),
            "{}: `source` keys with no citation place: {missing:#?}",
            file.display()
        );
        let extra: Vec<_> = listed
            .keys()
            .filter(|k| !written.contains_key(*k))
            .collect();
        assert!(
            extra.is_empty(),
            "{}: citation places where the map writes no `source`: {extra:#?}",
            file.display()
        );
        // The text as written (a block's template steps its line per register: the first
        // register's is the template's).
        for (path, text) in &written {
            if !text.contains('{') {
                assert!(
                    listed[path].contains(text),
                    "{}: the citation at {path}: written {text:?}, listed {:?}",
                    file.display(),
                    listed[path]
                );
            }
        }
    }
    // Each kind of place is written somewhere in the corpus, so the comparison above covers it.
    let all: BTreeSet<&str> = PlaceKind::NAMES.iter().copied().collect();
    let unseen: Vec<_> = all.difference(&kinds_seen).collect();
    assert!(
        unseen.is_empty(),
        "kinds of citation place no map or fixture writes: {unseen:?}"
    );
}

/// The form check reads the list: a citation place the old walk missed (`request_gap`,
/// `protocol.exceptions` written as `{unknown, source}`) is checked like every other, and a
/// register without a citation is named where the register is written.
#[test]
fn the_form_check_reads_every_place_of_the_list() {
    let map = |exceptions: &str, request_gap: &str, speed_source: &str| {
        format!(
            "drive: {{id: t, vendor: T, models: [T], manuals: [{{file: m.txt, title: M}}]}}\n\
             protocol:\n\
             \x20 transports: [rtu]\n\
             \x20 function_codes: [0x03]\n\
             \x20 max_read: 1\n\
             \x20 max_write: 1\n\
             \x20 slave_address: {{min: 1, max: 31}}\n\
             \x20 exceptions: {{unknown: \"none printed\", source: \"{exceptions}\"}}\n\
             \x20 timing: {{request_gap: {{ms: 10, source: \"{request_gap}\"}}}}\n\
             groups:\n\
             \x20 - id: g\n\
             \x20   name: G\n\
             \x20   registers:\n\
             \x20     - {{id: speed, name: Speed, access: r, address: 0x0001{speed_source}}}\n"
        )
    };
    let errors = |text: &str| match drivemap_map::Loader::new().load_str("t.yaml", text) {
        Ok(_) => Vec::new(),
        Err(d) => d.iter().map(|d| d.to_string()).collect::<Vec<_>>(),
    };
    assert_eq!(
        errors(&map("m.txt:1", "m.txt:2", ", source: \"m.txt:3\"")),
        Vec::<String>::new()
    );
    let bad = errors(&map("other.txt:1", "m.txt", ", source: \"m.txt:3\""));
    assert_eq!(bad.len(), 2, "{bad:#?}");
    assert!(
        bad[0].starts_with("t.yaml:8:")
            && bad[0].contains("citation `other.txt:1` names `other.txt`, which is not among"),
        "{bad:#?}"
    );
    assert!(
        bad[1].starts_with("t.yaml:9:")
            && bad[1].contains("citation `m.txt` is neither `file:line`"),
        "{bad:#?}"
    );
    let missing = errors(&map("m.txt:1", "m.txt:2", ""));
    assert_eq!(missing.len(), 1, "{missing:#?}");
    assert!(
        missing[0].starts_with("t.yaml:14:")
            && missing[0].contains("register `speed`")
            && missing[0].contains("missing citation"),
        "{missing:#?}"
    );
}

/// An example frame's citation (one line or a line range of a text manual) is checked in the
/// same loop, with the frame's id in the message.
#[test]
fn an_example_frame_cites_a_line_range_of_a_text_manual() {
    let map = |source: &str| {
        format!(
            "drive: {{id: t, vendor: T, models: [T], manuals: [{{file: m.txt, title: M}}, {{id: scan, title: S, document: \"S-1 rev. A\"}}]}}\n\
             protocol: {{transports: [rtu], function_codes: [0x03], max_read: 1, max_write: 1, slave_address: {{min: 1, max: 31}}}}\n\
             groups:\n\
             \x20 - {{id: g, name: G, registers: [{{id: speed, name: Speed, access: r, address: 0x0001, source: \"m.txt:1\"}}]}}\n\
             examples:\n\
             \x20 - {{id: ask, transport: rtu, direction: request, bytes: \"01 03 00 01 00 01 D5 CA\", source: \"{source}\"}}\n"
        )
    };
    let ctx = drivemap_map::Loader::new().manual_lines("m.txt", 20);
    let errors = |source: &str| match ctx.load_str("t.yaml", &map(source)) {
        Ok(_) => Vec::new(),
        Err(d) => d.iter().map(|d| d.to_string()).collect::<Vec<_>>(),
    };
    assert_eq!(errors("m.txt:3-5"), Vec::<String>::new());
    assert_eq!(errors("m.txt:7"), Vec::<String>::new());
    for (source, says) in [
        (
            "m.txt",
            "citation `m.txt` is not `file:line` or `file:first-last`",
        ),
        (
            "scan:p2",
            "citation `scan:p2` is not `file:line` or `file:first-last`",
        ),
        (
            "other.txt:2-3",
            "citation `other.txt:2-3` names `other.txt`, which is not a text manual of `drive.manuals`",
        ),
        ("m.txt:19-21", "citation `m.txt:19-21`: m.txt has 20 lines"),
    ] {
        let found = errors(source);
        assert_eq!(
            found,
            [format!("t.yaml:6:85: error: example `ask`: {says}")],
            "{source}"
        );
    }
}
