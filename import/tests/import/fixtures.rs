//! `drivemap import` on fixture manuals of fictional vendors, in layouts the seed manuals do not
//! use, against maps of them transcribed by hand (`tests/fixtures/import/`): every row found
//! with every field right, codes and bits included, nothing else proposed, and the draft checks.

use drivemap_test_support::paths;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::PathBuf;

use drivemap_import::columns::{Role, parse_roles};
use drivemap_import::{Manual, compare, import, import_with, known, row::row_shaped};
use drivemap_map::{Map as Drive, RegisterRef};

fn fixtures() -> PathBuf {
    paths::fixture("import")
}

/// A fixture: the hand-written map, its manual, and what the map's `# import:` comments say
/// (the layout in a few words, the lines the reader must report as of the wrong kind, the
/// columns a user names with `--columns`).
struct Case {
    truth: Drive,
    file: String,
    text: String,
    layout: String,
    wrong_kind: BTreeSet<usize>,
    columns: BTreeMap<usize, Vec<Role>>,
}

fn lines_of(list: &str) -> BTreeSet<usize> {
    let mut out = BTreeSet::new();
    for part in list.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        match part.split_once('-') {
            Some((a, b)) => {
                out.extend(a.trim().parse::<usize>().unwrap()..=b.trim().parse().unwrap())
            }
            None => {
                out.insert(part.parse().unwrap());
            }
        }
    }
    out
}

/// Every hand-written map of the fixture directory, with its manual.
fn cases() -> Vec<Case> {
    let dir = fixtures();
    let mut out = Vec::new();
    for map in drivemap_map::find_maps(&dir).unwrap() {
        let drive = drivemap_map::Loader::new()
            .load(&map)
            .unwrap_or_else(|e| panic!("{}: {e}", map.display()));
        let file = drive.meta().text_manuals().next().unwrap().to_string();
        let text = std::fs::read_to_string(dir.join("manuals").join(&file)).unwrap();
        let source = std::fs::read_to_string(&map).unwrap();
        let mut case = Case {
            truth: drive,
            file,
            text,
            layout: String::new(),
            wrong_kind: BTreeSet::new(),
            columns: BTreeMap::new(),
        };
        for l in source.lines() {
            let Some(rest) = l.strip_prefix("# import: ") else {
                continue;
            };
            if let Some(v) = rest.strip_prefix("layout ") {
                case.layout = v.trim().to_string();
            } else if let Some(v) = rest.strip_prefix("wrong_kind ") {
                case.wrong_kind = lines_of(v);
            } else if let Some(v) = rest.strip_prefix("columns ") {
                let (line, roles) = v.trim().split_once(':').unwrap();
                case.columns
                    .insert(line.parse().unwrap(), parse_roles(roles).unwrap());
            } else {
                panic!("{}: unknown `# import:` line {l}", map.display());
            }
        }
        out.push(case);
    }
    assert!(out.len() >= 2, "fixture maps in {}", dir.display());
    out
}

/// The figures of one fixture.
#[derive(Debug, Default)]
struct Figures {
    rows: usize,
    proposed: usize,
    found: usize,
    right: usize,
    wrong_kind: usize,
    invented: usize,
    unaccounted: usize,
    /// Lines the map's comments name as of the wrong kind that the report does not list.
    unreported: usize,
}

fn codes(r: RegisterRef<'_>) -> Vec<(u16, String, Option<String>)> {
    r.values()
        .iter()
        .map(|v| (v.value, v.name.clone(), v.source.clone()))
        .collect()
}

/// A bit field as compared: its bit or bits, name and citation.
type Bits = (Option<u8>, Option<[u8; 2]>, String, Option<String>);

fn bits(r: RegisterRef<'_>) -> Vec<Bits> {
    r.fields()
        .iter()
        .map(|f| (f.bit, f.bits, f.name.clone(), f.source.clone()))
        .collect()
}

/// Imports a fixture as a user would (with its `--columns`, if any) and scores the draft
/// against the hand-written map; `wrong` collects what is not right, for the failure message.
fn score(case: &Case, wrong: &mut Vec<String>) -> Figures {
    let id = case.truth.id().to_owned();
    let imported = import_with(
        &id,
        &[Manual {
            file: &case.file,
            text: &case.text,
        }],
        None,
        &case.columns,
        "test",
    );
    let registers = known::registers(&case.truth);
    let (reading, _) = &imported.readings[0];
    let c = compare::compare(&reading.rows, &registers, &case.file);
    let draft = drivemap_map::Loader::new()
        .load_str(&format!("{id}.yaml"), &imported.yaml)
        .unwrap_or_else(|e| panic!("{id}: the draft does not check:\n{e}\n{}", imported.yaml));
    assert!(draft.draft().is_some(), "{id}: the draft is marked");
    if !imported.unresolved.is_empty() || !imported.left_out.is_empty() {
        wrong.push(format!(
            "{id}: the front end refused rows: {:?} {:?}",
            imported.unresolved, imported.left_out
        ));
    }
    let mut f = Figures {
        rows: registers.len(),
        proposed: imported.proposed(&case.file),
        found: c.matched.len(),
        invented: c.new_rows.len(),
        ..Figures::default()
    };
    for r in &c.new_rows {
        wrong.push(format!(
            "{id}:{}: proposed, not in the map: {:?}",
            r.line, r.name
        ));
        if case.wrong_kind.contains(&r.line) {
            f.wrong_kind += 1;
        }
    }
    for k in &c.missed {
        wrong.push(format!("{id}: not found: {}", k.id));
    }
    for m in &c.matched {
        let t = case
            .truth
            .registers()
            .find(|t| t.id() == m.known.id)
            .unwrap();
        let Some(d) = draft
            .registers()
            .find(|d| d.address() == t.address() && d.param() == t.param())
        else {
            wrong.push(format!("{id}: {} read but not in the draft", t.id()));
            continue;
        };
        let mut why = Vec::new();
        if !m.differences.is_empty() {
            why.push(format!("{:?}", m.differences));
        }
        if codes(d) != codes(t) {
            why.push(format!("codes {:?} / {:?}", codes(d), codes(t)));
        }
        if bits(d) != bits(t) {
            why.push(format!("bits {:?} / {:?}", bits(d), bits(t)));
        }
        // An access the manual prints is read; one it does not print is left unknown (to
        // confirm), and a draft register without one is read-only.
        if t.access_written().is_some() {
            if d.plan().info.access != t.plan().info.access {
                why.push(format!(
                    "access {:?} / {:?}",
                    d.plan().info.access,
                    t.plan().info.access
                ));
            }
        } else if d.plan().info.access.writable()
            || !imported
                .to_confirm
                .iter()
                .any(|c| c.starts_with(&format!("{}.access: unknown", d.id())))
        {
            why.push(format!(
                "access {:?} not left unknown",
                d.plan().info.access
            ));
        }
        if d.signed() != t.signed() {
            why.push(format!("signed {} / {}", d.signed(), t.signed()));
        }
        if d.width() != t.width() {
            why.push("pair".to_string());
        }
        if why.is_empty() {
            f.right += 1;
        } else {
            wrong.push(format!("{id}: {}: {}", t.id(), why.join("; ")));
        }
    }
    // Lines of the wrong kind are reported, never proposed.
    for line in &case.wrong_kind {
        if !reading.unread.iter().any(|u| u.line == *line) {
            f.unreported += 1;
            wrong.push(format!("{id}:{line}: of the wrong kind, but not reported"));
        }
    }
    // Every row-shaped line is a row, part of one (codes, bits) or reported.
    let mut accounted: BTreeSet<usize> = reading.unread.iter().map(|u| u.line).collect();
    accounted.extend(&reading.taken);
    for r in &reading.rows {
        accounted.insert(r.line);
        accounted.extend(r.values.iter().map(|v| v.line));
        accounted.extend(r.fields.iter().map(|b| b.line));
    }
    for (i, l) in case.text.lines().enumerate() {
        if row_shaped(l) && !accounted.contains(&(i + 1)) {
            f.unaccounted += 1;
            wrong.push(format!(
                "{id}:{}: row-shaped, not accounted for: {l}",
                i + 1
            ));
        }
    }
    f
}

fn percent(a: usize, b: usize) -> f64 {
    if b == 0 {
        0.0
    } else {
        100.0 * a as f64 / b as f64
    }
}

const BEGIN: &str = "<!-- BEGIN catalogue figures: generated by `cargo test -p drivemap-import --test import fixtures::` (DRIVEMAP_UPDATE_DOCS=1 rewrites), do not edit -->";
const END: &str = "<!-- END catalogue figures -->";

#[test]
fn every_catalogue_fixture_is_read_to_its_map() {
    let mut table = String::new();
    let _ = writeln!(
        table,
        "| fixture | layout | rows in the manual | proposed | found | every field right | wrong kind | invented | unaccounted lines |"
    );
    let _ = writeln!(table, "|---|---|---:|---:|---:|---:|---:|---:|---:|");
    let mut failures = Vec::new();
    for case in cases() {
        let mut wrong = Vec::new();
        let f = score(&case, &mut wrong);
        let _ = writeln!(
            table,
            "| `{}` | {} | {} | {} | {} ({:.0} %) | {} ({:.0} %) | {} | {} | {} |",
            case.file,
            case.layout,
            f.rows,
            f.proposed,
            f.found,
            percent(f.found, f.rows),
            f.right,
            percent(f.right, f.found),
            f.wrong_kind,
            f.invented,
            f.unaccounted
        );
        let id = &case.truth.id();
        let ok = percent(f.found, f.rows) >= 95.0
            && percent(f.right, f.found) >= 85.0
            && f.wrong_kind == 0
            && f.invented == 0
            && f.unaccounted == 0
            && f.unreported == 0
            && f.proposed == f.found + f.invented;
        if !ok {
            failures.push(format!("{id}: {f:?}: {wrong:#?}"));
        }
        // The protocol facts the manual prints.
        let imported = import_with(
            id,
            &[Manual {
                file: &case.file,
                text: &case.text,
            }],
            None,
            &case.columns,
            "test",
        );
        let draft = drivemap_map::Loader::new()
            .load_str(&format!("{id}.yaml"), &imported.yaml)
            .unwrap();
        let (tp, dp) = (case.truth.protocol(), draft.protocol());
        for (what, d, t) in [
            (
                "function codes",
                format!("{:?}", dp.function_codes),
                format!("{:?}", tp.function_codes),
            ),
            // A limit the manual does not print is a placeholder in the draft (to confirm).
            (
                "max_read",
                format!(
                    "{:?}",
                    dp.max_read.value.filter(|_| tp.max_read.value.is_some())
                ),
                format!("{:?}", tp.max_read.value),
            ),
            (
                "slave address",
                format!("{:?}", dp.slave_address),
                format!("{:?}", tp.slave_address),
            ),
            (
                "exceptions",
                format!(
                    "{:?}",
                    dp.exceptions
                        .iter()
                        .map(|e| (e.code, e.name.clone(), e.description.clone()))
                        .collect::<Vec<_>>()
                ),
                format!(
                    "{:?}",
                    tp.exceptions
                        .iter()
                        .map(|e| (e.code, e.name.clone(), e.description.clone()))
                        .collect::<Vec<_>>()
                ),
            ),
            (
                "serial format",
                format!(
                    "{:?}",
                    dp.serial
                        .as_ref()
                        .map(|s| (&s.parities, s.data_bits, s.stop_bits))
                ),
                format!(
                    "{:?}",
                    tp.serial
                        .as_ref()
                        .map(|s| (&s.parities, s.data_bits, s.stop_bits))
                ),
            ),
            (
                "broadcast",
                format!("{:?}", dp.broadcast.as_ref().map(|b| &b.source)),
                format!("{:?}", tp.broadcast.as_ref().map(|b| &b.source)),
            ),
        ] {
            if d != t {
                failures.push(format!("{id}: {what}: draft {d} / map {t}"));
            }
        }
    }
    print!("{table}");
    let doc_path = paths::workspace().join("docs/import.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap();
    let (Some(b), Some(e)) = (doc.find(BEGIN), doc.find(END)) else {
        panic!(
            "{}: the catalogue figures' markers are missing",
            doc_path.display()
        )
    };
    let generated = format!("{BEGIN}\n{table}{END}");
    let current = &doc[b..e + END.len()];
    if current != generated {
        if std::env::var_os("DRIVEMAP_UPDATE_DOCS").is_some() {
            std::fs::write(&doc_path, doc.replace(current, &generated)).unwrap();
        } else {
            failures.push(format!(
                "{}: the catalogue figures differ from the reader's; rerun with DRIVEMAP_UPDATE_DOCS=1 and review the change",
                doc_path.display()
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn every_citation_of_a_draft_shows_its_row() {
    for Case {
        truth, file, text, ..
    } in cases()
    {
        let imported = import(
            truth.id(),
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
    let Case {
        truth, file, text, ..
    } = cases().remove(0);
    let imported = import(
        truth.id(),
        &[Manual {
            file: &file,
            text: &text,
        }],
        None,
        "test",
    );
    let dir = std::env::temp_dir().join(format!("drivemap-import-draft-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let map = dir.join(format!("{}.yaml", truth.id()));
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

#[test]
fn a_column_the_reader_cannot_decide_is_reported_and_named_with_columns() {
    let case = cases()
        .into_iter()
        .find(|c| !c.columns.is_empty())
        .expect("a fixture with `# import: columns`");
    let (&header, roles) = case.columns.iter().next().unwrap();
    let manual = [Manual {
        file: &case.file,
        text: &case.text,
    }];
    // Without the user's names: the report names the table and every column it cannot decide,
    // and no number of those columns is used (no limit, no default is made up).
    let plain = import(case.truth.id(), &manual, None, "test");
    let report = drivemap_import::report(&plain);
    let undecided: Vec<&str> = report
        .lines()
        .filter(|l| l.contains("is not understood"))
        .collect();
    assert!(
        undecided.len() >= 3
            && undecided
                .iter()
                .all(|l| l.contains(&format!("{}:{header}:", case.file)) && l.contains("--columns")),
        "{report}"
    );
    for title in ["\"Lo\"", "\"Hi\"", "\"Preset\""] {
        assert!(
            undecided.iter().any(|l| l.contains(title)),
            "{title}: {report}"
        );
    }
    let rows = &plain.readings[0].0.rows;
    assert_eq!(rows.len(), case.truth.registers().len());
    for r in rows {
        assert_eq!((r.min, r.max, r.default), (None, None, None), "{r:?}");
    }
    // Named: every field as the map has it (the figures above), and the report says so.
    let named = import_with(case.truth.id(), &manual, None, &case.columns, "test");
    let report = drivemap_import::report(&named);
    assert!(!report.contains("is not understood"), "{report}");
    assert!(
        report.contains("\"Lo\" = min") && report.contains("\"Preset\" = default"),
        "{report}"
    );
    assert_eq!(roles.len(), named.readings[0].0.layouts[0].columns.len());
}

#[test]
fn two_numbers_per_row_in_spaced_bars_give_the_drives_own_register() {
    // The drive's register beside its 40001-style reference, cells between spaced bars and a
    // header introduced by a label: the address is the drive's own number, the reference a note.
    let text = "Columns: Register | Modbus reference | Name | Access | Unit | Scaling factor | Range\n\
                0 | 40001 | Watchdog time | R/W | ms | 1 | 0 - 65535\n\
                1 | 40002 | Frequency setpoint | R/W | Hz | 100 | -200.00 - 200.00\n\
                2 | 40003 | Run enable | R/W | - | 1 | 0 - 1\n";
    let reading = drivemap_import::read_manual("v.txt", text, None);
    let rows: Vec<_> = reading
        .rows
        .iter()
        .map(|r| {
            (
                r.address,
                r.name.as_str(),
                r.access,
                r.unit.as_deref(),
                r.scale,
                r.min,
            )
        })
        .collect();
    assert_eq!(
        rows,
        [
            (
                Some(0),
                "Watchdog time",
                Some("rw"),
                Some("ms"),
                Some(1.0),
                Some(0.0)
            ),
            (
                Some(1),
                "Frequency setpoint",
                Some("rw"),
                Some("Hz"),
                Some(0.01),
                Some(-200.0)
            ),
            (Some(2), "Run enable", Some("rw"), None, None, Some(0.0)),
        ]
    );
    assert!(
        reading.rows[1]
            .notes
            .iter()
            .any(|n| n.contains("also printed as 40002")),
        "{:?}",
        reading.rows[1].notes
    );
}
