//! Text in consecutive registers (`string:`): model names, serial numbers, firmware versions.
//! A string is read whole in one request, in a register table (holding or input), and is only
//! text: no key of a number, a code or a bit applies to it, nothing depends on it, and it is not
//! written (the manuals read so far print identification text as read-only; writing text is
//! not supported yet). Its `example`, as the manual prints it, fits and is printable ASCII.

use drivemap_core::register::Access;
use drivemap_core::text;

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let depended_on = super::settings_read(drive);
    for r in &drive.registers {
        let Some(t) = &r.def.string else { continue };
        let d = &r.def;
        let id = r.id();
        let mut err = |key: &str, message: String| {
            let path = if key.is_empty() {
                r.path.clone()
            } else {
                r.key_path(key)
            };
            out.push(drive.error(&path, Some(id), message));
        };
        if r.table.is_bits() {
            err(
                "string",
                format!(
                    "`{id}` is text in a coil or discrete-input table: text is held in holding or input registers"
                ),
            );
        }
        // The keys of a number, a code or a bit, each with why it does not apply to text.
        let number = "text is not a number";
        let refused = [
            (
                "pair",
                d.pair.is_some(),
                "a string gives its own length in `string.registers`",
            ),
            ("scale", d.scale.is_some(), number),
            ("unit", d.unit.is_some(), number),
            ("signed", d.signed, number),
            ("min", d.min.is_some(), number),
            ("max", d.max.is_some(), number),
            ("max_relative", d.max_relative.is_some(), number),
            (
                "default",
                d.default.is_some(),
                "a default is a number or a code; give the manual's example as `string.example`",
            ),
            (
                "by_variant",
                !d.by_variant.is_empty(),
                "its keys are limits and defaults of a number",
            ),
            ("values", !d.values.is_empty(), "text has no codes"),
            (
                "read_values",
                !d.read_values.is_empty(),
                "text has no codes",
            ),
            ("fields", !d.fields.is_empty(), "text has no bit fields"),
            ("display_steps", !d.display_steps.is_empty(), number),
            (
                "repeat_needs_change",
                d.repeat_needs_change.is_some(),
                "text is not written",
            ),
            (
                "address_alternatives",
                !d.address_alternatives.is_empty(),
                "a string that moves is not supported",
            ),
            (
                "indexed",
                d.indexed.is_some(),
                "indexed text is not supported",
            ),
        ];
        for (key, given, why) in refused {
            if given {
                err(
                    key,
                    format!("`{id}` is a string (`string:`); `{key}` does not apply: {why}"),
                );
            }
        }
        if matches!(d.access, Some(Access::Write | Access::ReadWrite)) {
            err(
                "access",
                format!(
                    "`{id}` is a string declared writable: writing text is not supported (a string is read-only; drop `access` or write `access: r`)"
                ),
            );
        }
        let n = u16::from(t.registers);
        if n == 0 {
            err(
                "string",
                format!("`{id}`: `string.registers` is 0; a string takes at least one register"),
            );
            continue;
        }
        let max_read = drive.protocol.max_read();
        if n > max_read {
            err(
                "string",
                format!(
                    "`{id}` is text in {n} registers, but `protocol.max_read` is {max_read}: a string is read whole in one request"
                ),
            );
        }
        let Some(last) = d.address.checked_add(n - 1) else {
            err(
                "string",
                format!(
                    "`{id}` is text in {n} registers from {:04X}h: it would run past FFFFh",
                    d.address
                ),
            );
            continue;
        };
        if let Some(other) = drive.registers.iter().find(|o| {
            o.index() != r.index()
                && super::shares_space(o, r)
                && o.def.address > d.address
                && o.def.address <= last
        }) {
            let at = drive.locate(&other.path);
            err(
                "string",
                format!(
                    "`{id}` is text in {:04X}h-{last:04X}h, but {:04X}h is `{}` (line {}): a string takes all its registers",
                    d.address,
                    other.def.address,
                    other.id(),
                    at.line
                ),
            );
        }
        if depended_on.contains(&id) {
            err(
                "",
                format!(
                    "`{id}` is a string, but a scale, reference or address depends on it: settings are numbers read from one register"
                ),
            );
        }
        if let Some(example) = &t.example {
            let mut words = vec![0u16; usize::from(n)];
            if let Err(e) = text::encode(example.as_bytes(), t.byte_order, &mut words) {
                err("string", format!("`{id}`: `string.example`: {e}"));
            }
        }
    }
}
