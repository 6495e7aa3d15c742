//! The serial line is one the runtime can open: defaults among the listed settings, 7 or 8
//! data bits, 1 or 2 stop bits, a character length that holds them; and `serial.formats`, when
//! given, is the whole truth of the line's characters (its selector a register of the map, each
//! code once, the line's `parities`, `stop_bits` and `char_bits` agreeing with the formats).

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register};
use crate::model::{Parity, Serial, SerialFormatCase, SerialFormats};
use crate::source::Path;

/// One rule of the serial line: reads `protocol.serial` (found at `serial`) and appends its
/// findings.
type Rule = fn(&Drive, &Serial, &Path, &mut Vec<Diagnostic>);

/// The rules, in the order their findings are reported.
const RULES: &[Rule] = &[
    default_baud,
    default_parity,
    data_bits,
    char_bits,
    stop_bits,
    formats,
];

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let Some(ser) = &drive.protocol.serial else {
        return;
    };
    let sp = Path::root().key("protocol").key("serial");
    for rule in RULES {
        rule(drive, ser, &sp, out);
    }
}

fn default_baud(drive: &Drive, ser: &Serial, sp: &Path, out: &mut Vec<Diagnostic>) {
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
}

fn default_parity(drive: &Drive, ser: &Serial, sp: &Path, out: &mut Vec<Diagnostic>) {
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
}

fn data_bits(drive: &Drive, ser: &Serial, sp: &Path, out: &mut Vec<Diagnostic>) {
    if !matches!(ser.data_bits, 7 | 8) {
        out.push(drive.error(&sp.key("data_bits"), None, "data_bits must be 7 or 8"));
    }
}

fn char_bits(drive: &Drive, ser: &Serial, sp: &Path, out: &mut Vec<Diagnostic>) {
    if let Some(c) = ser.char_bits
        && (!(9..=12).contains(&c) || c < 1 + ser.data_bits + ser.stop_bits)
    {
        out.push(drive.error(
            &sp.key("char_bits"),
            None,
            "char_bits must cover start, data and stop bits (9..=12)",
        ));
    }
}

fn stop_bits(drive: &Drive, ser: &Serial, sp: &Path, out: &mut Vec<Diagnostic>) {
    if !matches!(ser.stop_bits, 1 | 2) {
        out.push(drive.error(&sp.key("stop_bits"), None, "stop_bits must be 1 or 2"));
    }
}

/// What a rule of the formats reads.
struct Formats<'a> {
    drive: &'a Drive,
    ser: &'a Serial,
    f: &'a SerialFormats,
    /// Where `serial` is.
    sp: &'a Path,
    /// Where `serial.formats` is.
    fp: Path,
    /// The register selecting the format, when the map has it.
    selector: Option<&'a Register>,
}

/// One rule of the formats as a whole.
type FormatsRule = fn(&Formats, &mut Vec<Diagnostic>);

/// One rule of a format (the `i`th case, found at `cp`).
type CaseRule = fn(&Formats, usize, &SerialFormatCase, &Path, &mut Vec<Diagnostic>);

/// The rules of the formats, in the order their findings are reported: `cases` runs
/// [`CASE_RULES`] on each format in turn.
const FORMATS_RULES: &[FormatsRule] = &[
    selector_known,
    cases_given,
    cases,
    parities_used,
    no_line_stop_bits,
];

/// The rules of each format, in the order their findings are reported.
const CASE_RULES: &[CaseRule] = &[
    when_a_code,
    when_once,
    case_stop_bits,
    case_data_bits,
    case_parity,
    case_length,
];

/// `serial.formats`: the selector is a register of the map and each `when` one of its codes,
/// once; each format is a valid character; the line's `parities`, `stop_bits` and
/// `char_bits` agree with the formats (the formats are the whole truth: `parities` lists
/// exactly their parities, `stop_bits` is not given, `char_bits` is every format's length).
fn formats(drive: &Drive, ser: &Serial, sp: &Path, out: &mut Vec<Diagnostic>) {
    let Some(f) = &ser.formats else {
        return;
    };
    let ctx = Formats {
        drive,
        ser,
        f,
        sp,
        fp: sp.key("formats"),
        selector: drive.find(&f.selected_by),
    };
    for rule in FORMATS_RULES {
        rule(&ctx, out);
    }
}

fn selector_known(x: &Formats, out: &mut Vec<Diagnostic>) {
    if x.selector.is_some() {
        return;
    }
    let candidates = x
        .drive
        .registers
        .iter()
        .flat_map(|r| std::iter::once(r.id()).chain(r.def.param.as_deref()));
    let hint = crate::hints::closest(&x.f.selected_by, candidates)
        .map(|c| format!(" (did you mean `{c}`?)"))
        .unwrap_or_default();
    out.push(x.drive.error(
        &x.fp.key("selected_by"),
        None,
        format!(
            "serial formats selected by `{}`, which names no register of this map (by id or parameter number){hint}",
            x.f.selected_by
        ),
    ));
}

fn cases_given(x: &Formats, out: &mut Vec<Diagnostic>) {
    if x.f.cases.is_empty() {
        out.push(x.drive.error(
            &x.fp.key("cases"),
            None,
            "list the formats: `{when: <code>, parity: .., stop_bits: ..}` per code",
        ));
    }
}

fn cases(x: &Formats, out: &mut Vec<Diagnostic>) {
    for (i, c) in x.f.cases.iter().enumerate() {
        let cp = x.fp.key("cases").index(i);
        for rule in CASE_RULES {
            rule(x, i, c, &cp, out);
        }
    }
}

/// The code is one of the selector's, when it is an enumeration (a plain word takes any code).
fn when_a_code(x: &Formats, _: usize, c: &SerialFormatCase, cp: &Path, out: &mut Vec<Diagnostic>) {
    let Some(r) = x.selector.filter(|r| !r.def.values.is_empty()) else {
        return;
    };
    let codes: Vec<u16> = r.def.values.iter().map(|v| v.value).collect();
    if !codes.contains(&c.when) {
        let listed: Vec<String> = codes.iter().map(u16::to_string).collect();
        out.push(x.drive.error(
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
}

fn when_once(x: &Formats, i: usize, c: &SerialFormatCase, cp: &Path, out: &mut Vec<Diagnostic>) {
    if let Some(j) = x.f.cases[..i].iter().position(|y| y.when == c.when) {
        out.push(x.drive.error(
            &cp.key("when"),
            None,
            format!(
                "code {} is listed twice: format {} already has it",
                c.when,
                j + 1
            ),
        ));
    }
}

fn case_stop_bits(
    x: &Formats,
    _: usize,
    c: &SerialFormatCase,
    cp: &Path,
    out: &mut Vec<Diagnostic>,
) {
    if !matches!(c.stop_bits, 1 | 2) {
        out.push(
            x.drive
                .error(&cp.key("stop_bits"), None, "stop_bits must be 1 or 2"),
        );
    }
}

/// The format's data bits, or the line's.
fn case_data(x: &Formats, c: &SerialFormatCase) -> u8 {
    c.data_bits.unwrap_or(x.ser.data_bits)
}

fn case_data_bits(
    x: &Formats,
    _: usize,
    c: &SerialFormatCase,
    cp: &Path,
    out: &mut Vec<Diagnostic>,
) {
    if !matches!(case_data(x, c), 7 | 8) {
        out.push(
            x.drive
                .error(&cp.key("data_bits"), None, "data_bits must be 7 or 8"),
        );
    }
}

fn case_parity(x: &Formats, _: usize, c: &SerialFormatCase, cp: &Path, out: &mut Vec<Diagnostic>) {
    if !x.ser.parities.contains(&c.parity) {
        out.push(x.drive.error(
            &cp.key("parity"),
            None,
            format!(
                "parity {} is not among the line's `parities`",
                c.parity.name()
            ),
        ));
    }
}

/// The format's character length is the line's `char_bits`, when given.
fn case_length(x: &Formats, _: usize, c: &SerialFormatCase, cp: &Path, out: &mut Vec<Diagnostic>) {
    let Some(bits) = x.ser.char_bits else {
        return;
    };
    let length = 1 + case_data(x, c) + u8::from(c.parity != Parity::None) + c.stop_bits;
    if length != bits {
        out.push(x.drive.error(
            cp,
            None,
            format!(
                "this format has {length} bits per character, but `char_bits` says every character has {bits}"
            ),
        ));
    }
}

/// Every parity of the line is some format's.
fn parities_used(x: &Formats, out: &mut Vec<Diagnostic>) {
    for (i, parity) in x.ser.parities.iter().enumerate() {
        if !x.f.cases.is_empty() && !x.f.cases.iter().any(|c| c.parity == *parity) {
            out.push(x.drive.error(
                &x.sp.key("parities").index(i),
                None,
                format!(
                    "parity {} is in `parities` but no format has it",
                    parity.name()
                ),
            ));
        }
    }
}

/// `stop_bits` has a default of 1, so only a written one contradicts the formats.
fn no_line_stop_bits(x: &Formats, out: &mut Vec<Diagnostic>) {
    let stop_path = x.sp.key("stop_bits");
    if x.drive.tree.at(&stop_path).is_some() {
        out.push(x.drive.error(
            &stop_path,
            None,
            "with `formats`, each format gives its stop bits: remove `stop_bits`",
        ));
    }
}
