//! Registers by the names a user types: id, parameter number as printed, printed name
//! (case-insensitively), the address in the manual's notation (`2101H`, `2101h`, `0x2101`; the
//! register number as printed, `45`, when the manual numbers registers in decimal), or a Modicon
//! reference (`40024`, `400024`, `30002`), with the nearest names suggested when nothing matches.
//!
//! A Modicon reference is five or six digits: the table (`4` holding registers, `3` input
//! registers, `0` coils, `1` discrete inputs) and the register's number counted from 1, so
//! `40001` and `400001` are PDU address 0. The map's address of that PDU address follows from
//! its `protocol.addressing` offset on each transport it lists. Digits are read as a reference
//! only where that reading is unambiguous for the map ([`modicon_reading`]): never in a map
//! whose decimal register numbers reach five digits (`40024` could be its own number), and only
//! when every transport the map lists puts the reference on the same address.

use std::fmt;

use drivemap_map::{Map, RegisterRef};

/// No register has that name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NotFound {
    /// The name as given.
    pub name: String,
    /// The id of the drive whose map was searched.
    pub drive: String,
    /// Nearest ids (with parameter numbers), best first.
    pub suggestions: Vec<String>,
    /// When the name is an address inside one of the map's gaps (a reserved or illegible
    /// range): the gap as the map describes it, with its citation (boxed: the error stays
    /// small where it is carried).
    pub gap: Option<Box<str>>,
    /// When the name is a Modicon reference: how it was read and why it names no register
    /// here (no register at that address or in that table, or a reading the map leaves
    /// ambiguous).
    pub reference: Option<Box<str>>,
}

impl fmt::Display for NotFound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(why) = &self.reference {
            return write!(
                f,
                "{} has no register `{}`: {why}",
                self.drive,
                crate::codec::shorten(&self.name)
            );
        }
        if let Some(gap) = &self.gap {
            return write!(
                f,
                "{} has no register at `{}`: it is in a gap of the map, where nothing is mapped ({gap})",
                self.drive,
                crate::codec::shorten(&self.name)
            );
        }
        write!(
            f,
            "{} has no register `{}`",
            self.drive,
            crate::codec::shorten(&self.name)
        )?;
        if !self.suggestions.is_empty() {
            write!(f, "; did you mean {}?", self.suggestions.join(", "))?;
        }
        Ok(())
    }
}

impl std::error::Error for NotFound {}

fn norm(s: &str) -> String {
    normalized(s).collect()
}

/// The characters of [`norm`]`(s)`, without building the string.
fn normalized(s: &str) -> impl Iterator<Item = char> + '_ {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
}

/// `norm(s) == key`, without allocating (a lookup compares every register's names). Bytes
/// suffice: [`norm`] keeps ASCII only, and no byte of a longer UTF-8 character is ASCII.
fn norm_is(s: &str, key: &str) -> bool {
    let key = key.as_bytes();
    let mut at = 0;
    for b in s.bytes().filter(u8::is_ascii_alphanumeric) {
        if key.get(at) != Some(&b.to_ascii_lowercase()) {
            return false;
        }
        at += 1;
    }
    at == key.len()
}

/// Levenshtein distance, for suggestions.
pub(crate) fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let cost = usize::from(ca != *cb);
            cur[j + 1] = (prev[j] + cost).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The address a name writes in a manual's notation: hex with a marker (`2101H`, `2101h`,
/// `0x2101`), or bare decimal digits when `decimal` (a manual numbering registers in decimal).
fn address_in(name: &str, decimal: bool) -> Option<u16> {
    let t = name.trim();
    let hex = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .or_else(|| t.strip_suffix(['h', 'H']));
    match hex {
        Some(h) if !h.is_empty() && h.len() <= 4 && h.bytes().all(|b| b.is_ascii_hexdigit()) => {
            u16::from_str_radix(h, 16).ok()
        }
        Some(_) => None,
        None if decimal
            && !t.is_empty()
            && t.len() <= 5
            && t.bytes().all(|b| b.is_ascii_digit()) =>
        {
            t.parse().ok()
        }
        None => None,
    }
}

/// The Modbus table a Modicon reference names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceTable {
    /// `0xxxx`: coils.
    Coil,
    /// `1xxxx`: discrete inputs.
    DiscreteInput,
    /// `3xxxx`: input registers.
    Input,
    /// `4xxxx`: holding registers.
    Holding,
}

/// A Modicon reference: five digits (`40024`: table digit, register 1 to 9999) or six
/// (`400024`: register 1 to 65536). `40001` is PDU address 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Modicon {
    /// The table its first digit names.
    pub table: ReferenceTable,
    /// The PDU address (the register's number minus 1).
    pub pdu: u16,
}

/// Reads `name` as a Modicon reference, if it is one in form (digits only, five or six, the
/// first 0, 1, 3 or 4, the register number at least 1). Whether the map reads it so is
/// [`modicon_reading`]'s decision.
pub fn modicon(name: &str) -> Option<Modicon> {
    let t = name.trim();
    if !(5..=6).contains(&t.len()) || !t.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let table = match t.as_bytes()[0] {
        b'0' => ReferenceTable::Coil,
        b'1' => ReferenceTable::DiscreteInput,
        b'3' => ReferenceTable::Input,
        b'4' => ReferenceTable::Holding,
        _ => return None,
    };
    let number: u32 = t[1..].parse().ok()?;
    let pdu = u16::try_from(number.checked_sub(1)?).ok()?;
    Some(Modicon { table, pdu })
}

/// How a map reads a Modicon reference: the map's address it names, or why the map does not
/// read it so.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ModiconReading {
    /// The map's (communication) address in the reference's table, the same on every transport
    /// the map lists.
    Address {
        /// The reference.
        reference: Modicon,
        /// The map's address.
        address: u16,
    },
    /// Not read as a reference: why (boxed text for the error).
    Refused(String),
}

/// Whether `name` is a Modicon reference for `drive`, and what it names. `None` when it is not
/// one in form ([`modicon`]). The map decides:
/// - in a map that prints decimal register numbers (`address_format: decimal`) whose numbers
///   (addresses, alternatives, gaps) reach 10000, five or six digits could be its own number:
///   not read as a reference (refused, naming the ids and hex notations that are unambiguous);
/// - the PDU address is turned into the map's address with the `protocol.addressing` offset of
///   each transport the map lists (serial side and Modbus TCP); where they differ (ACN: RTU
///   -1, TCP 0) the reference names two registers and is refused.
pub fn modicon_reading(drive: &Map, name: &str) -> Option<ModiconReading> {
    use drivemap_map::facts::{AddressFormat, TransportName};
    let reference = modicon(name)?;
    if drive.address_format() == AddressFormat::Decimal {
        let big = drive.registers().any(|r| {
            r.address() >= 10_000 || r.address_alternatives().iter().any(|a| a.address >= 10_000)
        }) || drive
            .gaps()
            .iter()
            .any(|g| g.addresses.is_some_and(|[_, hi]| hi >= 10_000));
        if big {
            return Some(ModiconReading::Refused(format!(
                "the map numbers its registers in decimal up to five digits, so `{}` is not read as a Modicon reference (it could be the map's own number); name the register by id or in hex (`0x...`)",
                name.trim()
            )));
        }
    }
    let (rtu, tcp) = drive.address_offsets();
    let listed = &drive.protocol().transports;
    let mut offsets: Vec<(&str, i32)> = Vec::new();
    if listed.iter().any(|t| t.is_serial()) {
        offsets.push(("the serial side", rtu));
    }
    if listed.contains(&TransportName::Tcp) {
        offsets.push(("Modbus TCP", tcp));
    }
    if offsets.is_empty() {
        offsets.push(("the serial side", rtu));
    }
    let address = |offset: i32| u16::try_from(i32::from(reference.pdu) - offset).ok();
    let first = address(offsets[0].1);
    if offsets.iter().any(|(_, o)| address(*o) != first) {
        let each: Vec<String> = offsets
            .iter()
            .map(|(link, o)| match address(*o) {
                Some(a) => format!("{a:04X}h on {link}"),
                None => format!("no address on {link}"),
            })
            .collect();
        return Some(ModiconReading::Refused(format!(
            "as a Modicon reference it is PDU address {:04X}h, which the map's addressing offsets make {}; name the register by id or by its address",
            reference.pdu,
            each.join(" and ")
        )));
    }
    Some(match first {
        Some(address) => ModiconReading::Address { reference, address },
        None => ModiconReading::Refused(format!(
            "as a Modicon reference it is PDU address {:04X}h, below the map's address offset",
            reference.pdu
        )),
    })
}

/// The register a Modicon reference names in `drive`, or why none.
fn by_reference<'a>(drive: &'a Map, name: &str) -> Option<Result<RegisterRef<'a>, String>> {
    use drivemap_runtime::core::register::Table as ModbusTable;
    let (reference, address) = match modicon_reading(drive, name)? {
        ModiconReading::Address { reference, address } => (reference, address),
        ModiconReading::Refused(why) => return Some(Err(why)),
    };
    let table = match reference.table {
        ReferenceTable::Holding => ModbusTable::Holding,
        ReferenceTable::Input => ModbusTable::Input,
        ReferenceTable::Coil => ModbusTable::Coil,
        ReferenceTable::DiscreteInput => ModbusTable::DiscreteInput,
    };
    if table.is_bits() && !drive.registers().any(|r| r.plan().info.table == table) {
        let none = if drive.registers().any(|r| r.plan().info.table.is_bits()) {
            "has none"
        } else {
            "holds registers only"
        };
        return Some(Err(format!(
            "`{}` is a Modicon reference to a {}, and this map {none}",
            name.trim(),
            table.item()
        )));
    }
    let what = table.item();
    // Where the table has none, the register of the other register table there is named (an
    // input register for a holding reference); coils and discrete inputs are their own spaces.
    let found = at_address_in(drive, address, Some(table)).or_else(|| {
        let other = match table {
            ModbusTable::Holding => ModbusTable::Input,
            ModbusTable::Input => ModbusTable::Holding,
            ModbusTable::Coil | ModbusTable::DiscreteInput => return None,
        };
        at_address_in(drive, address, Some(other))
    });
    Some(match found {
        Some(r) if r.plan().info.table == table => Ok(r),
        Some(r) => Err(format!(
            "as a Modicon reference it is {what} {}, and {} there is {} {}",
            printed_number(drive, address),
            r.id(),
            match r.plan().info.table {
                ModbusTable::Input => "an",
                _ => "a",
            },
            r.plan().info.table.item()
        )),
        None => Err(format!(
            "as a Modicon reference it is {what} {} (PDU address {:04X}h), where the map has no register",
            printed_number(drive, address),
            reference.pdu
        )),
    })
}

/// The Modicon reference of `r` on the map's serial side (`00001` for coil 0001h with no
/// offset), or its id where the offset puts it below 1.
fn modicon_of(drive: &Map, r: RegisterRef<'_>) -> String {
    let digit = match r.plan().info.table {
        drivemap_runtime::core::register::Table::Coil => 0,
        drivemap_runtime::core::register::Table::DiscreteInput => 1,
        drivemap_runtime::core::register::Table::Input => 3,
        drivemap_runtime::core::register::Table::Holding => 4,
    };
    let (rtu, _) = drive.address_offsets();
    match u32::try_from(i64::from(r.address()) + i64::from(rtu) + 1) {
        Ok(n) if (1..=9999).contains(&n) => format!("{digit}{n:04}"),
        Ok(n) if (1..=65536).contains(&n) => format!("{digit}{n:05}"),
        _ => r.id().to_owned(),
    }
}

/// An address as the map prints it: decimal in a decimal map, else `2101H`.
fn printed_number(drive: &Map, address: u16) -> String {
    match drive.address_format() {
        drivemap_map::facts::AddressFormat::Decimal => address.to_string(),
        drivemap_map::facts::AddressFormat::Hex => format!("{address:04X}H"),
    }
}

/// The register at `address` (its own address, an alternative, or the second word of a pair),
/// among those found by name.
fn at_address(drive: &Map, address: u16) -> Option<RegisterRef<'_>> {
    at_address_in(drive, address, None)
}

/// [`at_address`] in one table (`None`: any).
fn at_address_in(
    drive: &Map,
    address: u16,
    table: Option<drivemap_runtime::core::register::Table>,
) -> Option<RegisterRef<'_>> {
    let normal = || {
        drive
            .registers()
            .filter(|r| !r.broadcast_only())
            .filter(move |r| table.is_none_or(|t| r.plan().info.table == t))
    };
    normal().find(|r| r.address() == address).or_else(|| {
        normal().find(|r| {
            r.address_alternatives()
                .iter()
                .any(|a| a.address == address)
                || (r.width() != drivemap_runtime::core::width::Width::Word
                    && r.address().checked_add(1) == Some(address))
        })
    })
}

/// How the manual prints a register's address: `2101H`, or its number in a decimal manual.
fn printed_address(drive: &Map, r: RegisterRef<'_>) -> String {
    match drive.address_format() {
        drivemap_map::facts::AddressFormat::Decimal => r.address().to_string(),
        drivemap_map::facts::AddressFormat::Hex => format!("{:04X}H", r.address()),
    }
}

/// For a register read from one parameter and written to another (`read_param`, Siemens BICO:
/// read r0055.8, write P2200), why `name` cannot be used to read it (`writing` false: the name
/// is the parameter a write sets) or to write it (`writing` true: the name is the parameter a
/// read returns), naming the other; `None` for every other name and register.
pub fn wrong_side(r: RegisterRef<'_>, name: &str, writing: bool) -> Option<String> {
    let (read, write) = (r.read_param()?, r.param()?);
    let key = norm(name);
    if norm(r.id()) == key {
        return None;
    }
    let at = printed_address(r.map(), r);
    if writing && norm(read) == key {
        Some(format!(
            "{read} is what a read of {} ({at}) returns; a write there sets {write}: write `{write}=<value>` (or `{}=<value>`)",
            r.id(),
            r.id()
        ))
    } else if !writing && norm(write) == key {
        Some(format!(
            "{write} is the parameter a write of {} ({at}) sets; a read there returns {read}, not {write}: read `{read}` (or `{}`)",
            r.id(),
            r.id()
        ))
    } else {
        None
    }
}

/// Finds a register by id, parameter number, printed name (case and punctuation ignored), or
/// address in the manual's notation. Broadcast-only registers are found by id only.
pub fn find<'a>(drive: &'a Map, name: &str) -> Result<RegisterRef<'a>, NotFound> {
    if let Some(r) = drive.registers().find(|r| r.id() == name) {
        return Ok(r);
    }
    let key = norm(name);
    let normal = || drive.registers().filter(|r| !r.broadcast_only());
    let hit = normal()
        .find(|r| {
            norm_is(r.id(), &key)
                || r.param().is_some_and(|p| norm_is(p, &key))
                || r.read_param().is_some_and(|p| norm_is(p, &key))
        })
        .or_else(|| normal().find(|r| norm_is(r.name(), &key)));
    if let Some(r) = hit {
        return Ok(r);
    }
    // The Modicon reference a register records (`reference: 40024`), as the manual prints it
    // beside the register: that register, whatever the offsets would make of it.
    if let Some(m) = drivemap_map::modicon::Modicon::parse(name)
        && let Some(r) = normal().find(|r| r.modicon() == Some(m))
    {
        return Ok(r);
    }
    let decimal = drive.address_format() == drivemap_map::facts::AddressFormat::Decimal;
    if let Some(a) = address_in(name, decimal)
        && let Some(r) = at_address(drive, a)
    {
        // An address several tables hold (coil 0001h, discrete input 0001h, holding register
        // 0001h) names none of them: the user says which.
        let others: Vec<RegisterRef<'_>> = drivemap_runtime::core::register::Table::ALL
            .into_iter()
            .filter_map(|t| at_address_in(drive, a, Some(t)))
            .collect();
        if others.len() > 1 {
            let each: Vec<String> = others
                .iter()
                .map(|o| {
                    format!(
                        "{} {} ({})",
                        o.plan().info.table.item(),
                        o.id(),
                        modicon_of(drive, *o)
                    )
                })
                .collect();
            return Err(NotFound {
                name: name.to_owned(),
                drive: drive.id().to_owned(),
                suggestions: Vec::new(),
                gap: None,
                reference: Some(
                    format!(
                        "the address is that of {}: name one by id or Modicon reference",
                        each.join(", ")
                    )
                    .into_boxed_str(),
                ),
            });
        }
        return Ok(r);
    }
    // A Modicon reference (40024), where the map reads it so.
    match by_reference(drive, name) {
        Some(Ok(r)) => return Ok(r),
        Some(Err(why)) => {
            return Err(NotFound {
                name: name.to_owned(),
                drive: drive.id().to_owned(),
                suggestions: Vec::new(),
                gap: None,
                reference: Some(why.into_boxed_str()),
            });
        }
        None => {}
    }
    // An address the map records as a gap (reserved, illegible): said so, not suggested away.
    let gap = address_in(name, decimal).and_then(|a| {
        drive.gaps().iter().find_map(|g| {
            let [lo, hi] = g.addresses?;
            (lo..=hi).contains(&a).then(|| {
                // The map's text, on one line, at most 120 characters.
                let mut d: String = g
                    .description
                    .chars()
                    .map(|c| if c.is_control() { ' ' } else { c })
                    .collect();
                if let Some((i, _)) = d.char_indices().nth(120) {
                    d.truncate(i);
                    d.push_str("...");
                }
                format!("{d}; {}", g.source).into_boxed_str()
            })
        })
    });
    if gap.is_some() {
        return Err(NotFound {
            name: name.to_owned(),
            drive: drive.id().to_owned(),
            suggestions: Vec::new(),
            gap,
            reference: None,
        });
    }
    // Digits alone in a manual that prints hex: the register they would be as hex, suggested.
    let as_hex = (!decimal)
        .then(|| address_in(&format!("{}H", name.trim()), false))
        .flatten()
        .and_then(|a| at_address(drive, a))
        .map(|r| format!("{} ({})", printed_address(drive, r), r.id()));
    let mut scored: Vec<(usize, String)> = drive
        .registers()
        .map(|r| {
            let mut d = distance(&key, &norm(r.id()));
            if let Some(p) = r.param() {
                d = d.min(distance(&key, &norm(p)));
            }
            if !key.is_empty() && norm(r.id()).contains(&key) {
                d = d.min(1);
            }
            let shown = match r.param() {
                Some(p) => format!("{} ({p})", r.id()),
                None => r.id().to_owned(),
            };
            (d, shown)
        })
        .collect();
    scored.sort();
    let limit = (key.len() / 2).max(3);
    Err(NotFound {
        name: name.to_owned(),
        drive: drive.id().to_owned(),
        gap: None,
        reference: None,
        suggestions: as_hex
            .into_iter()
            .chain(
                scored
                    .into_iter()
                    .filter(|(d, _)| *d <= limit)
                    .take(5)
                    .map(|(_, s)| s),
            )
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture(path: &str) -> Map {
        let p = drivemap_test_support::paths::fixture(path);
        drivemap_map::Loader::new().load(&p).expect("fixture map")
    }

    fn id<'a>(drive: &'a Map, name: &str) -> Result<&'a str, NotFound> {
        find(drive, name).map(|r| r.id())
    }

    /// The allocation-free comparison the lookup uses is `norm(s) == norm(name)`, for every
    /// pair of texts of up to three characters from letters of both cases, a digit,
    /// punctuation and a non-ASCII letter.
    #[test]
    fn norm_is_is_comparing_the_normalized_strings() {
        let alphabet = ['a', 'B', 'b', '1', '-', ' ', 'é'];
        let mut texts = vec![String::new()];
        for len in 1..=3 {
            let shorter: Vec<String> = texts
                .iter()
                .filter(|t| t.chars().count() == len - 1)
                .cloned()
                .collect();
            for t in shorter {
                for c in alphabet {
                    texts.push(format!("{t}{c}"));
                }
            }
        }
        assert_eq!(texts.len(), 1 + 7 + 49 + 343);
        for s in &texts {
            for name in &texts {
                assert_eq!(
                    norm_is(s, &norm(name)),
                    norm(s) == norm(name),
                    "{s:?} {name:?}"
                );
            }
        }
    }

    #[test]
    fn a_register_is_found_by_the_manuals_hex_address() {
        let acme = fixture("acme-vf1/acme-vf1.yaml");
        for name in ["2101H", "2101h", "0x2101", "0X2101", " 2101H "] {
            assert_eq!(id(&acme, name), Ok("output_frequency"), "{name}");
        }
        // The second word of a 32-bit pair names the pair.
        assert_eq!(id(&acme, "2201H"), Ok("energy_counter"));
        assert_eq!(id(&acme, "0x2200"), Ok("energy_counter"));
        // Digits alone in a hex manual are not an address, but the register they would be is
        // suggested first.
        let e = id(&acme, "2101").unwrap_err().to_string();
        assert!(
            e.starts_with("acme-vf1 has no register `2101`; did you mean 2101H (output_frequency)"),
            "{e}"
        );
        // An address no register has: not found, no guess from it.
        let e = id(&acme, "0x7777").unwrap_err();
        assert_eq!((e.name.as_str(), e.drive.as_str()), ("0x7777", "acme-vf1"));
        let e = e.to_string();
        assert!(e.starts_with("acme-vf1 has no register `0x7777`"), "{e}");
    }

    #[test]
    fn a_decimal_manuals_register_is_found_by_its_number() {
        let z3 = fixture("zenith-z3/zenith-z3.yaml");
        assert_eq!(id(&z3, "45"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "P-01"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "p01"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "10"), Ok("output_frequency"));
        // The hex notations stay hex: 2DH is register 45.
        assert_eq!(id(&z3, "2DH"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "0x2D"), Ok("acceleration_time"));
        let e = id(&z3, "49").unwrap_err().to_string();
        assert!(e.starts_with("zenith-z3 has no register `49`"), "{e}");
        let e = id(&z3, "P-05").unwrap_err();
        assert!(!e.suggestions.is_empty(), "{e}");
        assert!(e.to_string().contains("did you mean"), "{e}");
    }

    #[test]
    fn modicon_references_name_registers_where_the_map_reads_them_so() {
        // A hex map with no address offset: 40258 is PDU address 0101h.
        let quill = fixture("quill-q2/quill-q2.yaml");
        for name in ["40258", "400258", " 40258 "] {
            assert_eq!(id(&quill, name), Ok("frequency_command"), "{name}");
        }
        assert_eq!(id(&quill, "40260"), Ok("status"));
        // The table is the reference's: 3xxxx is an input register, 0xxxx a coil.
        let e = id(&quill, "30258").unwrap_err().to_string();
        assert!(
            e.contains("input register 0101H")
                && e.contains("frequency_command there is a holding register"),
            "{e}"
        );
        let e = id(&quill, "00001").unwrap_err().to_string();
        assert!(
            e.contains("a coil, and this map holds registers only"),
            "{e}"
        );
        let e = id(&quill, "49999").unwrap_err().to_string();
        assert!(
            e.contains("holding register 270EH (PDU address 270Eh), where the map has no register"),
            "{e}"
        );
        // Not references: seven digits, a first digit of 2, register 0.
        assert!(modicon("4000001").is_none());
        assert!(modicon("20001").is_none());
        assert!(modicon("40000").is_none());
        assert_eq!(
            modicon("465536"),
            Some(Modicon {
                table: ReferenceTable::Holding,
                pdu: 0xFFFF
            })
        );
        assert!(modicon("465537").is_none());

        // A decimal map whose numbers stay below 10000: 40046 is register 45.
        let z3 = fixture("zenith-z3/zenith-z3.yaml");
        assert_eq!(id(&z3, "40046"), Ok("acceleration_time"));
        assert_eq!(id(&z3, "45"), Ok("acceleration_time"));

        // Offsets that differ per transport (RTU -1, TCP 0): two registers, refused.
        let acn = drivemap_map::Loader::new()
            .load(&drivemap_test_support::paths::shipped_map(
                "automationdirect-acn",
            ))
            .expect("the ACN map");
        let e = id(&acn, "44356").unwrap_err().to_string();
        assert!(
            e.contains("PDU address 1103h")
                && e.contains("1104h on the serial side and 1103h on Modbus TCP"),
            "{e}"
        );
    }

    #[test]
    fn a_decimal_map_with_five_digit_numbers_never_reads_a_modicon_reference() {
        let text = r#"
schema: 2
drive: {id: big-decimal, vendor: Nobody, models: [X], manuals: [{file: x.txt, title: X}]}
address_format: decimal
protocol:
  transports: [rtu]
  function_codes: [0x03, 0x06]
  max_read: 8
  max_write: 8
  slave_address: {min: 1, max: 31}
groups:
  - id: g
    name: G
    registers:
      - {id: low, name: Low, address: 23, source: "x.txt:1"}
      - {id: high, name: High, address: 40024, source: "x.txt:2"}
"#;
        let drive = drivemap_map::Loader::new()
            .load_str("big-decimal.yaml", text)
            .expect("the map");
        // 40024 is the map's own number, not holding register 24 (PDU 23).
        assert_eq!(id(&drive, "40024"), Ok("high"));
        let e = id(&drive, "40025").unwrap_err().to_string();
        assert!(
            e.contains("not read as a Modicon reference (it could be the map's own number)"),
            "{e}"
        );
        assert!(matches!(
            modicon_reading(&drive, "40024"),
            Some(ModiconReading::Refused(_))
        ));
    }
}
