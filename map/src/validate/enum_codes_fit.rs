//! Enumeration codes fit where they are stored: a field's codes fit its width.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::names::field_span as span;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        for (fi, f) in r.def.fields.iter().enumerate() {
            let Some((_, width)) = span(f) else { continue };
            let limit = 1u32 << width;
            for (vi, v) in f.values.iter().enumerate() {
                if u32::from(v.value) >= limit {
                    out.push(drive.error(
                        &r.key_path("fields").index(fi).key("values").index(vi).key("value"),
                        Some(r.id()),
                        format!(
                            "code {} of `{}` does not fit field `{}` ({width} bit{}, codes 0..={})",
                            v.value,
                            v.id,
                            f.id,
                            if width == 1 { "" } else { "s" },
                            limit - 1
                        ),
                    ));
                }
            }
        }
        if r.def.signed {
            for (vi, v) in r.def.values.iter().enumerate() {
                if v.value > i16::MAX as u16 {
                    out.push(drive.error(
                        &r.key_path("values").index(vi).key("value"),
                        Some(r.id()),
                        format!("code {} does not fit a signed word", v.value),
                    ));
                }
            }
        }
    }
}
