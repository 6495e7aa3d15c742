//! `drivemap check <map>...`

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;

use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Map files to check (default: every map in the maps directory).
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub dir: MapsDir,
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let files = if args.files.is_empty() {
        drivemap_codegen::find_maps(&args.dir.maps)
            .map_err(|e| format!("{}: {e}", args.dir.maps.display()))?
    } else {
        args.files
    };
    let mut failed = 0;
    let mut errors = 0;
    for file in &files {
        match args.dir.read(file) {
            Ok(drive) => outln!(
                "ok   {} ({}: {} registers)",
                file.display(),
                drive.meta.id,
                drive.registers.len()
            ),
            Err(diags) => {
                failed += 1;
                errors += diags.len();
                for d in diags.iter() {
                    eprintln!("{d}");
                }
                outln!(
                    "FAIL {} ({} error{})",
                    file.display(),
                    diags.len(),
                    if diags.len() == 1 { "" } else { "s" }
                );
            }
        }
    }
    if failed > 0 {
        eprintln!(
            "{failed} of {} map(s) failed with {errors} error(s)",
            files.len()
        );
        Ok(ExitCode::FAILURE)
    } else {
        Ok(ExitCode::SUCCESS)
    }
}
