//! Register values as an aligned terminal table.

use drivemap_map::RegisterRef;

use drivemap_live::session::{ReadError, Session, field_lines};

/// One register's line.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Row {
    /// `accel_time_1 (Bn-01)`.
    pub(crate) register: String,
    /// `0200h`.
    pub(crate) address: String,
    /// Decoded value, or the error.
    pub(crate) value: String,
    /// Raw word in hex, when read.
    pub(crate) raw: String,
    /// Lines shown under the row (bit fields).
    pub(crate) details: Vec<String>,
    /// Whether the value failed.
    pub(crate) failed: bool,
}

impl Row {
    /// The row of a register read as `word` (or its error).
    pub(crate) fn of(
        session: &Session<'_>,
        r: RegisterRef<'_>,
        word: &Result<u32, ReadError>,
        details: bool,
    ) -> Row {
        let register = r.label();
        let address = crate::live::output::address_text(session.drive, session.shown_address(r));
        match word {
            Err(e) => Row {
                register,
                address,
                value: format!("error: {e}"),
                raw: String::new(),
                details: Vec::new(),
                failed: true,
            },
            Ok(raw) => match session.decode(r, *raw) {
                Ok(v) => Row {
                    register,
                    address,
                    details: if details { field_lines(&v) } else { Vec::new() },
                    value: v.to_string(),
                    raw: session.raw_text(r, *raw),
                    failed: false,
                },
                Err(e) => Row {
                    register,
                    address,
                    value: format!("error: {e}"),
                    raw: session.raw_text(r, *raw),
                    details: Vec::new(),
                    failed: true,
                },
            },
        }
    }
}

fn width(s: &str) -> usize {
    s.chars().count()
}

fn pad(s: &str, w: usize) -> String {
    format!("{s}{}", " ".repeat(w.saturating_sub(width(s))))
}

/// Renders rows under a header. `highlight[i]` shows row `i`'s value in bold (changed since
/// the last poll); pass an empty slice for none.
pub(crate) fn render(rows: &[Row], highlight: &[bool]) -> String {
    let head = ["REGISTER", "ADDRESS", "VALUE", "RAW"];
    let w0 = rows
        .iter()
        .map(|r| width(&r.register))
        .chain([width(head[0])])
        .max()
        .unwrap_or(0);
    let w1 = rows
        .iter()
        .map(|r| width(&r.address))
        .chain([width(head[1])])
        .max()
        .unwrap_or(0);
    let w2 = rows
        .iter()
        .map(|r| width(&r.value))
        .chain([width(head[2])])
        .max()
        .unwrap_or(0)
        .min(60);
    let mut out = format!(
        "{}  {}  {}  {}\n",
        pad(head[0], w0),
        pad(head[1], w1),
        pad(head[2], w2),
        head[3]
    );
    for (i, r) in rows.iter().enumerate() {
        let value = if highlight.get(i).copied().unwrap_or(false) {
            let fill = " ".repeat(w2.saturating_sub(width(&r.value)));
            format!("\x1b[1m{}\x1b[0m{fill}", r.value)
        } else {
            pad(&r.value, w2)
        };
        let line = format!(
            "{}  {}  {value}  {}",
            pad(&r.register, w0),
            pad(&r.address, w1),
            r.raw
        );
        out += line.trim_end();
        out.push('\n');
        for d in &r.details {
            out += &format!("{}  {d}\n", " ".repeat(w0 + w1 + 2));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(register: &str, value: &str) -> Row {
        Row {
            register: register.into(),
            address: "0001h".into(),
            value: value.into(),
            raw: "5DC0h".into(),
            details: vec!["run = 1".into()],
            failed: false,
        }
    }

    #[test]
    fn columns_align_and_highlight_marks_only_the_value() {
        let rows = [row("frequency_command", "48.00 Hz"), row("x", "1")];
        let plain = render(&rows, &[]);
        let lines: Vec<&str> = plain.lines().collect();
        assert_eq!(lines[0].find("ADDRESS"), lines[1].find("0001h"));
        assert_eq!(lines[1].find("48.00 Hz"), lines[3].find("1 "));
        assert!(lines[2].trim_start().starts_with("run = 1"));
        let bold = render(&rows, &[false, true]);
        assert!(!bold.lines().nth(1).unwrap().contains("\x1b[1m"));
        assert!(bold.lines().nth(3).unwrap().contains("\x1b[1m1"));
    }
}
