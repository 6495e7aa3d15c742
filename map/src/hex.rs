//! Register addresses and protocol codes as the manuals print them: in hexadecimal.
//!
//! A manual prints "2001H"; YAML reads `address: 2001` as the decimal 2001 = 07D1H, a silently
//! wrong register. So the keys whose numbers the manuals print in hex — `address` (registers,
//! `address_alternatives`, command writes), `addresses` (gaps), `code` (exceptions),
//! `function_codes` (or its `codes`) and `broadcast.functions` — accept the manual's notations `0x2001`, `2001H`
//! and `2001h` (quoted or not), and refuse a bare decimal, naming the hex it would mean. A map
//! whose manual numbers its registers in decimal declares `address_format: decimal` at the top;
//! then a decimal address is taken as written. Codes 0-9 read the same in both bases and are
//! accepted as decimals.
//!
//! The work is split in two because the decision needs the scalar's raw text, which only the
//! parser sees, and the map's `address_format`, which may come after the addresses: while
//! parsing, [`literal`] turns hex notations into integers and marks the doubtful ones (decimal
//! digits, hex digits without a marker) with a private YAML tag; [`resolve`] then decides each
//! marked scalar once the whole file is read.

use serde_yaml::Value;
use serde_yaml::value::{Tag, TaggedValue};

use crate::diagnostic::{Diagnostic, Loc};
use crate::source::{Node, NodeKind, Path, Seg};

/// What a hexadecimal number at this place is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// A register address.
    Address,
    /// An exception code.
    ExceptionCode,
    /// A Modbus function code.
    FunctionCode,
}

impl Slot {
    /// The slot of a value written under mapping key `key`.
    pub fn of_key(key: &str) -> Option<Slot> {
        match key {
            "address" => Some(Slot::Address),
            "code" | "exception" => Some(Slot::ExceptionCode),
            _ => None,
        }
    }

    /// The slot of an item of a sequence written under mapping key `key`.
    pub fn of_items(key: &str) -> Option<Slot> {
        match key {
            "addresses" => Some(Slot::Address),
            "function_codes" | "codes" | "functions" => Some(Slot::FunctionCode),
            _ => None,
        }
    }

    fn tag(self) -> &'static str {
        match self {
            Slot::Address => "drivemap-address",
            Slot::ExceptionCode => "drivemap-exception-code",
            Slot::FunctionCode => "drivemap-function-code",
        }
    }

    fn from_tag(tag: &Tag) -> Option<Slot> {
        [Slot::Address, Slot::ExceptionCode, Slot::FunctionCode]
            .into_iter()
            .find(|s| *tag == Tag::new(s.tag()))
    }
}

/// The value of a scalar written as `text` at `slot`: an integer for the hex notations
/// (`0x2001`, `2001H`, `2001h`), a marked scalar for digits without a hex marker (decided by
/// [`resolve`]), or `None` to let YAML resolve it as usual (and the schema refuse it).
pub(crate) fn literal(text: &str, slot: Slot) -> Option<Value> {
    let t = text.trim();
    let hex_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_hexdigit());
    let digits = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .or_else(|| t.strip_suffix(['h', 'H']));
    if let Some(digits) = digits {
        return hex_digits(digits)
            .then(|| u64::from_str_radix(digits, 16).ok())
            .flatten()
            .map(Value::from);
    }
    hex_digits(t).then(|| {
        Value::Tagged(Box::new(TaggedValue {
            tag: Tag::new(slot.tag()),
            value: Value::String(t.to_owned()),
        }))
    })
}

/// A bare decimal read as its decimal value because the file is written in schema 1, where
/// schema 2 would refuse it: where it is, how it is written, what it means, what kind of number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reread {
    /// Where the number is written.
    pub loc: Loc,
    /// The register it belongs to, if any.
    pub register: Option<String>,
    /// The key path of the number.
    pub path: Path,
    /// The number as written.
    pub text: String,
    /// What schema 1 reads it as.
    pub value: u64,
    /// What kind of number it is.
    pub slot: Slot,
}

impl Reread {
    /// How the current schema writes the same number.
    pub fn hex(&self) -> String {
        match self.slot {
            Slot::Address => format!("0x{:04X}", self.value),
            Slot::ExceptionCode | Slot::FunctionCode => format!("0x{:02X}", self.value),
        }
    }

    /// The warning naming what changed for this value.
    pub fn warning(&self) -> Diagnostic {
        let what = match self.slot {
            Slot::Address => "address",
            Slot::ExceptionCode => "exception code",
            Slot::FunctionCode => "function code",
        };
        Diagnostic::new(
            self.loc.clone(),
            self.register.as_deref(),
            format!(
                "{}: {what} {} is decimal {} ({:02X}H), as schema 1 reads it; schema {} writes it {}",
                self.path,
                self.text,
                self.value,
                self.value,
                crate::schema::CURRENT,
                self.hex(),
            ),
        )
    }
}

/// What [`resolve`] decided: the errors, and the numbers read as schema 1 reads them.
#[derive(Debug, Default)]
pub(crate) struct Resolved {
    pub errors: Vec<Diagnostic>,
    pub reread: Vec<Reread>,
}

/// Decides every scalar [`literal`] marked in one file's tree (before a variant is merged onto
/// its base, so each file's own `address_format` applies to its own addresses), as schema
/// `version` reads them (see [`crate::schema`]): in schema 1 a bare decimal is the decimal
/// number. The tree is left with plain values either way.
pub(crate) fn resolve(tree: &mut Node, version: u32) -> Resolved {
    let decimal = matches!(
        tree.get("address_format").map(|n| &n.kind),
        Some(NodeKind::Scalar(Value::String(s))) if s == "decimal"
    );
    let mut marked = Vec::new();
    collect(tree, &Path::root(), &mut marked);
    let mut out = Resolved::default();
    for (path, slot, text) in marked {
        let mut decided = decide(&text, slot, decimal);
        if version < 2
            && decided.is_err()
            && text.len() <= 20
            && text.bytes().all(|b| b.is_ascii_digit())
        {
            // Schema 1: YAML's reading, a decimal number.
            if let Ok(value) = text.parse::<u64>() {
                decided = Ok(value);
                let register = crate::load::register_at(tree, &path);
                if let Some(node) = tree.at(&path) {
                    out.reread.push(Reread {
                        loc: node.loc.clone(),
                        register,
                        path: path.clone(),
                        text: text.clone(),
                        value,
                        slot,
                    });
                }
            }
        }
        let register = crate::load::register_at(tree, &path);
        let Some(node) = node_mut(tree, &path) else {
            continue;
        };
        match decided {
            Ok(n) => node.kind = NodeKind::Scalar(Value::from(n)),
            Err(message) => {
                out.errors.push(Diagnostic::new(
                    node.loc.clone(),
                    register.as_deref(),
                    format!("{path}: {message}"),
                ));
                node.kind = NodeKind::Scalar(Value::String(text));
            }
        }
    }
    out
}

fn collect(node: &Node, path: &Path, out: &mut Vec<(Path, Slot, String)>) {
    match &node.kind {
        NodeKind::Scalar(Value::Tagged(t)) => {
            if let (Some(slot), Value::String(text)) = (Slot::from_tag(&t.tag), &t.value) {
                out.push((path.clone(), slot, text.clone()));
            }
        }
        NodeKind::Scalar(_) => {}
        NodeKind::Seq(items) => {
            for (i, item) in items.iter().enumerate() {
                collect(item, &path.index(i), out);
            }
        }
        NodeKind::Map(entries) => {
            for (k, _, v) in entries {
                collect(v, &path.key(k), out);
            }
        }
    }
}

fn node_mut<'a>(mut node: &'a mut Node, path: &Path) -> Option<&'a mut Node> {
    for seg in path.segs() {
        node = match (seg, &mut node.kind) {
            (Seg::Key(k), NodeKind::Map(entries)) => {
                &mut entries.iter_mut().find(|(key, _, _)| key == k)?.2
            }
            (Seg::Index(i), NodeKind::Seq(items)) => items.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(node)
}

/// The number a marked scalar stands for, or why it is refused.
fn decide(text: &str, slot: Slot, decimal_addresses: bool) -> Result<u64, Undecided> {
    let what = match slot {
        Slot::Address => "address",
        Slot::ExceptionCode => "exception code",
        Slot::FunctionCode => "function code",
    };
    if text.len() > 20 {
        // No address or code has this many digits; a hostile map's megabyte of them is not
        // repeated in the message.
        let head: String = text.chars().take(20).collect();
        return Err(Undecided::TooLong {
            what,
            head,
            digits: text.len(),
        });
    }
    if !text.bytes().all(|b| b.is_ascii_digit()) {
        // Hex digits with a letter (`1E08`, which YAML would read as 1.0e8).
        return Err(Undecided::NoMarker {
            what,
            text: text.to_owned(),
        });
    }
    let Ok(n) = text.parse::<u64>() else {
        return Err(Undecided::TooLarge {
            what,
            text: text.to_owned(),
        });
    };
    match slot {
        Slot::Address if decimal_addresses => Ok(n),
        Slot::Address => Err(Undecided::DecimalAddress {
            n,
            text: text.to_owned(),
        }),
        _ if n <= 9 => Ok(n),
        Slot::ExceptionCode | Slot::FunctionCode => Err(Undecided::DecimalCode {
            what,
            n,
            text: text.to_owned(),
        }),
    }
}

/// Why a marked scalar is refused (said at the scalar, after its path).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
enum Undecided {
    /// More digits than any address or code has; only the first 20 are repeated.
    #[error("{what} `{head}…` is too long ({digits} digits)")]
    TooLong {
        what: &'static str,
        head: String,
        digits: usize,
    },
    /// Hex digits with a letter but no marker (`1E08`, which YAML reads as 1.0e8).
    #[error("{what} `{text}` has no hexadecimal marker; write it as 0x{text} or {text}H")]
    NoMarker { what: &'static str, text: String },
    #[error("{what} {text} is too large")]
    TooLarge { what: &'static str, text: String },
    #[error(
        "address {n} is decimal ({n:04X}H); write it as the manual prints it: 0x{text} or \
         {text}H, or declare `address_format: decimal` at the top of the map if the manual \
         numbers registers in decimal"
    )]
    DecimalAddress { n: u64, text: String },
    #[error(
        "{what} {n} is decimal ({n:02X}H); write codes in hex as the manual prints them: \
         0x{n:02X} for {n:02X}H, or 0x{text} for {text}H"
    )]
    DecimalCode {
        what: &'static str,
        n: u64,
        text: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_notations_are_integers() {
        for text in ["0x2001", "0X2001", "2001H", "2001h", " 2001h "] {
            assert_eq!(
                literal(text, Slot::Address),
                Some(Value::from(0x2001u64)),
                "{text}"
            );
        }
        assert_eq!(literal("twelve", Slot::Address), None);
        assert_eq!(literal("0xZZ", Slot::Address), None);
        assert_eq!(literal("h", Slot::Address), None);
        assert_eq!(literal("0x1FFFFFFFFFFFFFFFFF", Slot::Address), None);
    }

    #[test]
    fn decimals_are_decided_by_the_map() {
        assert!(
            decide("2001", Slot::Address, false)
                .unwrap_err()
                .to_string()
                .contains("address 2001 is decimal (07D1H)")
        );
        assert_eq!(decide("2001", Slot::Address, true), Ok(2001));
        assert!(
            decide("1E08", Slot::Address, true)
                .unwrap_err()
                .to_string()
                .contains("0x1E08 or 1E08H")
        );
        assert_eq!(decide("3", Slot::FunctionCode, false), Ok(3));
        assert!(
            decide("16", Slot::FunctionCode, true)
                .unwrap_err()
                .to_string()
                .contains("0x10 for 10H, or 0x16 for 16H")
        );
        assert!(
            decide("99999999999999999999", Slot::Address, true)
                .unwrap_err()
                .to_string()
                .contains("too large")
        );
        let long = "7".repeat(1 << 20);
        let e = decide(&long, Slot::Address, false).unwrap_err().to_string();
        assert!(e.len() < 100 && e.contains("1048576 digits"), "{e}");
    }
}
