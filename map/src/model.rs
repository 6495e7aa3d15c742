//! The map schema as written in YAML: serde types, one per construct, nothing derived.
//!
//! Every struct rejects unknown keys, so a misspelt key is an error with its location rather than
//! a silently ignored line. `maps/README.md` documents each construct with an example; this file
//! is its precise definition. Semantic checks live in `validate`; the checked form the
//! generator consumes is [`crate::ir`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One map file: a drive, or a variant of another drive (`drive.extends`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MapFile {
    /// The schema version the file is written in (`schema: 2`); a file without it is read as
    /// schema 1. Each file of a variant map is read in its own version (`schema`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<u32>,
    /// How the manual numbers its registers: `hex` (the default: addresses are written `0x2001`
    /// or `2001H`, and a bare decimal is refused) or `decimal` (bare decimals are addresses as
    /// written). Decided per file while reading, see [`crate::hex`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub address_format: Option<AddressFormat>,
    /// A draft not yet reviewed against its manual (`drivemap import` writes one): it loads and
    /// checks, with a warning listing what to confirm, and the generator refuses it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub draft: Option<Draft>,
    pub drive: DriveMeta,
    /// Model variants selectable at run time, by axis (voltage class, firmware).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub variants: Vec<VariantAxis>,
    pub protocol: Protocol,
    /// Registers, grouped as the manual groups them.
    #[serde(default)]
    pub groups: Vec<Group>,
    /// Contradictions that concern the whole map or several registers.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub conflicts: Vec<Conflict>,
    /// Address ranges or parameters the manual does not make legible.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gaps: Vec<Gap>,
    /// In a variant map: registers of the base map this drive does not have.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub removed: Vec<Removed>,
    /// Which registers and fields play the standard parts of a drive (run, direction, reference,
    /// monitors, status), by role id (`drivemap_core::roles::Role::id`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub roles: BTreeMap<String, Vec<RolePlace>>,
    /// The drive's command profile: a control-word state machine that run, stop and fault reset
    /// walk ([`crate::command_profile`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<crate::command_profile::ProfileSpec>,
    /// Example frames the manual prints, with what they say ([`crate::examples`]). A variant
    /// map's list replaces its base's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub examples: Vec<crate::examples::Example>,
}

/// The mark of a draft map: who made it and what the reviewer must confirm before removing it.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Draft {
    /// What made the draft (`drivemap import`).
    pub by: String,
    /// Items written as placeholders or read with doubt, one sentence each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub to_confirm: Vec<String>,
}

/// One place a role lives: a register, a field of one, or an external quantity.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RolePlace {
    /// Register id (or parameter number).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub register: Option<String>,
    /// Field id of `register`, for command and status roles.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field: Option<String>,
    /// An external quantity of the map (`max_frequency` only), instead of a register.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external: Option<String>,
    /// The field's code(s) meaning the role holds (default 1 for a 1-bit field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on: Option<Codes>,
    /// The code releasing a command (stop, forward) or shown when a status does not hold
    /// (default 0 for a 1-bit field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub off: Option<CodeRef>,
    /// How the drive acts on a command: `true` on the off → on transition only, `false` (the
    /// default) on the level, `{unknown: reason}` where the manual does not print which.
    #[serde(default, skip_serializing_if = "EdgeSpec::is_level")]
    pub edge: EdgeSpec,
    /// A number role on a `field`: the field is two's complement (default: unsigned).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub signed: bool,
    /// A number role on a `field`: one count of the field in the role's unit (`0.1` for
    /// 0.1 A per count; default 1). Required for a role with a unit (Hz, A, V, s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Another role (by id) whose place is the same register or bits, as the manual says: one
    /// ramp register for both directions (`shared_with: decel_time` on `accel_time`). Without
    /// it two setpoint or command roles on the same register bits are refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shared_with: Option<String>,
    /// The links on which this place holds (default: every transport of the map). A source
    /// role's network code differs by link: V7 n003 = 2 (built-in RTU), 3 (TCP option card).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transports: Option<Vec<TransportName>>,
    /// A source role the manual does not print (no parameter, or no address for it): why. The
    /// place names no register then; the drive trait cannot check the source on such a drive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// The manual line that says this register or field plays the role.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
    /// Notes on the role place.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// How a drive acts on a command field: `true` (edge), `false` (level), or `{unknown: reason}`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum EdgeSpec {
    /// Printed: `true` on the off → on transition, `false` on the level.
    Known(bool),
    /// Not printed: why.
    Unknown(EdgeUnknown),
}

/// `edge: {unknown: reason}`: the manual does not print whether the drive acts on the edge or
/// the level.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EdgeUnknown {
    /// Why the map cannot say (what the manual prints and does not).
    pub unknown: String,
}

impl Default for EdgeSpec {
    fn default() -> Self {
        EdgeSpec::Known(false)
    }
}

impl EdgeSpec {
    /// `edge: false` or left out.
    pub fn is_level(&self) -> bool {
        *self == EdgeSpec::Known(false)
    }

    /// The reason, where the manual does not print it.
    pub fn unknown(&self) -> Option<&str> {
        match self {
            EdgeSpec::Unknown(u) => Some(&u.unknown),
            EdgeSpec::Known(_) => None,
        }
    }
}

/// A code of a field: its number, or its `id` among the field's `values`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum CodeRef {
    /// The code as a number.
    Number(u16),
    /// The `id` of one of the field's `values`.
    Id(String),
}

/// One code or a list of codes.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum Codes {
    /// One code.
    One(CodeRef),
    /// A list of codes.
    Many(Vec<CodeRef>),
}

impl Codes {
    /// The codes, in order.
    pub fn list(&self) -> Vec<&CodeRef> {
        match self {
            Codes::One(c) => vec![c],
            Codes::Many(v) => v.iter().collect(),
        }
    }
}

/// How a manual numbers its registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AddressFormat {
    /// Hexadecimal, as most drive manuals print communication addresses ("2001H").
    Hex,
    /// Decimal register numbers.
    Decimal,
}

/// Who the drive is and where the map comes from.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DriveMeta {
    /// Lower-case, dash-separated identifier (`ptlk-tds-v8`); the generated module is the same
    /// with underscores.
    pub id: String,
    /// Identifier of the base map this one inherits from and overrides (`yaskawa-v7`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extends: Option<String>,
    /// The vendor as the manuals print it.
    pub vendor: String,
    /// The models the map covers.
    pub models: Vec<String>,
    /// The manuals the map was transcribed from. Every citation must name one of them.
    pub manuals: Vec<Manual>,
    /// One paragraph on the drive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
}

/// A manual the map was transcribed from: an OCR text file in the manuals directory, cited by
/// line (`file:line`), or a document with no text at hand, cited by page (`<id>:p<page>`).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Manual {
    /// File name under the manuals directory (`002_661580cce154f322.txt`): a text manual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Name page citations use (`acme-um` in `acme-um:p42`): a manual with no text at hand.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<String>,
    /// The manual's title.
    pub title: String,
    /// The vendor's document number and revision as printed (`UM-1234 rev C`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub document: Option<String>,
    /// Where the document is published.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub url: Option<String>,
}

impl Manual {
    /// The text file of a manual cited by line; `None` for a manual cited by page.
    pub fn text_file(&self) -> Option<&str> {
        self.file.as_deref()
    }

    /// The name citations give it: its file, or its id.
    pub fn name(&self) -> &str {
        self.file.as_deref().or(self.id.as_deref()).unwrap_or("")
    }

    /// One line naming it for a reader: "`file` — title", or "title (document, url)".
    pub fn describe(&self) -> String {
        match &self.file {
            Some(f) => format!("`{f}` — {}", self.title),
            None => {
                let more: Vec<&str> = [self.document.as_deref(), self.url.as_deref()]
                    .into_iter()
                    .flatten()
                    .collect();
                let id = self.id.as_deref().unwrap_or("");
                if more.is_empty() {
                    format!("`{id}` — {}", self.title)
                } else {
                    format!(
                        "`{id}` — {} ({}; cited by page)",
                        self.title,
                        more.join(", ")
                    )
                }
            }
        }
    }
}

impl DriveMeta {
    /// The text files of the manuals cited by line (the ones `--require-manuals` expects).
    pub fn text_manuals(&self) -> impl Iterator<Item = &str> {
        self.manuals.iter().filter_map(Manual::text_file)
    }
}

/// One axis of model variants, e.g. voltage class.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VariantAxis {
    /// The axis id (`voltage_class`).
    pub id: String,
    /// Its name.
    pub name: String,
    /// The first option is the base variant: top-level limits and defaults describe it.
    pub options: Vec<VariantOption>,
}

/// One option of a variant axis.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VariantOption {
    /// The option id.
    pub id: String,
    /// Its name.
    pub name: String,
    /// Where the manual names it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// How the drive speaks Modbus.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Protocol {
    /// Transports the drive (or its option card) offers natively.
    pub transports: Vec<TransportName>,
    /// The function codes the drive implements: a plain list, or with its citation, or marked
    /// not printed (see `FunctionCodes`).
    pub function_codes: FunctionCodes,
    /// Maximum registers per read (03h/04h).
    pub max_read: Limit,
    /// Maximum registers per write (10h).
    pub max_write: Limit,
    /// Maximum coils or discrete inputs per read (01h/02h): stated (cited or `unknown`) by a
    /// map with coils or discrete inputs; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_read_bits: Option<Limit>,
    /// Maximum coils per write (0Fh): stated by a map with writable coils; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_write_bits: Option<Limit>,
    /// The slave addresses the drive answers to.
    pub slave_address: SlaveAddress,
    /// Broadcast writes (slave 0), when the drive takes them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub broadcast: Option<Broadcast>,
    /// The drive's exception codes: the list, or `{unknown: "<why>", source: ..}` when the
    /// manual prints none (see `Exceptions`).
    #[serde(default)]
    pub exceptions: Exceptions,
    /// ENTER / ACCEPT / save commands.
    #[serde(default)]
    pub commands: Vec<Command>,
    /// How the drive stores written values, and its write endurance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eeprom: Option<Eeprom>,
    /// Transport-dependent mapping from the manual's addresses to PDU addresses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub addressing: Option<Addressing>,
    /// Response times and gaps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
    /// The serial line's settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub serial: Option<Serial>,
    /// The protocol section's citation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
    /// Notes on the protocol.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// A transport a drive offers: Modbus RTU, ASCII or TCP.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TransportName {
    /// Modbus RTU on a serial line (also carried over TCP by a gateway).
    Rtu,
    /// Modbus TCP.
    Tcp,
    /// Modbus ASCII on the serial line (`:` ... LRC CR LF). In `protocol.transports` it says
    /// the drive's serial line speaks ASCII (and RTU too where `rtu` is listed); in a
    /// register's, role place's or condition's list it names the drive's serial side, as `rtu`
    /// does.
    Ascii,
}

impl TransportName {
    /// Whether this names the drive's serial side (`rtu` or `ascii`).
    pub fn is_serial(self) -> bool {
        matches!(self, TransportName::Rtu | TransportName::Ascii)
    }

    /// The word a map writes it as: `rtu`, `tcp`, `ascii`.
    pub fn word(self) -> &'static str {
        match self {
            TransportName::Rtu => "rtu",
            TransportName::Tcp => "tcp",
            TransportName::Ascii => "ascii",
        }
    }
}

impl std::fmt::Display for TransportName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TransportName::Rtu => "RTU",
            TransportName::Tcp => "TCP",
            TransportName::Ascii => "ASCII",
        })
    }
}

/// `protocol.slave_address`: the range of slave addresses the drive accepts, its factory
/// default and the parameter that sets it, as the manual prints them.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SlaveAddress {
    /// Lowest address; not given when the range is `unknown`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<u8>,
    /// Highest address; not given when the range is `unknown`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<u8>,
    /// The manual prints no range: why (`slave_address: {unknown: "<why>"}`). The tools use
    /// the Modbus unicast range 1-247 then, and say so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// The factory setting, where the manual prints one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<u8>,
    /// Parameter that sets it (`Sn-36`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param: Option<String>,
    /// Where the manual says it (`file:line`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// `protocol.broadcast`: what the drive executes when a request is addressed to slave 0.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Broadcast {
    /// Function codes executed when addressed to slave 0 (never answered). Required unless the
    /// rules are `unknown`.
    #[serde(default)]
    pub functions: Vec<u8>,
    /// Register ids a broadcast may write. Registers of a `broadcast: true` group are implied.
    #[serde(default)]
    pub registers: Vec<String>,
    /// The manual says the drive has a broadcast but does not print its rules (which
    /// functions, which registers): why, as `broadcast: {unknown: "<why>", source: ...}`. Then
    /// `functions` and `registers` are not given, and the runtime sends no broadcast at all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// Where the manual says it (`file:line`).
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// One exception code of `protocol.exceptions`, as the manual prints it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExceptionCode {
    /// The code in the exception reply's data byte.
    pub code: u8,
    /// Its name as the manual prints it (`Illegal data address`).
    pub name: String,
    /// What the manual says it means, if more than the name.
    #[serde(default)]
    pub description: String,
    /// Where the manual says it (`file:line`).
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// `accept` (activates written data without storing it) or `persist` (stores it in
/// non-volatile memory; wears the EEPROM): the vocabulary crate's.
pub(crate) use drivemap_core::profile::CommandKind;

/// One of `protocol.commands`: a command the drive executes on a write (the V7's ENTER, which
/// stores written parameters), with the writes that give it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Command {
    /// Its id in the map (`enter`).
    pub id: String,
    /// Its name as the manual prints it.
    pub name: String,
    /// `accept` or `persist` (stores into non-volatile memory).
    pub kind: CommandKind,
    /// Writes in order.
    pub writes: Vec<CommandWrite>,
    /// Where the manual says it (`file:line`).
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// One write of a [`Command`]: a word to a register.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CommandWrite {
    /// The register's address as the manual numbers it.
    pub address: u16,
    /// The word written.
    pub value: u16,
}

/// `protocol.eeprom`: the non-volatile memory's endurance, as the manual prints it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Eeprom {
    /// Writes the manual says the memory endures.
    pub endurance: u32,
    /// Where the manual says it (`file:line`).
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// `protocol.addressing`: how the manual's register numbers become the addresses in requests,
/// per transport.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Addressing {
    /// PDU address = manual address + `rtu_offset` on RTU (and RTU over TCP).
    #[serde(default)]
    pub rtu_offset: i32,
    /// PDU address = manual address + `tcp_offset` on Modbus TCP.
    #[serde(default)]
    pub tcp_offset: i32,
    /// The manual's own words on it (`RTU PLC address 40000+hex`).
    pub description: String,
    /// Where the manual says it (`file:line`).
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// `protocol.timing`: the silences and delays of the serial line, as the manual prints them.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Timing {
    /// The manual prints no timing at all: why (`timing: {unknown: "<why>"}`). No other figure
    /// is given then; the runtime keeps the Modbus RTU rule (3.5 characters between frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// Silence between frames in character times; 3.5 (the Modbus RTU rule) when not given
    /// ([`Timing::frame_gap_chars`]). Not given when `frame_gap` is `unknown`.
    #[serde(
        default,
        rename = "frame_gap_chars",
        skip_serializing_if = "Option::is_none"
    )]
    pub frame_gap_chars_given: Option<f64>,
    /// Silence between frames in milliseconds, when the manual states it so ("at least 10 ms"):
    /// `frame_gap: {ms: 10, source: ...}`. Only `ms` is taken (a gap in characters is
    /// `frame_gap_chars`); the runtime keeps the larger of the two at the line's baud rate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_gap: Option<Interval>,
    /// Longest gap between two characters of a frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inter_char_timeout: Option<Interval>,
    /// How long the drive takes to answer, if the manual says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub response_time: Option<Interval>,
    /// Parameter that adds a configurable delay before the drive answers (V7 n156).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub response_delay_param: Option<String>,
    /// Least time the master must leave after a reply before its next request (V7/J7:
    /// 24 bits + 10 ms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub request_gap: Option<Interval>,
    /// Where the manual says it (`file:line`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
    /// What the transcriber notes about the timing.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl Timing {
    /// Silence between frames in character times: as given, else 3.5 (the Modbus RTU rule).
    pub fn frame_gap_chars(&self) -> f64 {
        self.frame_gap_chars_given.unwrap_or(3.5)
    }

    /// The timing figures given as intervals, with their keys, in the schema's order:
    /// `frame_gap`, `inter_char_timeout`, `response_time`, `request_gap`.
    pub fn figures(&self) -> [(&'static str, Option<&Interval>); 4] {
        [
            ("frame_gap", self.frame_gap.as_ref()),
            ("inter_char_timeout", self.inter_char_timeout.as_ref()),
            ("response_time", self.response_time.as_ref()),
            ("request_gap", self.request_gap.as_ref()),
        ]
    }
}

/// A duration: milliseconds, bit times, character times, or a sum of them (`{bits: 24, ms: 10}`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Interval {
    /// Milliseconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ms: Option<f64>,
    /// Bit times at the line's baud rate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bits: Option<u32>,
    /// Character times at the line's baud rate and format.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chars: Option<f64>,
    /// The manual prints no such interval: why (`response_time: {unknown: "<why>"}`); no
    /// `ms`, `bits` or `chars` then.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// Where the manual says it (`file:line`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// `protocol.serial`: the serial line's settings the drive offers, as the manual prints them.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Serial {
    /// The manual prints no serial settings: why (`serial: {unknown: "<why>"}`). No baud
    /// rates, parities or formats are given then; `source` only where the manual says so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unknown: Option<String>,
    /// The baud rates the drive offers.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub baud_rates: Vec<u32>,
    /// The factory setting among them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default_baud: Option<u32>,
    /// The parities the drive offers.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parities: Vec<Parity>,
    /// The factory setting among them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default_parity: Option<Parity>,
    /// Data bits per character (8 when not given).
    #[serde(default = "default_data_bits")]
    pub data_bits: u8,
    /// Stop bits per character (1 when not given).
    #[serde(default = "default_stop_bits")]
    pub stop_bits: u8,
    /// Bits per character on the wire when the manual fixes it regardless of parity (TDS-V8:
    /// always 11 — without parity the parity slot is sent as a second stop bit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub char_bits: Option<u8>,
    /// The only character formats the line offers, chosen on the drive by a parameter (ACN
    /// CM.04: 8N1, 8N2, 8E1, 8O1). With them, `stop_bits` is not given (each format has its
    /// own), `parities` lists exactly the formats' parities, and `char_bits`, if given, is the
    /// length of every format.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formats: Option<SerialFormats>,
    /// Required, except with `unknown` (then only where the manual says it prints none).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// `serial.formats`: the formats a parameter selects.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SerialFormats {
    /// The parameter (register id or parameter number) whose code selects the format.
    pub selected_by: String,
    /// Each format with the code that selects it.
    pub cases: Vec<SerialFormatCase>,
    /// Where the manual says it (`file:line`).
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// One format: the selecting parameter's code and the character it gives.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SerialFormatCase {
    /// The code of `selected_by` that selects this format.
    pub when: u16,
    /// Data bits; the line's `data_bits` when not given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data_bits: Option<u8>,
    /// The format's parity.
    pub parity: Parity,
    /// The format's stop bits.
    pub stop_bits: u8,
    /// Where the manual says it (`file:line`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

fn default_data_bits() -> u8 {
    8
}

fn default_stop_bits() -> u8 {
    1
}

/// Parity of a serial line: the vocabulary crate's, read as `none`, `even`, `odd`.
pub use drivemap_core::profile::Parity;

/// Registers as the manual groups them (command, monitor, one parameter group...).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Group {
    pub id: String,
    pub name: String,
    /// The manual's table name ("Table 4.3 Monitor Registers").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// Default access of the group's registers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub access: Option<Access>,
    /// Default Modbus table of the group's registers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modbus_table: Option<ModbusTable>,
    /// Default write restriction of the group's registers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub write_restriction: Option<WriteRestriction>,
    /// Registers of this group exist only on these transports (V7 Modbus TCP option card).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transports: Option<Vec<TransportName>>,
    /// Broadcast registers: written to slave 0 only, in their own layout and address space.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub broadcast: bool,
    /// Default of the group's registers: the drive executes a written value only when it
    /// differs from the previous write.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeat_needs_change: Option<RepeatNeedsChange>,
    /// Default of the group's registers: the Modbus functions they accept, where the manual
    /// restricts them below `protocol.function_codes`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub function_codes: Option<RegisterFunctions>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    pub registers: Vec<Register>,
}

/// The Modbus functions a register (or every register of a group) accepts, where the manual
/// restricts them below the drive's `protocol.function_codes` ("function 10h is accepted on
/// registers 0001h-0004h only"): `{codes: [0x03, 0x06], source: "file:line"}`, with
/// `refused_with: 0x02` when the drive answers another function with illegal data address
/// instead of illegal function (01h, the default).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RegisterFunctions {
    /// The function codes accepted: a subset of `protocol.function_codes` among 03h, 04h, 06h
    /// and 10h.
    pub codes: Vec<u8>,
    /// The exception code the drive answers another function with (01h or 02h; absent: 01h).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refused_with: Option<u8>,
    /// `file:line` of the manual's statement.
    pub source: String,
}

impl RegisterFunctions {
    /// The exception code another function is answered with.
    pub fn refusal(&self) -> u8 {
        self.refused_with.unwrap_or(0x01)
    }
}

/// The drive executes a written value only when it differs from the previous write ("if you
/// want to enter 244 twice, enter it in the following order: 244 > 0 > 244"): writers write
/// `between` first, then the value.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RepeatNeedsChange {
    /// The value written in between, in the register's engineering units (a code for an
    /// enumeration, the word for a plain word); it must be a value the register accepts.
    pub between: f64,
    /// `file:line` of the manual's rule.
    pub source: String,
}

/// `r`, `w`, `rw`: the vocabulary crate's access.
pub(crate) use drivemap_core::register::Access;
/// `holding`, `input`, `coil`, `discrete_input`: the vocabulary crate's table.
pub(crate) use drivemap_core::register::Table as ModbusTable;
/// When the drive accepts a write (`none`, `stopped`, `prg_mode`): the vocabulary crate's.
pub(crate) use drivemap_core::register::WriteRestriction;

/// One register (one 16-bit word, or a 32-bit pair with `pair`), or a block of them with `repeat`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Register {
    /// snake_case identifier; becomes the generated type name in PascalCase.
    pub id: String,
    /// Parameter number exactly as printed (`Bn-01`, `n019`, `CM.03`); with `read_param`, the
    /// parameter a write sets.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param: Option<String>,
    /// The parameter a read returns when it is not `param` (Siemens BICO: read r0055 bit 8,
    /// write P2200), exactly as printed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub read_param: Option<String>,
    /// Name as printed.
    pub name: String,
    /// Communication address as the manual prints it.
    pub address: u16,
    /// The Modicon reference the manual prints beside the register's own number (`40001`, a
    /// coil's `00001`), its digits as printed ([`crate::modicon`]): held to `address`, the
    /// register's table and `protocol.addressing`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub access: Option<Access>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modbus_table: Option<ModbusTable>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// `0.1`, `{relative_to: .., full_scale: ..}`, `{counts: .., equals: ..}` or
    /// `{selected_by: .., cases: [..]}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<Scale>,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub signed: bool,
    /// A 32-bit value in this register and the next (`{order: high_first, source: ..}`):
    /// read in one request, written whole with 10h. Absent: one 16-bit register.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pair: Option<Pair>,
    /// Text in this register and the ones after it (`{registers: 8, byte_order: high_first,
    /// source: ..}`): read whole in one request, two characters per register. Absent: a number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub string: Option<StringText>,
    /// Lower limit in engineering units, for the base variant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Upper limit in engineering units, for the base variant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<DefaultValue>,
    /// Limits and defaults of other variants, keyed by variant option id.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub by_variant: BTreeMap<String, VariantOverride>,
    /// An upper limit the manual states through another register or quantity (a frequency
    /// reference at most 100 % of the maximum output frequency n011), with its citation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_relative: Option<RelativeLimit>,
    /// Limits chosen by another parameter's code while the scale stays fixed ("10.0-400.0 %
    /// under V/f, 10.0-150.0 % under vector control"): `{selected_by: .., cases: [..]}`.
    /// Expanded into a selected scale whose cases all carry the register's own `scale`
    /// ([`crate::ir::expand`]): one mechanism decides both.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<SelectedLimits>,
    /// Addresses the register moves to under some condition.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub address_alternatives: Vec<AddressAlternative>,
    /// Enumeration codes (sparse codes allowed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<EnumValue>,
    /// Bit fields and multi-bit fields. Bits no field covers are reserved and written as 0.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fields: Vec<Field>,
    /// What a word read from the register means, when it differs from what a write means
    /// (ACN 0h03E7: a password is written, 0 Unlock / 1 Lock is read). The register's own
    /// description (a plain word, `min`/`max`) is its write side.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub read_values: Vec<EnumValue>,
    /// The drive executes a written value only when it differs from the previous write.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeat_needs_change: Option<RepeatNeedsChange>,
    /// Indexed access: the value belongs to the entry selected by an index written to another
    /// register ([`crate::indexed`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indexed: Option<crate::indexed::Indexed>,
    /// The Modbus functions the register accepts (overrides its group's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub function_codes: Option<RegisterFunctions>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub write_restriction: Option<WriteRestriction>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transports: Option<Vec<TransportName>>,
    /// Keypad resolution bands ("0.0 - 999.9 or 1000 - 6000 s"): documentation of what the
    /// operator shows; the register carries `scale` throughout.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub display_steps: Vec<DisplayStep>,
    /// A block of `count` registers generated from this template.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeat: Option<Repeat>,
    /// `file:line` of the row in the manual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the item has no row of its own there); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub conflicts: Vec<Conflict>,
    /// What the manual leaves unknown about this register (range, default, unit...).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unknown: Vec<Unknown>,
}

/// A 32-bit value held in two consecutive registers.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Pair {
    /// Which word sits at the register's own (lower) address.
    pub order: WordOrder,
    /// `file:line` where the manual states the word order, when not on the register's row.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// Which half of a 32-bit pair comes first (at the lower address).
pub(crate) use drivemap_core::width::WordOrder;

/// Text held in consecutive registers, two characters each (model names, serial numbers,
/// firmware versions).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct StringText {
    /// How many registers the text takes, from the register's address on.
    pub registers: u8,
    /// Which byte of each register holds the earlier character.
    pub byte_order: ByteOrder,
    /// An example of the text as the manual prints it (`"Q2-0400"`): what the simulator
    /// serves; cited by `source` (or the register's row). Absent: the simulator serves its
    /// documented placeholder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub example: Option<String>,
    /// `file:line` where the manual states the byte order or the example, when not on the
    /// register's row.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// Which byte of a register holds the earlier character: the vocabulary crate's.
pub(crate) use drivemap_core::text::ByteOrder;

/// How a raw word becomes an engineering value.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Scale {
    /// engineering = raw × factor.
    Factor(f64),
    /// `full_scale` raw = 100 % of the reference ("30000 = 100 % of Cn-02").
    Relative(RelativeScale),
    /// The scale follows the setting of another parameter (V7 n152, n018).
    Selected(SelectedScale),
    /// `counts` raw = `equals` in the register's unit, exactly ("60.0 Hz = 3600").
    Ratio(RatioScale),
}

/// An exact ratio scale: `counts` raw counts equal `equals` in the register's unit ("60.0 Hz =
/// 3600": `{counts: 3600, equals: 60.0}`), so raw `r` means `r × equals / counts` exactly.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RatioScale {
    /// The raw count the manual prints (a whole number > 0).
    pub counts: u32,
    /// The value it equals in the register's unit (a decimal > 0).
    pub equals: f64,
}

/// `max_relative`: the value is at most `percent` % of another register's value or of an
/// external quantity, in the register's unit.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RelativeLimit {
    /// A register id or parameter number (`n011`), or an external quantity (as in `scale`).
    pub relative_to: Reference,
    /// The limit in percent of the reference's value (finite, > 0).
    pub percent: f64,
    /// `file:line` of the manual's statement.
    pub source: String,
}

/// A relative scale: `full_scale` raw = 100 % of another register or quantity ("30000 = 100 %
/// of Cn-02").
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RelativeScale {
    /// A register id or parameter number (`max_output_frequency`, `Cn-02`), or an external
    /// quantity the application supplies.
    pub relative_to: Reference,
    /// The raw value that means 100 % of the reference.
    pub full_scale: f64,
}

/// What a relative scale or limit refers to.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Reference {
    /// A register of the drive, by id or parameter number.
    Register(String),
    /// A quantity the application supplies.
    External(ExternalQuantity),
}

/// A quantity that is not a register of the drive ("drive rating").
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExternalQuantity {
    /// snake_case name; becomes a field of the generated `Settings`.
    pub external: String,
    /// Its unit.
    pub unit: String,
    /// What it is (the motor's rated current).
    pub description: String,
}

/// A scale chosen by the setting of another parameter (or a field of it).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SelectedScale {
    /// A register id or parameter number whose value selects the case.
    pub selected_by: String,
    /// The cases, in the map's order.
    pub cases: Vec<ScaleCase>,
}

/// One case of a selected scale.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScaleCase {
    /// The selector's codes for which this case applies.
    pub when: Vec<u16>,
    /// A factor or a relative scale (not another selection).
    pub scale: Scale,
    /// The lower limit in engineering units under this case (base variant).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// The upper limit in engineering units under this case (base variant).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// `file:line` of the case's row in the manual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// `limits: {selected_by: .., cases: [..]}`: a register's range chosen by another parameter's
/// code, its scale fixed.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SelectedLimits {
    /// A register id or parameter number (or `<register>.<field>`) whose code selects the case.
    pub selected_by: String,
    /// The cases, in the map's order.
    pub cases: Vec<LimitCase>,
}

/// One case of [`SelectedLimits`]: the selector's codes and the range under them.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LimitCase {
    /// The selector's codes for which this case applies.
    pub when: Vec<u16>,
    /// The lower limit in engineering units under this case (base variant).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// The upper limit in engineering units under this case (base variant).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// `file:line` of the case's row in the manual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// A default value, or why there is none to give.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum DefaultValue {
    /// A number in engineering units.
    Value(f64),
    /// A default that depends on another setting.
    Depends(DependentDefault),
}

/// A default the manual gives as depending on another setting.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DependentDefault {
    /// What it depends on.
    pub depends_on: Dependency,
    /// The manual's words on it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// What a default depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Dependency {
    /// Drive capacity (kVA, rated current).
    Capacity,
    /// Control method (V/f, vector).
    ControlMethod,
    /// Model variant (voltage class) without a value printed.
    Variant,
    /// Another parameter's setting.
    Setting,
    /// The manual prints no legible default.
    Unknown,
}

/// What one variant option overrides of a register (`by_variant.<option>`).
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VariantOverride {
    /// The option's lower limit (the base's where it gives none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// The option's upper limit (the base's where it gives none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// The option's default (the base's where it gives none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<DefaultValue>,
    /// What the manual leaves unknown for this variant only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unknown: Vec<Unknown>,
    /// `file:line` of the option's row in the manual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// An address the register moves to under a condition.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AddressAlternative {
    /// The address.
    pub address: u16,
    /// When.
    pub when: Condition,
    /// Its citation.
    pub source: String,
}

/// A condition on a setting's value, a model variant, or the transport.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Condition {
    /// Register id or parameter number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setting: Option<String>,
    /// The setting's codes for which the condition holds.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub is: Vec<u16>,
    /// A variant option id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<String>,
    /// A transport.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transport: Option<TransportName>,
}

/// The one wording of a condition, shared by rustdoc, `drivemap doc`, `describe` and `diff`:
/// `o2-09 is 1`, `o2-09 is 0, 2`, `variant 400v`, `transport RTU`.
impl std::fmt::Display for Condition {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(s) = &self.setting {
            write!(f, "{s} is ")?;
            for (i, code) in self.is.iter().enumerate() {
                if i > 0 {
                    f.write_str(", ")?;
                }
                write!(f, "{code}")?;
            }
            Ok(())
        } else if let Some(v) = &self.variant {
            write!(f, "variant {v}")
        } else if let Some(t) = self.transport {
            write!(f, "transport {t}")
        } else {
            f.write_str("never")
        }
    }
}

/// One code of an enumeration.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EnumValue {
    /// The code.
    pub value: u16,
    /// snake_case identifier; becomes the enum variant in PascalCase.
    pub id: String,
    /// Meaning as printed.
    pub name: String,
    /// Its citation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the item has no row of its own there); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// A bit field (`bit`) or multi-bit field (`bits`) of a register.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Field {
    /// The field id.
    pub id: String,
    /// Meaning as printed.
    pub name: String,
    /// A single bit (0..=15).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bit: Option<u8>,
    /// A multi-bit field, lowest and highest bit inclusive (`[12, 15]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bits: Option<[u8; 2]>,
    /// Codes of a multi-bit field.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<EnumValue>,
    /// Its citation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The citation is deliberately indirect (the item has no row of its own there); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
    /// Notes on the field.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// A keypad resolution band.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DisplayStep {
    /// Lowest value shown with this step.
    pub from: f64,
    /// The step shown from `from` on.
    pub step: f64,
}

/// Expands a register into `count` registers. In `id`, `param`, `name`, the placeholder `{n}`
/// is the instance number (from `start`, default 1) and `{p}` is `param_start + index`;
/// `{n:02}` pads to two digits. Addresses advance by `address_step`, citations by `line_step`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Repeat {
    pub count: u16,
    #[serde(default = "one_u16")]
    pub start: u16,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param_start: Option<u16>,
    #[serde(default = "one_u16")]
    pub address_step: u16,
    #[serde(default = "one_u16")]
    pub line_step: u16,
}

fn one_u16() -> u16 {
    1
}

/// A place where the manual contradicts itself or another manual, and the reading taken.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Conflict {
    /// What the readings disagree on.
    pub topic: String,
    /// The readings, each cited.
    pub readings: Vec<Reading>,
    /// The reading the map follows.
    pub chosen: String,
    /// Why.
    pub reason: String,
}

/// One reading of the manual.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Reading {
    /// Where.
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
    /// What it says.
    pub says: String,
}

/// Something the manual leaves unknown about a register.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Unknown {
    /// The item.
    pub what: UnknownItem,
    /// Why the manual leaves it unknown.
    pub reason: String,
}

/// An item of a register the manual may leave unknown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum UnknownItem {
    /// Its range.
    Range,
    /// Its default.
    Default,
    /// Its unit.
    Unit,
    /// Its scale.
    Scale,
    /// Whether the word is signed (two's complement) or unsigned.
    Signed,
    /// Its list of codes.
    Values,
    /// Its bit fields.
    Fields,
    /// Its access.
    Access,
}

/// Addresses or parameters the manual leaves illegible or missing.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Gap {
    /// First and last address covered, inclusive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub addresses: Option<[u16; 2]>,
    /// Parameter numbers covered, as printed ("U1-15 .. U1-18").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub params: Option<String>,
    /// What the addresses hold (or why none is listed).
    pub description: String,
    /// Its citation.
    pub source: String,
    /// The citation is deliberately indirect (the line does not mention the item itself); the
    /// reason is required. Review does not check such a citation by content.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<String>,
}

/// A register of the base map that a variant map does not have.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Removed {
    /// The register id.
    pub id: String,
    /// Why the variant lacks it.
    pub reason: String,
    /// Its citation.
    pub source: String,
}

/// A per-request limit (`max_read`, `max_write`): a plain number (`8`), the number with its
/// citation (`{value: 8, source: "..."}`), a limit the manual does not print (`{unknown:
/// "<why>"}`: the tools use the Modbus limit, 125 per read and 123 per write), or a working
/// number chosen although the manual prints none, with why (`{value: 8, unknown: "the chapter
/// prints no limit; 8 is ..."}`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Limit {
    /// The number, when the map gives one.
    pub value: Option<u16>,
    /// Where the manual says it (`file:line`).
    pub source: Option<String>,
    /// Why the manual prints no such limit and where `value` comes from.
    pub unknown: Option<String>,
}

impl Limit {
    /// A plain number, neither cited nor marked unknown.
    pub fn plain(value: u16) -> Limit {
        Limit {
            value: Some(value),
            source: None,
            unknown: None,
        }
    }

    /// The number the tools use: the map's, else `modbus` (the protocol's own limit).
    pub fn working(&self, modbus: u16) -> u16 {
        self.value.unwrap_or(modbus)
    }

    /// Whether the limit says more than its number (a citation or a reason).
    pub fn stated(&self) -> bool {
        self.source.is_some() || self.unknown.is_some()
    }
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct LimitForm {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    value: Option<u16>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    source: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    unknown: Option<String>,
}

impl<'de> Deserialize<'de> for Limit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Limit, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Limit;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number of registers, `{value: N, source: ..}` or `{unknown: <why>}`")
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Limit, E> {
                u16::try_from(v).map(Limit::plain).map_err(|_| {
                    E::invalid_value(serde::de::Unexpected::Unsigned(v), &"a number of registers")
                })
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Limit, E> {
                u16::try_from(v).map(Limit::plain).map_err(|_| {
                    E::invalid_value(serde::de::Unexpected::Signed(v), &"a number of registers")
                })
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Limit, A::Error> {
                let f = LimitForm::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(Limit {
                    value: f.value,
                    source: f.source,
                    unknown: f.unknown,
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Limit {
    /// A plain limit as its number (as shipped maps and exports always had it), else the mapping.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if let (None, None, Some(v)) = (&self.source, &self.unknown, self.value) {
            return s.serialize_u16(v);
        }
        LimitForm {
            value: self.value,
            source: self.source.clone(),
            unknown: self.unknown.clone(),
        }
        .serialize(s)
    }
}

/// The function codes a drive implements (`protocol.function_codes`): a plain list (`[0x03,
/// 0x06]`), the list with its citation (`{codes: [...], source: "file:line"}`), or a list the
/// manual does not print as such, with why it is the working list (`{codes: [...], unknown:
/// "<why>", source: ...}`). `codes` is always required: the runtime refuses any other function.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FunctionCodes {
    /// The function codes, in the map's order.
    pub codes: Vec<u8>,
    /// Where the manual says it (`file:line`).
    pub source: Option<String>,
    /// Why the manual prints no list of function codes and where `codes` come from.
    pub unknown: Option<String>,
}

impl FunctionCodes {
    /// A plain list, neither cited nor marked unknown.
    pub fn plain(codes: Vec<u8>) -> FunctionCodes {
        FunctionCodes {
            codes,
            source: None,
            unknown: None,
        }
    }

    /// Whether the list carries more than its codes (a citation or a reason).
    pub fn stated(&self) -> bool {
        self.source.is_some() || self.unknown.is_some()
    }
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct FunctionCodesForm {
    codes: Vec<u8>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    source: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    unknown: Option<String>,
}

impl<'de> Deserialize<'de> for FunctionCodes {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<FunctionCodes, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = FunctionCodes;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a list of function codes, `{codes: [..], source: ..}` or `{codes: [..], unknown: <why>}`",
                )
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<FunctionCodes, A::Error> {
                Vec::<u8>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
                    .map(FunctionCodes::plain)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<FunctionCodes, A::Error> {
                let f = FunctionCodesForm::deserialize(
                    serde::de::value::MapAccessDeserializer::new(map),
                )?;
                Ok(FunctionCodes {
                    codes: f.codes,
                    source: f.source,
                    unknown: f.unknown,
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for FunctionCodes {
    /// A plain list as the list (as shipped maps and exports always had it), else the mapping.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if !self.stated() {
            return self.codes.serialize(s);
        }
        FunctionCodesForm {
            codes: self.codes.clone(),
            source: self.source.clone(),
            unknown: self.unknown.clone(),
        }
        .serialize(s)
    }
}

/// `protocol.exceptions`: the drive's exception codes as a list, or `{unknown: "<why>", source:
/// ..}` when the manual prints none (the tools then name only the standard Modbus exceptions).
/// Reads as the list ([`std::ops::Deref`]).
#[derive(Debug, Clone, Default)]
pub struct Exceptions {
    /// The codes the manual prints (empty with `unknown`).
    pub list: Vec<ExceptionCode>,
    /// Why the manual prints no exception list.
    pub unknown: Option<String>,
    /// Where the manual says so, when it does.
    pub source: Option<String>,
    /// The citation is deliberately indirect: why.
    pub indirect: Option<String>,
}

impl std::ops::Deref for Exceptions {
    type Target = Vec<ExceptionCode>;
    fn deref(&self) -> &Vec<ExceptionCode> {
        &self.list
    }
}

impl std::ops::DerefMut for Exceptions {
    fn deref_mut(&mut self) -> &mut Vec<ExceptionCode> {
        &mut self.list
    }
}

impl<'a> IntoIterator for &'a Exceptions {
    type Item = &'a ExceptionCode;
    type IntoIter = std::slice::Iter<'a, ExceptionCode>;
    fn into_iter(self) -> Self::IntoIter {
        self.list.iter()
    }
}

impl From<Vec<ExceptionCode>> for Exceptions {
    fn from(list: Vec<ExceptionCode>) -> Exceptions {
        Exceptions {
            list,
            ..Exceptions::default()
        }
    }
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct ExceptionsForm {
    unknown: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    source: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    indirect: Option<String>,
}

impl<'de> Deserialize<'de> for Exceptions {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Exceptions, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Exceptions;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a list of exception codes or `{unknown: <why>, source: ..}`")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<Exceptions, A::Error> {
                Vec::<ExceptionCode>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
                    .map(Exceptions::from)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Exceptions, A::Error> {
                let f =
                    ExceptionsForm::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(Exceptions {
                    list: Vec::new(),
                    unknown: Some(f.unknown),
                    source: f.source,
                    indirect: f.indirect,
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Exceptions {
    /// The list (as maps and exports always had it), or the mapping when not printed.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match &self.unknown {
            None => self.list.serialize(s),
            Some(why) => ExceptionsForm {
                unknown: why.clone(),
                source: self.source.clone(),
                indirect: self.indirect.clone(),
            }
            .serialize(s),
        }
    }
}

impl SlaveAddress {
    /// The range the tools use: the map's, else the Modbus unicast range 1-247.
    pub fn range(&self) -> (u8, u8) {
        match (self.min, self.max) {
            (Some(lo), Some(hi)) => (lo, hi),
            _ => (
                drivemap_core::stated::MODBUS_SLAVE_MIN,
                drivemap_core::stated::MODBUS_SLAVE_MAX,
            ),
        }
    }
}

impl Protocol {
    /// Registers per read the tools use: the map's, else the Modbus 125.
    pub fn max_read(&self) -> u16 {
        self.max_read
            .working(drivemap_core::stated::MODBUS_MAX_READ)
    }

    /// Registers per write the tools use: the map's, else the Modbus 123.
    pub fn max_write(&self) -> u16 {
        self.max_write
            .working(drivemap_core::stated::MODBUS_MAX_WRITE)
    }

    /// Coils or discrete inputs per read the tools use: the map's, else the Modbus 2000.
    pub fn max_read_bits(&self) -> u16 {
        self.max_read_bits
            .as_ref()
            .map_or(drivemap_core::stated::MODBUS_MAX_READ_BITS, |l| {
                l.working(drivemap_core::stated::MODBUS_MAX_READ_BITS)
            })
    }

    /// Coils per write the tools use: the map's, else the Modbus 1968.
    pub fn max_write_bits(&self) -> u16 {
        self.max_write_bits
            .as_ref()
            .map_or(drivemap_core::stated::MODBUS_MAX_WRITE_BITS, |l| {
                l.working(drivemap_core::stated::MODBUS_MAX_WRITE_BITS)
            })
    }
}
