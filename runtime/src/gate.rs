//! The one gate before the wire for writes.
//!
//! Every write a client sends — typed ([`Client::write`](crate::client::Client::write)), by rule from a
//! map interpreted at run time ([`Client::write_rule`](crate::client::Client::write_rule)), by raw
//! address ([`Client::write_register`](crate::client::Client::write_register)), from the blocking or the
//! async client — is checked by [`check`] after the protocol checks of the profile (function,
//! slave range, quantity, broadcast function and addresses, command registers) and before a byte
//! is framed. A tool can call [`check`] itself to refuse early; the client calls it again anyway.
//!
//! What the map allows for one register is a [`WriteRule`]: generated as
//! [`Writable::RULE`](drivemap_core::register::Writable::RULE) for every writable register and collected in
//! [`Profile::writes`](drivemap_core::profile::Profile::writes). The gate refuses
//! - a register that is read-only ([`Refusal::ReadOnly`]);
//! - a register the map lists for other transports only ([`Refusal::NotOnTransport`]): the V7's
//!   RTU command register 0001h is the Modbus TCP option card's digital-input register;
//! - any broadcast when the drive's broadcast rules are not printed (the map's
//!   `broadcast: {unknown: ..}`) ([`Refusal::BroadcastRulesNotPrinted`]);
//! - a broadcast-only register sent to one slave, or a register the drive does not let a
//!   broadcast write sent to slave 0 (on the V7 that address is, in the broadcast space, another
//!   register with another bit layout) ([`Refusal::BroadcastOnly`], [`Refusal::NotBroadcast`]);
//! - an address the register does not occupy ([`Refusal::NotAtAddress`]), or, for a raw write,
//!   an address where no writable register of the map is ([`Refusal::NoWritableRegister`]);
//! - a word outside every range the map gives the register, or with reserved bits set
//!   ([`Refusal::RawOutOfRange`], [`Refusal::ReservedBits`]).
//!
//! - a write to one table by another table's rule or function (a coil's rule sent as a
//!   register write, a raw coil write where the map has no coil): coils and registers are two
//!   address spaces ([`Refusal::WrongTable`], [`Refusal::NoWritableCoil`]);
//!
//! - a function the register does not accept, where the map restricts its functions
//!   (`function_codes`: [`Refusal::FunctionNotAccepted`], checked by `check_function` on
//!   every address a request covers).
//!
//! Function codes per register: a single word goes out with 06h unless its register refuses
//! 06h and accepts 10h (`single_write_function`). A multi-register write (10h) that covers a
//! register refusing 10h is **refused, not split**: split requests are no longer one write (the
//! drive would hold part of the new values between them, and a failure part-way leaves a
//! half-written block), so the caller decides, writing each register on its own
//! (`write_register` picks the function each one accepts).
//!
//! The raw range of a rule is the envelope of the register's ranges over every model variant
//! and every case of a selected scale. The exact range for the settings in force is checked when
//! a value is encoded ([`Writable::encode`](drivemap_core::register::Writable::encode), or the run-time codec), so
//! a value is checked twice and the gate alone never lets through a word the map allows for no
//! setting at all.

use crate::error::Refusal;
use crate::rtu;
use drivemap_core::profile::{Profile, TransportKind};
use drivemap_core::register::Table;
use drivemap_core::rule::{Broadcast, WriteRule};
use drivemap_core::width::Width;

/// What a write is addressed to.
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub enum WriteTarget<'a> {
    /// A register whose rule the caller has: the typed API and map interpreters.
    Rule(&'a WriteRule),
    /// Raw addresses: each must be a writable register of [`Profile::writes`] that allows its
    /// word. A profile with no write table (such as [`Profile::GENERIC`]) checks only the
    /// protocol.
    Addresses,
}

/// Checks a write of `words` starting at communication address `address` to `slave` over
/// `kind` against the map. Nothing is sent; see the module documentation for what is refused.
/// A 32-bit pair is checked as one value, and only whole: a write that covers one of its words
/// without the other is refused ([`Refusal::SplitPair`]).
///
/// The table is the rule's for [`WriteTarget::Rule`] (a coil's rule: `words` are its raw
/// values, 1 on and 0 off), holding registers for [`WriteTarget::Addresses`]; a raw coil write
/// is checked by [`check_coils`].
pub fn check(
    profile: &Profile,
    kind: TransportKind,
    slave: u8,
    target: WriteTarget<'_>,
    address: u16,
    words: impl IntoIterator<Item = u16>,
) -> Result<(), Refusal> {
    let table = match target {
        WriteTarget::Rule(rule) => rule.table,
        WriteTarget::Addresses => Table::Holding,
    };
    check_in(profile, kind, slave, target, table, address, words)
}

/// [`check`] for a write of coils (05h, 0Fh) from communication address `address`: a rule's
/// register must be a coil, and a raw write must find a writable coil of the map at each
/// address ([`Refusal::NoWritableCoil`]).
pub fn check_coils(
    profile: &Profile,
    kind: TransportKind,
    slave: u8,
    target: WriteTarget<'_>,
    address: u16,
    states: impl IntoIterator<Item = bool>,
) -> Result<(), Refusal> {
    let words = states.into_iter().map(u16::from);
    check_in(profile, kind, slave, target, Table::Coil, address, words)
}

/// The write of `words` into `table`.
pub(crate) fn check_in(
    profile: &Profile,
    kind: TransportKind,
    slave: u8,
    target: WriteTarget<'_>,
    table: Table,
    address: u16,
    words: impl IntoIterator<Item = u16>,
) -> Result<(), Refusal> {
    broadcast_known(profile, slave)?;
    let mut words = words.into_iter().peekable();
    let mut at = address;
    while let Some(word) = words.next() {
        let used = match target {
            WriteTarget::Rule(rule) => {
                if rule.table != table {
                    return Err(Refusal::WrongTable {
                        register: rule.register,
                        table: rule.table,
                        requested: table,
                    });
                }
                check_rule(profile, kind, slave, rule, at, word, words.peek())?
            }
            WriteTarget::Addresses if profile.writes.is_empty() => 1,
            WriteTarget::Addresses => {
                check_address(profile, kind, slave, table, at, word, words.peek())?
            }
        };
        if used == 2 {
            words.next();
        }
        at = at.wrapping_add(used);
    }
    Ok(())
}

/// Whether a broadcast to this drive writes only the registers it lists.
fn listed_broadcast(profile: &Profile) -> bool {
    profile.broadcast.is_some_and(|b| !b.addresses.is_empty())
}

/// Refuses a broadcast (slave 0) to a drive whose broadcast rules the manual does not print:
/// the map cannot say which functions and registers the drives would execute.
pub(crate) fn broadcast_known(profile: &Profile, slave: u8) -> Result<(), Refusal> {
    match profile.broadcast {
        Some(b) if slave == rtu::BROADCAST => match b.not_printed {
            Some(why) => Err(Refusal::BroadcastRulesNotPrinted {
                drive: profile.drive_id,
                why,
            }),
            None => Ok(()),
        },
        _ => Ok(()),
    }
}

/// Whether `rule`'s register may be addressed as `slave`.
fn space(profile: &Profile, slave: u8, rule: &WriteRule) -> Result<(), Refusal> {
    let register = rule.register;
    match (slave == rtu::BROADCAST, rule.broadcast) {
        (false, Broadcast::Only) => Err(Refusal::BroadcastOnly { register }),
        (true, Broadcast::No) if listed_broadcast(profile) => Err(Refusal::NotBroadcast {
            drive: profile.drive_id,
            register,
        }),
        _ => Ok(()),
    }
}

/// Checks the write at `address` against the writable registers there; the number of words
/// the register that accepts it takes (2 for a pair, whose second word is `next`).
fn check_address(
    profile: &Profile,
    kind: TransportKind,
    slave: u8,
    table: Table,
    address: u16,
    word: u16,
    next: Option<&u16>,
) -> Result<u16, Refusal> {
    let mut first_refusal = None;
    for rule in profile.writes.iter().filter(|r| {
        r.table == table
            && r.word_index(address).is_some()
            && r.transports.contains(kind)
            && space(profile, slave, r).is_ok()
    }) {
        match check_rule(profile, kind, slave, rule, address, word, next) {
            Ok(used) => return Ok(used),
            Err(e) => {
                first_refusal.get_or_insert(e);
            }
        }
    }
    Err(first_refusal.unwrap_or(if table == Table::Coil {
        Refusal::NoWritableCoil {
            drive: profile.drive_id,
            address,
            transport: kind,
            broadcast: slave == rtu::BROADCAST,
        }
    } else {
        Refusal::NoWritableRegister {
            drive: profile.drive_id,
            address,
            transport: kind,
            broadcast: slave == rtu::BROADCAST,
        }
    }))
}

/// The write rule of the map's register `register`, or why it cannot be written at all (it is
/// not in the write table: read-only).
pub fn rule<'p>(profile: &'p Profile, register: &'static str) -> Result<&'p WriteRule, Refusal> {
    profile
        .write_rule(register)
        .ok_or(Refusal::ReadOnly { register })
}

/// The part of the gate that does not depend on the address or the word: access, transport,
/// broadcast space. A tool calls it before connecting to refuse early; [`check`] repeats it.
pub fn check_link(
    profile: &Profile,
    kind: TransportKind,
    slave: u8,
    rule: &WriteRule,
) -> Result<(), Refusal> {
    let register = rule.register;
    if !rule.access.writable() {
        return Err(Refusal::ReadOnly { register });
    }
    broadcast_known(profile, slave)?;
    if !rule.transports.contains(kind) {
        return Err(Refusal::NotOnTransport {
            register,
            transport: kind,
        });
    }
    space(profile, slave, rule)
}

/// Checks the write of `word` (and, for a pair, `next`) at `address` against `rule`; the number
/// of words the register takes.
fn check_rule(
    profile: &Profile,
    kind: TransportKind,
    slave: u8,
    rule: &WriteRule,
    address: u16,
    word: u16,
    next: Option<&u16>,
) -> Result<u16, Refusal> {
    check_link(profile, kind, slave, rule)?;
    let register = rule.register;
    let raw = match (rule.width, rule.word_index(address), next) {
        (_, None, _) => return Err(Refusal::NotAtAddress { register, address }),
        (Width::Word, _, _) => u32::from(word),
        (Width::Pair(_), Some(0), Some(&second)) => rule.width.join(&[word, second]),
        (Width::Pair(_), _, _) => return Err(Refusal::SplitPair { register, address }),
        (Width::Text(_), _, _) => return Err(Refusal::Text { register }),
    };
    let reserved = (raw as u16) & rule.reserved;
    if reserved != 0 {
        return Err(Refusal::ReservedBits {
            register,
            bits: reserved,
        });
    }
    let raw = rule.width.to_int(raw, rule.raw.min < 0);
    if !rule.raw.contains(raw) {
        return Err(Refusal::RawOutOfRange {
            register,
            raw,
            min: rule.raw.min,
            max: rule.raw.max,
        });
    }
    Ok(rule.width.count())
}

/// The rules of registers that cover `address` for this target on `kind`, in the table
/// `function` writes (holding registers for a function that writes none).
fn covering<'p>(
    profile: &'p Profile,
    kind: TransportKind,
    target: WriteTarget<'p>,
    address: u16,
    function: u8,
) -> impl Iterator<Item = &'p WriteRule> {
    let rules: &'p [WriteRule] = match target {
        WriteTarget::Rule(rule) => core::slice::from_ref(rule),
        WriteTarget::Addresses => profile.writes,
    };
    let table = Table::of_function(function).unwrap_or(Table::Holding);
    rules.iter().filter(move |r| {
        r.table == table && r.word_index(address).is_some() && r.transports.contains(kind)
    })
}

/// Whether the register at `address` accepts `function`: true where no rule covers it or one
/// that covers it accepts the function (a register that moves may have several). A coil
/// function looks at coils, a register function at registers.
pub fn accepts(
    profile: &Profile,
    kind: TransportKind,
    target: WriteTarget<'_>,
    address: u16,
    function: u8,
) -> bool {
    let mut rules = covering(profile, kind, target, address, function).peekable();
    rules.peek().is_none() || rules.any(|r| r.functions.allows(function))
}

/// The function one word written at `address` goes out with: 06h, unless the drive lacks it or
/// the register there refuses it while accepting 10h (one drive takes 10h only on its first
/// registers, another writes some registers with 10h only).
pub(crate) fn single_write_function(
    profile: &Profile,
    kind: TransportKind,
    target: WriteTarget<'_>,
    address: u16,
) -> u8 {
    use crate::pdu::function::{WRITE_MULTIPLE, WRITE_SINGLE};
    let usable = |f| profile.supports(f) && accepts(profile, kind, target, address, f);
    if usable(WRITE_SINGLE) || !usable(WRITE_MULTIPLE) {
        WRITE_SINGLE
    } else {
        WRITE_MULTIPLE
    }
}

/// The function one coil written at `address` goes out with: 05h, unless the drive lacks it
/// or the coil refuses it while accepting 0Fh.
pub(crate) fn single_coil_function(
    profile: &Profile,
    kind: TransportKind,
    target: WriteTarget<'_>,
    address: u16,
) -> u8 {
    use crate::pdu::function::{WRITE_COIL, WRITE_COILS};
    let usable = |f| profile.supports(f) && accepts(profile, kind, target, address, f);
    if usable(WRITE_COIL) || !usable(WRITE_COILS) {
        WRITE_COIL
    } else {
        WRITE_COILS
    }
}

/// Refuses a write with `function` over `quantity` registers from `address` when a register
/// it covers does not accept that function ([`Refusal::FunctionNotAccepted`]). Nothing is
/// split: see the module documentation.
pub(crate) fn check_function(
    profile: &Profile,
    kind: TransportKind,
    target: WriteTarget<'_>,
    function: u8,
    address: u16,
    quantity: usize,
) -> Result<(), Refusal> {
    for i in 0..quantity {
        let Some(at) = u16::try_from(usize::from(address) + i).ok() else {
            break;
        };
        if accepts(profile, kind, target, at, function) {
            continue;
        }
        if let Some(rule) = covering(profile, kind, target, at, function).next() {
            return Err(Refusal::FunctionNotAccepted {
                register: rule.register,
                address: at,
                function,
                accepted: rule.functions.codes,
                citation: rule.functions.source,
            });
        }
    }
    Ok(())
}
