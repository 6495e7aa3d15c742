//! `drivemap diff` on number roles in fields and on edge/level: the acme-vf1 fixture's fault
//! code moved from its register (2105H) to the status word's high byte is a re-pointed role
//! (breaking: `fault_code()` reads another place); a field made signed, a reset's edge made
//! "not printed", and the reason of a not-printed edge changed each show, with their kind.

use drivemap_test_support::paths;

use drivemap_map::Map;
use drivemap_review::diff::{ChangeKind, compare};

fn acme_text() -> String {
    std::fs::read_to_string(paths::fixture("acme-vf1/acme-vf1.yaml")).unwrap()
}

fn read(text: &str) -> Map {
    drivemap_map::Loader::new()
        .load_str("acme-vf1.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// `text` with `from` replaced by `to` (which must be there).
fn changed(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from}");
    text.replace(from, to)
}

/// The changes of the `roles` subject, as (kind, what, old, new).
fn role_changes(old: &Map, new: &Map) -> Vec<(ChangeKind, String, String, String)> {
    compare(old, new)
        .changes
        .into_iter()
        .filter(|c| c.subject == "roles")
        .map(|c| {
            (
                c.kind,
                c.what,
                c.old.unwrap_or_default(),
                c.new.unwrap_or_default(),
            )
        })
        .collect()
}

const FIELD: &str =
    r#"    - {register: status_word, field: active_fault, source: "acme-vf1.txt:58"}"#;
const REGISTER: &str = r#"    - {register: fault_code, source: "acme-vf1.txt:33"}"#;

#[test]
fn a_role_moved_from_a_register_to_a_field_is_re_pointed() {
    let new_text = acme_text();
    // Before: the register alone (its place is the second now).
    let old = read(&changed(
        &new_text,
        &format!("{FIELD}\n{REGISTER}\n"),
        &format!("{REGISTER}\n"),
    ));
    let new = read(&new_text);
    let changes = role_changes(&old, &new);
    assert_eq!(changes.len(), 1, "{changes:?}");
    let (kind, what, before, after) = &changes[0];
    assert_eq!(*kind, ChangeKind::RoleRepointed);
    assert_eq!(what, "fault_code");
    assert_eq!(before, "fault_code (2105h)");
    assert!(
        after.starts_with(
            "field `active_fault` (bits 8–15) of status_word (2100h), unsigned, 1 per count"
        ),
        "{after}"
    );
    // And back.
    let back = role_changes(&new, &old);
    assert_eq!(back.len(), 1, "{back:?}");
    assert_eq!(back[0].0, ChangeKind::RoleRepointed);
}

#[test]
fn signed_scale_and_edge_changes_show() {
    let text = acme_text();
    let base = read(&text);
    let signed = read(&changed(
        &text,
        FIELD,
        r#"    - {register: status_word, field: active_fault, signed: true, source: "acme-vf1.txt:58"}"#,
    ));
    let changes = role_changes(&base, &signed);
    assert_eq!(changes.len(), 1, "{changes:?}");
    assert_eq!(changes[0].0, ChangeKind::RoleCodesChanged);
    assert!(changes[0].3.contains("signed, 1 per count"), "{changes:?}");

    let scaled = read(&changed(
        &text,
        FIELD,
        r#"    - {register: status_word, field: active_fault, scale: 2, source: "acme-vf1.txt:58"}"#,
    ));
    let changes = role_changes(&base, &scaled);
    assert_eq!(changes.len(), 1, "{changes:?}");
    assert_eq!(changes[0].0, ChangeKind::RoleCodesChanged);

    let edge = r#"field: fault_reset, edge: true,"#;
    let unknown = |why: &str| {
        changed(
            &text,
            edge,
            &format!("field: fault_reset, edge: {{unknown: \"{why}\"}},"),
        )
    };
    let not_printed = read(&unknown("no timing printed"));
    let changes = role_changes(&base, &not_printed);
    assert_eq!(changes.len(), 1, "{changes:?}");
    assert_eq!(changes[0].0, ChangeKind::RoleCodesChanged);
    assert!(changes[0].2.contains("on the transition"), "{changes:?}");
    assert!(
        changes[0].3.contains("edge or level not printed"),
        "{changes:?}"
    );
    let level = read(&changed(&text, edge, "field: fault_reset,"));
    assert_eq!(
        role_changes(&not_printed, &level)[0].0,
        ChangeKind::RoleCodesChanged
    );
    // Another reason: documentation only.
    let other = read(&unknown("the timing table is cut off"));
    let changes = role_changes(&not_printed, &other);
    assert_eq!(changes.len(), 1, "{changes:?}");
    assert_eq!(changes[0].0, ChangeKind::DocumentationChanged);
}

/// `doc` shows a number field with its bits, sign and scale, and an edge the manual does not
/// print as "not printed" with the reason; `export` carries both keys as written.
#[test]
fn doc_and_export_show_a_number_field_and_an_unknown_edge() {
    let path = paths::fixture("brenner-fx4/brenner-fx4.yaml");
    let drive = drivemap_map::Loader::new()
        .load(path.as_ref())
        .unwrap_or_else(|e| panic!("{e}"));
    let doc = drivemap_review::reference::render(&drive, "brenner-fx4.yaml");
    let row = |role: &str| {
        doc.lines()
            .find(|l| l.starts_with(&format!("| `{role}` |")))
            .unwrap_or_else(|| panic!("no {role} row in:\n{doc}"))
            .to_owned()
    };
    assert_eq!(
        row("fault_code"),
        "| `fault_code` | `state_word` | `last_event` (signed bits 8–15, 1 per count) |  |  | `brenner-fx4.txt:17` |"
    );
    assert!(
        row("fault_reset")
            .contains("edge or level not printed in the manual: the guide names the bit"),
        "{}",
        row("fault_reset")
    );
    let json = drive.export();
    let roles = &json["roles"];
    assert_eq!(roles["fault_code"][0]["signed"], true, "{roles}");
    assert_eq!(roles["fault_code"][0]["field"], "last_event", "{roles}");
    assert!(
        roles["fault_reset"][0]["edge"]["unknown"]
            .as_str()
            .is_some_and(|s| s.starts_with("the guide names the bit")),
        "{roles}"
    );
}
