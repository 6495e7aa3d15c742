//! The typed part of the facts view (`RegisterFacts::data`), which the JSON export maps: the
//! values beside each worded row say the same thing as the row, taken from the plan where the
//! plan decides, and the export's registers are the view's, in the export's order.

use drivemap_test_support::paths;

use std::path::{Path, PathBuf};

use drivemap_core::width::{Width, WordOrder};
use drivemap_map::describe;
use drivemap_map::facts::data::{Quantity, ScaleData};
use drivemap_map::facts::{FactKey, RegisterFacts};

/// Every map of the repository and every fixture map (each a different vendor's constructs).
fn maps() -> Vec<PathBuf> {
    let mut out = drivemap_map::find_maps(&paths::maps()).unwrap();
    for dir in std::fs::read_dir(paths::fixtures()).unwrap() {
        let dir = dir.unwrap().path();
        if dir.is_dir() {
            out.extend(drivemap_map::find_maps(&dir).unwrap());
        }
    }
    assert!(out.len() >= 12, "{out:?}");
    out
}

fn read(path: &Path) -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(path)
        .unwrap_or_else(|d| panic!("{d}"))
}

fn value(f: &RegisterFacts, key: FactKey) -> Option<&str> {
    f.get(key).map(|r| r.value.as_str())
}

fn citation(f: &RegisterFacts, key: FactKey) -> Option<&str> {
    f.get(key).and_then(|r| r.citation.as_deref())
}

/// Each typed value words to its row (or its absence to the row's), for every register of
/// every map: a value lost or changed on either side fails here.
#[test]
fn every_typed_value_says_what_its_worded_row_says() {
    for path in maps() {
        let drive = read(&path);
        for f in drive.facts().registers {
            let d = &f.data;
            let at = format!("{}: {}", path.display(), f.id);
            let unit = d.unit.as_deref().unwrap_or("");
            assert_eq!(
                value(&f, FactKey::Access),
                Some(describe::access(d.access)),
                "{at}"
            );
            assert_eq!(value(&f, FactKey::Unit), d.unit.as_deref(), "{at}");
            let range = describe::range(d.min, d.max, unit);
            assert_eq!(
                value(&f, FactKey::Range),
                (!range.is_empty()).then_some(range.as_str()),
                "{at}"
            );
            assert_eq!(
                value(&f, FactKey::Default).map(str::to_owned),
                d.default.as_ref().map(describe::default),
                "{at}"
            );
            match d.width {
                Width::Word => assert!(f.get(FactKey::Width).is_none(), "{at}"),
                Width::Pair(_) => {
                    assert_eq!(
                        value(&f, FactKey::Width).map(str::to_owned),
                        Some(describe::width(d.width)),
                        "{at}"
                    );
                    assert_eq!(
                        citation(&f, FactKey::Width),
                        d.word_order_source.as_deref(),
                        "{at}"
                    );
                }
                Width::Text(n) => {
                    let t = d.string.as_ref().expect("a string's typed layout");
                    assert_eq!(t.registers, n, "{at}");
                    assert_eq!(
                        value(&f, FactKey::Width).map(str::to_owned),
                        Some(describe::text(n, t.byte_order, t.example.as_deref())),
                        "{at}"
                    );
                    assert_eq!(citation(&f, FactKey::Width), t.source.as_deref(), "{at}");
                }
            }
            assert_eq!(f.get(FactKey::Broadcast).is_some(), d.broadcast, "{at}");
            assert_eq!(
                value(&f, FactKey::WriteRestriction),
                (d.write_restriction != drivemap_core::register::WriteRestriction::None)
                    .then(|| describe::write_restriction(d.write_restriction)),
                "{at}"
            );
            let read: Vec<String> = d
                .read_values
                .iter()
                .map(|l| format!("{} {}", l.code, l.name))
                .collect();
            assert_eq!(
                value(&f, FactKey::ReadValues).map(str::to_owned),
                (!read.is_empty()).then(|| read.join(", ")),
                "{at}"
            );
            assert_eq!(
                citation(&f, FactKey::RepeatNeedsChange),
                d.repeat_needs_change.as_ref().map(|x| x.source.as_str()),
                "{at}"
            );
            assert_eq!(
                citation(&f, FactKey::FunctionCodes),
                d.function_codes.as_ref().map(|x| x.source.as_str()),
                "{at}"
            );
            assert_eq!(
                citation(&f, FactKey::RelativeLimit),
                d.max_relative.as_ref().map(|x| x.source.as_str()),
                "{at}"
            );
            let alternatives: Vec<String> = f
                .all(FactKey::AlternativeAddress)
                .map(|r| r.value.clone())
                .collect();
            let typed: Vec<String> = d
                .address_alternatives
                .iter()
                .map(|a| describe::address(a.address))
                .collect();
            assert_eq!(alternatives, typed, "{at}");
            // By what the typed scale says, not by its kind: a new kind needs no arm here.
            let cases = d.scale.cases();
            if !cases.is_empty() {
                assert!(f.get(FactKey::SelectedBy).is_some(), "{at}");
                let codes: Vec<String> = cases.iter().map(|c| describe::codes(&c.when)).collect();
                let worded: Vec<String> = f.cases.iter().map(|c| c.codes.clone()).collect();
                assert_eq!(codes, worded, "{at}");
            } else if d.scale == ScaleData::None {
                assert!(f.get(FactKey::Scale).is_none(), "{at}");
                assert!(f.get(FactKey::SelectedBy).is_none(), "{at}");
            } else {
                assert!(
                    f.get(FactKey::Scale).is_some() || d.unit.is_none(),
                    "{at}: a scaled value has a scale row"
                );
                let unit = d.unit.as_deref().unwrap_or("");
                if let Some(row) = f.get(FactKey::Scale) {
                    assert_eq!(
                        row.value,
                        d.scale.describe(unit),
                        "{at}: worded by its kind"
                    );
                }
            }
            assert_eq!(
                f.variants.iter().map(|v| &v.option).collect::<Vec<_>>(),
                d.by_variant.iter().map(|v| &v.option).collect::<Vec<_>>(),
                "{at}"
            );
        }
    }
}

/// The codes and bits taken from the plan are the map's, all of them.
#[test]
fn codes_and_fields_from_the_plan_are_the_maps() {
    for path in maps() {
        let drive = read(&path);
        let view = drive.facts();
        for (f, r) in view.registers.iter().zip(drive.registers()) {
            let at = format!("{}: {}", path.display(), f.id);
            let listed = |v: &[drivemap_map::facts::EnumValue]| -> Vec<(u16, String, String)> {
                v.iter()
                    .map(|x| (x.value, x.id.clone(), x.name.clone()))
                    .collect()
            };
            let planned = |v: &[drivemap_core::plan::Label]| -> Vec<(u16, String, String)> {
                v.iter()
                    .map(|x| (x.code, x.id.to_owned(), x.name.to_owned()))
                    .collect()
            };
            assert_eq!(planned(f.data.values), listed(r.values()), "{at}");
            assert_eq!(planned(f.data.read_values), listed(r.read_values()), "{at}");
            assert_eq!(f.data.fields.len(), r.fields().len(), "{at}");
            for (x, y) in f.data.fields.iter().zip(r.fields()) {
                assert_eq!((x.id, x.name), (y.id.as_str(), y.name.as_str()), "{at}");
                assert_eq!(Some((x.lsb, x.width)), span(y), "{at}");
                assert_eq!(planned(x.values), listed(&y.values), "{at}");
            }
        }
    }
}

/// The export lists the view's registers (broadcast ones last, by address) and writes the
/// view's typed values.
#[test]
fn the_export_is_the_views_registers_in_address_order() {
    let drive = read(&paths::fixture("acme-vf1/acme-vf1.yaml"));
    let mut view = drive.facts().registers;
    view.sort_by_key(|f| (f.data.broadcast, f.address));
    let export = drive.export();
    let ids: Vec<&str> = export["registers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, view.iter().map(|f| f.id.as_str()).collect::<Vec<_>>());
    let energy = view.iter().find(|f| f.id == "energy_counter").unwrap();
    assert_eq!(energy.data.width, Width::Pair(WordOrder::HighFirst));
    assert_eq!(
        energy.data.word_order_source.as_deref(),
        Some("acme-vf1.txt:34")
    );
    let json = export["registers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == "energy_counter")
        .unwrap();
    assert_eq!(json["words"], 2);
    assert_eq!(json["word_order"], "high_first");
    assert_eq!(json["word_order_source"], "acme-vf1.txt:34");
    let current = view.iter().find(|f| f.id == "motor_current").unwrap();
    let ScaleData::Selected {
        selector, cases, ..
    } = &current.data.scale
    else {
        panic!("motor_current: {:?}", current.data.scale)
    };
    let json = export["registers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == "motor_current")
        .unwrap();
    assert_eq!(json["scale_selected_by"], selector.as_str());
    assert_eq!(json["scale_cases"].as_array().unwrap().len(), cases.len());
}

/// A relative scale names its reference as a user does; a relative limit as the map does.
#[test]
fn a_reference_is_shown_by_parameter_and_a_limit_keeps_the_maps_name() {
    let drive = read(&paths::shipped_map("ptlk-tds-v8"));
    let view = drive.facts().registers;
    let reference = view.iter().find(|f| f.id == "frequency_command").unwrap();
    let ScaleData::Relative {
        reference: q,
        full_scale,
    } = &reference.data.scale
    else {
        panic!("{:?}", reference.data.scale)
    };
    assert_eq!(*full_scale, 30000.0);
    let Quantity::Register { shown, .. } = q else {
        panic!("{q:?}")
    };
    assert_eq!(shown, "Cn-02");
    let limit = reference.data.max_relative.as_ref().unwrap();
    assert_eq!(limit.percent, 100.0);
    let export = drive.export();
    let json = export["registers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == "frequency_command")
        .unwrap();
    assert_eq!(json["scale_relative_to"]["reference"], "Cn-02");
    let Quantity::Register { name, .. } = &limit.relative_to else {
        panic!("{:?}", limit.relative_to)
    };
    assert_eq!(json["max_relative"]["relative_to"], name.as_str());
}

/// The export's protocol is the protocol facts': the working figures are the rows' figures,
/// each object is the row's entry, and `not_printed` lists exactly the rows marked so.
#[test]
fn the_exported_protocol_is_the_protocol_facts() {
    use drivemap_map::facts::{Figure, ProtocolKey};
    for path in maps() {
        let drive = read(&path);
        let view = drive.facts().protocol;
        let export = drive.export();
        let p = &export["protocol"];
        let at = path.display();
        let figure = |key| &view.get(key).unwrap().figure;
        let Figure::Codes(codes) = figure(ProtocolKey::FunctionCodes) else {
            panic!("{at}: function codes")
        };
        assert_eq!(p["function_codes"], serde_json::json!(codes), "{at}");
        for (key, name) in [
            (ProtocolKey::MaxRead, "max_read"),
            (ProtocolKey::MaxWrite, "max_write"),
        ] {
            let Figure::Count(n) = figure(key) else {
                panic!("{at}: {name}")
            };
            assert_eq!(p[name], *n, "{at}: {name}");
        }
        let Figure::Range { min, max } = figure(ProtocolKey::SlaveAddress) else {
            panic!("{at}: slave address")
        };
        // The slave range is written out when something is not printed, else as the map has it.
        if p["not_printed"].is_object() {
            assert_eq!(p["slave_address"]["min"], *min, "{at}");
            assert_eq!(p["slave_address"]["max"], *max, "{at}");
        }
        assert_eq!(
            p["transports"],
            view.get(ProtocolKey::Transports).unwrap().entry,
            "{at}"
        );
        assert_eq!(
            p["commands"].as_array().unwrap().len(),
            view.commands.len(),
            "{at}"
        );
        let mut marked: Vec<&str> = view
            .rows
            .iter()
            .filter(|r| r.not_printed.is_some())
            .filter_map(|r| r.key.fact())
            .map(|f| f.key())
            .collect();
        marked.sort_unstable();
        let mut listed: Vec<&str> = p["not_printed"]
            .as_object()
            .map(|o| o.keys().map(String::as_str).collect())
            .unwrap_or_default();
        listed.sort_unstable();
        assert_eq!(listed, marked, "{at}");
        if let Some(chars) = view.data.frame_gap_chars {
            assert_eq!(p["timing"]["frame_gap_chars"], chars, "{at}");
        }
    }
}

/// The bit span a field is written with: `bit: b` or `bits: [lo, hi]`.
fn span(f: &drivemap_map::facts::BitField) -> Option<(u8, u8)> {
    match (f.bit, f.bits) {
        (Some(b), None) => Some((b, 1)),
        (None, Some([lo, hi])) => Some((lo, hi - lo + 1)),
        _ => None,
    }
}
