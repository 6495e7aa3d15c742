//! The protocol part of the facts view: one row per protocol fact of a map — transports,
//! function codes, registers per read and per write, slave range, broadcast, addressing, each
//! timing figure, serial settings, EEPROM endurance, the exception list when not printed — each
//! with its key, its value in `drivemap doc`'s words, its typed figure, whether the manual
//! prints it (the `unknown:` reason and what the tools use instead) and its citation; then the
//! exception codes and the commands as lists, and the protocol's notes.
//!
//! `drivemap doc` prints the rows whose key has no [`ProtocolKey::part_of`] (a part is shown
//! inside its whole: `max_read` inside "registers per request"); `drivemap diff` compares the
//! two sides' rows key by key (`review/src/diff/protocol.rs`).

use serde::Serialize;

use drivemap_core::stated::{
    MODBUS_MAX_READ, MODBUS_MAX_READ_BITS, MODBUS_MAX_WRITE, MODBUS_MAX_WRITE_BITS, ProtocolFact,
};

use crate::describe::{self, num};
use crate::ir::Drive;
use crate::model::{self, CommandKind, Interval, Limit, Protocol};

/// What a row of the protocol facts says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ProtocolKey {
    /// The transports the drive offers: `RTU, TCP`, cited by the protocol's own line.
    Transports,
    /// The function codes the drive implements: `03h, 06h, 10h`.
    FunctionCodes,
    /// Registers per request, read and write together as `drivemap doc` prints them.
    RegistersPerRequest,
    /// Registers per read (03h/04h): the working number.
    MaxRead,
    /// Registers per write (10h): the working number.
    MaxWrite,
    /// Coils and discrete inputs per request, read and write together (a map with coils or
    /// discrete inputs).
    BitsPerRequest,
    /// Coils or discrete inputs per read (01h/02h): the working number.
    MaxReadBits,
    /// Coils per write (0Fh): the working number.
    MaxWriteBits,
    /// The slave-address range, its default and the parameter that sets it.
    SlaveAddress,
    /// What slave 0 executes without reply.
    Broadcast,
    /// The manual's addresses against PDU addresses per transport.
    Addressing,
    /// The timing as one sentence (or why the manual prints none).
    Timing,
    /// The silence between frames.
    FrameGap,
    /// The longest gap inside a frame.
    InterCharTimeout,
    /// How long the drive takes to answer.
    ResponseTime,
    /// The parameter that delays the drive's answer.
    ResponseDelay,
    /// The least time after a reply before the next request.
    RequestGap,
    /// Baud rates, parities, character format.
    Serial,
    /// Writes the non-volatile memory endures.
    Eeprom,
    /// The exception list, when the manual prints none (the codes are [`ProtocolFacts::exceptions`]).
    Exceptions,
}

impl ProtocolKey {
    /// Every key, in the order the rows are listed.
    pub const ALL: [ProtocolKey; 20] = [
        ProtocolKey::Transports,
        ProtocolKey::FunctionCodes,
        ProtocolKey::RegistersPerRequest,
        ProtocolKey::MaxRead,
        ProtocolKey::MaxWrite,
        ProtocolKey::BitsPerRequest,
        ProtocolKey::MaxReadBits,
        ProtocolKey::MaxWriteBits,
        ProtocolKey::SlaveAddress,
        ProtocolKey::Broadcast,
        ProtocolKey::Addressing,
        ProtocolKey::Timing,
        ProtocolKey::FrameGap,
        ProtocolKey::InterCharTimeout,
        ProtocolKey::ResponseTime,
        ProtocolKey::ResponseDelay,
        ProtocolKey::RequestGap,
        ProtocolKey::Serial,
        ProtocolKey::Eeprom,
        ProtocolKey::Exceptions,
    ];

    /// The row's label as `drivemap doc` writes it in the item column.
    pub const fn label(self) -> &'static str {
        match self {
            ProtocolKey::Transports => "Transports",
            ProtocolKey::FunctionCodes => "Function codes",
            ProtocolKey::RegistersPerRequest => "Registers per request",
            ProtocolKey::MaxRead => "Registers per read",
            ProtocolKey::MaxWrite => "Registers per write",
            ProtocolKey::BitsPerRequest => "Coils and discrete inputs per request",
            ProtocolKey::MaxReadBits => "Coils or discrete inputs per read",
            ProtocolKey::MaxWriteBits => "Coils per write",
            ProtocolKey::SlaveAddress => "Slave address",
            ProtocolKey::Broadcast => "Broadcast",
            ProtocolKey::Addressing => "Addressing",
            ProtocolKey::Timing => "Timing",
            ProtocolKey::FrameGap => "Frame gap",
            ProtocolKey::InterCharTimeout => "Inter-character timeout",
            ProtocolKey::ResponseTime => "Response time",
            ProtocolKey::ResponseDelay => "Response delay",
            ProtocolKey::RequestGap => "Gap before the next request",
            ProtocolKey::Serial => "Serial line",
            ProtocolKey::Eeprom => "EEPROM endurance",
            ProtocolKey::Exceptions => "Exception codes",
        }
    }

    /// The row this one is shown inside, for a part of a whole: a limit inside registers per
    /// request, a timing figure inside the timing.
    pub const fn part_of(self) -> Option<ProtocolKey> {
        match self {
            ProtocolKey::MaxRead | ProtocolKey::MaxWrite => Some(ProtocolKey::RegistersPerRequest),
            ProtocolKey::MaxReadBits | ProtocolKey::MaxWriteBits => {
                Some(ProtocolKey::BitsPerRequest)
            }
            ProtocolKey::FrameGap
            | ProtocolKey::InterCharTimeout
            | ProtocolKey::ResponseTime
            | ProtocolKey::ResponseDelay
            | ProtocolKey::RequestGap => Some(ProtocolKey::Timing),
            _ => None,
        }
    }

    /// The fact as the vocabulary crate names it when a map can mark it not printed.
    pub const fn fact(self) -> Option<ProtocolFact> {
        Some(match self {
            ProtocolKey::FunctionCodes => ProtocolFact::FunctionCodes,
            ProtocolKey::MaxRead => ProtocolFact::MaxRead,
            ProtocolKey::MaxWrite => ProtocolFact::MaxWrite,
            ProtocolKey::MaxReadBits => ProtocolFact::MaxReadBits,
            ProtocolKey::MaxWriteBits => ProtocolFact::MaxWriteBits,
            ProtocolKey::SlaveAddress => ProtocolFact::SlaveAddress,
            ProtocolKey::Broadcast => ProtocolFact::Broadcast,
            ProtocolKey::Exceptions => ProtocolFact::Exceptions,
            ProtocolKey::Serial => ProtocolFact::Serial,
            ProtocolKey::Timing => ProtocolFact::Timing,
            ProtocolKey::FrameGap => ProtocolFact::FrameGap,
            ProtocolKey::InterCharTimeout => ProtocolFact::InterCharTimeout,
            ProtocolKey::ResponseTime => ProtocolFact::ResponseTime,
            ProtocolKey::RequestGap => ProtocolFact::RequestGap,
            ProtocolKey::Transports
            | ProtocolKey::RegistersPerRequest
            | ProtocolKey::BitsPerRequest
            | ProtocolKey::ResponseDelay
            | ProtocolKey::Addressing
            | ProtocolKey::Eeprom => return None,
        })
    }
}

/// A fact the manual does not print: why, as the map's `unknown:` gives it, and what the tools
/// use in its place (none where the map gives its own working figure with the reason).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NotPrinted {
    /// Why, as the map's `unknown:` gives it.
    pub why: String,
    /// What the tools use in its place, if the map gives none of its own.
    pub fallback: Option<String>,
}

/// A row's figure, typed, for tools that compare (the diff) rather than print.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Figure {
    /// Nothing beyond the words (a parameter, a sentence).
    Words,
    /// Transports by name.
    Names(Vec<String>),
    /// Function codes.
    Codes(Vec<u8>),
    /// A number the tools use (registers per request, EEPROM writes).
    Count(u32),
    /// The slave addresses the tools use.
    Range {
        /// The lowest.
        min: u8,
        /// The highest.
        max: u8,
    },
    /// What a broadcast may carry: functions and registers (none: any writable register).
    Broadcast {
        /// The functions a broadcast may carry.
        functions: Vec<u8>,
        /// The registers it may write.
        registers: Vec<String>,
    },
    /// PDU address = manual address + offset.
    Offsets {
        /// On RTU framing.
        rtu: i32,
        /// On Modbus TCP.
        tcp: i32,
    },
}

/// One protocol fact.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProtocolRow {
    /// What the row says.
    pub key: ProtocolKey,
    /// The row's label as `drivemap doc` writes it.
    pub label: &'static str,
    /// The value in `drivemap doc`'s words (with the citation of a part inline where the row
    /// gathers parts cited apart).
    pub value: String,
    /// The row's figure, typed.
    pub figure: Figure,
    /// Set when the manual does not print the fact.
    pub not_printed: Option<NotPrinted>,
    /// The citation of the fact.
    pub citation: Option<String>,
    /// The map's entry for the fact as written, for comparison (the JSON export shows it).
    #[serde(skip)]
    pub entry: serde_json::Value,
}

/// A drive-specific exception code.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExceptionFacts {
    /// `01h`.
    pub code: String,
    /// The exception's name.
    pub name: String,
    /// What it means.
    pub description: String,
    /// Its citation.
    pub citation: String,
}

/// A command (ENTER, ACCEPT, save): its writes in order, as `drivemap doc` prints them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CommandFacts {
    /// The command's id.
    pub id: String,
    /// Its name as the map gives it.
    pub name: String,
    /// What it does.
    pub kind: CommandKind,
    /// `accept (activates, no EEPROM write)`.
    pub kind_text: &'static str,
    /// `0900h ← 0000h`, the addresses as the manual prints them.
    pub writes: Vec<String>,
    /// The same writes as `[address, value]` words.
    pub words: Vec<(u16, u16)>,
    /// Its citation.
    pub citation: String,
    /// The map's entry as written, for comparison.
    #[serde(skip)]
    pub entry: serde_json::Value,
}

/// Everything the printers say about a drive's protocol.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProtocolFacts {
    /// One row per protocol fact.
    pub rows: Vec<ProtocolRow>,
    /// The drive's own exception codes.
    pub exceptions: Vec<ExceptionFacts>,
    /// The commands (ENTER, ACCEPT, save).
    pub commands: Vec<CommandFacts>,
    /// The protocol's notes; the timing's are [`ProtocolFacts::timing_notes`].
    pub notes: Vec<String>,
    /// The timing's notes.
    pub timing_notes: Vec<String>,
    /// The protocol's own citation, and why it is indirect when it is.
    pub source: Option<String>,
    /// Why the protocol's citation is indirect, when it is.
    pub indirect: Option<String>,
    /// What the JSON export writes beside the rows' figures and entries (not part of this
    /// view's JSON).
    #[serde(skip)]
    pub data: ProtocolData,
}

/// The protocol's working figures and entries that no row carries, for the JSON export.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProtocolData {
    /// The map's exception list (or why it prints none) as written.
    pub exceptions: serde_json::Value,
    /// The silence between frames in characters: as given, else the Modbus 3.5; none
    /// without timing.
    pub frame_gap_chars: Option<f64>,
    /// The serial formats a parameter selects, decided, in the map's order of cases.
    pub serial_formats: Vec<drivemap_core::profile::SerialFormat>,
}

impl ProtocolFacts {
    /// The row with `key`.
    pub fn get(&self, key: ProtocolKey) -> Option<&ProtocolRow> {
        self.rows.iter().find(|r| r.key == key)
    }

    /// The rows `drivemap doc` prints, in its order: every row that is not part of another.
    pub fn wholes(&self) -> impl Iterator<Item = &ProtocolRow> {
        self.rows.iter().filter(|r| r.key.part_of().is_none())
    }
}

fn row(key: ProtocolKey, value: String, figure: Figure, citation: Option<&str>) -> ProtocolRow {
    ProtocolRow {
        key,
        label: key.label(),
        value,
        figure,
        not_printed: None,
        citation: citation.map(str::to_owned),
        entry: serde_json::Value::Null,
    }
}

impl ProtocolRow {
    fn unknown(mut self, why: Option<&String>, fallback: Option<&str>) -> ProtocolRow {
        self.not_printed = why.map(|w| NotPrinted {
            why: w.clone(),
            fallback: fallback.map(str::to_owned),
        });
        self
    }

    fn entry<T: Serialize>(mut self, entry: &T) -> ProtocolRow {
        self.entry = serde_json::to_value(entry).unwrap_or_default();
        self
    }
}

/// The protocol facts of `drive`.
pub(crate) fn protocol(drive: &Drive) -> ProtocolFacts {
    let p = &drive.protocol;
    // Every key of the protocol is in the view (and so in `drivemap doc` and `drivemap diff`,
    // which read it): a key added to the schema fails to compile here until it is.
    let Protocol {
        transports: _,     // transports()
        function_codes: _, // function_codes()
        max_read: _,       // per_request()
        max_write: _,      // per_request()
        max_read_bits: _,  // bits_per_request()
        max_write_bits: _, // bits_per_request()
        slave_address: _,  // slave_address()
        broadcast: _,      // broadcast()
        exceptions: _,     // the `Exceptions` row, `exceptions`
        commands: _,       // `commands`
        eeprom: _,         // the `Eeprom` row
        addressing: _,     // addressing()
        timing: _,         // timing()
        serial: _,         // serial()
        source: _,         // `source`
        notes: _,          // `notes`
        indirect: _,       // `indirect`
    } = p;
    let timing = p.timing.as_ref();
    let mut rows = vec![transports(p), function_codes(p)];
    rows.extend(per_request(p));
    rows.extend(bits_per_request(p).into_iter().flatten());
    rows.push(slave_address(&p.slave_address));
    rows.extend(p.broadcast.as_ref().map(|b| broadcast(drive, b)));
    rows.extend(p.addressing.as_ref().map(addressing));
    rows.extend(timing.into_iter().flat_map(self::timing));
    rows.extend(p.serial.as_ref().map(|s| serial(drive, s)));
    rows.extend(p.eeprom.as_ref().map(|e| {
        let text = format!("{} writes", e.endurance);
        row(
            ProtocolKey::Eeprom,
            text,
            Figure::Count(e.endurance),
            Some(&e.source),
        )
        .entry(e)
    }));
    let e = &p.exceptions;
    rows.extend(e.unknown.as_ref().map(|why| {
        let fallback = ProtocolFact::Exceptions.fallback();
        let text = describe::not_printed(why, fallback);
        row(
            ProtocolKey::Exceptions,
            text,
            Figure::Words,
            e.source.as_deref(),
        )
        .unknown(Some(why), Some(fallback))
    }));
    ProtocolFacts {
        rows,
        exceptions: p.exceptions.iter().map(exception).collect(),
        commands: p.commands.iter().map(|c| command(drive, c)).collect(),
        notes: p.notes.clone(),
        timing_notes: timing.map(|t| t.notes.clone()).unwrap_or_default(),
        source: p.source.clone(),
        indirect: p.indirect.clone(),
        data: ProtocolData {
            exceptions: serde_json::to_value(&p.exceptions).unwrap_or_default(),
            frame_gap_chars: timing.map(model::Timing::frame_gap_chars),
            serial_formats: drive.serial_format_list(),
        },
    }
}

fn transports(p: &Protocol) -> ProtocolRow {
    let names: Vec<String> = p.transports.iter().map(|t| t.to_string()).collect();
    let text = names.join(", ");
    row(
        ProtocolKey::Transports,
        text,
        Figure::Names(names),
        p.source.as_deref(),
    )
    .entry(&p.transports)
}

fn function_codes(p: &Protocol) -> ProtocolRow {
    let fc = &p.function_codes;
    let mut text = describe::functions(&fc.codes);
    if let Some(why) = &fc.unknown {
        text += &format!(". List not printed: {}", why.trim());
    }
    let figure = Figure::Codes(fc.codes.clone());
    row(
        ProtocolKey::FunctionCodes,
        text,
        figure,
        fc.source.as_deref(),
    )
    .unknown(
        fc.unknown.as_ref(),
        Some(ProtocolFact::FunctionCodes.fallback()),
    )
}

/// Registers per request as `drivemap doc` prints them, then each limit: one citation for both
/// goes in the source column, two are given beside each limit.
fn per_request(p: &Protocol) -> [ProtocolRow; 3] {
    let limits = [
        (
            ProtocolKey::MaxRead,
            "max_read",
            &p.max_read,
            MODBUS_MAX_READ,
        ),
        (
            ProtocolKey::MaxWrite,
            "max_write",
            &p.max_write,
            MODBUS_MAX_WRITE,
        ),
    ];
    let mut sources: Vec<&str> = limits
        .iter()
        .filter_map(|l| l.2.source.as_deref())
        .collect();
    sources.dedup();
    let column = match sources[..] {
        [one] => Some(one),
        _ => None,
    };
    let mut text = describe::per_request(p.max_read(), p.max_write());
    for (_, name, l, _) in &limits {
        text += &describe::limit_citation(name, l, column.is_none());
    }
    let whole = row(
        ProtocolKey::RegistersPerRequest,
        text,
        Figure::Words,
        column,
    );
    let [read, write] = limits.map(|(key, _, l, modbus)| limit(key, l, modbus));
    [whole, read, write]
}

/// Coils and discrete inputs per request, as [`per_request`] gives registers: the whole row, then
/// each limit the map states; nothing for a map that states neither (a map without coils).
fn bits_per_request(p: &Protocol) -> Option<Vec<ProtocolRow>> {
    if p.max_read_bits.is_none() && p.max_write_bits.is_none() {
        return None;
    }
    let limits: Vec<(ProtocolKey, &str, &Limit, u16)> = [
        (
            ProtocolKey::MaxReadBits,
            "max_read_bits",
            p.max_read_bits.as_ref(),
            MODBUS_MAX_READ_BITS,
        ),
        (
            ProtocolKey::MaxWriteBits,
            "max_write_bits",
            p.max_write_bits.as_ref(),
            MODBUS_MAX_WRITE_BITS,
        ),
    ]
    .into_iter()
    .filter_map(|(k, n, l, m)| Some((k, n, l?, m)))
    .collect();
    let mut sources: Vec<&str> = limits
        .iter()
        .filter_map(|l| l.2.source.as_deref())
        .collect();
    sources.dedup();
    let column = match sources[..] {
        [one] => Some(one),
        _ => None,
    };
    let mut text = describe::bits_per_request(
        p.max_read_bits.as_ref().map(|_| p.max_read_bits()),
        p.max_write_bits.as_ref().map(|_| p.max_write_bits()),
    );
    for (_, name, l, _) in &limits {
        text += &describe::limit_citation(name, l, column.is_none());
    }
    let mut rows = vec![row(
        ProtocolKey::BitsPerRequest,
        text,
        Figure::Words,
        column,
    )];
    rows.extend(
        limits
            .into_iter()
            .map(|(key, _, l, modbus)| limit(key, l, modbus)),
    );
    Some(rows)
}

fn limit(key: ProtocolKey, l: &Limit, modbus: u16) -> ProtocolRow {
    let working = l.working(modbus);
    let fallback = format!("the Modbus limit ({modbus})");
    row(
        key,
        working.to_string(),
        Figure::Count(working.into()),
        l.source.as_deref(),
    )
    .unknown(
        l.unknown.as_ref(),
        l.value.is_none().then_some(fallback.as_str()),
    )
    .entry(l)
}

fn slave_address(s: &model::SlaveAddress) -> ProtocolRow {
    let fallback = "the Modbus range 1 ..= 247";
    let (min, max) = s.range();
    let mut text = match &s.unknown {
        Some(why) => describe::not_printed(why, fallback),
        None => format!("{min} ..= {max}"),
    };
    if let Some(d) = s.default {
        text += &format!(", default {d}");
    }
    if let Some(param) = &s.param {
        text += &format!(", set by {param}");
    }
    let figure = Figure::Range { min, max };
    row(ProtocolKey::SlaveAddress, text, figure, s.source.as_deref())
        .unknown(s.unknown.as_ref(), Some(fallback))
        .entry(s)
}

fn broadcast(drive: &Drive, b: &model::Broadcast) -> ProtocolRow {
    let text = match &b.unknown {
        Some(why) => format!(
            "{}. The runtime sends no broadcast to this drive.",
            describe::broadcast_not_printed(why)
        ),
        None => {
            let mut text = format!(
                "slave 0 executes {} without reply",
                describe::functions(&b.functions)
            );
            if !b.registers.is_empty() {
                let regs: Vec<String> = (b.registers.iter())
                    .map(|name| match drive.find(name) {
                        Some(r) => format!("{name} ({})", manual_address(drive, r.def.address)),
                        None => name.clone(),
                    })
                    .collect();
                text += &format!("; registers {}", regs.join(", "));
            }
            text
        }
    };
    let figure = Figure::Broadcast {
        functions: b.functions.clone(),
        registers: b.registers.clone(),
    };
    row(ProtocolKey::Broadcast, text, figure, Some(&b.source))
        .unknown(b.unknown.as_ref(), Some(ProtocolFact::Broadcast.fallback()))
        .entry(b)
}

fn addressing(a: &model::Addressing) -> ProtocolRow {
    let text = format!(
        "PDU address = manual address {:+} on RTU, {:+} on TCP. {}",
        a.rtu_offset,
        a.tcp_offset,
        a.description.trim()
    );
    let figure = Figure::Offsets {
        rtu: a.rtu_offset,
        tcp: a.tcp_offset,
    };
    row(ProtocolKey::Addressing, text, figure, Some(&a.source)).entry(a)
}

/// The timing as one sentence, then each figure as its own row.
fn timing(t: &model::Timing) -> Vec<ProtocolRow> {
    let key = ProtocolKey::Timing;
    if let Some(why) = &t.unknown {
        let fallback = ProtocolFact::Timing.fallback();
        let text = describe::not_printed(why, fallback);
        let whole = row(key, text, Figure::Words, t.source.as_deref());
        return vec![whole.unknown(Some(why), Some(fallback)).entry(t)];
    }
    let parts: Vec<ProtocolRow> = [
        Some(frame_gap(t)),
        (t.inter_char_timeout.as_ref()).map(|i| interval(ProtocolKey::InterCharTimeout, i)),
        (t.response_time.as_ref()).map(|i| interval(ProtocolKey::ResponseTime, i)),
        (t.response_delay_param.as_ref()).map(|param| {
            let text = format!("response delay set by {param}");
            row(ProtocolKey::ResponseDelay, text, Figure::Words, None)
        }),
        t.request_gap.as_ref().map(request_gap),
    ]
    .into_iter()
    .flatten()
    .collect();
    let text = parts.iter().map(|r| r.value.as_str()).collect::<Vec<_>>();
    let whole = row(key, text.join("; "), Figure::Words, t.source.as_deref()).entry(t);
    std::iter::once(whole).chain(parts).collect()
}

/// ` (`file:line`)` after a part cited apart, or nothing.
fn inline(source: Option<&String>) -> String {
    source.map(|s| format!(" (`{s}`)")).unwrap_or_default()
}

fn frame_gap(t: &model::Timing) -> ProtocolRow {
    let key = ProtocolKey::FrameGap;
    let g = t.frame_gap.as_ref();
    let fallback = ProtocolFact::FrameGap.fallback();
    let why = g.and_then(|g| g.unknown.as_ref());
    let mut text = match why {
        Some(why) => format!("frame gap {}", describe::not_printed(why, fallback)),
        None => format!("frame gap {} characters", num(t.frame_gap_chars())),
    };
    if let Some(ms) = g.and_then(|g| g.ms) {
        let src = inline(g.and_then(|g| g.source.as_ref()));
        text += &format!(", at least {} ms{src}", num(ms));
    }
    let citation = g.and_then(|g| g.source.as_deref());
    row(key, text, Figure::Words, citation).unknown(why, Some(fallback))
}

/// An interval's parts: `10 ms / 24 bit times / 3.5 characters`.
fn interval_parts(i: &Interval) -> Vec<String> {
    let mut parts = Vec::new();
    parts.extend(i.ms.map(|ms| format!("{} ms", num(ms))));
    parts.extend(i.bits.map(|b| format!("{b} bit times")));
    parts.extend(i.chars.map(|c| format!("{} characters", num(c))));
    parts
}

fn interval(key: ProtocolKey, i: &Interval) -> ProtocolRow {
    let (name, fact) = match key {
        ProtocolKey::InterCharTimeout => {
            ("inter-character timeout", ProtocolFact::InterCharTimeout)
        }
        _ => ("response time", ProtocolFact::ResponseTime),
    };
    let fallback = fact.fallback();
    let mut text = match &i.unknown {
        Some(why) => describe::not_printed(why, fallback),
        None => interval_parts(i).join(" / "),
    };
    text += &inline(i.source.as_ref());
    row(
        key,
        format!("{name} {text}"),
        Figure::Words,
        i.source.as_deref(),
    )
    .unknown(i.unknown.as_ref(), Some(fallback))
}

/// The master's pause after a reply: its parts add up (V7/J7: 24 bits + 10 ms).
fn request_gap(g: &Interval) -> ProtocolRow {
    let key = ProtocolKey::RequestGap;
    let fallback = ProtocolFact::RequestGap.fallback();
    let text = match &g.unknown {
        Some(why) => format!(
            "gap before the next request {}",
            describe::not_printed(why, fallback)
        ),
        None => {
            let mut parts = Vec::new();
            parts.extend(g.bits.map(|b| format!("{b} bit times")));
            parts.extend(g.ms.map(|ms| format!("{} ms", num(ms))));
            parts.extend(g.chars.map(|c| format!("{} characters", num(c))));
            let src = inline(g.source.as_ref());
            format!("master waits {} after each reply{src}", parts.join(" + "))
        }
    };
    row(key, text, Figure::Words, g.source.as_deref()).unknown(g.unknown.as_ref(), Some(fallback))
}

fn serial(drive: &Drive, s: &model::Serial) -> ProtocolRow {
    let key = ProtocolKey::Serial;
    let source = (!s.source.is_empty()).then_some(s.source.as_str());
    if let Some(why) = &s.unknown {
        let fallback = ProtocolFact::Serial.fallback();
        let text = describe::not_printed(why, fallback);
        return row(key, text, Figure::Words, source)
            .unknown(Some(why), Some(fallback))
            .entry(s);
    }
    let list = |items: Vec<String>| items.join(", ");
    let mut text = format!(
        "baud {}",
        list(s.baud_rates.iter().map(u32::to_string).collect())
    );
    if let Some(d) = s.default_baud {
        text += &format!(" (default {d})");
    }
    let parities = list(s.parities.iter().map(|p| p.name().to_owned()).collect());
    text += &format!("; parity {parities}");
    if let Some(d) = s.default_parity {
        text += &format!(" (default {})", d.name());
    }
    match &s.formats {
        None => text += &format!("; {} data bits, {} stop bit(s)", s.data_bits, s.stop_bits),
        Some(f) => {
            let formats = drive.serial_format_list();
            let formats = list(
                formats
                    .iter()
                    .map(|x| format!("{} = {x}", x.code))
                    .collect(),
            );
            text += &format!(
                "; only the formats {} selects: {formats} (`{}`)",
                f.selected_by, f.source
            );
        }
    }
    if let Some(c) = s.char_bits {
        text += &format!("; always {c} bits per character");
    }
    row(key, text, Figure::Words, source).entry(s)
}

fn exception(e: &model::ExceptionCode) -> ExceptionFacts {
    ExceptionFacts {
        code: describe::function(e.code),
        name: e.name.clone(),
        description: e.description.clone(),
        citation: e.source.clone(),
    }
}

fn command(drive: &Drive, c: &model::Command) -> CommandFacts {
    CommandFacts {
        id: c.id.clone(),
        name: c.name.clone(),
        kind: c.kind,
        kind_text: match c.kind {
            CommandKind::Accept => "accept (activates, no EEPROM write)",
            CommandKind::Persist => "persist (writes EEPROM)",
        },
        writes: (c.writes.iter())
            .map(|w| format!("{} ← {:04X}h", manual_address(drive, w.address), w.value))
            .collect(),
        words: c.writes.iter().map(|w| (w.address, w.value)).collect(),
        citation: c.source.clone(),
        entry: serde_json::to_value(c).unwrap_or_default(),
    }
}

/// An address as the manual prints it: `0200h`, or `512 (0200h)` in a decimal manual.
pub(crate) fn manual_address(drive: &Drive, a: u16) -> String {
    match drive.address_format {
        model::AddressFormat::Hex => describe::address(a),
        model::AddressFormat::Decimal => format!("{a} ({})", describe::address(a)),
    }
}
