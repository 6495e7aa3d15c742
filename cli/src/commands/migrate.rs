//! `drivemap migrate <map>...`: rewrites maps written in an earlier schema version in the
//! current one, keeping their meaning (see `drivemap_map::migrate`).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use crate::error::Error;
use clap::Args as ClapArgs;
use drivemap_map::migrate as schema;

/// Arguments of `drivemap migrate`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// Map files to rewrite in place.
    #[arg(required = true)]
    pub(crate) files: Vec<PathBuf>,
    /// Print what would change and write nothing; exit 1 if any file is not in the current
    /// schema.
    #[arg(long)]
    pub(crate) check: bool,
}

pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let mut failed = false;
    let mut outdated = false;
    for path in &args.files {
        let text = std::fs::read_to_string(path).map_err(Error::io(path.display()))?;
        let name: Arc<str> = schema::display_name(path);
        let migrated = match schema::migrate(&name, &text) {
            Ok(m) => m,
            Err(errors) => {
                for e in errors.iter() {
                    eprintln!("{e}");
                }
                failed = true;
                continue;
            }
        };
        if migrated.from >= schema::CURRENT {
            outln!("{name}: already schema {}", schema::CURRENT);
            continue;
        }
        outdated = true;
        for r in &migrated.rewritten {
            outln!("{}: `{}` -> `{}` ({})", r.loc, r.text, r.hex(), r.path);
        }
        let done = if args.check {
            "would be rewritten (nothing written)"
        } else {
            "rewritten"
        };
        outln!(
            "{name}: schema {} -> {}, {} value(s) {done}; same meaning",
            migrated.from,
            schema::CURRENT,
            migrated.rewritten.len()
        );
        if !args.check {
            std::fs::write(path, &migrated.text).map_err(Error::io(path.display()))?;
        }
    }
    Ok(if failed || (args.check && outdated) {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
