//! Names that must become Rust identifiers: drive id, group, register, field, enumeration value,
//! variant and command ids.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::source::Path;

const KEYWORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern",
    "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut",
    "pub", "ref", "return", "self", "static", "struct", "super", "trait", "true", "type", "unsafe",
    "use", "where", "while", "abstract", "become", "box", "do", "final", "macro", "override",
    "priv", "try", "typeof", "unsized", "virtual", "yield",
];

/// A lower snake_case identifier that is not a Rust keyword: `[a-z][a-z0-9_]*`.
pub(crate) fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some('a'..='z'))
        && chars.all(|c| matches!(c, 'a'..='z' | '0'..='9' | '_'))
        && !s.ends_with('_')
        && !s.contains("__")
        && !KEYWORDS.contains(&s)
}

fn need(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    path: Path,
    register: Option<&str>,
    what: &str,
    id: &str,
) {
    if !is_identifier(id) {
        out.push(drive.error(
            &path,
            register,
            format!("{what} `{id}` is not a valid identifier: use lower snake_case starting with a letter (a-z, 0-9, _), not a Rust keyword"),
        ));
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let id = &drive.meta.id;
    let ok = id.chars().next().is_some_and(|c| c.is_ascii_lowercase())
        && id
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
        && !id.ends_with('-')
        && !id.contains("--");
    if !ok {
        out.push(drive.error(
            &Path::root().key("drive").key("id"),
            None,
            format!("drive id `{id}` must be lower case letters, digits and single dashes (`ptlk-tds-v8`)"),
        ));
    }
    if let Some(stem) = drive.file.file_stem()
        && drive.file.extension().is_some_and(|e| e == "yaml")
        && stem.to_string_lossy() != *id
    {
        out.push(drive.error(
            &Path::root().key("drive").key("id"),
            None,
            format!(
                "drive id `{id}` must match the file name `{}`",
                drive.file.display()
            ),
        ));
    }
    for (ai, axis) in drive.variants.iter().enumerate() {
        let ap = Path::root().key("variants").index(ai);
        need(drive, out, ap.key("id"), None, "variant axis", &axis.id);
        for (oi, o) in axis.options.iter().enumerate() {
            need(
                drive,
                out,
                ap.key("options").index(oi).key("id"),
                None,
                "variant option",
                &o.id,
            );
        }
    }
    for (ci, c) in drive.protocol.commands.iter().enumerate() {
        need(
            drive,
            out,
            Path::root()
                .key("protocol")
                .key("commands")
                .index(ci)
                .key("id"),
            None,
            "command",
            &c.id,
        );
    }
    for g in &drive.groups {
        need(drive, out, g.path.key("id"), None, "group", &g.id);
    }
    for r in &drive.registers {
        let rid = r.id();
        need(drive, out, r.key_path("id"), Some(rid), "register id", rid);
        for (fi, f) in r.def.fields.iter().enumerate() {
            let fp = r.key_path("fields").index(fi);
            need(drive, out, fp.key("id"), Some(rid), "field id", &f.id);
            for (vi, v) in f.values.iter().enumerate() {
                need(
                    drive,
                    out,
                    fp.key("values").index(vi).key("id"),
                    Some(rid),
                    "value id",
                    &v.id,
                );
            }
        }
        for (vi, v) in r.def.read_values.iter().enumerate() {
            need(
                drive,
                out,
                r.key_path("read_values").index(vi).key("id"),
                Some(rid),
                "value id",
                &v.id,
            );
        }
        for (vi, v) in r.def.values.iter().enumerate() {
            need(
                drive,
                out,
                r.key_path("values").index(vi).key("id"),
                Some(rid),
                "value id",
                &v.id,
            );
        }
    }
    for q in drive.externals() {
        if !is_identifier(&q.external) {
            out.push(drive.error(
                &Path::root(),
                None,
                format!(
                    "external quantity `{}` is not a valid identifier",
                    q.external
                ),
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::names::pascal_case;

    #[test]
    fn identifiers() {
        assert!(is_identifier("accel_time_1"));
        assert!(!is_identifier("1st_step"));
        assert!(!is_identifier("Accel"));
        assert!(!is_identifier("type"));
        assert!(!is_identifier("a-b"));
        assert_eq!(pascal_case("accel_time_1"), "AccelTime1");
        assert_eq!(pascal_case("n152"), "N152");
    }
}
