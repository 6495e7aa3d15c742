//! `drivemap save --drive <id> (--tcp | --gateway | --rtu-tcp | --serial) ... [-o set.yaml]`

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_live::paramset;
use drivemap_live::session::Session;

use crate::error::Error;
use crate::live::Target;
use crate::live::output::now_rfc3339;

/// Arguments of `drivemap save`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    #[command(flatten)]
    pub(crate) target: Target,
    /// Write the set to this file (default: standard output).
    #[arg(short = 'o', long, value_name = "FILE")]
    pub(crate) output: Option<PathBuf>,
}

/// Reads every setting of the drive (planned requests) and writes the parameter set; exits 1
/// when some settings could not be read (they are listed in the set's `unread`).
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = args.target.load()?;
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
    let count = paramset::settings_of(&drive).len();
    let tty = std::io::stderr().is_terminal();
    let bar = tty.then(|| {
        let bar = indicatif::ProgressBar::new(count as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} settings read")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let started = std::time::Instant::now();
    let report = paramset::save_with(&mut session, &now_rfc3339(), &mut |done, _| {
        if let Some(bar) = &bar {
            bar.set_position(done as u64);
        }
    })?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    if let Some(why) = session.silence.report() {
        return Err(Error::Refused(format!(
            "{} did not answer: {why}; no set written",
            session.link
        )));
    }
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    for (_, why) in paramset::left_out(&drive) {
        eprintln!("note: {why}");
    }
    let text = report.set.to_yaml(&drive);
    match &args.output {
        Some(path) => std::fs::write(path, &text).map_err(|source| Error::Io {
            what: format!("writing {}", path.display()),
            source,
        })?,
        None => out!("{text}"),
    }
    eprintln!(
        "saved {} of {count} settings of {} at slave {} in {} requests, {:.1} s{}",
        report.set.settings.len(),
        drive.id(),
        report.set.slave,
        report.requests,
        started.elapsed().as_secs_f64(),
        if report.set.unread.is_empty() {
            String::new()
        } else {
            format!(
                "; {} not read (listed under unread)",
                report.set.unread.len()
            )
        }
    );
    Ok(if report.set.unread.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
