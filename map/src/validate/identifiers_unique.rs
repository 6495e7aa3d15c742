//! Duplicate identifiers: register ids and parameter numbers, group, variant, command and
//! exception ids, field and value ids within a register, enumeration codes, and the Rust type
//! names they become.

use std::collections::HashMap;

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, ValueKind};
use crate::model::EnumValue;
use crate::names;
use crate::source::Path;

struct Seen<'a> {
    first: HashMap<String, Path>,
    what: &'a str,
}

impl<'a> Seen<'a> {
    fn new(what: &'a str) -> Self {
        Seen {
            first: HashMap::new(),
            what,
        }
    }

    fn add(
        &mut self,
        drive: &Drive,
        out: &mut Vec<Diagnostic>,
        key: &str,
        path: Path,
        register: Option<&str>,
    ) {
        if let Some(first) = self.first.get(key) {
            let at = drive.locate(first);
            out.push(drive.error(
                &path,
                register,
                format!(
                    "duplicate {} `{key}` (first at line {})",
                    self.what, at.line
                ),
            ));
        } else {
            self.first.insert(key.to_owned(), path);
        }
    }
}

fn values(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    list: &[EnumValue],
    path: &Path,
    register: &str,
) {
    let mut ids = Seen::new("value id");
    let mut codes = Seen::new("value code");
    let mut variants = Seen::new("enum variant name (ids differing only in underscores)");
    for (i, v) in list.iter().enumerate() {
        let p = path.index(i);
        ids.add(drive, out, &v.id, p.key("id"), Some(register));
        variants.add(
            drive,
            out,
            &crate::validate::pascal_case(&v.id),
            p.key("id"),
            Some(register),
        );
        codes.add(
            drive,
            out,
            &v.value.to_string(),
            p.key("value"),
            Some(register),
        );
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let mut groups = Seen::new("group id");
    for g in &drive.groups {
        groups.add(drive, out, &g.id, g.path.key("id"), None);
    }
    let mut options = Seen::new("variant id");
    for (ai, axis) in drive.variants.iter().enumerate() {
        let ap = Path::root().key("variants").index(ai);
        options.add(drive, out, &axis.id, ap.key("id"), None);
        for (oi, o) in axis.options.iter().enumerate() {
            options.add(
                drive,
                out,
                &o.id,
                ap.key("options").index(oi).key("id"),
                None,
            );
        }
    }
    let mut commands = Seen::new("command id");
    for (i, c) in drive.protocol.commands.iter().enumerate() {
        commands.add(
            drive,
            out,
            &c.id,
            Path::root()
                .key("protocol")
                .key("commands")
                .index(i)
                .key("id"),
            None,
        );
    }
    let mut exceptions = Seen::new("exception code");
    for (i, e) in drive.protocol.exceptions.iter().enumerate() {
        let key = format!("{:02X}h", e.code);
        exceptions.add(
            drive,
            out,
            &key,
            Path::root()
                .key("protocol")
                .key("exceptions")
                .index(i)
                .key("code"),
            None,
        );
    }

    let mut ids = Seen::new("register id");
    let mut params = Seen::new("parameter number");
    let mut types = Seen::new("generated type name");
    for t in names::FIXED_TYPES {
        types.first.insert((*t).to_owned(), Path::root());
    }
    for axis in &drive.variants {
        types
            .first
            .insert(names::axis_enum(axis), Path::root().key("variants"));
    }
    for r in &drive.registers {
        let rid = r.id();
        if ids.first.contains_key(rid) {
            // Reported once as a duplicate id; its type names would only repeat that.
            ids.add(drive, out, rid, r.key_path("id"), Some(rid));
            continue;
        }
        ids.add(drive, out, rid, r.key_path("id"), Some(rid));
        if let Some(p) = &r.def.param {
            // A broadcast register may repeat a command register's parameter; it lives in its own space.
            if !r.broadcast {
                params.add(drive, out, p, r.key_path("param"), Some(rid));
            }
        }
        types.add(
            drive,
            out,
            &names::register_type(r),
            r.key_path("id"),
            Some(rid),
        );
        if !r.def.read_values.is_empty() {
            types.add(
                drive,
                out,
                &names::read_enum(r),
                r.key_path("read_values"),
                Some(rid),
            );
            values(
                drive,
                out,
                &r.def.read_values,
                &r.key_path("read_values"),
                rid,
            );
        }
        match r.kind() {
            ValueKind::Enum(list) => {
                types.add(
                    drive,
                    out,
                    &names::value_enum(r),
                    r.key_path("values"),
                    Some(rid),
                );
                values(drive, out, list, &r.key_path("values"), rid);
            }
            ValueKind::Bits(fields) => {
                types.add(
                    drive,
                    out,
                    &names::bits_type(r),
                    r.key_path("fields"),
                    Some(rid),
                );
                let mut field_ids = Seen::new("field id");
                for (fi, f) in fields.iter().enumerate() {
                    let fp = r.key_path("fields").index(fi);
                    field_ids.add(drive, out, &f.id, fp.key("id"), Some(rid));
                    if !f.values.is_empty() {
                        types.add(
                            drive,
                            out,
                            &names::field_enum(r, f),
                            fp.key("id"),
                            Some(rid),
                        );
                        values(drive, out, &f.values, &fp.key("values"), rid);
                    }
                }
            }
            _ => {}
        }
    }
}
