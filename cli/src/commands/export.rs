//! `drivemap export (<map.yaml> | --drive <id>)`

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;

use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Map file to export.
    #[arg(conflicts_with = "drive", required_unless_present = "drive")]
    pub file: Option<PathBuf>,
    /// Drive id: a built-in map, or `<maps>/<id>.yaml`.
    #[arg(long)]
    pub drive: Option<String>,
    #[command(flatten)]
    pub dir: MapsDir,
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let read = match (&args.file, &args.drive) {
        (Some(f), _) => args.dir.read(f),
        (None, Some(id)) => match args.dir.load(id) {
            Ok(d) => Ok(d),
            Err(e) => return Err(e),
        },
        (None, None) => return Err("give a map file or --drive <id>".into()),
    };
    match read {
        Ok(drive) => {
            let json = drivemap_codegen::export::export(&drive);
            outln!(
                "{}",
                serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(diags) => {
            eprintln!("{diags}");
            Ok(ExitCode::FAILURE)
        }
    }
}
