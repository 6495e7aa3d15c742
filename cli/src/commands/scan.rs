//! `drivemap scan (--serial PATH | --tcp ADDR | --rtu-tcp ADDR) [--slaves 1-247] [--baud ...]
//! [--parity ...]`: what is on this line?
//!
//! For each baud rate and parity asked (serial only), sends one read of one register to every
//! slave address asked, waiting at most the drives' response time (from the maps' timing, or
//! `--timeout`): any reply — values or an exception — means a slave is there. The register is
//! the one readable in the most candidate maps. Then, for each slave that answered, reads the
//! monitor (read-only) registers of every candidate map and ranks the maps by how many of those
//! reads the slave answers with a value the map allows. Never writes.

use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{ArgGroup, Args as ClapArgs};
use drivemap_live::LiveSettings;
use drivemap_map::Map;
use drivemap_map::RegisterRef;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::error::Error;
use drivemap_runtime::transport::serial::char_times;

use crate::error::Error as CliError;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;

use super::probe::{Check, check_value};
use crate::live::output::Format;
use crate::maps::MapsDir;
use drivemap_live::link::{Link, ParityParser};
use drivemap_live::session::{Session, on_transport};
use drivemap_runtime::core::profile::Parity;

/// Monitor registers read per candidate map when identifying a slave.
const MAX_IDENTIFY_REGISTERS: usize = 48;

/// Arguments of `drivemap scan`.
#[derive(ClapArgs, Debug)]
#[command(group(ArgGroup::new("link").required(true).args(["tcp", "gateway", "rtu_tcp", "serial"])))]
pub(crate) struct Args {
    /// Modbus TCP server (`192.168.1.10:502`): drives with a Modbus TCP interface of their own
    /// (candidate maps without `tcp` in `protocol.transports` are not identified here).
    #[arg(long, value_name = "ADDR")]
    pub(crate) tcp: Option<String>,
    /// Modbus TCP to RTU gateway with the drives on its serial line (`192.168.1.20:502`):
    /// candidates are identified by their RTU addresses and registers.
    #[arg(long, value_name = "HOST:PORT")]
    pub(crate) gateway: Option<String>,
    /// RTU frames over TCP through a transparent serial gateway (`192.168.1.20:4001`).
    #[arg(long = "rtu-tcp", value_name = "ADDR")]
    pub(crate) rtu_tcp: Option<String>,
    /// Serial port speaking Modbus RTU (`/dev/ttyUSB0`).
    #[arg(long, value_name = "PATH")]
    pub(crate) serial: Option<String>,
    /// Modbus ASCII instead of RTU, on --serial or --rtu-tcp: only candidate maps that list
    /// `ascii` in `protocol.transports` are tried (the line's data bits are the first one's).
    #[arg(long, conflicts_with_all = ["tcp", "gateway"])]
    pub(crate) ascii: bool,
    /// Slave addresses to try: `1-247` (the Modbus serial-line range, the default), `1,2,5`,
    /// `1-10,31`; up to 255 where a manual gives more (ACN CM.01: 1-250).
    #[arg(long, default_value = "1-247", value_parser = parse_slaves)]
    pub(crate) slaves: SlaveList,
    /// Baud rates to try on --serial, comma-separated (default: the candidate maps' defaults).
    #[arg(long, value_delimiter = ',')]
    pub(crate) baud: Vec<u32>,
    /// Parities to try on --serial, comma-separated (default: the candidate maps' defaults).
    #[arg(long, value_parser = ParityParser, value_delimiter = ',')]
    pub(crate) parity: Vec<Parity>,
    /// Longest wait for each probe (default: from the maps' timing and the line speed).
    #[arg(long, value_parser = drivemap_live::duration::positive)]
    pub(crate) timeout: Option<Duration>,
    /// Candidate maps by drive id (default: every map known).
    #[arg(long = "drive", value_name = "ID")]
    pub(crate) drives: Vec<String>,
    /// Output: a table for eyes, JSON, or CSV (one row per slave and candidate map).
    #[arg(long, value_enum, default_value = "table")]
    pub(crate) format: Format,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
}

/// Slave addresses, in order, without repeats.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SlaveList(pub(crate) Vec<u8>);

/// The profile of the probe reads: generic Modbus, with every slave address a manual may give
/// (the ACN's CM.01 goes to 250; some manuals print 01H-FEH), not only the standard's 1-247.
static PROBE: Profile = Profile {
    slave_max: 255,
    ..Profile::GENERIC
};

/// Parses `1-247`, `1,2,5`, `1-10,31`: addresses 1-255 (0 is broadcast, which nobody answers).
pub(crate) fn parse_slaves(text: &str) -> Result<SlaveList, CliError> {
    let mut out: Vec<u8> = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let num = |s: &str| -> Result<u8, CliError> {
            match s.trim().parse::<u8>() {
                Ok(n) if n >= 1 => Ok(n),
                _ => Err(CliError::Refused(format!(
                    "`{s}` is not a slave address 1-255"
                ))),
            }
        };
        let (a, b) = match part.split_once('-') {
            Some((a, b)) => (num(a)?, num(b)?),
            None => (num(part)?, num(part)?),
        };
        if a > b {
            return Err(CliError::Refused(format!(
                "`{part}`: the range runs backwards"
            )));
        }
        for n in a..=b {
            if !out.contains(&n) {
                out.push(n);
            }
        }
    }
    if out.is_empty() {
        return Err(CliError::Refused("no slave address given".into()));
    }
    Ok(SlaveList(out))
}

/// The JSON report (`drivemap-scan/1`).
#[derive(Debug, Serialize)]
pub(crate) struct Report {
    pub(crate) format: &'static str,
    pub(crate) link: String,
    /// Line settings tried (serial), e.g. `9600 8E1`; `-` on TCP.
    pub(crate) lines: Vec<String>,
    pub(crate) slaves_tried: usize,
    pub(crate) probe_timeout_ms: u64,
    /// The register every slave was asked for.
    pub(crate) probe: String,
    pub(crate) elapsed_ms: u64,
    pub(crate) found: Vec<Found>,
    /// Why the probes that got no answer got none, counted by cause.
    pub(crate) unanswered: Unanswered,
}

/// Why probes got no answer, by cause: with 0 answered, this is what tells a quiet line (or
/// wrong settings) from a peer that floods it.
#[derive(Debug, Default, Serialize)]
pub(crate) struct Unanswered {
    /// Nothing (or nothing acceptable) arrived within the probe timeout.
    pub(crate) no_reply: usize,
    /// More bytes arrived than any answer could take: the peer floods the link.
    pub(crate) flooded: usize,
    /// The probe was held back: after an unanswered probe the RTU line never fell silent long
    /// enough to tell a late reply from the next answer (bytes kept arriving).
    pub(crate) never_silent: usize,
    /// The link failed (closed, reset).
    pub(crate) link_failed: usize,
    /// Anything else (refused before sending).
    pub(crate) other: usize,
    /// The first error of each cause seen, as the client said it.
    pub(crate) examples: Vec<String>,
}

impl Unanswered {
    fn count(&mut self, e: &Error) {
        let slot = match e {
            Error::Timeout { .. } => &mut self.no_reply,
            Error::Overrun { .. } => &mut self.flooded,
            Error::Unsettled { .. } => &mut self.never_silent,
            Error::Io { .. } => &mut self.link_failed,
            _ => &mut self.other,
        };
        if *slot == 0 {
            self.examples.push(e.to_string());
        }
        *slot += 1;
    }

    fn total(&self) -> usize {
        self.no_reply + self.flooded + self.never_silent + self.link_failed + self.other
    }

    /// "why no answer: 247 flooded (the peer floods the link), ..." or nothing.
    fn summary(&self) -> Option<String> {
        if self.total() == 0 {
            return None;
        }
        let parts: Vec<String> = [
            (self.flooded, "flooded: the peer sent more bytes than any answer, without the answer"),
            (self.never_silent, "held back: the line never fell silent after an unanswered probe (bytes kept arriving)"),
            (self.no_reply, "no reply within the probe timeout"),
            (self.link_failed, "the link failed"),
            (self.other, "refused before sending"),
        ]
        .into_iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, why)| format!("{n} {why}"))
        .collect();
        Some(format!(
            "why no answer ({} probe(s)): {}",
            self.total(),
            parts.join("; ")
        ))
    }
}

/// A slave that answered.
#[derive(Debug, Serialize)]
pub(crate) struct Found {
    pub(crate) slave: u8,
    pub(crate) line: String,
    /// What it answered to the probe: the word, or the exception.
    pub(crate) answer: String,
    /// Candidate maps, best first.
    pub(crate) maps: Vec<Candidate>,
}

/// How a slave answered one map's monitor registers.
#[derive(Debug, Serialize)]
pub(crate) struct Candidate {
    pub(crate) drive: String,
    /// Monitor registers read.
    pub(crate) tried: usize,
    /// Answered with a value the map allows.
    pub(crate) consistent: usize,
    /// Answered with a value outside the map's range or codes.
    pub(crate) inconsistent: usize,
    /// Refused with an exception.
    pub(crate) refused: usize,
    /// No reply, or not converted.
    pub(crate) unanswered: usize,
    /// `consistent / tried`.
    pub(crate) score: f64,
}

#[derive(Clone, Copy)]
struct Line {
    baud: u32,
    parity: Parity,
}

fn line_text(kind_serial: bool, line: Line, drive: &Map, base: &Link) -> String {
    if !kind_serial {
        return "-".into();
    }
    let mut l = base.clone();
    l.baud = Some(line.baud);
    l.parity = Some(line.parity);
    let (baud, parity, stops) = l.line(drive);
    format!("{baud} {}{}{stops}", l.data_bits(drive), parity.letter())
}

/// The longest time any candidate drive takes to answer a one-register read at `baud`:
/// request and reply on the wire (11 bits a character), the drive's response delay from its
/// map (bit times, microseconds, the delay parameter's factory setting), plus 20 ms for USB
/// adapters and scheduling.
pub(crate) fn probe_timeout(profiles: &[&Profile], baud: Option<u32>) -> Duration {
    let baud = baud.unwrap_or(9600).max(300);
    let wire = char_times(8.0 + 7.0, baud);
    let bit = Duration::from_secs_f64(1.0 / f64::from(baud));
    let delay = profiles
        .iter()
        .map(|p| {
            let t = &p.timing;
            bit * t.response_delay_bits.unwrap_or(0)
                + Duration::from_micros(u64::from(t.response_delay_us.unwrap_or(0)))
                + Duration::from_micros(u64::from(t.response_delay_param_default_us.unwrap_or(0)))
        })
        .max()
        .unwrap_or_default();
    wire + delay + Duration::from_millis(20)
}

/// The least pause between requests any candidate drive asks for.
fn request_gap(profiles: &[&Profile], baud: Option<u32>) -> Duration {
    let bit = Duration::from_secs_f64(1.0 / f64::from(baud.unwrap_or(9600).max(300)));
    profiles
        .iter()
        .map(|p| {
            bit * p.timing.request_gap_bits.unwrap_or(0)
                + Duration::from_micros(u64::from(p.timing.request_gap_us.unwrap_or(0)))
        })
        .max()
        .unwrap_or_default()
}

/// The holding register readable in the most candidate maps on this link (lowest address on
/// a tie), as a PDU address.
fn probe_address(drives: &[Map], base: &Link) -> u16 {
    let kind = base.kind();
    let mut counts: std::collections::BTreeMap<u16, usize> = Default::default();
    for d in drives {
        let settings = LiveSettings::default();
        let profile = drivemap_live::leak_profile(d);
        let mut seen = std::collections::BTreeSet::new();
        for r in readable_monitors(d, kind, usize::MAX) {
            if r.plan().info.table != drivemap_runtime::core::register::Table::Holding {
                continue;
            }
            let a = drivemap_live::session::address_of(d, r, &settings, kind);
            let Some(pdu) = profile.address_offsets.pdu_address(a, kind) else {
                continue;
            };
            if seen.insert(pdu) {
                *counts.entry(pdu).or_default() += 1;
            }
        }
    }
    counts
        .iter()
        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
        .map(|(a, _)| *a)
        .unwrap_or(0)
}

/// Read-only registers this link can read, at most `max`.
fn readable_monitors(
    d: &Map,
    kind: drivemap_runtime::core::profile::TransportKind,
    max: usize,
) -> Vec<RegisterRef<'_>> {
    d.registers()
        .filter(|r| r.readable() && !r.writable() && !r.broadcast_only())
        .filter(|&r| on_transport(d, r, kind))
        .take(max)
        .collect()
}

/// Reads a map's monitors from a slave and counts how the answers fit the map.
fn identify(drive: &Map, link: &Link) -> Candidate {
    let mut c = Candidate {
        drive: drive.id().to_owned(),
        tried: 0,
        consistent: 0,
        inconsistent: 0,
        refused: 0,
        unanswered: 0,
        score: 0.0,
    };
    let regs = readable_monitors(drive, link.kind(), MAX_IDENTIFY_REGISTERS);
    c.tried = regs.len();
    let Ok(mut session) = Session::open(drive, link, LiveSettings::default()) else {
        c.unanswered = c.tried;
        return c;
    };
    session.silence.disable();
    let _ = session.load_dependencies(&regs, &Default::default());
    let Ok(mut plan) = session.plan(&regs) else {
        c.unanswered = c.tried;
        return c;
    };
    let (words, _) = session.poll_detailed(&mut plan);
    for (r, w) in regs.iter().zip(&words) {
        match w {
            Ok(raw) => match check_value(drive, *r, *raw, &session) {
                Check::Agrees => c.consistent += 1,
                Check::Disagrees(..) => c.inconsistent += 1,
                Check::Unchecked(_) => c.unanswered += 1,
            },
            Err(f) if f.exception.is_some() => c.refused += 1,
            Err(_) => c.unanswered += 1,
        }
    }
    if c.tried > 0 {
        c.score = c.consistent as f64 / c.tried as f64;
    }
    c
}

/// Scans and prints; exit status 0 when any slave answered, 1 when none did.
pub(crate) fn run(args: Args) -> Result<ExitCode, CliError> {
    let ids: Vec<String> = if args.drives.is_empty() {
        args.dir.known().into_keys().collect()
    } else {
        args.drives.clone()
    };
    let mut drives: Vec<Map> = ids
        .iter()
        .map(|id| args.dir.load(id))
        .collect::<Result<_, _>>()?;
    if args.ascii {
        // A drive whose map does not list ASCII would not read the frames.
        drives.retain(|d| {
            d.protocol()
                .transports
                .contains(&drivemap_map::facts::TransportName::Ascii)
        });
        if drives.is_empty() {
            return Err(CliError::Refused(
                "--ascii: no candidate map lists `ascii` in protocol.transports".into(),
            ));
        }
    }
    let Some(first) = drives.first() else {
        return Err(CliError::Refused("no candidate maps".into()));
    };
    let profiles: Vec<&'static Profile> = drives.iter().map(drivemap_live::leak_profile).collect();
    let base = Link {
        tcp: args.tcp.clone(),
        gateway: args.gateway.clone(),
        rtu_tcp: args.rtu_tcp.clone(),
        serial: args.serial.clone(),
        ascii: args.ascii,
        data_bits: None,
        baud: None,
        parity: None,
        stop_bits: None,
        slave: None,
        timeout: Some(Duration::from_secs(1)),
        retries: 0,
        request_gap: Some(Duration::ZERO),
    };
    // What the scan relies on that a map marks not printed: the slave range (then 1-247 is
    // scanned) and the serial settings (then the runtime's defaults are tried).
    for d in &drives {
        for w in drivemap_live::unprinted::warnings(
            d,
            &base,
            &[
                drivemap_runtime::core::stated::ProtocolFact::SlaveAddress,
                drivemap_runtime::core::stated::ProtocolFact::Serial,
            ],
            Some(&args.slaves.0),
        ) {
            eprintln!("{w}");
        }
    }
    let serial = args.serial.is_some();
    let mut bauds = args.baud.clone();
    let mut parities = args.parity.clone();
    if serial {
        for d in &drives {
            let (b, p, _) = base.line(d);
            if args.baud.is_empty() && !bauds.contains(&b) {
                bauds.push(b);
            }
            if args.parity.is_empty() && !parities.contains(&p) {
                parities.push(p);
            }
        }
    }
    let lines: Vec<Option<Line>> = if serial {
        bauds
            .iter()
            .flat_map(|&baud| {
                parities
                    .iter()
                    .map(move |&parity| Some(Line { baud, parity }))
            })
            .collect()
    } else {
        vec![None]
    };
    let slaves = &args.slaves.0;
    let probe_pdu = probe_address(&drives, &base);
    let total = (lines.len() * slaves.len()) as u64;
    let bar = ProgressBar::with_draw_target(
        Some(total),
        if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed}] {bar:30} {pos}/{len} {msg}")
            .map_err(|e| e.to_string())?,
    );
    let started = Instant::now();
    let mut found: Vec<(u8, Option<Line>, String)> = Vec::new();
    let mut unanswered = Unanswered::default();
    let mut timeout_used = Duration::ZERO;
    let mut link_text = String::new();
    for line in &lines {
        let mut link = base.clone();
        if let Some(l) = line {
            link.baud = Some(l.baud);
            link.parity = Some(l.parity);
        }
        let timeout = args.timeout.unwrap_or_else(|| {
            probe_timeout(&profiles, link.baud) * if args.ascii { 2 } else { 1 }
        });
        link.timeout = Some(timeout);
        link.request_gap = Some(request_gap(&profiles, link.baud));
        timeout_used = timeout_used.max(timeout);
        let (mut client, text) = link.connect(first, &PROBE)?;
        link_text = match (&args.serial, text.rsplit_once(", slave")) {
            (Some(path), _) if args.ascii => format!("ASCII {path}"),
            (Some(path), _) => format!("RTU {path}"),
            (None, Some((a, _))) => a.to_string(),
            (None, None) => text,
        };
        let shown = line
            .map(|l| line_text(serial, l, first, &base))
            .unwrap_or_else(|| "-".into());
        bar.set_message(shown.clone());
        for &slave in slaves {
            let mut w = [0u16; 1];
            let answer = match client.read_holding(slave, probe_pdu, &mut w) {
                Ok(()) => Some(format!("{:04X}h", w[0])),
                Err(Error::Exception { exception, .. }) => Some(format!(
                    "exception {:02X}h ({})",
                    exception.code, exception.name
                )),
                Err(e) => {
                    unanswered.count(&e);
                    None
                }
            };
            if let Some(a) = answer {
                bar.println(format!("slave {slave} answered at {shown}: {a}"));
                found.push((slave, *line, a));
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let mut report_found = Vec::new();
    for (slave, line, answer) in found {
        let mut link = base.clone();
        link.slave = Some(slave);
        if let Some(l) = line {
            link.baud = Some(l.baud);
            link.parity = Some(l.parity);
        }
        link.timeout = Some(args.timeout.unwrap_or_else(|| {
            // An ASCII frame is about twice as many characters.
            probe_timeout(&profiles, link.baud) * if args.ascii { 2 } else { 1 }
        }));
        link.request_gap = Some(request_gap(&profiles, link.baud));
        let mut maps: Vec<Candidate> = drives.iter().map(|d| identify(d, &link)).collect();
        maps.sort_by(|a, b| {
            b.score
                .total_cmp(&a.score)
                .then(b.consistent.cmp(&a.consistent))
                .then(a.inconsistent.cmp(&b.inconsistent))
                .then(a.drive.cmp(&b.drive))
        });
        report_found.push(Found {
            slave,
            line: line
                .map(|l| line_text(serial, l, first, &base))
                .unwrap_or_else(|| "-".into()),
            answer,
            maps,
        });
    }
    let report = Report {
        format: "drivemap-scan/1",
        link: link_text,
        lines: lines
            .iter()
            .map(|l| {
                l.map(|l| line_text(serial, l, first, &base))
                    .unwrap_or_else(|| "-".into())
            })
            .collect(),
        slaves_tried: slaves.len(),
        probe_timeout_ms: timeout_used.as_millis() as u64,
        probe: format!("03h read of PDU {probe_pdu:04X}h x1"),
        elapsed_ms: started.elapsed().as_millis() as u64,
        found: report_found,
        unanswered,
    };
    match args.format {
        Format::Table => out!("{}", table(&report)),
        Format::Json => outln!("{}", serde_json::to_string_pretty(&report)?),
        Format::Csv => out!("{}", csv_rows(&report)?),
    }
    Ok(if report.found.is_empty() {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn table(r: &Report) -> String {
    let mut out = format!(
        "scan of {}: {} slave address(es) x {} line setting(s) ({}), {} each, at most {} ms a probe: {} answered in {:.1} s\n",
        r.link,
        r.slaves_tried,
        r.lines.len(),
        r.lines.join(", "),
        r.probe,
        r.probe_timeout_ms,
        r.found.len(),
        r.elapsed_ms as f64 / 1000.0
    );
    if let Some(why) = r.unanswered.summary() {
        out += &why;
        out += "\n";
        if r.found.is_empty() {
            for e in &r.unanswered.examples {
                out += &format!("  e.g. {e}\n");
            }
        }
    }
    if r.found.is_empty() {
        return out;
    }
    out += "SLAVE  LINE       ANSWER     MAPS (monitor reads consistent with the map / read)\n";
    for f in &r.found {
        let maps: Vec<String> = f
            .maps
            .iter()
            .filter(|m| m.consistent > 0)
            .map(|m| format!("{} {}/{}", m.drive, m.consistent, m.tried))
            .collect();
        out += &format!(
            "{:<5}  {:<9}  {:<9}  {}\n",
            f.slave,
            f.line,
            f.answer,
            if maps.is_empty() {
                "no map fits".into()
            } else {
                maps.join(", ")
            }
        );
    }
    out
}

fn csv_rows(r: &Report) -> Result<String, CliError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "slave",
        "line",
        "answer",
        "rank",
        "drive",
        "score",
        "consistent",
        "inconsistent",
        "refused",
        "unanswered",
        "tried",
    ])?;
    for f in &r.found {
        for (i, m) in f.maps.iter().enumerate() {
            w.write_record([
                f.slave.to_string(),
                f.line.clone(),
                f.answer.clone(),
                (i + 1).to_string(),
                m.drive.clone(),
                format!("{:.3}", m.score),
                m.consistent.to_string(),
                m.inconsistent.to_string(),
                m.refused.to_string(),
                m.unanswered.to_string(),
                m.tried.to_string(),
            ])?;
        }
    }
    let bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8(bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slave_lists() {
        assert_eq!(parse_slaves("1-3,7,2").unwrap().0, vec![1, 2, 3, 7]);
        assert_eq!(parse_slaves("1-247").unwrap().0.len(), 247);
        // Beyond the serial-line standard where a manual allows it (ACN 1-250), never 0 or 256.
        assert_eq!(parse_slaves("248-250").unwrap().0, vec![248, 249, 250]);
        assert!(parse_slaves("0").is_err());
        assert!(parse_slaves("250-256").is_err());
        assert_eq!(PROBE.slave_max, 255);
        assert!(parse_slaves("5-2").is_err());
    }

    #[test]
    fn the_probe_timeout_follows_the_line_speed_and_the_slowest_drive() {
        let fast = probe_timeout(&[&Profile::GENERIC], Some(19200));
        let slow = probe_timeout(&[&Profile::GENERIC], Some(1200));
        assert!(fast < slow, "{fast:?} {slow:?}");
        // 15 characters at 1200 baud is 137.5 ms on the wire.
        assert!(slow >= Duration::from_millis(150), "{slow:?}");
    }
}
