//! `drivemap restore set.yaml --drive <id> (--tcp | --gateway | --rtu-tcp | --serial) ... [--dry-run]`

use std::io::IsTerminal;
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_live::paramset::{self, Progress, StoreOutcome};
use drivemap_live::session::Session;

use crate::error::Error;
use crate::live::Target;

/// Arguments of `drivemap restore`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// The parameter set (`drivemap save`).
    #[arg(value_name = "SET")]
    pub(crate) set: String,
    #[command(flatten)]
    pub(crate) target: Target,
    /// Read the drive and print the writes, in order, without writing anything.
    #[arg(long = "dry-run")]
    pub(crate) dry_run: bool,
    /// Restore a set of another map or variant (refused without it, naming what differs).
    #[arg(long)]
    pub(crate) other: bool,
    /// Run the map's store command (ENTER, save) even when nothing differs: after a restore
    /// whose writes all went through but whose store command failed.
    #[arg(long)]
    pub(crate) store: bool,
}

/// Validates the whole set, reads the drive, writes what differs in the map's dependency order,
/// stores once, reads back. Exits 0 when the drive holds the set, verified; 1 when a write,
/// the store or a read-back failed (the report says which settings are in which state: run
/// it again, it writes only what still differs); 2 when the set is refused (nothing written).
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = args.target.load()?;
    let set = super::compare::read_set(&args.set)?;
    let given = args.target.settings.resolve(&drive)?;
    let validated = paramset::validate(&drive, &set, &given.settings, args.other)
        .map_err(|e| Error::Refused(e.to_string()))?;
    crate::output::warn_unprinted(
        &drive,
        &args.target.link,
        &[
            drivemap_runtime::core::stated::ProtocolFact::Serial,
            drivemap_runtime::core::stated::ProtocolFact::MaxRead,
            drivemap_runtime::core::stated::ProtocolFact::MaxWrite,
        ],
    );
    let mut session = Session::open(&drive, &args.target.link, given.settings)?;
    let mut plan =
        paramset::plan(&mut session, &validated).map_err(|e| Error::Refused(e.to_string()))?;
    if args.store && plan.store.is_none() {
        plan.store = paramset::store_command(&drive);
        if plan.store.is_none() {
            return Err(Error::Refused(format!(
                "{} has no store command (protocol.commands of kind persist)",
                drive.id()
            )));
        }
    }
    for w in &plan.warnings {
        eprintln!("note: {w}");
    }
    outln!(
        "{} of {} settings differ on slave {} over {}{}",
        plan.writes.len(),
        validated.entries.len(),
        session.slave,
        session.link,
        if args.dry_run {
            "; would write, in this order:"
        } else {
            ""
        }
    );
    if args.dry_run {
        for (i, w) in plan.writes.iter().enumerate() {
            outln!(
                "{:>4}. {}: {} -> {}",
                i + 1,
                w.register.label(),
                w.from.as_deref().unwrap_or("(not read)"),
                shown(w)
            );
        }
        if let Some(c) = plan.store {
            outln!("then {} ({}): one EEPROM write", c.id, c.name);
        }
        return Ok(ExitCode::SUCCESS);
    }
    let tty = std::io::stderr().is_terminal();
    let bar = (tty && !plan.writes.is_empty()).then(|| {
        let bar = indicatif::ProgressBar::new(plan.writes.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let mut progress = |p: &Progress| {
        if let Some(bar) = &bar {
            match p {
                Progress::Writing { done, id, .. } => {
                    bar.set_position(*done as u64);
                    bar.set_message(format!("writing {id}"));
                }
                Progress::Storing(c) => bar.set_message(format!("running {c}")),
                Progress::Verifying(n) => bar.set_message(format!("reading back {n}")),
            }
        }
    };
    let report = paramset::execute(&mut session, &plan, &mut progress);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    for id in &report.verified {
        outln!("written and verified: {}", name(&drive, id));
    }
    for s in &report.not_verified {
        outln!(
            "written, not verified: {}: {}",
            name(&drive, &s.id),
            s.reason
        );
    }
    for s in &report.not_written {
        outln!("not written: {}: {}", name(&drive, &s.id), s.reason);
    }
    match &report.store {
        StoreOutcome::NotNeeded => {}
        StoreOutcome::Stored { wear, .. } => outln!("stored: {wear}"),
        StoreOutcome::NotRun(why) => outln!("not stored: {why}"),
        StoreOutcome::Failed(why) => outln!("store failed: {why}"),
    }
    outln!(
        "{} written and verified, {} written but not verified, {} not written, {} already held the set's value",
        report.verified.len(),
        report.not_verified.len(),
        report.not_written.len(),
        report.unchanged
    );
    Ok(if report.complete() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn name(drive: &drivemap_map::Map, id: &str) -> String {
    drive
        .register_by_id(id)
        .map_or_else(|| id.to_owned(), |r| r.label())
}

/// The set's value with the register's unit.
fn shown(w: &paramset::Write<'_>) -> String {
    let unit = w.register.plan().unit;
    if unit.is_empty() || w.to.parse::<f64>().is_err() {
        w.to.clone()
    } else {
        format!("{} {unit}", w.to)
    }
}
