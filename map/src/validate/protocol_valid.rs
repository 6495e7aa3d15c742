//! The protocol profile is one the runtime can honour: known function codes, quantities within
//! the Modbus limits, a slave range that excludes broadcast, broadcast only for writes, well-formed timing and
//! serial settings, commands that write something.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::model::{Interval, Parity, Serial, SerialFormats};
use crate::source::Path;

const KNOWN: &[u8] = &[0x03, 0x04, 0x06, 0x08, 0x10];

fn interval(drive: &Drive, out: &mut Vec<Diagnostic>, i: &Interval, path: Path) {
    if i.unknown.is_some() {
        // Not printed: `protocol_stated` checks that no figure stands beside the reason.
        return;
    }
    if i.ms.is_none() && i.bits.is_none() && i.chars.is_none() {
        out.push(drive.error(&path, None, "give `ms`, `bits` or `chars` (several add up)"));
    }
    if i.ms.is_some_and(|v| v.is_nan() || v < 0.0) || i.chars.is_some_and(|v| v.is_nan() || v < 0.0)
    {
        out.push(drive.error(&path, None, "an interval cannot be negative"));
    }
}

pub fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let p = &drive.protocol;
    let pp = Path::root().key("protocol");
    if p.transports.is_empty() {
        out.push(drive.error(
            &pp.key("transports"),
            None,
            "name at least one transport (rtu, tcp)",
        ));
    }
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
                format!("function {f:02X}h is not one drivemap speaks (03h, 04h, 06h, 08h, 10h)"),
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
    let s = &p.slave_address;
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
    if let Some(d) = s.default {
        if d < s_min || d > s_max {
            out.push(drive.error(
                &pp.key("slave_address").key("default"),
                None,
                format!("default slave {d} is outside {s_min}..={s_max}"),
            ));
        }
    }
    if let Some(b) = &p.broadcast {
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
            if !matches!(f, 0x06 | 0x10) || !fcs.contains(f) {
                out.push(drive.error(
                    &pp.key("broadcast").key("functions").index(i),
                    None,
                    format!(
                        "broadcast function {f:02X}h must be a write (06h/10h) the drive implements"
                    ),
                ));
            }
        }
    }
    for (name, limit) in [("max_read", &p.max_read), ("max_write", &p.max_write)] {
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
    for (i, e) in p.exceptions.iter().enumerate() {
        if e.code == 0 || e.code >= 0x80 {
            out.push(drive.error(
                &pp.key("exceptions").index(i).key("code"),
                None,
                format!("exception code {:02X}h must be 01h..7Fh", e.code),
            ));
        }
    }
    for (i, c) in p.commands.iter().enumerate() {
        if c.writes.is_empty() {
            out.push(drive.error(
                &pp.key("commands").index(i),
                None,
                format!("command `{}` writes nothing", c.id),
            ));
        }
    }
    if let Some(e) = &p.eeprom {
        if e.endurance == 0 {
            out.push(drive.error(
                &pp.key("eeprom").key("endurance"),
                None,
                "endurance must be positive",
            ));
        }
    }
    if let Some(t) = &p.timing {
        let tp = pp.key("timing");
        if t.frame_gap_chars().is_nan() || t.frame_gap_chars() <= 0.0 {
            out.push(drive.error(
                &tp.key("frame_gap_chars"),
                None,
                "the frame gap must be positive",
            ));
        }
        if let Some(g) = &t.frame_gap
            && g.unknown.is_none()
        {
            // Only milliseconds: a gap in characters is `frame_gap_chars`, and the two are not
            // contradictory (the larger at the line's baud rate is kept).
            let gp = tp.key("frame_gap");
            let other = g.bits.is_some() || g.chars.is_some();
            match g.ms {
                None if other => {}
                None => out.push(drive.error(
                    &gp,
                    None,
                    "give the frame gap in `ms` (a gap in characters is `frame_gap_chars`)",
                )),
                Some(ms) if !ms.is_finite() || ms <= 0.0 => out.push(drive.error(
                    &gp.key("ms"),
                    None,
                    "the frame gap in ms must be finite and positive",
                )),
                Some(_) => {}
            }
            if other {
                out.push(drive.error(
                    &gp,
                    None,
                    "`frame_gap` takes `ms` only; write a gap in characters as `frame_gap_chars`",
                ));
            }
        }
        if let Some(i) = &t.inter_char_timeout {
            interval(drive, out, i, tp.key("inter_char_timeout"));
        }
        if let Some(i) = &t.response_time {
            interval(drive, out, i, tp.key("response_time"));
        }
        if let Some(i) = &t.request_gap {
            interval(drive, out, i, tp.key("request_gap"));
        }
    }
    if let Some(ser) = &p.serial {
        let sp = pp.key("serial");
        if ser
            .default_baud
            .is_some_and(|b| !ser.baud_rates.contains(&b))
        {
            out.push(drive.error(
                &sp.key("default_baud"),
                None,
                "default_baud is not among baud_rates",
            ));
        }
        if ser
            .default_parity
            .is_some_and(|b| !ser.parities.contains(&b))
        {
            out.push(drive.error(
                &sp.key("default_parity"),
                None,
                "default_parity is not among parities",
            ));
        }
        if !matches!(ser.data_bits, 7 | 8) {
            out.push(drive.error(&sp.key("data_bits"), None, "data_bits must be 7 or 8"));
        }
        if let Some(c) = ser.char_bits {
            if !(9..=12).contains(&c) || c < 1 + ser.data_bits + ser.stop_bits {
                out.push(drive.error(
                    &sp.key("char_bits"),
                    None,
                    "char_bits must cover start, data and stop bits (9..=12)",
                ));
            }
        }
        if !matches!(ser.stop_bits, 1 | 2) {
            out.push(drive.error(&sp.key("stop_bits"), None, "stop_bits must be 1 or 2"));
        }
        if let Some(f) = &ser.formats {
            formats(drive, out, ser, f, &sp);
        }
    }
}

/// `serial.formats`: the selector is a register of the map and each `when` one of its codes,
/// once; each format is a valid character; the line's `parities`, `stop_bits` and
/// `char_bits` agree with the formats (the formats are the whole truth: `parities` lists
/// exactly their parities, `stop_bits` is not given, `char_bits` is every format's length).
fn formats(drive: &Drive, out: &mut Vec<Diagnostic>, ser: &Serial, f: &SerialFormats, sp: &Path) {
    let fp = sp.key("formats");
    let selector = drive.find(&f.selected_by);
    if selector.is_none() {
        {
            let candidates = drive
                .registers
                .iter()
                .flat_map(|r| std::iter::once(r.id()).chain(r.def.param.as_deref()));
            let hint = crate::hints::closest(&f.selected_by, candidates)
                .map(|c| format!(" (did you mean `{c}`?)"))
                .unwrap_or_default();
            out.push(drive.error(
                &fp.key("selected_by"),
                None,
                format!(
                    "serial formats selected by `{}`, which names no register of this map (by id or parameter number){hint}",
                    f.selected_by
                ),
            ));
        }
    }
    if f.cases.is_empty() {
        out.push(drive.error(
            &fp.key("cases"),
            None,
            "list the formats: `{when: <code>, parity: .., stop_bits: ..}` per code",
        ));
    }
    // An enumeration's codes; a plain word takes any code.
    let codes: Option<Vec<u16>> = selector
        .filter(|r| !r.def.values.is_empty())
        .map(|r| r.def.values.iter().map(|v| v.value).collect());
    for (i, c) in f.cases.iter().enumerate() {
        let cp = fp.key("cases").index(i);
        if let (Some(codes), Some(r)) = (&codes, selector)
            && !codes.contains(&c.when)
        {
            let listed: Vec<String> = codes.iter().map(u16::to_string).collect();
            out.push(drive.error(
                &cp.key("when"),
                None,
                format!(
                    "code {} is not one of `{}`'s values ({})",
                    c.when,
                    r.def.param.as_deref().unwrap_or(r.id()),
                    listed.join(", ")
                ),
            ));
        }
        if let Some(j) = f.cases[..i].iter().position(|x| x.when == c.when) {
            out.push(drive.error(
                &cp.key("when"),
                None,
                format!(
                    "code {} is listed twice: format {} already has it",
                    c.when,
                    j + 1
                ),
            ));
        }
        if !matches!(c.stop_bits, 1 | 2) {
            out.push(drive.error(&cp.key("stop_bits"), None, "stop_bits must be 1 or 2"));
        }
        let data_bits = c.data_bits.unwrap_or(ser.data_bits);
        if !matches!(data_bits, 7 | 8) {
            out.push(drive.error(&cp.key("data_bits"), None, "data_bits must be 7 or 8"));
        }
        if !ser.parities.contains(&c.parity) {
            out.push(drive.error(
                &cp.key("parity"),
                None,
                format!(
                    "parity {} is not among the line's `parities`",
                    c.parity.name()
                ),
            ));
        }
        if let Some(bits) = ser.char_bits {
            let length = 1 + data_bits + u8::from(c.parity != Parity::None) + c.stop_bits;
            if length != bits {
                out.push(drive.error(
                    &cp,
                    None,
                    format!(
                        "this format has {length} bits per character, but `char_bits` says every character has {bits}"
                    ),
                ));
            }
        }
    }
    for (i, parity) in ser.parities.iter().enumerate() {
        if !f.cases.is_empty() && !f.cases.iter().any(|c| c.parity == *parity) {
            out.push(drive.error(
                &sp.key("parities").index(i),
                None,
                format!(
                    "parity {} is in `parities` but no format has it",
                    parity.name()
                ),
            ));
        }
    }
    // `stop_bits` has a default of 1, so only a written one contradicts the formats.
    let stop_path = sp.key("stop_bits");
    if drive.tree.at(&stop_path).is_some() {
        out.push(drive.error(
            &stop_path,
            None,
            "with `formats`, each format gives its stop bits: remove `stop_bits`",
        ));
    }
}
