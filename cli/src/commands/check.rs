//! `drivemap check <map>...`

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;

use drivemap_codegen::{Diagnostics, Drive};

use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Map files to check (default: every map of --maps, else every built-in map).
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub dir: MapsDir,
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let files: Vec<(String, Result<Drive, Diagnostics>)> = if !args.files.is_empty() {
        let read = |f: &PathBuf| (f.display().to_string(), args.dir.read(f));
        args.files.iter().map(read).collect()
    } else if let Some(dir) = &args.dir.maps {
        drivemap_codegen::find_maps(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .iter()
            .map(|f| (f.display().to_string(), args.dir.read(f)))
            .collect()
    } else {
        // The built-in maps.
        crate::maps::BUILTIN_MAPS
            .iter()
            .map(|(id, text)| {
                let r = args.dir.read_builtin(id, text);
                (format!("<built-in>/{id}.yaml"), r)
            })
            .collect()
    };
    let mut failed = 0;
    let mut errors = 0;
    for (file, read) in files.iter() {
        match read {
            Ok(drive) => println!(
                "ok   {} ({}: {} registers)",
                file,
                drive.meta.id,
                drive.registers.len()
            ),
            Err(diags) => {
                failed += 1;
                errors += diags.len();
                for d in diags.iter() {
                    eprintln!("{d}");
                }
                println!(
                    "FAIL {} ({} error{})",
                    file,
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
