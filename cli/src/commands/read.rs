//! `drivemap read --drive <id> <register|param>... (--tcp | --rtu-tcp | --serial) ...`

use std::process::ExitCode;

use clap::Args as ClapArgs;

use crate::error::Error;
use crate::live::Target;
use crate::live::output::{Emitter, Format, Reading, now_rfc3339};
use crate::live::table::{self, Row};
use drivemap_live::session::{Session, find_all};

/// Arguments of `drivemap read`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    #[command(flatten)]
    pub(crate) target: Target,
    /// Registers by id, parameter number, printed name or address as the manual prints it
    /// (2101H, 0x2101; 45 in a manual numbering registers in decimal), or entries of an
    /// indexed register by id, parameter number or printed name (read through its index).
    #[arg(required = true, value_name = "REGISTER")]
    pub(crate) names: Vec<String>,
    /// Output: an aligned table, JSON (an array of records) or CSV.
    #[arg(long, value_enum, default_value = "table")]
    pub(crate) format: Format,
}

/// Reads the named registers and prints them decoded; exits 1 when any failed.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = args.target.load()?;
    let (names, entries) = super::entries::split(&drive, &args.names);
    if !entries.is_empty() {
        return super::entries::read(&drive, &args.target, &names, &entries);
    }
    let regs = find_all(&drive, &args.names)?;
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
    let words = session.read_words(&regs)?;
    // Said once for the command: what went unanswered and what was then not sent.
    if let Some(why) = session.silence.report() {
        eprintln!("drivemap: {} did not answer: {why}", session.link);
    }
    if args.format != Format::Table {
        let time = now_rfc3339();
        let records: Vec<Reading> = regs
            .iter()
            .zip(&words)
            .map(|(r, w)| Reading::of(&session, *r, w, &time))
            .collect();
        let mut out = std::io::stdout().lock();
        Emitter::new(args.format)
            .write(&mut out, &records, false)
            .map_err(Error::io("writing standard output"))?;
        return Ok(if records.iter().any(|r| r.status != "ok") {
            ExitCode::FAILURE
        } else {
            ExitCode::SUCCESS
        });
    }
    let rows: Vec<Row> = regs
        .iter()
        .zip(&words)
        .map(|(r, w)| Row::of(&session, *r, w, true))
        .collect();
    out!("{}", table::render(&rows, &[]));
    Ok(if rows.iter().any(|r| r.failed) {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
