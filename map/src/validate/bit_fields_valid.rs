//! Bit fields name one bit (`bit`) or an inclusive range (`bits: [lo, hi]`) inside 0..=15, and
//! no two fields of a register share a bit.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;

use crate::names::field_span as span;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        let rid = Some(r.id());
        let mut used: u16 = 0;
        let mut owner: [Option<&str>; 16] = [None; 16];
        for (fi, f) in r.def.fields.iter().enumerate() {
            let fp = r.key_path("fields").index(fi);
            let Some((lo, width)) = span(f) else {
                let msg = match (f.bit, f.bits) {
                    (Some(_), Some(_)) => "give either `bit` or `bits`, not both".to_owned(),
                    (None, None) => "a field needs `bit: n` or `bits: [lo, hi]`".to_owned(),
                    (Some(b), None) => format!("bit {b} is outside 0..=15"),
                    (None, Some([lo, hi])) => {
                        format!("bits [{lo}, {hi}] must satisfy lo <= hi <= 15")
                    }
                };
                out.push(drive.error(&fp, rid, format!("field `{}`: {msg}", f.id)));
                continue;
            };
            let mask = (((1u32 << width) - 1) << lo) as u16;
            if used & mask != 0 {
                let clash = (lo..lo + width)
                    .find(|b| used & (1 << b) != 0)
                    .unwrap_or(lo);
                out.push(drive.error(
                    &fp,
                    rid,
                    format!(
                        "field `{}` overlaps field `{}` at bit {clash}",
                        f.id,
                        owner[clash as usize].unwrap_or("?")
                    ),
                ));
            }
            for b in lo..lo + width {
                owner[b as usize].get_or_insert(&f.id);
            }
            used |= mask;
        }
    }
}
