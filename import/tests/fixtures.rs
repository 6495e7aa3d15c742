//! `drivemap import` on fixture manuals of fictional vendors, in layouts the seed manuals do not
//! use, against maps of them transcribed by hand (`tests/fixtures/import/`): every row found
//! with every field right, codes and bits included, nothing else proposed, and the draft checks.

use std::path::{Path, PathBuf};

use drivemap_import::{Manual, compare, import, known};
use drivemap_map::ir::Drive;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/import")
}

/// Every hand-written map of the fixture directory, with its manual.
fn cases() -> Vec<(Drive, String, String)> {
    let dir = fixtures();
    let mut out = Vec::new();
    for map in drivemap_map::find_maps(&dir).unwrap() {
        let drive = drivemap_map::read_map(&map, &Default::default())
            .unwrap_or_else(|e| panic!("{}: {e}", map.display()));
        let file = drive.meta.text_manuals().next().unwrap().to_string();
        let text = std::fs::read_to_string(dir.join("manuals").join(&file)).unwrap();
        out.push((drive, file, text));
    }
    assert!(out.len() >= 2, "fixture maps in {}", dir.display());
    out
}

#[test]
fn every_row_of_a_fixture_manual_is_read_right() {
    for (truth, file, text) in cases() {
        let id = truth.meta.id.clone();
        let imported = import(
            &id,
            &[Manual {
                file: &file,
                text: &text,
            }],
            None,
            "test",
        );
        let registers = known::registers(&truth);
        let (reading, _) = &imported.readings[0];
        let c = compare::compare(&reading.rows, &registers, &file);
        let wrong: Vec<String> = c
            .matched
            .iter()
            .filter(|m| !m.differences.is_empty())
            .map(|m| format!("{}: {:?}", m.known.id, m.differences))
            .collect();
        assert!(wrong.is_empty(), "{id}: rows read wrong: {wrong:#?}");
        assert!(
            c.missed.is_empty(),
            "{id}: rows not found: {:?}",
            c.missed.iter().map(|k| &k.id).collect::<Vec<_>>()
        );
        assert!(
            c.new_rows.is_empty(),
            "{id}: rows proposed that the manual's map does not have: {:?}",
            c.new_rows
                .iter()
                .map(|r| (r.line, &r.name))
                .collect::<Vec<_>>()
        );
        assert_eq!(c.matched.len(), registers.len(), "{id}");

        // The draft loads and checks, and carries the codes and bits of every register.
        assert!(
            imported.unresolved.is_empty(),
            "{id}: {:?}",
            imported.unresolved
        );
        assert!(
            imported.left_out.is_empty(),
            "{id}: {:?}",
            imported.left_out
        );
        let draft =
            drivemap_map::read_map_str(&format!("{id}.yaml"), &imported.yaml, &Default::default())
                .unwrap_or_else(|e| {
                    panic!("{id}: the draft does not check:\n{e}\n{}", imported.yaml)
                });
        assert!(draft.draft.is_some(), "{id}: the draft is marked");
        for t in &truth.registers {
            let d = draft
                .registers
                .iter()
                .find(|d| d.def.address == t.def.address)
                .unwrap_or_else(|| panic!("{id}: {} not in the draft", t.def.id));
            let codes = |r: &drivemap_map::ir::Register| {
                r.def
                    .values
                    .iter()
                    .map(|v| (v.value, v.name.clone(), v.source.clone()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(codes(d), codes(t), "{id}: codes of {}", t.def.id);
            let bits = |r: &drivemap_map::ir::Register| {
                r.def
                    .fields
                    .iter()
                    .map(|f| (f.bit, f.bits, f.name.clone(), f.source.clone()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(d), bits(t), "{id}: bits of {}", t.def.id);
            // An access the manual prints is read; one it does not print is left unknown, and
            // a draft register without one is read-only.
            if t.def.access.is_some() {
                assert_eq!(d.access, t.access, "{id}: access of {}", t.def.id);
            } else {
                assert_eq!(
                    d.access,
                    drivemap_map::model::Access::Read,
                    "{id}: {} prints no access",
                    t.def.id
                );
                assert!(
                    imported
                        .to_confirm
                        .iter()
                        .any(|c| c.starts_with(&format!("{}.access: unknown", d.def.id))),
                    "{id}: {} has no access to confirm",
                    t.def.id
                );
            }
            assert_eq!(
                d.def.signed, t.def.signed,
                "{id}: signedness of {}",
                t.def.id
            );
        }
        // The protocol facts the manual prints.
        let (tp, dp) = (&truth.protocol, &draft.protocol);
        assert_eq!(
            format!("{:?}", dp.function_codes),
            format!("{:?}", tp.function_codes),
            "{id}"
        );
        assert_eq!(
            format!("{:?}", dp.max_read),
            format!("{:?}", tp.max_read),
            "{id}"
        );
        assert_eq!(
            format!("{:?}", dp.slave_address),
            format!("{:?}", tp.slave_address),
            "{id}"
        );
        assert_eq!(
            dp.exceptions
                .iter()
                .map(|e| (e.code, e.name.clone()))
                .collect::<Vec<_>>(),
            tp.exceptions
                .iter()
                .map(|e| (e.code, e.name.clone()))
                .collect::<Vec<_>>(),
            "{id}"
        );
    }
}

#[test]
fn every_citation_of_a_draft_shows_its_row() {
    for (truth, file, text) in cases() {
        let imported = import(
            &truth.meta.id,
            &[Manual {
                file: &file,
                text: &text,
            }],
            None,
            "test",
        );
        let lines: Vec<&str> = text.lines().collect();
        for r in imported.readings[0]
            .0
            .rows
            .iter()
            .filter(|r| r.address.is_some() && !r.reserved)
        {
            let line = lines[r.line - 1];
            let shows = r.shown_by(line);
            assert!(
                shows,
                "{file}:{}: `{line}` shows neither {:?} nor {:?}",
                r.line, r.param, r.address_printed
            );
        }
    }
}

#[test]
fn the_generator_refuses_a_draft() {
    let (truth, file, text) = cases().remove(0);
    let imported = import(
        &truth.meta.id,
        &[Manual {
            file: &file,
            text: &text,
        }],
        None,
        "test",
    );
    let dir = std::env::temp_dir().join(format!("drivemap-import-draft-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let map = dir.join(format!("{}.yaml", truth.meta.id));
    std::fs::write(&map, &imported.yaml).unwrap();
    let compile = || {
        drivemap_codegen::Config::new()
            .map(&map)
            .out_dir(dir.join("out"))
            .cargo_directives(false)
            .compile()
    };
    let err = compile().expect_err("a draft must not generate");
    let text = err.to_string();
    assert!(
        text.contains("draft") && text.contains(&map.display().to_string()),
        "{text}"
    );
    // Without the mark it generates.
    let reviewed: String = imported
        .yaml
        .lines()
        .scan(false, |in_draft, l| {
            if l.starts_with("draft:") {
                *in_draft = true;
                return Some(None);
            }
            if *in_draft && l.starts_with(' ') {
                return Some(None);
            }
            *in_draft = false;
            Some(Some(l))
        })
        .flatten()
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&map, reviewed).unwrap();
    compile().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}
