//! Register values for other tools: JSON and CSV (`--format json|csv` of `read` and `poll`).
//!
//! One record per register read, the same fields in both formats:
//!
//! | field | what |
//! |---|---|
//! | `time` | when the value was read, UTC, RFC 3339 with milliseconds |
//! | `drive` | the map's drive id (`ptlk-tds-v8`) |
//! | `slave` | the slave address talked to (0: broadcast) |
//! | `register` | the map's register id |
//! | `parameter` | the manual's parameter number (`Bn-01`), or empty |
//! | `name` | the printed name |
//! | `address` | the register's address as the map (the manual) numbers it, a number (`1`): after the settings and the transport that move it, before the link's address offset |
//! | `address_text` | the same address in the manual's notation (`0001h`, or `45` in a manual numbering registers in decimal) |
//! | `pdu_address` | the address the request carried on the wire (the PDU address: `address` plus the map's offset for this link), a number; empty when the offset puts it outside 0 to 65535 |
//! | `value` | the number: engineering value, plain word, enumeration code, or the raw bits |
//! | `unit` | the unit of `value`, or empty |
//! | `text` | the value as the table shows it (`48.00 Hz`, `2: Remote`, `0019h [running, ready]`) |
//! | `raw` | the word read, as a decimal number |
//! | `status` | `ok` or `error` |
//! | `error` | why the value is missing or could not be decoded |
//!
//! JSON adds `fields` for bit registers (`{"running": 1, ...}`). The JSON Schema of a record is
//! `docs/schema/reading.schema.json`.

use std::collections::BTreeMap;
use std::io::Write;
use std::time::{SystemTime, UNIX_EPOCH};

use clap::ValueEnum;
use drivemap_live::codec::Value;
use drivemap_map::Map;
use drivemap_map::RegisterRef;
use drivemap_map::facts::AddressFormat;
use serde::Serialize;

use drivemap_live::session::{ReadError, Session};
use drivemap_map::describe;

/// How values are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub(crate) enum Format {
    /// An aligned table for eyes.
    #[default]
    Table,
    /// JSON (`read`: an array; `poll`: one object a line).
    Json,
    /// CSV with a header line.
    Csv,
}

/// One register's value as a record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Reading {
    pub(crate) time: String,
    pub(crate) drive: String,
    pub(crate) slave: u8,
    pub(crate) register: String,
    pub(crate) parameter: Option<String>,
    pub(crate) name: String,
    pub(crate) address: u16,
    pub(crate) address_text: String,
    pub(crate) pdu_address: Option<u16>,
    pub(crate) value: Option<f64>,
    pub(crate) unit: Option<String>,
    pub(crate) text: Option<String>,
    pub(crate) raw: Option<u32>,
    pub(crate) status: &'static str,
    pub(crate) error: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) fields: Option<BTreeMap<String, u16>>,
}

/// The CSV header, in record order.
pub(crate) const CSV_HEADER: [&str; 15] = [
    "time",
    "drive",
    "slave",
    "register",
    "parameter",
    "name",
    "address",
    "address_text",
    "pdu_address",
    "value",
    "unit",
    "text",
    "raw",
    "status",
    "error",
];

impl Reading {
    /// The record of a register read as `word` (or its error) at `time`.
    pub(crate) fn of(
        session: &Session<'_>,
        r: RegisterRef<'_>,
        word: &Result<u32, ReadError>,
        time: &str,
    ) -> Reading {
        let address = session.shown_address(r);
        let mut rec = Reading {
            time: time.to_owned(),
            drive: session.drive.id().to_owned(),
            slave: session.slave,
            register: r.id().to_owned(),
            parameter: r.param().map(str::to_owned),
            name: r.name().to_owned(),
            address,
            address_text: address_text(session.drive, address),
            pdu_address: pdu_address(session.drive, address, session.kind),
            value: None,
            unit: None,
            text: None,
            raw: None,
            status: "error",
            error: None,
            fields: None,
        };
        match word {
            Err(e) => rec.error = Some(e.to_string()),
            Ok(raw) => {
                rec.raw = Some(*raw);
                match session.decode(r, *raw) {
                    Err(e) => rec.error = Some(e.to_string()),
                    Ok(v) => {
                        rec.status = "ok";
                        rec.value = v.as_f64();
                        rec.text = Some(v.to_string());
                        if let Some(text) = v.text() {
                            // A string: the whole text, escaped, unquoted (the record's own
                            // quoting holds it); its first word alone is no raw value.
                            rec.text = Some(text);
                            rec.raw = None;
                        }
                        match &v {
                            Value::Quantity { unit, .. } if !unit.is_empty() => {
                                rec.unit = Some(unit.clone())
                            }
                            Value::Bits { fields, .. } => {
                                rec.fields =
                                    Some(fields.iter().map(|f| (f.id.clone(), f.value)).collect())
                            }
                            _ => {}
                        }
                    }
                }
            }
        }
        rec
    }

    fn csv_record(&self) -> [String; 15] {
        let opt = |o: &Option<String>| o.clone().unwrap_or_default();
        [
            self.time.clone(),
            self.drive.clone(),
            self.slave.to_string(),
            self.register.clone(),
            opt(&self.parameter),
            self.name.clone(),
            self.address.to_string(),
            self.address_text.clone(),
            self.pdu_address.map(|a| a.to_string()).unwrap_or_default(),
            self.value.map(|v| v.to_string()).unwrap_or_default(),
            opt(&self.unit),
            opt(&self.text),
            self.raw.map(|v| v.to_string()).unwrap_or_default(),
            self.status.to_owned(),
            opt(&self.error),
        ]
    }
}

/// The PDU address `address` (the map's) goes on the wire as on a link of `kind`: the map's
/// `protocol.addressing` offset for that transport applied; `None` outside 0 to 65535.
pub(crate) fn pdu_address(
    drive: &Map,
    address: u16,
    kind: drivemap_runtime::core::profile::TransportKind,
) -> Option<u16> {
    let (rtu, tcp) = drive.address_offsets();
    drivemap_runtime::core::profile::AddressOffsets { rtu, tcp }.pdu_address(address, kind)
}

/// An address in the notation of the drive's manual: `0024h`, or the plain number in a manual
/// that numbers its registers in decimal (`address_format: decimal`).
pub(crate) fn address_text(drive: &Map, address: u16) -> String {
    match drive.address_format() {
        AddressFormat::Decimal => address.to_string(),
        AddressFormat::Hex => describe::address(address),
    }
}

/// Writes records as JSON (an array, or one object a line) or CSV (the header once).
pub(crate) struct Emitter {
    format: Format,
    header_written: bool,
}

impl Emitter {
    pub(crate) fn new(format: Format) -> Emitter {
        Emitter {
            format,
            header_written: false,
        }
    }

    /// Writes `records`: JSON lines when `lines`, else one JSON array; CSV rows after the
    /// header (written before the first batch).
    pub(crate) fn write(
        &mut self,
        out: &mut impl Write,
        records: &[Reading],
        lines: bool,
    ) -> std::io::Result<()> {
        match self.format {
            Format::Table => Ok(()),
            Format::Json if lines => {
                for r in records {
                    serde_json::to_writer(&mut *out, r)?;
                    out.write_all(b"\n")?;
                }
                Ok(())
            }
            Format::Json => {
                serde_json::to_writer_pretty(&mut *out, records)?;
                out.write_all(b"\n")
            }
            Format::Csv => {
                let mut w = csv::WriterBuilder::new().from_writer(&mut *out);
                if !self.header_written {
                    w.write_record(CSV_HEADER)?;
                    self.header_written = true;
                }
                for r in records {
                    w.write_record(r.csv_record())?;
                }
                w.flush()
            }
        }
    }
}

/// Now, UTC, RFC 3339 with milliseconds: `2026-11-25T07:47:01.123Z`.
pub(crate) fn now_rfc3339() -> String {
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    rfc3339(now.as_secs(), now.subsec_millis())
}

/// Seconds since 1970 as an RFC 3339 UTC time (days to civil date: H. Hinnant's algorithm).
pub(crate) fn rfc3339(secs: u64, millis: u32) -> String {
    let days = (secs / 86_400) as i64;
    let s = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{millis:03}Z",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rfc3339_dates() {
        assert_eq!(rfc3339(0, 0), "1970-01-01T00:00:00.000Z");
        assert_eq!(rfc3339(951_782_400, 5), "2000-02-29T00:00:00.005Z");
        assert_eq!(rfc3339(1_795_599_999, 999), "2026-11-25T09:46:39.999Z");
    }

    #[test]
    fn csv_quotes_and_writes_the_header_once() {
        let r = Reading {
            time: "t".into(),
            drive: "ptlk-tds-v8".into(),
            slave: 1,
            register: "inverter_status".into(),
            parameter: None,
            name: "Inverter status".into(),
            address: 32,
            address_text: "0020h".into(),
            pdu_address: Some(31),
            value: Some(25.0),
            unit: None,
            text: Some("0019h [running, ready]".into()),
            raw: Some(25),
            status: "ok",
            error: None,
            fields: None,
        };
        let mut e = Emitter::new(Format::Csv);
        let mut out = Vec::new();
        e.write(&mut out, std::slice::from_ref(&r), true).unwrap();
        e.write(&mut out, &[r], true).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], CSV_HEADER.join(","));
        assert_eq!(
            lines[1],
            "t,ptlk-tds-v8,1,inverter_status,,Inverter status,32,0020h,31,25,,\"0019h [running, ready]\",25,ok,"
        );
    }
}
