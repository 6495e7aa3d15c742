//! Protocol facts a manual prints in prose or small tables: function codes, the most registers
//! one request may read or write, the slave address range, exception codes, transports. Each is
//! read from one line and cites it; what is not found is left for the reviewer.

use std::collections::BTreeMap;
use std::sync::LazyLock;

use regex::Regex;

/// A fact and the 1-based line it was read from.
#[derive(Debug, Clone, PartialEq)]
pub struct Cited<T> {
    /// The fact.
    pub value: T,
    /// The 1-based line it was read from.
    pub line: usize,
}

/// An exception code as printed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Exception {
    /// The exception code.
    pub code: u8,
    /// Its name, as printed.
    pub name: String,
    /// Its description, when the manual prints one on the lines under the code.
    pub description: Option<String>,
    /// The 1-based line of the code.
    pub line: usize,
}

/// A character format as printed (`8 data bits, 1 parity-even bit and 1 stop bit`, `8N1`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Format {
    /// Data bits.
    pub data_bits: u8,
    /// `none`, `even` or `odd`.
    pub parity: &'static str,
    /// Stop bits.
    pub stop_bits: u8,
}

/// The protocol facts found in a manual.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Protocol {
    /// Function codes, each with the first line that names it as a function.
    pub function_codes: BTreeMap<u8, usize>,
    /// The most registers one request may read.
    pub max_read: Option<Cited<u16>>,
    /// The most registers one request may write.
    pub max_write: Option<Cited<u16>>,
    /// The slave address range.
    pub slave_range: Option<Cited<(u8, u8)>>,
    /// The exception codes, in the manual's order.
    pub exceptions: Vec<Exception>,
    /// `rtu` and/or `tcp`, with a line naming each.
    pub transports: BTreeMap<&'static str, usize>,
    /// The character format, where one line prints it whole.
    pub format: Option<Cited<Format>>,
    /// The line saying that slave address 0 is a broadcast.
    pub broadcast: Option<usize>,
    /// The baud rates of the first line that lists them, with the default where the line says.
    pub bauds: Option<Cited<(Vec<u32>, Option<u32>)>>,
}

/// Function codes a drive manual may print (Modbus public codes).
const FUNCTIONS: &[u8] = &[
    0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x0B, 0x0F, 0x10, 0x11, 0x16, 0x17, 0x2B,
];

/// Reads the protocol facts of `lines` (numbered from `first_line`).
pub fn read(lines: &[&str], first_line: usize) -> Protocol {
    static HEX: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"\b(?:0x([0-9A-Fa-f]{2})\b|([0-9A-F]{2})[hH]\b)").expect("pattern")
    });
    static MAX: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"(?i)\b(?:max(?:imum|\.)?(?:\s+of)?|up\s+to|at\s+most)\s+(\d{1,3})\s+(?:\w+\s+)?(?:registers|words|data)\b")
            .expect("pattern")
    });
    static SLAVE: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"(?i)\b(\d{1,3})\s*(?:~|to|-|–|through|\.{2,3}|…)\s*(\d{1,3})\b")
            .expect("pattern")
    });
    // A code of a function-code table, its digits perhaps spaced as PDF text leaves them
    // (`0 3 h`, `1 0 h`, `03H`, `0x10`), then what the function does.
    static FUNCTION_ROW: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"(?i)^\s*(?:0x([0-9a-f]{2})|([0-9a-f])\s?([0-9a-f])\s?h)\b[\s:|-]*(?:\(\s*\d+\s*\)\s*)?(read|write|preset|force|diagnos|loop|report|mask)")
            .expect("pattern")
    });
    static DATA_BITS: LazyLock<Regex> =
        LazyLock::new(|| Regex::new(r"(?i)\b([78])\s*data\s*bits?").expect("pattern"));
    static STOP_BITS: LazyLock<Regex> =
        LazyLock::new(|| Regex::new(r"(?i)\b([12])\s*stop\s*bits?").expect("pattern"));
    static PARITY: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"(?i)\b(?:(even|odd|no|none)[\s-]*parity|parity[\s-]*(even|odd|none))\b")
            .expect("pattern")
    });
    let mut function_region_until = 0usize;
    static EXC: LazyLock<Regex> = LazyLock::new(|| {
        Regex::new(r"^\s*(?:0x)?([0-9A-F]{2})[hH]?\s*[\t:|-]?\s*([A-Za-z][^\t]{2,80})")
            .expect("pattern")
    });
    let mut p = Protocol::default();
    let mut exception_region_until = 0usize;
    for (i, raw) in lines.iter().enumerate() {
        let line_no = first_line + i;
        let line = raw.trim();
        let lower = line.to_lowercase();
        if lower.contains("function code") {
            function_region_until = line_no + 10;
        }
        if line_no <= function_region_until
            && let Some(c) = FUNCTION_ROW.captures(line)
        {
            let digits = match c.get(1) {
                Some(d) => d.as_str().to_string(),
                None => format!("{}{}", &c[2], &c[3]),
            };
            if let Ok(code) = u8::from_str_radix(&digits, 16)
                && FUNCTIONS.contains(&code)
            {
                p.function_codes.entry(code).or_insert(line_no);
            }
        }
        if p.format.is_none()
            && let (Some(d), Some(st), Some(pa)) = (
                DATA_BITS.captures(line),
                STOP_BITS.captures(line),
                PARITY.captures(line),
            )
        {
            let word = pa
                .get(1)
                .or_else(|| pa.get(2))
                .map_or("", |m| m.as_str())
                .to_ascii_lowercase();
            p.format = Some(Cited {
                value: Format {
                    data_bits: d[1].parse().unwrap_or(8),
                    parity: match word.as_str() {
                        "even" => "even",
                        "odd" => "odd",
                        _ => "none",
                    },
                    stop_bits: st[1].parse().unwrap_or(1),
                },
                line: line_no,
            });
        }
        if p.bauds.is_none() && (lower.contains("baud") || lower.contains("bps")) {
            static BAUD: LazyLock<Regex> = LazyLock::new(|| {
                Regex::new(r"\b(1200|2400|4800|9600|14400|19200|38400|57600|115200)\b")
                    .expect("pattern")
            });
            static DEFAULT: LazyLock<Regex> = LazyLock::new(|| {
                Regex::new(r"(?i)(?:default|factory setting)\D{0,12}(\d{4,6})").expect("pattern")
            });
            let mut rates: Vec<u32> = BAUD
                .captures_iter(line)
                .filter_map(|c| c[1].parse().ok())
                .collect();
            rates.sort_unstable();
            rates.dedup();
            if !rates.is_empty() {
                let default = DEFAULT
                    .captures(line)
                    .and_then(|c| c[1].parse().ok())
                    .filter(|d| rates.contains(d));
                p.bauds = Some(Cited {
                    value: (rates, default),
                    line: line_no,
                });
            }
        }
        if p.broadcast.is_none()
            && lower.contains("broadcast")
            && (lower.contains("address 0")
                || lower.contains("slave 0")
                || lower.contains("station 0"))
        {
            p.broadcast = Some(line_no);
        }
        if lower.contains("function code") {
            for c in HEX.captures_iter(line) {
                let digits = c.get(1).or_else(|| c.get(2)).map_or("", |m| m.as_str());
                if let Ok(code) = u8::from_str_radix(digits, 16)
                    && FUNCTIONS.contains(&code)
                {
                    p.function_codes.entry(code).or_insert(line_no);
                }
            }
        }
        // A sentence may wrap onto the next line (`reads at most` / `100 registers`): the limit
        // is read from the line and the next, when it starts on this line.
        let next = lines.get(i + 1).map_or("", |l| l.trim());
        let joined = format!("{line} {next}");
        if let Some(c) = MAX.captures(line).or_else(|| {
            MAX.captures(&joined)
                .filter(|c| c.get(0).is_some_and(|m| m.start() < line.len()))
        }) && let Ok(n) = c[1].parse::<u16>()
            && (1..=125).contains(&n)
        {
            let cited = Cited {
                value: n,
                line: line_no,
            };
            let m = c.get(0).map_or("", |m| m.as_str()).to_lowercase();
            let around = if m.contains("read") || m.contains("writ") {
                m
            } else {
                lower.clone()
            };
            if around.contains("read") && p.max_read.is_none() {
                p.max_read = Some(cited.clone());
            }
            if around.contains("writ") && p.max_write.is_none() {
                p.max_write = Some(cited);
            }
        }
        if p.slave_range.is_none()
            && (lower.contains("slave address")
                || lower.contains("station")
                || lower.contains("node address")
                || lower.contains("inverter number")
                || lower.contains("drive address")
                || lower.contains("device address"))
            && let Some(c) = SLAVE.captures(line)
            && let (Ok(a), Ok(b)) = (c[1].parse::<u8>(), c[2].parse::<u8>())
            && a <= 1
            && b > a
            && b <= 247
        {
            p.slave_range = Some(Cited {
                value: (a.max(1), b),
                line: line_no,
            });
        }
        if lower.contains("exception") || lower.contains("error code") {
            exception_region_until = line_no + 40;
        }
        // A blank line after the list ends it.
        if line.is_empty() && !p.exceptions.is_empty() && line_no <= exception_region_until {
            exception_region_until = 0;
        }
        // An exception is a code, a name and perhaps a description: a row of more cells is a
        // register table's row (`10 | 40011 | Motor current | R`), not an exception.
        let cell_count = crate::text::cells(&line.replace('|', "\t")).len();
        if line_no <= exception_region_until
            && cell_count <= 3
            && let Some(c) = EXC.captures(line)
            && let Ok(code) = u8::from_str_radix(&c[1], 16)
            && code > 0
            && code < 0x80
            && !p.exceptions.iter().any(|e| e.code == code)
        {
            // Codes are listed in ascending order; a line out of order ends the list.
            if p.exceptions.last().is_none_or(|e| e.code < code) {
                p.exceptions.push(Exception {
                    code,
                    name: c[2].trim().to_string(),
                    description: None,
                    line: line_no,
                });
            }
        } else if line_no <= exception_region_until
            && raw.starts_with(char::is_whitespace)
            && line.starts_with(char::is_alphabetic)
            && let Some(e) = p.exceptions.last_mut()
            && e.line + 1 == line_no
            && e.description.is_none()
        {
            // The description printed under the exception's name.
            e.description = Some(line.to_string());
        }
        if line.contains("RTU") {
            p.transports.entry("rtu").or_insert(line_no);
        }
        if line.contains("Modbus TCP") || line.contains("MODBUS TCP") || line.contains("Modbus/TCP")
        {
            p.transports.entry("tcp").or_insert(line_no);
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facts_with_their_lines() {
        let text = "The drive supports Modbus RTU.\n\
                    Function codes 03H (read) and 06H, 10H (write) are used.\n\
                    A maximum of 16 registers can be read at a time.\n\
                    Up to 8 registers can be written in one message.\n\
                    The slave address is set from 1 to 31.\n\
                    Exception codes\n\
                    01H  Illegal function\n\
                    02H  Illegal address\n";
        let lines: Vec<&str> = text.lines().collect();
        let p = read(&lines, 1);
        assert_eq!(
            p.function_codes.keys().copied().collect::<Vec<_>>(),
            vec![0x03, 0x06, 0x10]
        );
        assert_eq!(p.max_read, Some(Cited { value: 16, line: 3 }));
        assert_eq!(p.max_write, Some(Cited { value: 8, line: 4 }));
        assert_eq!(
            p.slave_range,
            Some(Cited {
                value: (1, 31),
                line: 5
            })
        );
        assert_eq!(
            p.exceptions
                .iter()
                .map(|e| (e.code, e.line))
                .collect::<Vec<_>>(),
            vec![(1, 7), (2, 8)]
        );
        assert_eq!(p.transports.get("rtu"), Some(&1));
    }

    #[test]
    fn table_rows_after_an_exception_line_are_not_exceptions() {
        let text = "Exception codes are listed in chapter 9.\n\
                    10 | 40011 | Motor current | R\n\
                    11 | 40012 | Motor voltage | R\n\
                    Exception codes\n\
                    01h  Illegal function\n\
                    02h  Illegal data address\n\
                    \n\
                    03  Acceleration time  0.1 s\n";
        let lines: Vec<&str> = text.lines().collect();
        let p = read(&lines, 1);
        assert_eq!(
            p.exceptions.iter().map(|e| e.code).collect::<Vec<_>>(),
            vec![1, 2]
        );
    }

    #[test]
    fn facts_printed_in_words() {
        let text = "It knows only three Function Codes:\n\
                    \u{20}\u{20}0 3 h   Read Holding Registers\n\
                    \u{20}\u{20}1 0 h   Write Multiple Registers\n\
                    Drive address (parameter H-01). Range: 1 ... 247\n\
                    Character format: 8 data bits, 1 parity-even bit and 1 stop bit.\n\
                    Baud rate: 4800, 9600 or 19200 bps (factory setting 9600).\n\
                    A message sent to address 0 is a broadcast.\n\
                    The drive reads at most\n\
                    20 registers per request.\n";
        let lines: Vec<&str> = text.lines().collect();
        let p = read(&lines, 1);
        assert_eq!(
            p.function_codes.keys().copied().collect::<Vec<_>>(),
            vec![0x03, 0x10]
        );
        assert_eq!(p.slave_range.map(|c| c.value), Some((1, 247)));
        assert_eq!(
            p.format.map(|f| f.value),
            Some(Format {
                data_bits: 8,
                parity: "even",
                stop_bits: 1
            })
        );
        assert_eq!(
            p.bauds.map(|b| b.value),
            Some((vec![4800, 9600, 19200], Some(9600)))
        );
        assert_eq!(p.broadcast, Some(7));
        assert_eq!(p.max_read, Some(Cited { value: 20, line: 8 }));
    }
}
