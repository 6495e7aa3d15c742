//! Protocol figures a manual states in its own terms: a frame gap in milliseconds
//! (`timing.frame_gap: {ms: ..}`), carried through lowering into `core::profile::Timing` and
//! into the Markdown reference.

use drivemap_test_support::paths;

fn fixture() -> String {
    std::fs::read_to_string(paths::fixture("crafted/maps/mini-drive.yaml")).unwrap()
}

fn with_frame_gap(text: &str) -> String {
    let timing = "  timing:\n";
    assert!(text.contains(timing), "the fixture's timing moved");
    text.replace(
        timing,
        "  timing:\n    frame_gap: {ms: 10, source: \"manual.txt:17\"}\n",
    )
}

#[test]
fn a_frame_gap_in_ms_is_lowered_into_the_profile_timing() {
    let text = with_frame_gap(&fixture());
    let drive = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap();
    let plan = drive.plan();
    assert_eq!(plan.profile.timing.frame_gap_us, Some(10_000));
    assert_eq!(plan.profile.timing.frame_gap_chars, 3.5);
    // Without it, none.
    let plain = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &fixture())
        .unwrap();
    assert_eq!(plain.plan().profile.timing.frame_gap_us, None);
    // The reference's timing row states it with its citation.
    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains("frame gap 3.5 characters, at least 10 ms (`manual.txt:17`)"),
        "{md}"
    );
    // The export carries it as written.
    let json = drive.export();
    assert_eq!(json["protocol"]["timing"]["frame_gap"]["ms"], 10.0);
    assert_eq!(
        json["protocol"]["timing"]["frame_gap"]["source"],
        "manual.txt:17"
    );
}

/// `max_read`/`max_write` take a plain number, `{value, source}` or `{value, unknown: <why>}`;
/// the runtime uses the value, the reference and the export say which is not printed and why.
#[test]
fn a_limit_not_printed_keeps_its_value_and_says_why() {
    let text = fixture().replace(
        "  max_read: 8\n  max_write: 8\n",
        "  max_read: {value: 8, unknown: \"no limit printed; 8 is its own frame\", source: \"manual.txt:18\"}\n  max_write: {value: 4, source: \"manual.txt:19\"}\n",
    );
    assert_ne!(text, fixture(), "the fixture's limits moved");
    let drive = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap();
    let plan = drive.plan();
    assert_eq!((plan.profile.max_read, plan.profile.max_write), (8, 4));
    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains(
            "at most 8 per read, 4 per write. max_read 8 not printed: no limit printed; 8 is its own frame (`manual.txt:18`). max_write (`manual.txt:19`)"
        ),
        "{md}"
    );
    let json = drive.export();
    assert_eq!(json["protocol"]["max_read"], 8);
    let l = &json["protocol"]["limits"]["max_read"];
    assert_eq!(l["not_printed"], "no limit printed; 8 is its own frame");
    assert_eq!(l["source"], "manual.txt:18");
    assert_eq!(
        json["protocol"]["limits"]["max_write"]["source"],
        "manual.txt:19"
    );
    // A plain number: no `limits` in the export.
    let plain = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &fixture())
        .unwrap();
    assert!(plain.export()["protocol"].get("limits").is_none());
    // Without a value the Modbus limit stands in (125 per read), and every tool says so.
    let drive = drivemap_map::Loader::new()
        .load_str(
            "mini-drive.yaml",
            &fixture().replace(
                "  max_read: 8\n",
                "  max_read: {unknown: \"not printed\"}\n",
            ),
        )
        .unwrap();
    let plan = drive.plan();
    assert_eq!(plan.profile.max_read, 125);
    assert_eq!(
        plan.profile.max_read_stated(),
        drivemap_core::stated::Stated::NotPrinted("not printed")
    );
    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains(
            "at most 125 per read, 8 per write. max_read not printed in the manual: not printed; used instead: the Modbus limit (125)"
        ),
        "{md}"
    );
    let json = drive.export();
    assert_eq!(json["protocol"]["max_read"], 125);
    assert_eq!(json["protocol"]["limits"]["max_read"]["value"], 125);
    assert_eq!(
        json["protocol"]["not_printed"]["max_read"]["why"],
        "not printed"
    );
}

/// `function_codes` takes a plain list, `{codes, source}` or `{codes, unknown: <why>, source}`;
/// the profile keeps the codes, the reference and the export say where they come from.
#[test]
fn function_codes_carry_their_citation_or_why_they_are_not_printed() {
    let plain_line = "  function_codes: [0x03, 0x06, 0x08, 0x10]\n";
    assert!(
        fixture().contains(plain_line),
        "the fixture's function codes moved"
    );
    let with = |form: &str| fixture().replace(plain_line, &format!("  function_codes: {form}\n"));
    let text = with(
        "{codes: [03h, 0x06, 0x08, 0x10], unknown: \"no list printed; the codes of its examples\", source: \"manual.txt:9\"}",
    );
    let drive = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap();
    assert_eq!(
        drive.protocol().function_codes.codes,
        [0x03, 0x06, 0x08, 0x10]
    );
    let plan = drive.plan();
    assert_eq!(plan.profile.function_codes, &[0x03, 0x06, 0x08, 0x10]);
    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains(
            "| Function codes | 03h, 06h, 08h, 10h. List not printed: no list printed; the codes of its examples | `manual.txt:9` |"
        ),
        "{md}"
    );
    let json = drive.export();
    assert_eq!(
        json["protocol"]["function_codes"],
        serde_json::json!([3, 6, 8, 16])
    );
    let l = &json["protocol"]["limits"]["function_codes"];
    assert_eq!(
        l["not_printed"],
        "no list printed; the codes of its examples"
    );
    assert_eq!(l["source"], "manual.txt:9");
    assert_eq!(l["codes"], serde_json::json!([3, 6, 8, 16]));
    // The per-request limits are plain: only the function codes are in `limits`.
    assert!(json["protocol"]["limits"].get("max_read").is_none());

    // Cited only: the citation in the source column, no "not printed".
    let cited = drivemap_map::Loader::new()
        .load_str(
            "mini-drive.yaml",
            &with("{codes: [0x03, 0x06, 0x08, 0x10], source: \"manual.txt:9\"}"),
        )
        .unwrap();
    let md = drivemap_review::reference::render(&cited, "mini-drive.yaml");
    assert!(
        md.contains("| Function codes | 03h, 06h, 08h, 10h | `manual.txt:9` |"),
        "{md}"
    );
    // The codes are required: they are the working list.
    let e = drivemap_map::Loader::new()
        .load_str(
            "mini-drive.yaml",
            &with("{unknown: \"not printed\", source: \"manual.txt:9\"}"),
        )
        .unwrap_err();
    assert!(e.to_string().contains("missing field `codes`"), "{e}");
    // A code of the mapping form is read in hex and located in `codes`.
    let e = drivemap_map::Loader::new()
        .load_str(
            "mini-drive.yaml",
            &with("{codes: [0x03, 0x17, 0x06, 0x08, 0x10], source: \"manual.txt:9\"}"),
        )
        .unwrap_err();
    let e = e.to_string();
    assert!(
        e.contains("mini-drive.yaml:16:34: error: function 17h is not one drivemap speaks"),
        "{e}"
    );
    let e = drivemap_map::Loader::new()
        .load_str(
            "mini-drive.yaml",
            &with("{codes: [3, 16], source: \"manual.txt:9\"}"),
        )
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("function_codes.codes[1]: function code 16 is decimal (10H)"),
        "{e}"
    );
}

/// `broadcast: {unknown: <why>, source}`: the drive has a broadcast whose rules the manual does
/// not print. The profile says so (no functions, no addresses, the reason), and the reference
/// and the export say "broadcast exists, rules not printed".
#[test]
fn a_broadcast_whose_rules_are_not_printed_is_lowered_as_such() {
    let known = "  broadcast:\n    functions: [0x06, 0x10]\n    registers: [command]\n    source: \"manual.txt:11\"\n";
    assert!(fixture().contains(known), "the fixture's broadcast moved");
    // The fixture's broadcast group goes too: with rules not printed there is none.
    let group = "  - id: broadcast\n    name: Broadcast registers\n    broadcast: true\n    access: w\n    registers:\n      - id: broadcast_frequency\n        name: Broadcast frequency\n        address: 0x0002\n        unit: Hz\n        scale: {relative_to: max_frequency, full_scale: 30000}\n        source: \"manual.txt:25\"\n";
    assert!(
        fixture().contains(group),
        "the fixture's broadcast group moved"
    );
    let text = fixture().replace(group, "").replace(
        known,
        "  broadcast: {unknown: \"slave 0 is broadcast; no functions or registers printed\", source: \"manual.txt:11\"}\n",
    );
    let drive = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap();
    let plan = drive.plan();
    let b = plan.profile.broadcast.expect("the broadcast exists");
    assert_eq!(
        b.not_printed,
        Some("slave 0 is broadcast; no functions or registers printed")
    );
    assert!(b.functions.is_empty() && b.addresses.is_empty());
    // A known broadcast keeps its rules and no reason.
    let plain = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &fixture())
        .unwrap();
    let b = plain.plan().profile.broadcast.unwrap();
    assert_eq!((b.functions, b.not_printed), (&[0x06u8, 0x10][..], None));

    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains(
            "| Broadcast | broadcast exists, rules not printed: slave 0 is broadcast; no functions or registers printed. The runtime sends no broadcast to this drive. | `manual.txt:11` |"
        ),
        "{md}"
    );
    let json = drive.export();
    let b = &json["protocol"]["broadcast"];
    assert_eq!(
        b["not_printed"],
        "slave 0 is broadcast; no functions or registers printed"
    );
    assert_eq!(
        b["text"],
        "broadcast exists, rules not printed: slave 0 is broadcast; no functions or registers printed (manual.txt:11)"
    );
    assert_eq!(b["functions"], serde_json::json!([]));
    // The generated profile carries the reason too.
    let options = drivemap_codegen::generate::Options {
        runtime: "::drivemap_runtime".parse().unwrap(),
        source_name: "mini-drive.yaml".into(),
    };
    let code = drivemap_codegen::generate::drive_module(&drive, &options).unwrap();
    let squeezed: String = code.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        squeezed.contains(
            "BroadcastInfo::not_printed( \"slave 0 is broadcast; no functions or registers printed\", )"
        ),
        "the generated PROFILE carries the reason"
    );
}

/// `serial.formats`: the formats a parameter selects, lowered into the profile (the runtime's
/// serial configuration holds the line to them), shown by the reference and carried by the
/// export.
#[test]
fn serial_formats_chosen_by_a_parameter_reach_the_profile() {
    let serial = "  serial: {baud_rates: [9600, 19200], default_baud: 9600, parities: [none, even], source: \"manual.txt:16\"}\n";
    assert!(
        fixture().contains(serial),
        "the fixture's serial line moved"
    );
    let text = fixture().replace(
        serial,
        "  serial:\n    baud_rates: [9600, 19200]\n    parities: [none, even]\n    formats:\n      selected_by: response_delay\n      source: \"manual.txt:17\"\n      cases:\n        - {when: 0, parity: none, stop_bits: 2, source: \"manual.txt:18\"}\n        - {when: 1, parity: even, stop_bits: 1}\n        - {when: 2, data_bits: 7, parity: even, stop_bits: 1}\n    source: \"manual.txt:16\"\n",
    );
    let drive = drivemap_map::Loader::new()
        .load_str("mini-drive.yaml", &text)
        .unwrap_or_else(|d| panic!("{d}"));
    let plan = drive.plan();
    let f = plan.profile.serial_formats.expect("formats lowered");
    assert_eq!(
        (f.selected_by, f.source),
        ("response_delay", "manual.txt:17")
    );
    let listed: Vec<(u16, String)> = f.formats.iter().map(|x| (x.code, x.to_string())).collect();
    assert_eq!(
        listed,
        [(0, "8N2".into()), (1, "8E1".into()), (2, "7E1".into())]
    );
    use drivemap_core::profile::Parity;
    assert_eq!(f.stop_bits_for(Parity::None), Some(2));
    assert!(f.check("mini-drive", 8, Parity::None, 1).is_err());
    assert_eq!(f.check("mini-drive", 7, Parity::Even, 1).unwrap().code, 2);
    assert_eq!(
        drivemap_map::Loader::new()
            .load_str("mini-drive.yaml", &fixture())
            .unwrap()
            .plan()
            .profile
            .serial_formats,
        None
    );

    let md = drivemap_review::reference::render(&drive, "mini-drive.yaml");
    assert!(
        md.contains(
            "parity none, even; only the formats response_delay selects: 0 = 8N2, 1 = 8E1, 2 = 7E1 (`manual.txt:17`) | `manual.txt:16` |"
        ),
        "{md}"
    );
    let json = drive.export();
    let s = &json["protocol"]["serial"];
    assert!(
        s.get("stop_bits").is_none(),
        "each format gives its stop bits"
    );
    assert_eq!(s["formats"]["selected_by"], "response_delay");
    assert_eq!(s["formats"]["cases"][0]["format"], "8N2");
    assert_eq!(s["formats"]["cases"][0]["source"], "manual.txt:18");
    assert_eq!(s["formats"]["cases"][2]["data_bits"], 7);
    assert_eq!(s["formats"]["cases"][1]["parity"], "even");
    // The generated PROFILE carries them.
    let options = drivemap_codegen::generate::Options {
        runtime: "::drivemap_runtime".parse().unwrap(),
        source_name: "mini-drive.yaml".into(),
    };
    let code = drivemap_codegen::generate::drive_module(&drive, &options).unwrap();
    let squeezed: String = code.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        squeezed.contains(
            "serial_formats: Some(rt::profile::SerialFormats { selected_by: \"response_delay\""
        ),
        "the generated PROFILE carries the formats"
    );
}
