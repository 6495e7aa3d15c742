//! 32-bit values in two registers (`pair:`): the pair holds a plain or scaled number, its second
//! address is free and exists, the drive can read it (and write it, when writable) in one
//! request, and no conversion or address depends on it.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;

/// 10h, the only function that writes both words of a pair in one request.
const WRITE_MULTIPLE: u8 = 0x10;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let depended_on = super::settings_read(drive);
    for r in drive.registers.iter().filter(|r| r.def.pair.is_some()) {
        let path = r.key_path("pair");
        let mut err = |message: String| out.push(drive.error(&path, Some(r.id()), message));
        let codes = [
            ("values", !r.def.values.is_empty()),
            ("fields", !r.def.fields.is_empty()),
            ("read_values", !r.def.read_values.is_empty()),
        ];
        if let Some((key, _)) = codes.iter().find(|(_, given)| *given) {
            err(format!(
                "`{}` is a pair with `{key}`: enumerations, bit fields and read codes in two registers are not supported; give the value as a number (the manuals read so far keep codes and bits in one word)",
                r.id(),
            ));
        }
        if !r.def.address_alternatives.is_empty() {
            err(format!(
                "`{}` is a pair with `address_alternatives`: a pair that moves is not supported",
                r.id()
            ));
        }
        let Some(second) = r.def.address.checked_add(1) else {
            err(format!(
                "`{}` is a pair at FFFFh: its second word would be past the last address",
                r.id()
            ));
            continue;
        };
        if let Some(other) = drive
            .registers
            .iter()
            .find(|o| o.def.address == second && super::shares_space(o, r))
        {
            let at = drive.locate(&other.path);
            let shown = |a: u16| crate::describe::address_as(drive.address_format, a);
            err(format!(
                "`{}` is a pair at {}-{}, but {} is `{}` (line {}): a pair takes both addresses",
                r.id(),
                shown(r.def.address),
                shown(second),
                shown(second),
                other.id(),
                at.line
            ));
        }
        if depended_on.contains(&r.id()) {
            err(format!(
                "`{}` is a pair, but a scale, reference or address depends on it: settings are read one word at a time; a selector or reference must be one register",
                r.id()
            ));
        }
        let p = &drive.protocol;
        if r.readable() && p.max_read() < 2 {
            err(format!(
                "`{}` is a pair, but `protocol.max_read` is {}: both words must be read in one request",
                r.id(),
                p.max_read()
            ));
        }
        if r.writable() {
            if p.max_write() < 2 {
                err(format!(
                    "`{}` is a writable pair, but `protocol.max_write` is {}: both words must be written in one request",
                    r.id(),
                    p.max_write()
                ));
            }
            if !p.function_codes.codes.is_empty()
                && !p.function_codes.codes.contains(&WRITE_MULTIPLE)
            {
                err(format!(
                    "`{}` is a writable pair, but `protocol.function_codes` lacks 10h: only 10h writes both words in one request",
                    r.id()
                ));
            }
        }
    }
}
