//! The protocol profile is one the runtime can honour: known function codes, quantities within
//! the Modbus limits, a slave range that excludes broadcast, broadcast only for writes, commands
//! that write something. One rule per fact of the profile, run in the order of [`RULES`]; the
//! timing (`timing_valid`) and the serial line (`serial_valid`) are passes of their own.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::source::Path;

const KNOWN: &[u8] = &[0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x0F, 0x10];

/// One rule of the profile: reads `drive.protocol` (found at `protocol`) and appends its
/// findings.
type Rule = fn(&Drive, &Path, &mut Vec<Diagnostic>);

/// The rules, in the order their findings are reported.
const RULES: &[Rule] = &[
    transports,
    function_codes,
    request_sizes,
    slave_address,
    broadcast,
    request_size_reasons,
    exceptions,
    commands,
    eeprom,
];

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let pp = Path::root().key("protocol");
    for rule in RULES {
        rule(drive, &pp, out);
    }
}

/// At least one transport.
fn transports(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    if drive.protocol.transports.is_empty() {
        out.push(drive.error(
            &pp.key("transports"),
            None,
            "name at least one transport (rtu, tcp)",
        ));
    }
}

/// The function codes: some, each one drivemap speaks, once; a list marked unknown gives its
/// reason.
fn function_codes(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    // The list itself, or the `codes` of `{codes: [...], source: ...}`.
    let fcp = {
        let p = pp.key("function_codes");
        if drive.tree.at(&p.key("codes")).is_some() {
            p.key("codes")
        } else {
            p
        }
    };
    let fcs = &p.function_codes.codes;
    if fcs.is_empty() {
        out.push(drive.error(&fcp, None, "name the function codes the drive implements"));
    }
    if let Some(why) = &p.function_codes.unknown
        && why.trim().is_empty()
    {
        out.push(drive.error(
            &pp.key("function_codes").key("unknown"),
            None,
            format!(
                "`function_codes` marked unknown needs its reason: why the manual prints no list and where {} come from",
                crate::describe::functions(fcs)
            ),
        ));
    }
    for (i, f) in fcs.iter().enumerate() {
        if !KNOWN.contains(f) {
            out.push(drive.error(
                &fcp.index(i),
                None,
                format!(
                    "function {f:02X}h is not one drivemap speaks (01h, 02h, 03h, 04h, 05h, 06h, 08h, 0Fh, 10h)"
                ),
            ));
        }
        if fcs[..i].contains(f) {
            out.push(drive.error(
                &fcp.index(i),
                None,
                format!("function {f:02X}h listed twice"),
            ));
        }
    }
}

/// `max_read`, `max_write`, `max_read_bits` and `max_write_bits` within what a Modbus request
/// can carry.
fn request_sizes(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    for (name, limit, max) in [
        ("max_read_bits", &p.max_read_bits, 2000),
        ("max_write_bits", &p.max_write_bits, 1968),
    ] {
        if let Some(v) = limit.as_ref().and_then(|l| l.value)
            && !(1..=max).contains(&v)
        {
            out.push(drive.error(&pp.key(name), None, format!("{name} {v} must be 1..={max}")));
        }
    }
    if let Some(v) = p.max_read.value
        && !(1..=125).contains(&v)
    {
        out.push(drive.error(
            &pp.key("max_read"),
            None,
            format!("max_read {v} must be 1..=125"),
        ));
    }
    if let Some(v) = p.max_write.value
        && !(1..=123).contains(&v)
    {
        out.push(drive.error(
            &pp.key("max_write"),
            None,
            format!("max_write {v} must be 1..=123"),
        ));
    }
}

/// The slave range excludes broadcast and holds its default.
fn slave_address(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    let s = &drive.protocol.slave_address;
    // Without a printed range (`unknown`) the Modbus 1..=247 is used; `protocol_stated` checks
    // that the map gives one or the other.
    let (s_min, s_max) = s.range();
    // The map records the range the manual gives: the Modbus serial-line specification's 1..=247
    // is not every drive's (some manuals print 01H-FEH). 0 is broadcast, never a slave.
    if s_min == 0 || s_min > s_max {
        out.push(drive.error(
            &pp.key("slave_address"),
            None,
            format!(
                "slave addresses {s_min}..={s_max} must lie in 1..=255 with min <= max (0 is broadcast)"
            ),
        ));
    }
    if let Some(d) = s.default
        && (d < s_min || d > s_max)
    {
        out.push(drive.error(
            &pp.key("slave_address").key("default"),
            None,
            format!("default slave {d} is outside {s_min}..={s_max}"),
        ));
    }
}

/// A broadcast gives its rules (writes the drive implements) or says why it cannot.
fn broadcast(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    let Some(b) = &p.broadcast else {
        return;
    };
    let bp = pp.key("broadcast");
    match &b.unknown {
        Some(why) if why.trim().is_empty() => out.push(drive.error(
            &bp.key("unknown"),
            None,
            "a broadcast marked unknown needs its reason: what the manual says of it and which rules it does not print",
        )),
        Some(_) => {
            // Rules not printed are all unknown: a list beside them would be half a rule
            // the runtime does not use (it sends no broadcast then).
            let given = [
                ("functions", !b.functions.is_empty()),
                ("registers", !b.registers.is_empty()),
            ];
            for (key, _) in given.iter().filter(|(_, g)| *g) {
                out.push(drive.error(
                    &bp.key(key),
                    None,
                    format!(
                        "a broadcast whose rules are not printed (`unknown`) lists no `{key}`; say what the manual prints in `unknown`, or drop `unknown` and give the rules"
                    ),
                ));
            }
            if let Some(r) = drive.registers.iter().find(|r| r.broadcast) {
                out.push(drive.error(
                    &bp.key("unknown"),
                    Some(r.id()),
                    "a broadcast whose rules are not printed has no broadcast registers; a `broadcast: true` group prints them",
                ));
            }
        }
        None if b.functions.is_empty() => out.push(drive.error(
            &bp,
            None,
            "list the `functions` a broadcast executes (06h, 10h), or say `unknown: <why>` when the manual prints no rules for it",
        )),
        None => {}
    }
    for (i, f) in b.functions.iter().enumerate() {
        if !matches!(f, 0x05 | 0x06 | 0x0F | 0x10) || !p.function_codes.codes.contains(f) {
            out.push(drive.error(
                &bp.key("functions").index(i),
                None,
                format!(
                    "broadcast function {f:02X}h must be a write (06h/10h, or 05h/0Fh for coils) the drive implements"
                ),
            ));
        }
    }
}

/// A request size marked unknown gives its reason.
fn request_size_reasons(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    let bits = [
        ("max_read_bits", p.max_read_bits.as_ref()),
        ("max_write_bits", p.max_write_bits.as_ref()),
    ];
    let limits = [
        ("max_read", Some(&p.max_read)),
        ("max_write", Some(&p.max_write)),
    ];
    for (name, limit) in limits.into_iter().chain(bits) {
        let Some(limit) = limit else { continue };
        if limit.unknown.as_ref().is_some_and(|r| r.trim().is_empty()) {
            out.push(drive.error(
                &pp.key(name).key("unknown"),
                None,
                format!(
                    "`{name}` marked unknown needs its reason: why the manual prints none{}",
                    match limit.value {
                        Some(v) => format!(" and where {v} comes from"),
                        None => String::new(),
                    }
                ),
            ));
        }
    }
}

/// Exception codes fit the 7 bits a reply has for them.
fn exceptions(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    for (i, e) in drive.protocol.exceptions.iter().enumerate() {
        if e.code == 0 || e.code >= 0x80 {
            out.push(drive.error(
                &pp.key("exceptions").index(i).key("code"),
                None,
                format!("exception code {:02X}h must be 01h..7Fh", e.code),
            ));
        }
    }
}

/// Every command writes something.
fn commands(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    for (i, c) in drive.protocol.commands.iter().enumerate() {
        if c.writes.is_empty() {
            out.push(drive.error(
                &pp.key("commands").index(i),
                None,
                format!("command `{}` writes nothing", c.id),
            ));
        }
    }
}

/// An EEPROM's endurance is some writes.
fn eeprom(drive: &Drive, pp: &Path, out: &mut Vec<Diagnostic>) {
    if let Some(e) = &drive.protocol.eeprom
        && e.endurance == 0
    {
        out.push(drive.error(
            &pp.key("eeprom").key("endurance"),
            None,
            "endurance must be positive",
        ));
    }
}
