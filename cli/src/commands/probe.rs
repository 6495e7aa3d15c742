//! `drivemap probe --drive <id> (--tcp | --rtu-tcp | --serial) ...`: is this map right for the
//! drive in front of me?
//!
//! Reads every register of the map this link can read, in the requests the runtime's planner
//! chooses (a request the drive refuses is split so each register gets its own answer), and
//! never writes. Reports what disagrees with the map: registers the drive refuses (an exception
//! reply, 02h "illegal data address" for a register it does not have), values outside the map's
//! range (under the scale selected and references read), codes the map does not list, reserved
//! bits set; the scale selectors and references read first; and what it could not check.
//! Exit status: 0 when everything read agrees, 1 when anything disagrees, 2 on an error.

use drivemap_runtime::core::plan::Conversion;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_live::codec;
use drivemap_map::Map;
use drivemap_map::RegisterRef;
use drivemap_runtime::core::scale::ValueError;
use serde::Serialize;

use crate::error::Error;
use crate::live::Target;
use crate::live::output::{Format, address_text, now_rfc3339};
use drivemap_live::session::{Failure, Session, on_transport};
use drivemap_map::describe;

/// Arguments of `drivemap probe`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    #[command(flatten)]
    pub(crate) target: Target,
    /// Output: a summary for eyes, the JSON report, or one CSV row per register.
    #[arg(long, value_enum, default_value = "table")]
    pub(crate) format: Format,
    /// Also write the JSON report to this file (to attach to a map's pull request).
    #[arg(long, value_name = "FILE")]
    pub(crate) report: Option<PathBuf>,
}

/// The JSON report (`drivemap-probe/1`).
#[derive(Debug, Serialize)]
pub(crate) struct Report {
    pub(crate) format: &'static str,
    pub(crate) drive: String,
    pub(crate) map_version: Option<String>,
    pub(crate) link: String,
    pub(crate) slave: u8,
    pub(crate) time: String,
    /// Scale selectors and references conversions depend on: given or read first.
    pub(crate) settings: Vec<Setting>,
    /// Registers read and compared with the map.
    pub(crate) checked: usize,
    /// Of those, how many agree.
    pub(crate) agreed: usize,
    /// Requests sent for the registers (splits included).
    pub(crate) requests: u32,
    pub(crate) disagreements: Vec<Finding>,
    /// Registers of the map not checked, each with why.
    pub(crate) unchecked: Vec<Finding>,
    /// Other parts of the map a read cannot check.
    pub(crate) not_checkable: Vec<String>,
    pub(crate) warnings: Vec<String>,
}

/// A scale selector or reference value.
#[derive(Debug, Serialize)]
pub(crate) struct Setting {
    pub(crate) register: String,
    pub(crate) parameter: Option<String>,
    pub(crate) role: &'static str,
    pub(crate) value: String,
    pub(crate) origin: &'static str,
}

/// One register's result.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Finding {
    /// `refused`, `out_of_range`, `unlisted_code`, `reserved_bits`, `no_reply`,
    /// `not_on_link`, `write_only`, `broadcast_only`, `not_converted`.
    pub(crate) kind: &'static str,
    pub(crate) register: String,
    pub(crate) parameter: Option<String>,
    /// The address on this link, a number.
    pub(crate) address: u16,
    /// The same address in the manual's notation (`0024h`).
    pub(crate) address_text: String,
    pub(crate) raw: Option<u32>,
    pub(crate) exception: Option<u8>,
    pub(crate) detail: String,
    /// Where the map says what it says.
    pub(crate) source: Option<String>,
}

/// Arguments bundle for [`run_probe`], for tests.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = args.target.load()?;
    let report = run_probe(&drive, &args.target)?;
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(path) = &args.report {
        std::fs::write(path, format!("{json}\n"))
            .map_err(Error::io(format!("writing {}", path.display())))?;
    }
    match args.format {
        Format::Table => out!("{}", summary(&report)),
        Format::Json => outln!("{json}"),
        Format::Csv => out!("{}", csv_rows(&report)?),
    }
    Ok(if report.disagreements.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn finding(
    session: &Session<'_>,
    r: RegisterRef<'_>,
    kind: &'static str,
    detail: String,
) -> Finding {
    Finding {
        kind,
        register: r.id().to_owned(),
        parameter: r.param().map(str::to_owned),
        address: session.shown_address(r),
        address_text: address_text(session.drive, session.shown_address(r)),
        raw: None,
        exception: None,
        detail,
        source: r.source().map(str::to_owned),
    }
}

/// Reads the drive against its map and builds the report.
pub(crate) fn run_probe(drive: &Map, target: &Target) -> Result<Report, Error> {
    let given = target.settings.resolve(drive)?;
    crate::output::warn_unprinted(
        drive,
        &target.link,
        &[
            drivemap_runtime::core::stated::ProtocolFact::Serial,
            drivemap_runtime::core::stated::ProtocolFact::MaxRead,
        ],
    );
    let mut session = Session::open(drive, &target.link, given.settings)?;
    let mut unchecked = Vec::new();
    let mut readable: Vec<RegisterRef<'_>> = Vec::new();
    for r in drive.registers() {
        if r.broadcast_only() {
            unchecked.push(finding(
                &session,
                r,
                "broadcast_only",
                "broadcast-only: written to slave 0, never read".into(),
            ));
        } else if !r.readable() {
            unchecked.push(finding(&session, r, "write_only", "write-only".into()));
        } else if !on_transport(session.drive, r, session.kind) {
            unchecked.push(finding(
                &session,
                r,
                "not_on_link",
                format!(
                    "exists only on {}",
                    describe::transports(r.plan().transports)
                ),
            ));
        } else {
            readable.push(r);
        }
    }
    // One read first: a drive that is not there is reported after one timeout, not one per
    // planned request.
    if let Some(first) = readable.first() {
        let mut plan = session.plan(std::slice::from_ref(first))?;
        let (words, _) = session.poll_detailed(&mut plan);
        if let Some(Err(f)) = words.first()
            && f.sent
            && f.exception.is_none()
        {
            return Err(Error::Refused(format!(
                "{} did not answer; nothing checked ({})",
                session.link, f.message
            )));
        }
    }
    let mut warnings = session.load_dependencies(&readable, &given.fixed);
    warnings.extend(session.load_limits(&readable, &given.fixed));
    let mut settings = Vec::new();
    for (role, regs) in [
        ("scale selector", drive.selectors()),
        ("reference", drive.references()),
    ] {
        for r in regs {
            let id = r.id();
            let value = match role {
                "scale selector" => session.settings.selectors.get(id).map(|c| c.to_string()),
                _ => session.settings.references.get(id).map(|v| {
                    format!("{v} {}", r.unit().unwrap_or(""))
                        .trim_end()
                        .to_owned()
                }),
            };
            settings.push(Setting {
                register: id.to_owned(),
                parameter: r.param().map(str::to_owned),
                role,
                origin: if given.fixed.contains(id) {
                    "given with --set"
                } else if value.is_some() {
                    "read from the drive"
                } else {
                    "not read: no scale selected needs it, or see the warnings"
                },
                value: value.unwrap_or_default(),
            });
        }
    }
    for q in drive.externals() {
        settings.push(Setting {
            register: q.external.clone(),
            parameter: None,
            role: "external quantity",
            value: session
                .settings
                .references
                .get(&q.external)
                .map(|v| format!("{v} {}", q.unit))
                .unwrap_or_default(),
            origin: "external quantity, not a register: given with --set, else unknown",
        });
    }
    let mut plan = session.plan(&readable)?;
    let (words, requests) = session.poll_detailed(&mut plan);
    if let Some(why) = session.silence.report() {
        warnings.push(format!("{} stopped answering: {why}", session.link));
    }
    let answered = words.iter().any(|w| {
        matches!(
            w,
            Ok(_)
                | Err(Failure {
                    exception: Some(_),
                    ..
                })
        )
    });
    if !answered && !readable.is_empty() {
        let first = words
            .iter()
            .find_map(|w| w.as_ref().err())
            .map(|f| f.message.clone())
            .unwrap_or_default();
        return Err(Error::Refused(format!(
            "{} did not answer any read; nothing checked ({first})",
            session.link
        )));
    }
    let mut disagreements = Vec::new();
    let mut checked = 0;
    for (r, w) in readable.iter().zip(&words) {
        match w {
            Err(f) => {
                if let Some(code) = f.exception {
                    checked += 1;
                    let mut x = finding(&session, *r, "refused", f.message.clone());
                    x.exception = Some(code);
                    disagreements.push(x);
                } else {
                    unchecked.push(finding(&session, *r, "no_reply", f.message.clone()));
                }
            }
            Ok(raw) => match check_value(drive, *r, *raw, &session) {
                Check::Agrees => checked += 1,
                Check::Disagrees(kind, detail) => {
                    checked += 1;
                    let mut x = finding(&session, *r, kind, detail);
                    x.raw = Some(*raw);
                    disagreements.push(x);
                }
                Check::Unchecked(detail) => {
                    let mut x = finding(&session, *r, "not_converted", detail);
                    x.raw = Some(*raw);
                    unchecked.push(x);
                }
            },
        }
    }
    Ok(Report {
        format: "drivemap-probe/1",
        drive: drive.id().to_owned(),
        map_version: None,
        link: session.link.clone(),
        slave: session.slave,
        time: now_rfc3339(),
        settings,
        checked,
        agreed: checked - disagreements.len(),
        requests,
        disagreements,
        unchecked,
        not_checkable: not_checkable(drive, &readable, &session),
        warnings,
    })
}

pub(crate) enum Check {
    Agrees,
    Disagrees(&'static str, String),
    Unchecked(String),
}

/// Whether a word read is a value the map allows: decoded and encoded back as a write would
/// be (range under the selected scale and variant, listed codes), and no reserved bit set.
pub(crate) fn check_value(
    drive: &Map,
    r: RegisterRef<'_>,
    raw: u32,
    session: &Session<'_>,
) -> Check {
    if let Conversion::Bits { mask, .. } = r.plan().conversion {
        let reserved = raw & !u32::from(mask);
        return if reserved == 0 {
            Check::Agrees
        } else {
            Check::Disagrees(
                "reserved_bits",
                format!(
                    "{raw:04X}h sets bit(s) {reserved:04X}h, which the map gives no field; map: {}",
                    r.label()
                ),
            )
        };
    }
    let plan = r.plan();
    if !plan.read_values.is_empty() {
        // A word read means a read code (`read_values`), not a value a write would encode.
        if u16::try_from(raw)
            .ok()
            .and_then(|code| plan.read_label(code))
            .is_some()
        {
            return Check::Agrees;
        }
        let listed: Vec<String> = plan
            .read_values
            .iter()
            .map(|l| l.code.to_string())
            .collect();
        return Check::Disagrees(
            "unlisted_code",
            format!(
                "read code {raw} ({raw:04X}h), which the map's read_values do not list (listed: {})",
                listed.join(", ")
            ),
        );
    }
    if let drivemap_runtime::core::width::Width::Text(_) = plan.info.width {
        // Text: any bytes decode (shown escaped); the map states no range for it.
        return match session.decode(r, raw) {
            Ok(_) => Check::Agrees,
            Err(e) => Check::Unchecked(e.to_string()),
        };
    }
    let value = match codec::decode(drive, r, raw, &session.settings) {
        Ok(v) => v,
        Err(e) => {
            return Check::Unchecked(drivemap_live::session::value_error(drive, &e).to_string());
        }
    };
    let Some(number) = value.as_f64() else {
        return Check::Agrees;
    };
    match codec::encode(drive, r, number, &session.settings) {
        Ok(_) => Check::Agrees,
        Err(ValueError::UnknownCode { .. }) if codes_incomplete(r).is_some() => {
            Check::Unchecked(format!(
                "read code {raw} ({raw:04X}h), which the map does not list; its list is incomplete: {}",
                codes_incomplete(r).unwrap_or_default()
            ))
        }
        Err(ValueError::UnknownCode { .. }) => {
            let listed: Vec<String> = r
                .plan()
                .labels()
                .iter()
                .map(|l| l.code.to_string())
                .collect();
            Check::Disagrees(
                "unlisted_code",
                format!(
                    "read code {raw} ({raw:04X}h), which the map does not list (listed: {})",
                    listed.join(", ")
                ),
            )
        }
        Err(e @ (ValueError::MissingSetting { .. } | ValueError::LimitNotKnown { .. })) => {
            Check::Unchecked(drivemap_live::session::value_error(drive, &e).to_string())
        }
        Err(e) => Check::Disagrees("out_of_range", format!("read {value} ({raw:04X}h): {e}")),
    }
}

/// Why the map's list of codes of `r` is incomplete, when it says so (`unknown: values`): a
/// code it does not list is then not a disagreement.
fn codes_incomplete(r: RegisterRef<'_>) -> Option<&str> {
    r.unknown()
        .iter()
        .find(|u| u.what == drivemap_map::facts::UnknownItem::Values)
        .map(|u| u.reason.as_str())
}

/// What reading cannot check: gaps, unknown ranges, variant-specific ranges without a variant.
fn not_checkable(drive: &Map, readable: &[RegisterRef<'_>], session: &Session<'_>) -> Vec<String> {
    let mut out = Vec::new();
    for g in drive.gaps() {
        let at = match (&g.addresses, &g.params) {
            (Some([a, b]), _) => describe::address_span_as(drive.address_format(), *a, *b),
            (None, Some(p)) => p.clone(),
            (None, None) => String::new(),
        };
        out.push(format!("gap {at}: {} ({})", g.description, g.source));
    }
    let unknown_range: Vec<String> = readable
        .iter()
        .filter(|r| {
            r.unknown()
                .iter()
                .any(|u| u.what == drivemap_map::facts::UnknownItem::Range)
        })
        .map(|r| r.label())
        .collect();
    if !unknown_range.is_empty() {
        out.push(format!(
            "{} register(s) whose range the manual leaves unknown (read, not range-checked): {}",
            unknown_range.len(),
            unknown_range.join(", ")
        ));
    }
    let by_variant: BTreeSet<String> = readable
        .iter()
        .filter(|r| r.variant_options().next().is_some())
        .filter(|r| {
            !r.variant_options()
                .any(|k| session.settings.has_variant(drive, k))
        })
        .map(|r| r.label())
        .collect();
    if !by_variant.is_empty() {
        out.push(format!(
            "{} register(s) with ranges per model variant, checked against the widest since no \
             --variant was given: {}",
            by_variant.len(),
            by_variant.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    out.push(
        "writability, write ranges and defaults: probe never writes; values are checked as read"
            .into(),
    );
    out
}

fn count_by(findings: &[Finding]) -> String {
    let mut kinds: Vec<(&str, usize)> = Vec::new();
    for f in findings {
        match kinds.iter_mut().find(|(k, _)| *k == f.kind) {
            Some((_, n)) => *n += 1,
            None => kinds.push((f.kind, 1)),
        }
    }
    kinds
        .iter()
        .map(|(k, n)| format!("{n} {}", k.replace('_', "-")))
        .collect::<Vec<_>>()
        .join(", ")
}

fn label(f: &Finding) -> String {
    match &f.parameter {
        Some(p) => format!("{} ({p})", f.register),
        None => f.register.clone(),
    }
}

/// The report for eyes.
pub(crate) fn summary(r: &Report) -> String {
    let mut out = format!("probe of {} over {} at {}\n", r.drive, r.link, r.time);
    for s in r.settings.iter().filter(|s| !s.value.is_empty()) {
        let p = s
            .parameter
            .as_deref()
            .map(|p| format!(" ({p})"))
            .unwrap_or_default();
        out += &format!(
            "  {} {}{p} = {} ({})\n",
            s.role, s.register, s.value, s.origin
        );
    }
    for w in &r.warnings {
        out += &format!("  warning: {w}\n");
    }
    out += &format!(
        "checked {} readable register(s) in {} request(s): {} agree, {} disagree\n",
        r.checked,
        r.requests,
        r.agreed,
        r.disagreements.len()
    );
    for f in &r.disagreements {
        out += &format!(
            "  DISAGREE {:<14} {} {}: {}{}\n",
            f.kind.replace('_', "-"),
            label(f),
            f.address_text,
            f.detail,
            f.source
                .as_deref()
                .map(|s| format!(" [map: {s}]"))
                .unwrap_or_default()
        );
    }
    if !r.unchecked.is_empty() {
        out += &format!(
            "not checked: {} register(s): {}\n",
            r.unchecked.len(),
            count_by(&r.unchecked)
        );
        for f in r
            .unchecked
            .iter()
            .filter(|f| matches!(f.kind, "no_reply" | "not_converted"))
        {
            out += &format!("  {} {}: {}\n", label(f), f.address_text, f.detail);
        }
    }
    for n in &r.not_checkable {
        out += &format!("not checkable: {n}\n");
    }
    out += if r.disagreements.is_empty() {
        "result: the drive agrees with the map where it was read\n"
    } else {
        "result: the drive DISAGREES with the map (exit status 1)\n"
    };
    out
}

/// One CSV row per register result: disagreements, then unchecked registers, each naming the
/// drive and slave.
pub(crate) fn csv_rows(r: &Report) -> Result<String, Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "drive",
        "slave",
        "result",
        "kind",
        "register",
        "parameter",
        "address",
        "address_text",
        "raw",
        "exception",
        "detail",
        "source",
    ])?;
    for (result, f) in r
        .disagreements
        .iter()
        .map(|f| ("disagree", f))
        .chain(r.unchecked.iter().map(|f| ("unchecked", f)))
    {
        w.write_record([
            r.drive.clone(),
            r.slave.to_string(),
            result.to_owned(),
            f.kind.to_owned(),
            f.register.clone(),
            f.parameter.clone().unwrap_or_default(),
            f.address.to_string(),
            f.address_text.clone(),
            f.raw.map(|v| v.to_string()).unwrap_or_default(),
            f.exception.map(|v| format!("{v:02X}h")).unwrap_or_default(),
            f.detail.clone(),
            f.source.clone().unwrap_or_default(),
        ])?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8(bytes)?)
}
