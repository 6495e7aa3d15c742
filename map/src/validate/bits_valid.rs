//! Coils and discrete inputs (`modbus_table: coil` / `discrete_input`): one bit each, so a row
//! of those tables says what the bit is and nothing a word would say — no scale, unit, sign,
//! pair, limits, codes, fields, read meaning, indexed access, repeat rule, keypad steps or moving
//! address; a `default` is 0 or 1. They are not written as broadcast-only registers of their own
//! layout (a `broadcast: true` group), and no setting is read from one (a scale selector, a
//! reference quantity, an address condition, an index register or a serial-format selector is
//! read as a register word, never with 01h/02h). Access and function codes are checked with the
//! registers' (`access_consistent`, `function_codes_valid`); a map with such tables states its
//! bit limits (`protocol_stated`).

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register};
use crate::model::{DefaultValue, Reference, Scale};

/// The keys a word has and a bit has not, with whether the register gives each.
fn word_keys(r: &Register) -> [(&'static str, bool); 15] {
    let d = &r.def;
    [
        ("scale", d.scale.is_some()),
        ("unit", d.unit.is_some()),
        ("signed", d.signed),
        ("pair", d.pair.is_some()),
        ("min", d.min.is_some()),
        ("max", d.max.is_some()),
        ("by_variant", !d.by_variant.is_empty()),
        ("max_relative", d.max_relative.is_some()),
        ("values", !d.values.is_empty()),
        ("fields", !d.fields.is_empty()),
        ("read_values", !d.read_values.is_empty()),
        ("indexed", d.indexed.is_some()),
        ("repeat_needs_change", d.repeat_needs_change.is_some()),
        ("display_steps", !d.display_steps.is_empty()),
        ("address_alternatives", !d.address_alternatives.is_empty()),
    ]
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in drive.registers.iter().filter(|r| r.table.is_bits()) {
        let rid = Some(r.id());
        let item = r.table.item();
        for (key, given) in word_keys(r) {
            if given {
                out.push(drive.error(
                    &r.key_path(key),
                    rid,
                    format!(
                        "`{}` is a {item}, one bit (1 on, 0 off): a {item} has no `{key}`",
                        r.id()
                    ),
                ));
            }
        }
        if let Some(DefaultValue::Value(v)) = &r.def.default
            && *v != 0.0
            && *v != 1.0
        {
            out.push(drive.error(
                &r.key_path("default"),
                rid,
                format!(
                    "`{}` is a {item}: its default is 0 (off) or 1 (on), not {v}",
                    r.id()
                ),
            ));
        }
        if r.broadcast {
            out.push(drive.error(
                &r.path,
                rid,
                format!(
                    "`{}` is a {item} in a `broadcast: true` group: broadcast-only registers of their own layout are holding registers; a coil a broadcast may write is named in `protocol.broadcast.registers`",
                    r.id()
                ),
            ));
        }
    }
    settings_are_words(drive, out);
}

/// No setting is read from a coil or discrete input.
fn settings_are_words(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let bit = |name: &str| drive.find(name).filter(|x| x.table.is_bits());
    let mut refuse = |path: crate::source::Path, owner: Option<&str>, name: &str, what: &str| {
        if let Some(b) = bit(name) {
            out.push(drive.error(
                &path,
                owner,
                format!(
                    "`{name}` is a {}, but {what} is read as a register word (03h/04h): name a holding or input register",
                    b.table.item()
                ),
            ));
        }
    };
    for r in &drive.registers {
        let rid = Some(r.id());
        match &r.def.scale {
            Some(Scale::Selected(s)) => refuse(
                r.selection_path().key("selected_by"),
                rid,
                &s.selected_by,
                "a scale selector",
            ),
            Some(Scale::Relative(rel)) => {
                if let Reference::Register(name) = &rel.relative_to {
                    refuse(
                        r.key_path("scale").key("relative_to"),
                        rid,
                        name,
                        "a reference quantity",
                    );
                }
            }
            _ => {}
        }
        if let Some(l) = &r.def.max_relative
            && let Reference::Register(name) = &l.relative_to
        {
            refuse(
                r.key_path("max_relative").key("relative_to"),
                rid,
                name,
                "a limit's reference quantity",
            );
        }
        for (i, a) in r.def.address_alternatives.iter().enumerate() {
            if let Some(name) = &a.when.setting {
                refuse(
                    r.key_path("address_alternatives")
                        .index(i)
                        .key("when")
                        .key("setting"),
                    rid,
                    name,
                    "an address condition's setting",
                );
            }
        }
        if let Some(ix) = &r.def.indexed {
            refuse(
                r.key_path("indexed").key("by"),
                rid,
                &ix.by,
                "an index register",
            );
        }
    }
    if let Some(f) = drive
        .protocol
        .serial
        .as_ref()
        .and_then(|s| s.formats.as_ref())
    {
        refuse(
            crate::source::Path::root()
                .key("protocol")
                .key("serial")
                .key("formats")
                .key("selected_by"),
            None,
            &f.selected_by,
            "the serial formats' selector",
        );
    }
}
