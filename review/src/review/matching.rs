//! Does a line of OCR text mention an item: an address in any notation the manuals use, a
//! parameter number, a printed name, a code, a bit.
//!
//! Hand-written rather than with `regex`: every test is a substring search with a character-class
//! test at both ends, and OCR tolerance needs per-form boundary rules that read more plainly as
//! code than as patterns.

/// The ways an address is printed: `0x0200`, `0200H`, `200h`, `0h03E7`, bare `1E08` (ACN), and
/// the PLC decimals `40000 + address + 1 + offset` for each transport offset of `addressing`.
#[derive(Debug, Clone)]
pub(crate) struct AddressForms {
    /// Upper-case hexadecimal forms with their boundary rule.
    hex: Vec<(String, Boundary)>,
    decimal: Vec<String>,
    /// The register number in decimal, for a manual that numbers registers so
    /// (`address_format: decimal`).
    register_number: Option<String>,
    /// The Modicon reference the map records for the register (`reference: 40024`), in its
    /// five- and six-digit spellings: found on its own, as the register number is.
    references: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Boundary {
    /// Not preceded or followed by a letter or digit.
    Word,
    /// Not preceded by a letter or digit; anything may follow (`31AhE4-03` in the GPD tables).
    Start,
}

impl AddressForms {
    pub(crate) fn new(address: u16, offsets: Option<(i32, i32)>) -> AddressForms {
        let h4 = format!("{address:04X}");
        let h = format!("{address:X}");
        let h3 = format!("{address:03X}");
        let mut hex = vec![
            (format!("0X{h4}"), Boundary::Word),
            (format!("0X{h}"), Boundary::Word),
            (format!("0H{h4}"), Boundary::Word),
            (format!("{h4}H"), Boundary::Start),
            (format!("{h3}H"), Boundary::Start),
            (format!("{h}H"), Boundary::Start),
            (h4.clone(), Boundary::Word),
        ];
        hex.sort();
        hex.dedup();
        let mut decimal = Vec::new();
        if let Some((rtu, tcp)) = offsets {
            for off in [rtu, tcp] {
                let n = 40001 + i64::from(address) + i64::from(off);
                if (40000..=49999).contains(&n) {
                    decimal.push(n.to_string());
                }
            }
            decimal.sort();
            decimal.dedup();
        }
        AddressForms {
            hex,
            decimal,
            register_number: None,
            references: Vec::new(),
        }
    }

    /// Also finds the Modicon reference the map records for the register (`40024`, and
    /// `400024`), printed beside the drive's own number.
    pub(crate) fn with_reference(
        mut self,
        reference: Option<drivemap_map::modicon::Modicon>,
    ) -> AddressForms {
        if let Some(m) = reference {
            let five = drivemap_map::modicon::Modicon::text(m.table, m.pdu);
            let digit = drivemap_map::modicon::digit(m.table);
            self.references = vec![format!("{digit}{:05}", u32::from(m.pdu) + 1)];
            if five.len() == 5 {
                self.references.push(five);
            }
        }
        self
    }

    /// Also finds the address printed as a decimal register number (`2001` for 07D1H), for a
    /// map with `address_format: decimal`.
    pub(crate) fn with_decimal(mut self, address: u16) -> AddressForms {
        self.register_number = Some(address.to_string());
        self
    }

    /// Whether `line` (see [`Line`]) prints the address.
    pub(crate) fn found_in(&self, line: &Line) -> bool {
        let texts = [line.upper.as_str(), line.ocr.as_str()];
        // The PLC decimals count only all together: with RTU and TCP numbering one apart, the
        // TCP number of one register is the RTU number of the next.
        texts.iter().any(|t| {
            self.hex.iter().any(|(f, b)| find_bounded(t, f, *b))
                || self
                    .register_number
                    .as_ref()
                    .is_some_and(|d| find_bounded(t, d, Boundary::Word))
                || self
                    .references
                    .iter()
                    .any(|d| find_bounded(t, d, Boundary::Word))
                || (!self.decimal.is_empty()
                    && self
                        .decimal
                        .iter()
                        .all(|d| find_bounded(t, d, Boundary::Word)))
        })
    }
}

/// A manual line prepared for matching.
#[derive(Debug, Clone)]
pub(crate) struct Line {
    /// Upper case.
    pub(crate) upper: String,
    /// Upper case, with `O` and `Q` read as `0` inside hex-like words (`1EOA` → `1E0A`).
    pub(crate) ocr: String,
    /// Lower case, letters and digits only: names broken by OCR spaces still match.
    pub(crate) squashed: String,
    /// Lower-case words of letters and digits.
    pub(crate) words: Vec<String>,
}

impl Line {
    pub(crate) fn new(text: &str) -> Line {
        let upper = text.to_uppercase();
        let ocr = ocr_hex(&upper);
        let squashed = text
            .chars()
            .filter(|c| c.is_alphanumeric())
            .flat_map(char::to_lowercase)
            .collect();
        let words = words(text);
        Line {
            upper,
            ocr,
            squashed,
            words,
        }
    }
}

fn words(text: &str) -> Vec<String> {
    text.split(|c: char| !c.is_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(str::to_lowercase)
        .collect()
}

/// Reads `O` and `Q` as `0` in words made of hex digits, `O`, `Q` and at least one digit.
fn ocr_hex(upper: &str) -> String {
    let mut out = String::with_capacity(upper.len());
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        let hexlike = word.chars().any(|c| c.is_ascii_digit())
            && word
                .chars()
                .all(|c| c.is_ascii_hexdigit() || c == 'O' || c == 'Q' || c == 'H');
        if hexlike {
            out.extend(
                word.chars()
                    .map(|c| if c == 'O' || c == 'Q' { '0' } else { c }),
            );
        } else {
            out.push_str(word);
        }
        word.clear();
    };
    for c in upper.chars() {
        if c.is_ascii_alphanumeric() {
            word.push(c);
        } else {
            flush(&mut word, &mut out);
            out.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}

fn find_bounded(text: &str, needle: &str, boundary: Boundary) -> bool {
    if needle.is_empty() {
        return false;
    }
    text.match_indices(needle).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = text[i + needle.len()..].chars().next();
        let free = |c: Option<char>| c.is_none_or(|c| !c.is_alphanumeric());
        free(before) && (boundary == Boundary::Start || free(after))
    })
}

/// Whether `line` prints the parameter number: as printed, without its separators (`UF11`) or
/// with a space for them; case-insensitive; not followed by a digit; preceded by no letter or
/// digit, except an address's `h` glued before it (`31AhE4-03`).
pub(crate) fn param_found(param: &str, line: &Line) -> bool {
    let p = param.trim().to_uppercase();
    if p.is_empty() {
        return false;
    }
    let mut forms = vec![p.clone()];
    let bare: String = p.chars().filter(|c| c.is_alphanumeric()).collect();
    forms.push(bare);
    forms.push(p.replace(['-', '.'], " "));
    forms.dedup();
    let text = &line.upper;
    forms.iter().filter(|f| !f.is_empty()).any(|f| {
        text.match_indices(f.as_str()).any(|(i, _)| {
            let mut before = text[..i].chars().rev();
            let after = text[i + f.len()..].chars().next();
            let left = match before.next() {
                None => true,
                Some(c) if !c.is_alphanumeric() => true,
                Some('H') => before.next().is_some_and(|c| c.is_ascii_hexdigit()),
                Some(_) => false,
            };
            let right = after.is_none_or(|c| !c.is_ascii_digit());
            left && right
        })
    })
}

const STOP: &[&str] = &[
    "the", "of", "and", "for", "with", "to", "in", "on", "at", "by", "or", "an", "a",
];

/// The words of a printed name that identify it: letters and digits, no stop words, no lone
/// digits.
pub(crate) fn name_words(name: &str) -> Vec<String> {
    words(name)
        .into_iter()
        .filter(|w| !STOP.contains(&w.as_str()))
        .filter(|w| w.chars().any(|c| c.is_alphabetic()))
        .collect()
}

/// Whether the line prints a word (lower case): as a word of its own when short, anywhere in the
/// squashed line when it has four letters or more (OCR spaces inside words).
pub(crate) fn word_found(word: &str, line: &Line) -> bool {
    if word.chars().count() >= 4 {
        line.squashed.contains(word)
    } else {
        line.words.iter().any(|w| w == word)
    }
}

/// Whether the line prints the name: two of its words (all of them when it has fewer), or the
/// whole name with its spaces removed (`0.1 Hz` → `01hz`).
pub(crate) fn name_found(name: &str, line: &Line) -> bool {
    let ws = name_words(name);
    let need = ws.len().min(2);
    if need > 0 && ws.iter().filter(|w| word_found(w, line)).count() >= need {
        return true;
    }
    let squashed: String = name
        .chars()
        .filter(|c| c.is_alphanumeric())
        .flat_map(char::to_lowercase)
        .collect();
    squashed.chars().count() >= 2 && line.squashed.contains(&squashed)
}

/// Whether the line prints a number as a word of its own (`3`, `03`, `3:`), or as `bit 3`,
/// `b3`, `3h`, `0x3`, `1900h` (hexadecimal).
pub(crate) fn number_found(n: u16, line: &Line) -> bool {
    let forms = [
        format!("b{n}"),
        format!("bit{n}"),
        format!("{n:x}h"),
        format!("{n:02x}h"),
        format!("{n:04x}h"),
        format!("0x{n:x}"),
        format!("0x{n:04x}"),
    ];
    let ocr_words = words(&line.ocr);
    line.words.iter().chain(ocr_words.iter()).any(|w| {
        (w.chars().all(|c| c.is_ascii_digit()) && w.parse::<u32>().ok() == Some(u32::from(n)))
            || forms.iter().any(|f| f == w)
    })
}

/// The label without its parenthetical remarks (`2.2 kW (printed '22 kW')` → `2.2 kW`).
pub(crate) fn label_text(label: &str) -> String {
    let mut out = String::new();
    let mut depth = 0usize;
    for c in label.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            c if depth == 0 => out.push(c),
            _ => {}
        }
    }
    let out = out.trim().to_owned();
    if out.is_empty() {
        label.to_owned()
    } else {
        out
    }
}

/// Whether a code is printed with its label, tolerating OCR glue: as a word or a run of digits
/// between letters (`0Digital Operator`, `PUF1M`), glued to the label's first word
/// (`12400 bps` for code 1 "2400 bps"; `UV12A` for code 2 "UV1: ..."), inside a printed range
/// (`25-39`, `0 to 15`), or carried by the label itself (`0010: ...` for code 2).
pub(crate) fn code_found(code: u16, label: &str, line: &Line) -> bool {
    if number_found(code, line) {
        return true;
    }
    let dec = code.to_string();
    let runs = digit_runs(&line.upper);
    if runs.iter().any(|(r, _, _)| *r == dec) {
        return true;
    }
    let first: String = label
        .split(|c: char| !c.is_alphanumeric())
        .find(|w| !w.is_empty())
        .map(str::to_lowercase)
        .unwrap_or_default();
    if !first.is_empty()
        && (line.squashed.contains(&format!("{dec}{first}"))
            || line.squashed.contains(&format!("{first}{dec}"))
            || line.squashed.contains(&format!("{code:x}h{first}")))
    {
        return true;
    }
    // A printed range a-b, a~b or "a to b".
    let n = u32::from(code);
    for pair in runs.windows(2) {
        let ((a, _, end), (b, start, _)) = (&pair[0], &pair[1]);
        let between = line.upper[*end..*start].trim().to_lowercase();
        if matches!(between.as_str(), "-" | "~" | "to" | "..")
            && let (Ok(a), Ok(b)) = (a.parse::<u32>(), b.parse::<u32>())
            && a <= n
            && n <= b
        {
            return true;
        }
    }
    let label_words = words(label);
    let binary = format!("{code:04b}");
    label_words
        .iter()
        .any(|w| *w == dec || *w == binary || *w == format!("{code:x}h"))
}

/// Runs of ASCII digits: (digits, start, end) byte offsets.
fn digit_runs(text: &str) -> Vec<(String, usize, usize)> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = i;
            while i < bytes.len() && bytes[i].is_ascii_digit() {
                i += 1;
            }
            out.push((text[start..i].to_owned(), start, i));
        } else {
            i += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn address_notations() {
        let forms = AddressForms::new(0x0200, None);
        assert!(forms.found_in(&Line::new("0200H\tBn-01\tAcceleration time 1")));
        assert!(forms.found_in(&Line::new("n018 200h Accel")));
        assert!(forms.found_in(&Line::new("write 0x0200 now")));
        assert!(!forms.found_in(&Line::new("0.0~6000.0s 1200H")));
        assert!(!forms.found_in(&Line::new("0201H Bn-02")));
        let glued = AddressForms::new(0x031A, None);
        assert!(glued.found_in(&Line::new("31AhE4-03Motor 2 Max. Voltage")));
        let ocr = AddressForms::new(0x1E0A, Some((-1, 0)));
        assert!(ocr.found_in(&Line::new("UF.10 1EOA 47690 47691")));
        let decimal = AddressForms::new(2001, None).with_decimal(2001);
        assert!(decimal.found_in(&Line::new("2001 Speed reference")));
        assert!(!decimal.found_in(&Line::new("12001 Speed reference")));
        assert!(!AddressForms::new(2001, None).found_in(&Line::new("2001 Speed reference")));
        let plc = AddressForms::new(0x1E0A, Some((-1, 0)));
        assert!(plc.found_in(&Line::new("UF.10 ---- 47690 47691")));
        // The next register's RTU number is this one's TCP number: both are needed.
        assert!(!plc.found_in(&Line::new("UF.11 ---- 47691 47692")));
        assert!(!plc.found_in(&Line::new("UF.10 ---- 476900")));
    }

    #[test]
    fn parameters_names_numbers() {
        assert!(param_found("Bn-01", &Line::new("0200H\tBn-01\tAcc")));
        assert!(!param_found("Bn-01", &Line::new("0200H\tBn-010\tAcc")));
        assert!(param_found("UF.11", &Line::new("UF11 1E0B 47691")));
        assert!(!param_found("UF.1", &Line::new("UF.10 1E0A")));
        assert!(param_found("E4-03", &Line::new("31AhE4-03Motor")));
        assert!(!param_found("n01", &Line::new("pn01")));
        assert!(name_found(
            "Acceleration time 1",
            &Line::new("Accel eration time 1")
        ));
        assert!(!name_found(
            "Acceleration time 1",
            &Line::new("Deceleration time 1")
        ));
        assert!(name_found("0.1 Hz", &Line::new("0: 0.1 Hz 1: 0.01 Hz")));
        assert!(number_found(3, &Line::new("3: Timeover")));
        assert!(number_found(3, &Line::new("bit 03")));
        assert!(!number_found(3, &Line::new("13: x")));
    }
}
