//! `drivemap doc (<map.yaml> | --drive <id>) [-o file.md]`

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;

use crate::maps::{MapSource, MapsDir};
use drivemap_codegen::reference;

/// Arguments of `drivemap doc`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Map file to document.
    #[arg(conflicts_with = "drive", required_unless_present = "drive")]
    pub file: Option<PathBuf>,
    /// Drive id: a built-in map, or `<maps>/<id>.yaml`.
    #[arg(long)]
    pub drive: Option<String>,
    /// Write the Markdown here instead of standard output.
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub dir: MapsDir,
}

/// Writes the Markdown reference of one map.
pub fn run(args: Args) -> Result<ExitCode, String> {
    let (path, drive) = match (&args.file, &args.drive) {
        (Some(f), _) => match args.dir.read(f) {
            Ok(drive) => (f.clone(), drive),
            Err(diags) => {
                eprintln!("{diags}");
                return Ok(ExitCode::FAILURE);
            }
        },
        (None, Some(id)) => {
            let path = match args.dir.source_of(id)? {
                MapSource::File(p) => p,
                // Built-in maps are the repository's `maps/<id>.yaml`.
                MapSource::Builtin(_) => PathBuf::from("maps").join(format!("{id}.yaml")),
            };
            (path, args.dir.load(id)?)
        }
        (None, None) => return Err("give a map file or --drive <id>".into()),
    };
    // A stable name for the header: the file name, under `maps/` when it lives there.
    let file = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let in_maps = path
        .parent()
        .and_then(|p| p.file_name())
        .is_some_and(|d| d == "maps");
    let name = if in_maps {
        format!("maps/{file}")
    } else {
        file
    };
    let text = reference::render(&drive, &name);
    match &args.output {
        Some(out) => {
            std::fs::write(out, &text).map_err(|e| format!("{}: {e}", out.display()))?;
            eprintln!(
                "wrote {}: {} registers, {} lines",
                out.display(),
                drive.registers.len(),
                text.lines().count()
            );
        }
        None => out!("{text}"),
    }
    Ok(ExitCode::SUCCESS)
}
