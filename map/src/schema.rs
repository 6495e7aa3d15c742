//! Schema versions: a map says which version of this schema it is written in (`schema: 2` at
//! the top), and every earlier version keeps being read by its meaning.
//!
//! A map that states no version is read as schema 1, the schema of every map written before
//! versions were stated. Reading an earlier version gives warnings that name what changed (one
//! for the file, one for every value that the current schema would write otherwise);
//! [`migrate`] rewrites such a file in the current schema with the same meaning.
//!
//! The versions, and what each changed:
//!
//! | version | since | change |
//! |---|---|---|
//! | 1 | — | a bare number where an address or code goes is decimal (YAML's reading) |
//! | 2 | 2026-11-25 (commits abfacec, ff42287) | addresses and codes are written as the manual prints them, in hex (`0x2001`, `2001H`); a bare decimal is refused unless the map declares `address_format: decimal` (addresses), or is 0-9 (codes); a YAML alias there is refused |

use std::sync::Arc;

use serde_yaml::Value;

use crate::diagnostic::{Diagnostic, Loc};
use crate::hex::Reread;
use crate::source::{Node, NodeKind};

/// The schema version this generator writes and reads without warning.
pub const CURRENT: u32 = 2;

/// What each version changed, by version (index 0 is version 2): the text of a warning on a
/// map of an earlier version.
pub(crate) const CHANGES: &[(u32, &str)] = &[(
    2,
    "schema 2 reads addresses and codes as the manual prints them, in hex (0x2001, 2001H), and \
     refuses a bare decimal (unless `address_format: decimal`, or a code 0-9) and a YAML alias \
     there",
)];

/// The version a file is written in: its `schema:` (1 when it states none), or why it is refused.
pub(crate) fn version_of(tree: &Node) -> Result<u32, Diagnostic> {
    let Some(node) = tree.get("schema") else {
        return Ok(1);
    };
    let refuse = |what: String| {
        Diagnostic::new(
            node.loc.clone(),
            None,
            format!("schema: {what}; this drivemap reads schema versions 1 to {CURRENT}"),
        )
    };
    match &node.kind {
        NodeKind::Scalar(Value::Number(n)) => match n.as_u64() {
            Some(v) if (1..=u64::from(CURRENT)).contains(&v) => Ok(v as u32),
            Some(v) if v > u64::from(CURRENT) => Err(refuse(format!(
                "the map is written in schema {v}, newer than this drivemap: update drivemap"
            ))),
            _ => Err(refuse(format!("`{n}` is not a schema version"))),
        },
        _ => Err(refuse(
            "the version is a whole number (`schema: 2`)".to_owned(),
        )),
    }
}

/// The warning on a file read in an earlier version: what changed since.
pub(crate) fn file_warning(file: &Arc<str>, tree: &Node, version: u32) -> Option<Diagnostic> {
    if version >= CURRENT {
        return None;
    }
    let (loc, stated) = match tree.get("schema") {
        Some(n) => (n.loc.clone(), format!("states `schema: {version}`")),
        None => (
            Loc::new(file.clone(), 1, 1),
            "states no `schema:`, so it is schema 1 (maps written before 2026-11-25)".to_owned(),
        ),
    };
    let changes: Vec<&str> = CHANGES
        .iter()
        .filter(|(v, _)| *v > version)
        .map(|(_, what)| *what)
        .collect();
    Some(Diagnostic::new(
        loc,
        None,
        format!(
            "this map {stated} and is read by its meaning: a bare number where an address or \
             code goes is decimal. Changed since: {}. `drivemap migrate {file}` rewrites it in \
             schema {CURRENT}",
            changes.join("; ")
        ),
    ))
}

/// A map file rewritten in the current schema.
#[derive(Debug, Clone)]
pub struct Migrated {
    /// The file's text in schema [`CURRENT`] (the input unchanged if it was already).
    pub text: String,
    /// The version it was written in.
    pub from: u32,
    /// The values rewritten (each now in its hex notation).
    pub rewritten: Vec<Reread>,
}

/// Rewrites one map file in the current schema, keeping its meaning: every number that its
/// version reads otherwise than the current one is written as the current one reads it
/// (`code: 10` of schema 1, decimal ten, becomes `code: 0x0A`), and the file states
/// `schema: {CURRENT}`. Comments and layout are kept. The result is read back and compared with
/// the original, value by value; a difference is an error, never a silent change.
pub(crate) fn migrate(file: &Arc<str>, text: &str) -> Result<Migrated, Vec<Diagnostic>> {
    let parsed = crate::source::parse_map(file, text)?;
    if parsed.version >= CURRENT {
        return Ok(Migrated {
            text: text.to_owned(),
            from: parsed.version,
            rewritten: Vec::new(),
        });
    }
    if !parsed.slot_aliases.is_empty() {
        // An alias stands for a number written elsewhere; only its author knows which
        // notation it meant there.
        return Err(parsed
            .slot_aliases
            .iter()
            .map(|a| {
                Diagnostic::new(
                    a.loc.clone(),
                    None,
                    format!("migrate: {}; then migrate", a.message),
                )
            })
            .collect());
    }
    let mut lines: Vec<String> = text.split_inclusive('\n').map(str::to_owned).collect();
    let mut edits: Vec<&Reread> = parsed.reread.iter().collect();
    // From the end of each line, so the columns of earlier edits stay right.
    edits.sort_by_key(|r| std::cmp::Reverse((r.loc.line, r.loc.col)));
    let cannot = |loc: &Loc, what: &str| {
        vec![Diagnostic::new(
            loc.clone(),
            None,
            format!("migrate: cannot rewrite {what} here; edit it by hand"),
        )]
    };
    for r in edits {
        let Some(line) = lines.get_mut(r.loc.line.wrapping_sub(1)) else {
            return Err(cannot(&r.loc, &r.text));
        };
        let start = line
            .char_indices()
            .nth(r.loc.col.saturating_sub(1))
            .map_or(line.len(), |(i, _)| i);
        let rest = &line[start..];
        let len = match rest.chars().next() {
            Some(q @ ('"' | '\'')) if rest[1..].starts_with(&r.text) => {
                if !rest[1 + r.text.len()..].starts_with(q) {
                    return Err(cannot(&r.loc, &r.text));
                }
                r.text.len() + 2
            }
            _ if rest.starts_with(&r.text) => r.text.len(),
            _ => return Err(cannot(&r.loc, &r.text)),
        };
        line.replace_range(start..start + len, &r.hex());
    }
    let stamp = format!("schema: {CURRENT}");
    match parsed.tree.get("schema") {
        Some(node) => {
            let i = node.loc.line.wrapping_sub(1);
            let Some(line) = lines.get_mut(i) else {
                return Err(cannot(&node.loc, "`schema:`"));
            };
            let old = format!("schema: {}", parsed.version);
            if !line.starts_with(&old) {
                return Err(cannot(&node.loc, "`schema:`"));
            }
            line.replace_range(..old.len(), &stamp);
        }
        None => {
            // Before the first top-level key, after the comments that open the file.
            let at = lines
                .iter()
                .position(|l| l.starts_with(|c: char| c.is_ascii_alphabetic()))
                .unwrap_or(lines.len());
            let eol = if text.contains("\r\n") { "\r\n" } else { "\n" };
            lines.insert(at, format!("{stamp}{eol}"));
        }
    }
    let migrated: String = lines.concat();
    let again = crate::source::parse_map(file, &migrated)?;
    let meaning = |tree: &Node| {
        let mut v = tree.to_value();
        if let Value::Mapping(m) = &mut v {
            m.remove("schema");
        }
        v
    };
    if again.version != CURRENT
        || !again.reread.is_empty()
        || meaning(&again.tree) != meaning(&parsed.tree)
    {
        return Err(vec![Diagnostic::new(
            Loc::new(file.clone(), 1, 1),
            None,
            "migrate: the rewritten map would not mean what this one means; nothing written",
        )]);
    }
    Ok(Migrated {
        text: migrated,
        from: parsed.version,
        rewritten: parsed.reread,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const OLD: &str = "# an old map\ndrive: {id: t}\nprotocol:\n  function_codes: [3, 6, 16]\n  \
                       exceptions:\n    - {code: 10, name: Ten}\n    - {code: \"65\", name: A}\n\
                       groups:\n  - registers:\n      - {id: a, address: 8192}\n      \
                       - {id: b, address: 0x2001}\n";

    #[test]
    fn an_unstated_version_is_one_and_reads_decimals_as_decimals() {
        let file: Arc<str> = Arc::from("old.yaml");
        let p = crate::source::parse_map(&file, OLD).unwrap();
        assert_eq!(p.version, 1);
        let v = p.tree.to_value();
        assert_eq!(v["protocol"]["exceptions"][0]["code"], Value::from(10u64));
        assert_eq!(
            v["groups"][0]["registers"][0]["address"],
            Value::from(8192u64)
        );
        // The file's warning, then one per number read otherwise than schema 2 would.
        assert!(
            p.warnings[0].message.contains("states no `schema:`"),
            "{:?}",
            p.warnings
        );
        let rewritten: Vec<String> = p.reread.iter().map(Reread::hex).collect();
        assert_eq!(rewritten, ["0x10", "0x0A", "0x41", "0x2000"]);
        assert_eq!(p.warnings.len(), 5);
        assert!(
            p.warnings[2]
                .message
                .contains("exception code 10 is decimal 10 (0AH), as schema 1 reads it"),
            "{}",
            p.warnings[2].message
        );
    }

    #[test]
    fn migrate_keeps_the_meaning_and_states_the_version() {
        let file: Arc<str> = Arc::from("old.yaml");
        let m = migrate(&file, OLD).unwrap();
        assert_eq!(m.from, 1);
        assert_eq!(
            m.text,
            "# an old map\nschema: 2\ndrive: {id: t}\nprotocol:\n  function_codes: [3, 6, 0x10]\n  \
             exceptions:\n    - {code: 0x0A, name: Ten}\n    - {code: 0x41, name: A}\n\
             groups:\n  - registers:\n      - {id: a, address: 0x2000}\n      \
             - {id: b, address: 0x2001}\n"
        );
        let p = crate::source::parse_map(&file, &m.text).unwrap();
        assert!(p.warnings.is_empty() && p.version == CURRENT);
        // Migrating twice changes nothing.
        assert_eq!(migrate(&file, &m.text).unwrap().text, m.text);
        // Windows line ends are kept.
        let crlf = migrate(&file, &OLD.replace('\n', "\r\n")).unwrap();
        assert_eq!(crlf.text, m.text.replace('\n', "\r\n"));
        // `schema: 1` stated is rewritten in place.
        let stated = OLD.replace("drive:", "schema: 1\ndrive:");
        let m1 = migrate(&file, &stated).unwrap();
        assert_eq!(m1.text, m.text);
    }

    #[test]
    fn an_alias_where_an_address_goes_is_read_in_schema_1_and_refused_in_schema_2() {
        let file: Arc<str> = Arc::from("a.yaml");
        let text = "x: &a 8192\ngroups:\n  - registers:\n      - {id: a, address: *a}\n";
        let p = crate::source::parse_map(&file, text).unwrap();
        assert_eq!(
            p.tree.to_value()["groups"][0]["registers"][0]["address"],
            Value::from(8192u64)
        );
        let w = p.warnings.last().unwrap();
        assert_eq!((w.loc.line, w.loc.col), (4, 26));
        assert!(
            w.message.contains(
                "YAML alias `*a` where an address or code goes; schema 1 reads the anchored value"
            ),
            "{}",
            w.message
        );
        let e = migrate(&file, text).unwrap_err();
        assert!(
            e[0].message.starts_with("migrate: YAML alias `*a`"),
            "{}",
            e[0].message
        );
        let e = crate::source::parse_map(&file, &format!("schema: 2\n{text}")).unwrap_err();
        assert!(
            e[0].message.contains("write the number itself"),
            "{}",
            e[0].message
        );
    }

    #[test]
    fn versions_are_checked() {
        let file: Arc<str> = Arc::from("x.yaml");
        for (text, msg) in [
            (
                "schema: 3\ndrive: {}\n",
                "written in schema 3, newer than this drivemap",
            ),
            ("schema: 0\ndrive: {}\n", "`0` is not a schema version"),
            ("schema: two\ndrive: {}\n", "whole number"),
        ] {
            let e = crate::source::parse_map(&file, text).unwrap_err();
            assert!(e[0].message.contains(msg), "{text}: {}", e[0].message);
            assert_eq!((e[0].loc.line, e[0].loc.col), (1, 9), "{text}");
        }
        // In schema 2 a bare decimal is refused, as before versions were stated.
        let e =
            crate::source::parse_map(&file, "schema: 2\nprotocol: {exceptions: [{code: 10}]}\n")
                .unwrap_err();
        assert!(
            e[0].message.contains("exception code 10 is decimal"),
            "{}",
            e[0].message
        );
    }
}
