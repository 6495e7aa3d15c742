//! `drivemap poll --drive <id> [register...] --interval 500ms (--tcp | --rtu-tcp | --serial) ...`

use std::io::{IsTerminal, Write};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Args as ClapArgs;
use drivemap_map::Map;
use drivemap_map::RegisterRef;

use crate::error::Error;
use crate::live::Target;
use crate::live::output::{Emitter, Format, Reading, now_rfc3339};
use crate::live::table::{self, Row};
use drivemap_live::session::{Session, find_all, on_transport};

/// Arguments of `drivemap poll`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    #[command(flatten)]
    pub(crate) target: Target,
    /// Registers by id, parameter number, printed name or address as the manual prints it
    /// (2101H, 0x2101; 45 in a manual numbering registers in decimal); default: the read-only
    /// registers, i.e. the monitor groups, or those of --group.
    #[arg(value_name = "REGISTER")]
    pub(crate) names: Vec<String>,
    /// Poll the readable registers of this group (its id in the map).
    #[arg(long, conflicts_with = "names")]
    pub(crate) group: Option<String>,
    /// Time between polls.
    #[arg(long, default_value = "500ms", value_parser = drivemap_live::duration::parse)]
    pub(crate) interval: Duration,
    /// Stop after this many polls (default: until interrupted).
    #[arg(long)]
    pub(crate) count: Option<u64>,
    /// Output: a live table, JSON lines (one record per register and poll) or CSV rows.
    #[arg(long, value_enum, default_value = "table")]
    pub(crate) format: Format,
}

fn registers<'a>(drive: &'a Map, args: &Args) -> Result<Vec<RegisterRef<'a>>, Error> {
    if !args.names.is_empty() {
        return Ok(find_all(drive, &args.names)?);
    }
    // Registers chosen for the user: those this link can read.
    let kind = args.target.link.kind();
    let pollable =
        |r: RegisterRef<'_>| r.readable() && !r.broadcast_only() && on_transport(drive, r, kind);
    let regs: Vec<RegisterRef<'_>> = match &args.group {
        Some(id) => {
            let Some(gi) = drive.groups().iter().position(|g| &g.id == id) else {
                let ids: Vec<&str> = drive.groups().iter().map(|g| g.id.as_str()).collect();
                return Err(Error::Refused(format!(
                    "{} has no group `{id}`; groups: {}",
                    drive.id(),
                    ids.join(", ")
                )));
            };
            drive
                .registers()
                .filter(|r| std::ptr::eq(r.group(), &drive.groups()[gi]) && pollable(*r))
                .collect()
        }
        None => drive
            .registers()
            .filter(|r| !r.writable() && pollable(*r))
            .collect(),
    };
    if regs.is_empty() {
        return Err(Error::Refused(
            "no readable registers to poll; name some or give --group".into(),
        ));
    }
    Ok(regs)
}

/// Reads the registers every interval and redraws the table; exits 1 when any read failed.
/// Over TCP a connection the drive or gateway closes is re-established before the next request
/// (back-off from 100 ms to 5 s between failed attempts, `ClientOptions::reconnect`); the
/// header counts the reconnects.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = args.target.load()?;
    let regs = registers(&drive, &args)?;
    let given = args.target.settings.resolve(&drive)?;
    crate::output::warn_unprinted(
        &drive,
        &args.target.link,
        &[
            drivemap_runtime::core::stated::ProtocolFact::Serial,
            drivemap_runtime::core::stated::ProtocolFact::MaxRead,
        ],
    );
    let mut session = Session::open(&drive, &args.target.link, given.settings)?;
    for w in session.load_dependencies(&regs, &given.fixed) {
        eprintln!("warning: {w}");
    }
    // A --set the drive gives is checked against it; one it does not is said where used.
    let assumed = session.check_given(&given.given).map_err(Error::Refused)?;
    let mut notes: Vec<String> = Vec::new();
    for r in &regs {
        let n = assumed.for_register(&drive, *r, &session.settings);
        if !n.is_empty() && !notes.contains(&n) {
            notes.push(n);
        }
    }
    for n in notes {
        eprintln!("note: {n}");
    }
    let mut plan = session.plan(&regs)?;
    let tty = std::io::stdout().is_terminal();
    let started = Instant::now();
    let mut previous: Vec<String> = Vec::new();
    let mut any_failed = false;
    let mut n: u64 = 0;
    let mut emitter = Emitter::new(args.format);
    loop {
        let began = Instant::now();
        n += 1;
        // A drive that went silent in the last cycle (or while its settings were read) may be
        // back: this cycle tries again, and stops at its first request that goes unanswered.
        session.silence.rearm();
        let words = session.poll(&mut plan);
        if args.format != Format::Table {
            let time = now_rfc3339();
            let records: Vec<Reading> = regs
                .iter()
                .zip(&words)
                .map(|(r, w)| Reading::of(&session, *r, w, &time))
                .collect();
            any_failed |= records.iter().any(|r| r.status != "ok");
            let mut out = std::io::stdout().lock();
            if emitter
                .write(&mut out, &records, true)
                .and_then(|_| out.flush())
                .is_err()
            {
                break;
            }
            drop(out);
            if args.count.is_some_and(|c| n >= c) {
                break;
            }
            if let Some(rest) = args.interval.checked_sub(began.elapsed()) {
                std::thread::sleep(rest);
            }
            continue;
        }
        let rows: Vec<Row> = regs
            .iter()
            .zip(&words)
            .map(|(r, w)| Row::of(&session, *r, w, false))
            .collect();
        any_failed |= rows.iter().any(|r| r.failed);
        let changed: Vec<bool> = if tty && !previous.is_empty() {
            rows.iter()
                .zip(&previous)
                .map(|(r, p)| &r.value != p)
                .collect()
        } else {
            Vec::new()
        };
        let reconnects = session.client.reconnects();
        let header = format!(
            "{} over {} — poll {n} at {:.1} s, every {} ms{}",
            drive.id(),
            session.link,
            started.elapsed().as_secs_f64(),
            args.interval.as_millis(),
            if reconnects > 0 {
                format!(", reconnected {reconnects} time(s)")
            } else {
                String::new()
            }
        );
        let body = table::render(&rows, &changed);
        let mut out = std::io::stdout().lock();
        let written = if tty {
            write!(out, "\x1b[H\x1b[2J{header}\n\n{body}")
        } else {
            write!(out, "{header}\n{body}\n")
        };
        if written.and_then(|_| out.flush()).is_err() {
            // Standard output closed (a pipe ended): stop quietly.
            break;
        }
        drop(out);
        previous = rows.into_iter().map(|r| r.value).collect();
        if args.count.is_some_and(|c| n >= c) {
            break;
        }
        if let Some(rest) = args.interval.checked_sub(began.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    Ok(if any_failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
