//! The map's example frames verified against the codec and the map
//! (`drivemap_live::examples`), on the fictional Orbis Q5 of `tests/fixtures/orbis-q5/`, whose
//! manual prints twelve frames, one with a CRC that does not check (recorded in `conflicts:`).
//! Each way an example can contradict the codec or the map is injected into a copy of the map
//! and must be reported at the byte concerned; any single corrupted byte of any example is found.

use drivemap_test_support::paths;

use std::path::PathBuf;

use drivemap_live::examples::{self, Verified};
use drivemap_runtime::crc;

fn fixture() -> PathBuf {
    paths::fixture("orbis-q5")
}

fn original() -> String {
    std::fs::read_to_string(fixture().join("orbis-q5.yaml")).unwrap()
}

/// Reads `text` as the Q5 map (written to a file of its own, so that findings carry columns
/// as in the file) and verifies its examples.
fn verify(text: &str, name: &str) -> (PathBuf, Verified) {
    let dir = std::env::temp_dir().join(format!(
        "drivemap-example-frames-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("orbis-q5.yaml");
    std::fs::write(&path, text).unwrap();
    let drive = drivemap_map::Loader::new()
        .manuals(fixture().join("manuals"))
        .load(&path)
        .unwrap_or_else(|e| panic!("{e}"));
    let found = examples::verify(&drive);
    (path, found)
}

/// An RTU frame with its CRC, as the map writes bytes.
fn rtu(hex: &str) -> String {
    let mut bytes: Vec<u8> = hex
        .split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect();
    bytes.extend(crc::crc_bytes(&bytes));
    drivemap_map::facts::hex_text(&bytes)
}

fn errors(v: &Verified) -> Vec<String> {
    v.errors.iter().map(ToString::to_string).collect()
}

#[test]
fn the_fixture_verifies_with_its_recorded_crc_known() {
    let (path, v) = verify(&original(), "as-is");
    assert!(v.errors.is_empty(), "{:?}", errors(&v));
    assert_eq!(v.clean, 11);
    assert_eq!(v.known.len(), 1, "{:?}", v.known);
    let known = &v.known[0];
    assert_eq!(
        (known.example.as_str(), known.conflict.as_str()),
        (
            "frequency_too_high_refused",
            "CRC of the refused-write example"
        )
    );
    let findings: Vec<String> = known
        .findings
        .iter()
        .map(|f| f.diagnostic.to_string())
        .collect();
    // Line 108 is `bytes: "01 86 03 02 62"`; byte 5 (62, the CRC byte that differs) is at column 25.
    assert_eq!(
        findings,
        [format!(
            "{}:108:25: error: example `frequency_too_high_refused`, byte 5 (62): CRC: the frame \
             ends in 02 62, the CRC-16 of the bytes before it is 02 61 (low byte first)",
            path.display()
        )]
    );
    assert_eq!(
        known.warning(),
        format!(
            "{}:108:25: warning: example `frequency_too_high_refused`, byte 5 (62): CRC: the \
             frame ends in 02 62, the CRC-16 of the bytes before it is 02 61 (low byte first); \
             recorded in `conflicts:` as \"CRC of the refused-write example\"",
            path.display()
        )
    );
}

/// A recorded frame that contradicts the map at several bytes is one warning, at the first
/// byte that differs, naming each byte and the conflict: a write of four registers from 0001h
/// (0003h and 0004h are none of the map's), appended to a copy with a `conflict:` mark.
#[test]
fn a_recorded_frame_with_several_findings_is_one_warning() {
    let bytes = rtu("01 10 00 01 00 04 08 00 01 0B B8 00 00 00 00");
    let text = format!(
        "{}  - id: write_beyond_the_map\n    transport: rtu\n    direction: request\n    \
         bytes: \"{bytes}\"\n    source: \"orbis-q5.txt:23-24\"\n    \
         conflict: CRC of the refused-write example\n",
        original()
    );
    let (path, v) = verify(&text, "several");
    assert!(v.errors.is_empty(), "{:?}", errors(&v));
    assert_eq!(v.known.len(), 2, "{:?}", v.known);
    let known = &v.known[1];
    assert_eq!(known.example, "write_beyond_the_map");
    assert_eq!(known.findings.len(), 2, "{:?}", known.findings);
    assert_eq!(known.bytes(), "bytes 12, 14");
    let line = text.lines().position(|l| l.contains(&bytes)).unwrap() + 1;
    // `    bytes: "` puts byte 1 at column 13; byte 12 at 13 + 3 × 11 = 46.
    assert_eq!(
        known.warning(),
        format!(
            "{}:{line}:46: warning: example `write_beyond_the_map`, bytes 12, 14: address 0003h \
             (word 3 of the frame) is not a register of the map (the first of 2 findings); \
             recorded in `conflicts:` as \"CRC of the refused-write example\"",
            path.display()
        )
    );
}

#[test]
fn an_unrecorded_wrong_crc_is_an_error_at_its_byte() {
    let text = original().replace("    conflict: CRC of the refused-write example\n", "");
    let (path, v) = verify(&text, "unmarked");
    assert_eq!(
        errors(&v),
        [format!(
            "{}:108:25: error: example `frequency_too_high_refused`, byte 5 (62): CRC: the frame \
             ends in 02 62, the CRC-16 of the bytes before it is 02 61 (low byte first)",
            path.display()
        )]
    );
}

#[test]
fn a_mark_on_an_example_that_verifies_is_an_error() {
    let text = original().replace(
        "    source: \"orbis-q5.txt:25\"\n",
        "    source: \"orbis-q5.txt:25\"\n    conflict: CRC of the refused-write example\n",
    );
    let (_, v) = verify(&text, "marked-clean");
    let e = errors(&v);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains(
            "example `run_forward_echo` verifies against the codec and the map, but is marked"
        ),
        "{e:?}"
    );
}

/// Each contradiction injected into one example, and the error it must give.
#[test]
fn each_contradiction_is_reported_at_the_byte_concerned() {
    let set = "bytes: \"01 06 00 02 0B B8 2F 48\"\n    source: \"orbis-q5.txt:20-21\"";
    let cases: Vec<(&str, String, String, &str)> = vec![
        (
            "crc",
            set.into(),
            set.replace("2F 48", "2F 49"),
            // the quote of `    bytes: "` is column 12: byte 8 (49), at offset 21, is column 34.
            ":62:34: error: example `set_frequency`, byte 8 (49): CRC: the frame ends in 2F 49, the CRC-16 of the bytes before it is 2F 48",
        ),
        (
            "function",
            set.into(),
            set.replace("01 06 00 02 0B B8 2F 48", &rtu("01 05 00 02 0B B8")),
            ":62:16: error: example `set_frequency`, byte 2 (05): function 05h is not among the map's function codes (03h, 06h, 10h)",
        ),
        (
            "address",
            set.into(),
            set.replace("01 06 00 02 0B B8 2F 48", &rtu("01 06 00 30 0B B8")),
            ":62:19: error: example `set_frequency`, byte 3 (00): address 0030h is not a register of the map",
        ),
        (
            "range",
            set.into(),
            set.replace("01 06 00 02 0B B8 2F 48", &rtu("01 06 00 02 15 7C")),
            ":62:25: error in register `frequency_command`: example `set_frequency`, byte 5 (15): 157Ch = 55 is refused by the map",
        ),
        (
            "value",
            "write: frequency_command, values: [30.0]}\n  - id: set_frequency_echo".into(),
            "write: frequency_command, values: [25.0]}\n  - id: set_frequency_echo".into(),
            "example `set_frequency`, byte 5 (0B): 0BB8h decodes to 30 by the map, the example says 25",
        ),
        (
            "read_only",
            set.into(),
            set.replace("01 06 00 02 0B B8 2F 48", &rtu("01 06 00 10 0B B8")),
            "example `set_frequency`, byte 5 (0B): `output_frequency` is read-only in the map",
        ),
        (
            "says_register",
            "says: {read: output_frequency}\n  - id: read_monitors_answer".into(),
            "says: {read: output_current}\n  - id: read_monitors_answer".into(),
            "example `read_monitors`, byte 3 (00): address 0010h is `output_frequency`, the example says `output_current`",
        ),
        (
            "echo",
            "bytes: \"01 06 00 02 0B B8 2F 48\"\n    source: \"orbis-q5.txt:22\"".into(),
            format!(
                "bytes: \"{}\"\n    source: \"orbis-q5.txt:22\"",
                rtu("01 06 00 02 0B B9")
            ),
            "example `set_frequency_echo`, byte 6 (B9): does not answer `set_frequency`: value 0BB9h echoed, 0BB8h sent",
        ),
        (
            "byte_count",
            "bytes: \"01 03 04 0B B8 00 23 39 EB\"".into(),
            format!("bytes: \"{}\"", rtu("01 03 02 0B B8")),
            "example `read_monitors_answer`, byte 3 (02): does not answer `read_monitors`",
        ),
        (
            "slave",
            "bytes: \"01 10 00 01 00 02 10 08\"".into(),
            format!("bytes: \"{}\"", rtu("02 10 00 01 00 02")),
            "example `run_forward_echo`, byte 1 (02): slave 02h answers `run_forward`, which is addressed to slave 01h",
        ),
        (
            "exception_code",
            "bytes: \"01 83 02 C0 F1\"".into(),
            format!("bytes: \"{}\"", rtu("01 83 03")),
            "example `read_unknown_address_refused`, byte 3 (03): exception code 03h, the example says 02h",
        ),
        (
            "exception_unlisted",
            "bytes: \"01 83 02 C0 F1\"\n    source: \"orbis-q5.txt:28\"\n    says: {exception: 0x02}".into(),
            format!(
                "bytes: \"{}\"\n    source: \"orbis-q5.txt:28\"\n    says: {{exception: 0x21}}",
                rtu("01 83 21")
            ),
            "example `read_unknown_address_refused`, byte 3 (21): exception code 21h is not among the map's exception codes",
        ),
        (
            "mbap_length",
            "bytes: \"00 05 00 00 00 06 01 03 00 10 00 02\"".into(),
            "bytes: \"00 05 00 00 00 07 01 03 00 10 00 02\"".into(),
            "example `tcp_read_monitors`, byte 5 (00): MBAP length says 7 bytes follow it, the frame has 6 after it",
        ),
        (
            "transaction",
            "bytes: \"00 05 00 00 00 07 01 03 04 0B B8 00 23\"".into(),
            "bytes: \"00 06 00 00 00 07 01 03 04 0B B8 00 23\"".into(),
            "example `tcp_read_monitors_answer`, byte 1 (00): transaction 00 06 does not echo `tcp_read_monitors`'s 00 05",
        ),
    ];
    for (name, from, to, want) in cases {
        let text = original();
        assert!(text.contains(&from), "{name}: `{from}` not in the fixture");
        let (path, v) = verify(&text.replacen(&from, &to, 1), name);
        let e = errors(&v);
        assert!(
            e.iter().any(|d| d.contains(want)),
            "{name}: no error containing {want:?} in {e:#?}"
        );
        if want.starts_with(':') {
            assert!(
                e.iter()
                    .any(|d| d.starts_with(&format!("{}{want}", path.display()))),
                "{name}: not located as {want:?}: {e:#?}"
            );
        }
    }
}

/// Any single byte of any example changed (three ways) is found: an error of the map, not
/// passed as verified. The example whose contradiction is recorded is left out: its findings
/// are known by design.
#[test]
fn any_corrupted_byte_of_any_example_is_found() {
    let text = original();
    let (_, base) = verify(&text, "corrupt-base");
    assert!(base.errors.is_empty());
    let mut tried = 0;
    for line in text.lines() {
        let Some(bytes) = line
            .trim()
            .strip_prefix("bytes: \"")
            .and_then(|b| b.strip_suffix('"'))
        else {
            continue;
        };
        if bytes == "01 86 03 02 62" {
            continue;
        }
        let words: Vec<&str> = bytes.split(' ').collect();
        for i in 0..words.len() {
            for flip in [0x01u8, 0x80, 0xFF] {
                let b = u8::from_str_radix(words[i], 16).unwrap() ^ flip;
                let mut changed = words.clone();
                let hex = format!("{b:02X}");
                changed[i] = &hex;
                let new_line = line.replace(bytes, &changed.join(" "));
                let corrupted = text.replacen(line, &new_line, 1);
                let (_, v) = verify(&corrupted, "corrupt");
                assert!(
                    !v.errors.is_empty(),
                    "byte {} of `{bytes}` xor {flip:02X} passed as verified",
                    i + 1
                );
                tried += 1;
            }
        }
    }
    assert!(tried > 250, "{tried}");
}
