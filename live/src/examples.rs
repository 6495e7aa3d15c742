//! The map's example frames (`examples:`) verified against the Modbus codec and the map.
//!
//! The map front end (`drivemap-map`) checks their form; this module checks what the bytes
//! mean, with the runtime's codec (CRC-16, MBAP header, PDU decoding) and the map's plan (the
//! register at each address, each value's range and conversion):
//!
//! - an RTU frame's CRC (the printed CRC bytes against the CRC-16 of the frame), an ASCII
//!   frame's LRC (its bytes as the character pairs between `:` and CR LF stand for them), a TCP
//!   frame's MBAP protocol id and length;
//! - the function code is one the map allows;
//! - a request decodes, and every address it reads or writes is a register of the map;
//! - a written value is in its register's range and decodes to the value the example states;
//! - a response answers its request (slave, function and every echo, the byte count of a read),
//!   an exception response carries the stated code and one the map lists;
//! - `says.read` / `says.write` name the register at the frame's address.
//!
//! Each finding is located at the byte concerned: `file:line:col` of that byte in the
//! `bytes:` text. `drivemap check` runs it on every map.

use drivemap_map::facts::TransportName;
use drivemap_map::facts::{Byte, Direction, Example, hex_text, parse_bytes};
use drivemap_map::{Diagnostic, Loc};
use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::pdu::{self, Request, Response};
use drivemap_runtime::{crc, tcp};

use crate::codec;
use crate::settings::LiveSettings;

/// The PDU of an example frame and where it lies.
#[derive(Debug, Clone)]
pub struct Frame {
    /// The example's bytes.
    pub bytes: Vec<u8>,
    /// The slave address (RTU) or unit id (TCP).
    pub slave: u8,
    /// Index of the PDU's first byte (the function code) in `bytes`.
    pub pdu_start: usize,
    /// One past the PDU's last byte.
    pub pdu_end: usize,
}

impl Frame {
    /// The PDU.
    pub fn pdu(&self) -> &[u8] {
        &self.bytes[self.pdu_start..self.pdu_end]
    }
}

/// The transport kind an example's framing stands for.
pub fn kind_of(e: &Example) -> TransportKind {
    match e.transport {
        TransportName::Rtu => TransportKind::Rtu,
        TransportName::Tcp => TransportKind::Tcp,
        TransportName::Ascii => TransportKind::Ascii,
    }
}

/// Settings for decoding examples: the map's defaults of the registers conversions depend on.
pub(crate) fn default_settings(drive: &Map) -> LiveSettings {
    let mut settings = LiveSettings::default();
    let deps = LiveSettings::dependencies(drive);
    for r in drive.registers() {
        if !deps.contains(&r.address()) {
            continue;
        }
        if let Some(d) = r.default_value()
            && let Ok(raw) = codec::encode(drive, r, d, &settings)
        {
            settings.absorb(drive, r.address(), raw as u16);
        }
    }
    settings
}

/// `base` with the drive state an example assumes (`settings:`): a register's value (by id or
/// parameter number) taken as if read from the drive, else an external quantity.
pub fn with_settings(drive: &Map, e: &Example, base: &LiveSettings) -> LiveSettings {
    let mut settings = base.clone();
    for (name, &value) in &e.settings {
        match drive.register(name) {
            Some(r) => {
                if let Ok(raw) = codec::encode(drive, r, value, &settings) {
                    settings.absorb(drive, r.address(), raw as u16);
                }
            }
            None => {
                settings.references.insert(name.clone(), value);
            }
        }
    }
    settings
}

/// The register at communication address `address` on `kind`, as the plan places it (the word
/// of a 32-bit pair with its index), among broadcast registers when `broadcast`.
pub fn register_at<'a>(
    drive: &'a Map,
    settings: &LiveSettings,
    kind: TransportKind,
    address: u16,
    table: Option<Table>,
    broadcast: bool,
) -> Option<(RegisterRef<'a>, u16)> {
    let view = settings.view(drive);
    let find = |want_broadcast: bool| {
        drive.registers().find_map(|r| {
            if r.broadcast_only() != want_broadcast {
                return None;
            }
            let plan = r.plan();
            if !plan.transports.contains(kind) || table.is_some_and(|t| plan.info.table != t) {
                return None;
            }
            let at = plan.address_for(&view, kind);
            let word = address.checked_sub(at)?;
            (word < plan.info.width.count()).then_some((r, word))
        })
    };
    if broadcast {
        find(true).or_else(|| find(false))
    } else {
        find(false)
    }
}

/// Reads an example's bytes into its framing, or says what is wrong (with the byte index).
pub fn frame(e: &Example) -> Result<Frame, (usize, String)> {
    let bytes: Vec<u8> = parse_bytes(&e.bytes)
        .map_err(|(_, m)| (0, m))?
        .iter()
        .map(|b| b.value)
        .collect();
    let n = bytes.len();
    match e.transport {
        TransportName::Rtu => {
            if n < 4 {
                return Err((
                    n - 1,
                    format!(
                        "an RTU frame has at least 4 bytes (address, function, CRC); this one has {n}"
                    ),
                ));
            }
            if let Err((computed, _)) = crc::check(&bytes) {
                let want = computed.to_le_bytes();
                // The first printed CRC byte that differs.
                let at = if bytes[n - 2] != want[0] {
                    n - 2
                } else {
                    n - 1
                };
                return Err((
                    at,
                    format!(
                        "CRC: the frame ends in {}, the CRC-16 of the bytes before it is {} (low byte first)",
                        hex_text(&bytes[n - 2..]),
                        hex_text(&want)
                    ),
                ));
            }
            Ok(Frame {
                slave: bytes[0],
                pdu_start: 1,
                pdu_end: n - 2,
                bytes,
            })
        }
        TransportName::Ascii => {
            // The bytes the frame's character pairs stand for, as manuals print an ASCII frame
            // between its ':' and CR LF: address, PDU, LRC.
            if n < 3 {
                return Err((
                    n.saturating_sub(1),
                    format!(
                        "an ASCII frame carries at least 3 bytes between ':' and CR LF (address, function, LRC); this one has {n}"
                    ),
                ));
            }
            let want = drivemap_runtime::ascii::lrc(&bytes[..n - 1]);
            if bytes[n - 1] != want {
                return Err((
                    n - 1,
                    format!(
                        "LRC: the frame ends in {}, the LRC of the bytes before it is {want:02X}",
                        hex_text(&bytes[n - 1..])
                    ),
                ));
            }
            Ok(Frame {
                slave: bytes[0],
                pdu_start: 1,
                pdu_end: n - 1,
                bytes,
            })
        }
        TransportName::Tcp => {
            if n < 8 {
                return Err((
                    n - 1,
                    format!(
                        "a Modbus TCP frame has at least 8 bytes (MBAP header, function); this one has {n}"
                    ),
                ));
            }
            let protocol = u16::from_be_bytes([bytes[2], bytes[3]]);
            if protocol != 0 {
                return Err((
                    2,
                    format!("MBAP protocol id {protocol:04X}h: Modbus is 0000h"),
                ));
            }
            let length = usize::from(u16::from_be_bytes([bytes[4], bytes[5]]));
            if length != n - 6 {
                return Err((
                    4,
                    format!(
                        "MBAP length says {length} bytes follow it, the frame has {} after it",
                        n - 6
                    ),
                ));
            }
            debug_assert!(tcp::Header::parse(&bytes).is_ok());
            Ok(Frame {
                slave: bytes[6],
                pdu_start: 7,
                pdu_end: n,
                bytes,
            })
        }
    }
}

/// What verifying a map's examples found.
#[derive(Debug, Clone, Default)]
pub struct Verified {
    /// Errors: an example that contradicts the codec or the map without a `conflict` mark, or
    /// a mark on an example that verifies.
    pub errors: Vec<Diagnostic>,
    /// The examples whose contradiction the map records (`conflict:`), one each, with their
    /// findings.
    pub known: Vec<Recorded>,
    /// The examples verified with no finding.
    pub clean: usize,
}

/// One thing an example's bytes contradict.
#[derive(Debug, Clone)]
pub struct Finding {
    /// The byte concerned (from 1) and its value; `None` for a finding about the example's
    /// `says`.
    pub byte: Option<(usize, u8)>,
    /// What is wrong, without the example and byte that [`Finding::diagnostic`] names.
    pub reason: String,
    /// The finding located at its byte in the `bytes:` text (or at the `says` key), naming the
    /// example and the byte.
    pub diagnostic: Diagnostic,
}

/// An example whose contradiction of the codec or the map is recorded in `conflicts:` (its
/// `conflict:` topic), with what it contradicts.
#[derive(Debug, Clone)]
pub struct Recorded {
    /// The example's id.
    pub example: String,
    /// The topic of the `conflicts:` entry its `conflict:` names.
    pub conflict: String,
    /// Its findings, by the byte concerned (those about `says` last); never empty.
    pub findings: Vec<Finding>,
}

impl Recorded {
    /// The bytes that differ, as `byte 5 (62)` for one and `bytes 12, 14, 16` for several
    /// (empty when every finding is about `says`).
    pub fn bytes(&self) -> String {
        let mut bytes: Vec<(usize, u8)> = self.findings.iter().filter_map(|f| f.byte).collect();
        bytes.dedup_by_key(|(n, _)| *n);
        match bytes[..] {
            [] => String::new(),
            [(n, value)] => format!("byte {n} ({value:02X})"),
            _ => {
                let numbers: Vec<String> = bytes.iter().map(|(n, _)| n.to_string()).collect();
                format!("bytes {}", numbers.join(", "))
            }
        }
    }

    /// One warning for the frame, at its first finding's place (the first byte that differs):
    /// the example, the bytes that differ, the first finding (and how many there are) and the
    /// conflict recorded; as
    /// `drivemap check` prints it (`file:line:col: warning: ...`).
    pub fn warning(&self) -> String {
        let first = &self.findings[0];
        let bytes = self.bytes();
        let at = if bytes.is_empty() {
            String::new()
        } else {
            format!(", {bytes}")
        };
        let count = match self.findings.len() {
            1 => String::new(),
            n => format!(" (the first of {n} findings)"),
        };
        Diagnostic::new(
            first.diagnostic.loc.clone(),
            first.diagnostic.register.as_deref(),
            format!(
                "example `{}`{at}: {}{count}; recorded in `conflicts:` as \"{}\"",
                self.example, first.reason, self.conflict
            ),
        )
        .as_warning()
    }
}

/// Verifies every example of `drive`; the findings are located at the byte concerned.
pub fn verify(drive: &Map) -> Verified {
    let mut v = Verified::default();
    for (i, (e, found)) in drive.examples().iter().zip(findings(drive)).enumerate() {
        match (&e.conflict, found.is_empty()) {
            (None, true) => v.clean += 1,
            (None, false) => v.errors.extend(found.into_iter().map(|f| f.diagnostic)),
            (Some(topic), false) => {
                let mut findings = found;
                findings.sort_by_key(|f| f.byte.map_or(usize::MAX, |(n, _)| n));
                v.known.push(Recorded {
                    example: e.id.clone(),
                    conflict: topic.clone(),
                    findings,
                });
            }
            (Some(topic), true) => v.errors.push(drive.error_at(
                &format!("examples[{i}].conflict"),
                None,
                format!(
                    "example `{}` verifies against the codec and the map, but is marked as \
                     contradicting them (conflict \"{topic}\")",
                    e.id
                ),
            )),
        }
    }
    v
}

/// The findings of each example of `drive`, in order, marked or not.
pub(crate) fn findings(drive: &Map) -> Vec<Vec<Finding>> {
    let settings = default_settings(drive);
    let mut all = Vec::new();
    for (i, e) in drive.examples().iter().enumerate() {
        let path = format!("examples[{i}]");
        let Ok(offsets) = parse_bytes(&e.bytes) else {
            all.push(Vec::new()); // the front end reports it
            continue;
        };
        let bytes_loc = drive.locate_value(&format!("{path}.bytes"));
        let settings = with_settings(drive, e, &settings);
        let v = Verifier {
            drive,
            settings: &settings,
            example: e,
            offsets: &offsets,
            bytes_loc,
            path,
        };
        let mut out = Vec::new();
        v.run(&mut out);
        all.push(out);
    }
    all
}

struct Verifier<'a> {
    drive: &'a Map,
    settings: &'a LiveSettings,
    example: &'a Example,
    offsets: &'a [Byte],
    bytes_loc: Loc,
    path: String,
}

/// A function code in the manuals' notation.
fn fc(f: u8) -> String {
    format!("{f:02X}h")
}

impl Verifier<'_> {
    fn at(&self, index: usize) -> Loc {
        let b = self.offsets[index.min(self.offsets.len() - 1)];
        self.bytes_loc.at_offset(b.offset)
    }

    fn error(&self, out: &mut Vec<Finding>, index: usize, register: Option<&str>, msg: String) {
        let byte = self.offsets[index.min(self.offsets.len() - 1)].value;
        let diagnostic = Diagnostic::new(
            self.at(index),
            register,
            format!(
                "example `{}`, byte {} ({byte:02X}): {msg}",
                self.example.id,
                index + 1
            ),
        );
        out.push(Finding {
            byte: Some((index + 1, byte)),
            reason: msg,
            diagnostic,
        });
    }

    /// Whether an example of the map answers this request with an exception.
    fn refused(&self) -> bool {
        self.drive.examples().iter().any(|x| {
            x.answers.as_deref() == Some(self.example.id.as_str())
                && frame(x).is_ok_and(|f| f.bytes[f.pdu_start] & 0x80 != 0)
                || x.answers.as_deref() == Some(self.example.id.as_str())
                    && x.says.as_ref().is_some_and(|s| s.exception.is_some())
        })
    }

    fn says_error(&self, out: &mut Vec<Finding>, key: &str, msg: String) {
        let diagnostic = self.drive.error_at(
            &format!("{}.says.{key}", self.path),
            None,
            format!("example `{}`: {msg}", self.example.id),
        );
        out.push(Finding {
            byte: None,
            reason: msg,
            diagnostic,
        });
    }

    fn run(&self, out: &mut Vec<Finding>) {
        let e = self.example;
        let f = match frame(e) {
            Ok(f) => f,
            Err((index, msg)) => return self.error(out, index, None, msg),
        };
        let function = f.bytes[f.pdu_start];
        let allowed = &self.drive.protocol().function_codes.codes;
        if !allowed.contains(&(function & 0x7F)) {
            let list: Vec<String> = allowed.iter().map(|&c| fc(c)).collect();
            return self.error(
                out,
                f.pdu_start,
                None,
                format!(
                    "function {} is not among the map's function codes ({})",
                    fc(function & 0x7F),
                    list.join(", ")
                ),
            );
        }
        match e.direction {
            Direction::Request => self.request(&f, out),
            Direction::Response => self.response(&f, out),
        }
    }

    fn request(&self, f: &Frame, out: &mut Vec<Finding>) {
        let e = self.example;
        let req = match pdu::decode_request(f.pdu()) {
            Ok(r) => r,
            Err(err) => {
                return self.error(
                    out,
                    f.pdu_start,
                    None,
                    format!("the request does not decode: {err}"),
                );
            }
        };
        let says = e.says.clone().unwrap_or_default();
        match (&says.read, &says.write) {
            (Some(_), _) if !req.is_read() => self.says_error(
                out,
                "read",
                format!("the frame is function {}, not a read", fc(req.function())),
            ),
            (_, Some(_))
                if !matches!(
                    req,
                    Request::WriteSingle { .. } | Request::WriteMultiple { .. }
                ) =>
            {
                self.says_error(
                    out,
                    "write",
                    format!("the frame is function {}, not a write", fc(req.function())),
                )
            }
            _ => {}
        }
        let Some(address) = req.address() else {
            return;
        };
        if self.refused() {
            // The manual prints it to show the drive refusing it: its address or value may be
            // one the map refuses; the exception response is checked against it.
            return;
        }
        self.functions_accepted(f, out, req.function(), address, req.quantity());
        let words: Vec<u16> = match req {
            Request::WriteSingle { value, .. } => vec![value],
            Request::WriteMultiple { values, .. } => values.iter().collect(),
            _ => Vec::new(),
        };
        let table = match req {
            Request::ReadInput { .. } => Some(Table::Input),
            Request::ReadHolding { .. } => None,
            _ => Some(Table::Holding),
        };
        self.registers(
            f,
            out,
            address,
            req.quantity(),
            table,
            f.pdu_start + 1,
            &words,
            f.pdu_start + if words.len() > 1 { 6 } else { 3 },
            says.read.as_ref().or(says.write.as_ref()),
            &says.values,
        );
    }

    /// A request with a function a register it covers does not accept (the map's
    /// `function_codes`): the drive would refuse it, so the example is either one the manual
    /// prints to show that refusal (answered by an exception response) or the map is wrong. Reported at the
    /// function byte, once, naming the register and its list.
    fn functions_accepted(
        &self,
        f: &Frame,
        out: &mut Vec<Finding>,
        function: u8,
        pdu_address: u16,
        quantity: usize,
    ) {
        let kind = kind_of(self.example);
        let offsets = &self.drive.plan().profile.address_offsets;
        let table = (function == pdu::function::READ_INPUT).then_some(Table::Input);
        let table = table.or(Some(Table::Holding));
        for k in 0..quantity {
            let Some(comm) = pdu_address
                .checked_add(k as u16)
                .and_then(|pdu| offsets.communication_address(pdu, kind))
            else {
                return;
            };
            let Some((r, _)) =
                register_at(self.drive, self.settings, kind, comm, table, f.slave == 0)
            else {
                continue;
            };
            let functions = r.plan().functions;
            if !functions.allows(function) {
                let list: Vec<String> = functions.codes.iter().map(|&c| fc(c)).collect();
                return self.error(
                    out,
                    f.pdu_start,
                    Some(r.id()),
                    format!(
                        "function {} to {comm:04X}h: `{}` accepts only {} (`{}`), so the drive \
                         refuses it; if the manual prints the refusal, add its exception response \
                         (`answers: {}`, `says: {{exception: ..}}`)",
                        fc(function),
                        r.id(),
                        list.join(", "),
                        functions.source,
                        self.example.id
                    ),
                );
            }
        }
    }

    /// Checks the registers of a read or write: each address is a register of the map, the
    /// first is the one `says` names, and each word (if any) is in range and decodes to the
    /// stated value. `address_byte` and `data_byte` index the frame.
    // The fields of one frame (address, quantity, table, words, byte offsets) and what the
    // example says of them; the request and the reply (the two callers) hold them at
    // different bytes.
    #[allow(clippy::too_many_arguments)]
    fn registers(
        &self,
        f: &Frame,
        out: &mut Vec<Finding>,
        pdu_address: u16,
        quantity: usize,
        table: Option<Table>,
        address_byte: usize,
        words: &[u16],
        data_byte: usize,
        named: Option<&String>,
        values: &[f64],
    ) {
        let kind = kind_of(self.example);
        let offsets = &self.drive.plan().profile.address_offsets;
        let broadcast = f.slave == 0;
        for k in 0..quantity {
            let Some(pdu) = pdu_address.checked_add(k as u16) else {
                break;
            };
            let byte = if words.is_empty() || k >= words.len() {
                address_byte
            } else {
                data_byte + 2 * k
            };
            let Some(comm) = offsets.communication_address(pdu, kind) else {
                self.error(
                    out,
                    address_byte,
                    None,
                    format!("address {pdu:04X}h is below the {kind:?} address offset"),
                );
                return;
            };
            let Some((r, word)) =
                register_at(self.drive, self.settings, kind, comm, table, broadcast)
            else {
                self.error(
                    out,
                    if k == 0 { address_byte } else { byte },
                    None,
                    format!(
                        "address {comm:04X}h{} is not a register of the map",
                        if k == 0 {
                            String::new()
                        } else {
                            format!(" (word {} of the frame)", k + 1)
                        }
                    ),
                );
                if k == 0 {
                    return;
                }
                continue;
            };
            if k == 0
                && let Some(name) = named
                && r.id() != *name
            {
                self.error(
                    out,
                    address_byte,
                    Some(r.id()),
                    format!(
                        "address {comm:04X}h is `{}`, the example says `{name}`",
                        r.id()
                    ),
                );
            }
            let Some(&raw) = words.get(k) else { continue };
            let plan = r.plan();
            if plan.info.width.count() != 1 || word != 0 {
                continue; // a pair's words are checked as one value only through the typed API
            }
            let decoded = match codec::decode_written(self.drive, r, u32::from(raw), self.settings)
            {
                Ok(v) => v,
                // A conversion that rests on a setting the map gives no default for (a
                // frequency relative to a maximum read from the drive) cannot be decoded here;
                // only a value the example states for it is an error.
                Err(ValueError::MissingSetting { .. } | ValueError::LimitNotKnown { .. })
                    if values.get(k).is_none() =>
                {
                    continue;
                }
                Err(err) => {
                    self.error(
                        out,
                        byte,
                        Some(r.id()),
                        format!("{raw:04X}h does not decode: {err}"),
                    );
                    continue;
                }
            };
            let Some(number) = decoded.as_f64() else {
                continue;
            };
            // Words of a request are written; a response's are read (a monitor may read values
            // no write may give).
            let writing = self.example.direction == Direction::Request;
            if writing && !r.writable() {
                self.error(
                    out,
                    byte,
                    Some(r.id()),
                    format!("`{}` is read-only in the map", r.id()),
                );
            }
            if writing {
                // A limit that rests on a quantity the map does not hold (a maximum frequency
                // read from the drive) cannot be checked here: only a refusal is reported.
                if let Err(err) =
                    codec::encode(self.drive, r, number, self.settings).map_err(|e| match e {
                        ValueError::MissingSetting { .. } | ValueError::LimitNotKnown { .. } => {
                            None
                        }
                        e => Some(e),
                    })
                    && let Some(err) = err
                {
                    self.error(
                        out,
                        byte,
                        Some(r.id()),
                        format!("{raw:04X}h = {number} is refused by the map: {err}"),
                    );
                }
            }
            if let Some(&stated) = values.get(k) {
                let close = (number - stated).abs() <= 1e-9 * stated.abs().max(1.0);
                if !close {
                    self.error(
                        out,
                        byte,
                        Some(r.id()),
                        format!(
                            "{raw:04X}h decodes to {number} by the map, the example says {stated}"
                        ),
                    );
                }
            }
        }
        if values.len() > quantity {
            self.says_error(
                out,
                "values",
                format!(
                    "{} values stated for a frame of {quantity} register(s)",
                    values.len()
                ),
            );
        }
    }

    fn response(&self, f: &Frame, out: &mut Vec<Finding>) {
        let e = self.example;
        let says = e.says.clone().unwrap_or_default();
        let function = f.bytes[f.pdu_start];
        let exception = function & 0x80 != 0;
        if exception {
            let Some(&code) = f.bytes.get(f.pdu_start + 1).filter(|_| f.pdu().len() == 2) else {
                return self.error(
                    out,
                    f.pdu_end.saturating_sub(1),
                    None,
                    format!(
                        "an exception response is the function and one code; this PDU has {} bytes",
                        f.pdu().len()
                    ),
                );
            };
            let listed = &self.drive.protocol().exceptions;
            if !listed.is_empty() && !listed.iter().any(|x| x.code == code) {
                self.error(
                    out,
                    f.pdu_start + 1,
                    None,
                    format!("exception code {code:02X}h is not among the map's exception codes"),
                );
            }
            match says.exception {
                Some(stated) if stated != code => self.error(
                    out,
                    f.pdu_start + 1,
                    None,
                    format!("exception code {code:02X}h, the example says {stated:02X}h"),
                ),
                _ => {}
            }
        } else if let Some(stated) = says.exception {
            self.error(
                out,
                f.pdu_start,
                None,
                format!("function {} is not an exception response; the example says exception {stated:02X}h", fc(function)),
            );
        }
        let Some(req_id) = &e.answers else { return };
        let Some(req_ex) = self.drive.examples().iter().find(|x| x.id == *req_id) else {
            return; // the front end reports it
        };
        let Ok(rf) = frame(req_ex) else { return };
        let Ok(req) = pdu::decode_request(rf.pdu()) else {
            return;
        };
        if rf.slave != f.slave {
            let at = if e.transport == TransportName::Tcp {
                6
            } else {
                0
            };
            self.error(
                out,
                at,
                None,
                format!(
                    "slave {:02X}h answers `{req_id}`, which is addressed to slave {:02X}h",
                    f.slave, rf.slave
                ),
            );
        }
        if e.transport == TransportName::Tcp && rf.bytes[..2] != f.bytes[..2] {
            self.error(
                out,
                0,
                None,
                format!(
                    "transaction {} does not echo `{req_id}`'s {}",
                    hex_text(&f.bytes[..2]),
                    hex_text(&rf.bytes[..2])
                ),
            );
        }
        let response = match pdu::decode_response(&req, f.pdu()) {
            Ok(r) => r,
            Err(err) => {
                let at = first_difference(&req, rf.pdu(), f.pdu())
                    .map_or(f.pdu_start, |d| f.pdu_start + d);
                return self.error(out, at, None, format!("does not answer `{req_id}`: {err}"));
            }
        };
        if let (Response::Registers(words), Some(address)) = (response, req.address()) {
            let words: Vec<u16> = words.iter().collect();
            let table = match req {
                Request::ReadInput { .. } => Some(Table::Input),
                _ => None,
            };
            self.registers(
                f,
                out,
                address,
                words.len(),
                table,
                f.pdu_start,
                &words,
                f.pdu_start + 2,
                says.read.as_ref(),
                &says.values,
            );
        }
    }
}

/// Where an echo differs: the index in the response PDU of the first byte of an echoing
/// response (06h, 08h, 10h) that differs from the request's.
fn first_difference(req: &Request<'_>, request_pdu: &[u8], response_pdu: &[u8]) -> Option<usize> {
    if req.is_read() {
        return Some(1); // the byte count
    }
    let echo = request_pdu.len().min(5);
    (0..echo.min(response_pdu.len()))
        .find(|&i| request_pdu[i] != response_pdu[i])
        .or(Some(response_pdu.len().min(echo)))
}
