//! `drivemap diff <old.yaml> <new.yaml>` and `drivemap diff --git <rev> [map]`

use std::collections::BTreeSet;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_codegen::Drive;
use drivemap_codegen::validate::Context;

use crate::diff::{self, DriveDiff, render::Format};
use crate::maps::{MapsDir, context_for};

/// Arguments of `drivemap diff`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The old map file; with `--git`, the map to compare (a file or a drive id; every map of
    /// the maps directory when omitted).
    pub old: Option<PathBuf>,
    /// The new map file.
    #[arg(conflicts_with = "git")]
    pub new: Option<PathBuf>,
    /// Compare the working tree with this git revision (`HEAD`, `main`, `HEAD~3`).
    #[arg(long, value_name = "REV")]
    pub git: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
    /// Print every kind of change with its classification (breaking or compatible) and why.
    #[arg(long, conflicts_with_all = ["old", "new", "git"])]
    pub kinds: bool,
    #[command(flatten)]
    pub dir: MapsDir,
}

fn read(path: &Path, ctx: &Context) -> Result<Drive, String> {
    drivemap_codegen::read_map(path, ctx).map_err(|d| format!("{d}"))
}

/// Compares maps and prints the changes; exits 1 when any is breaking.
pub fn run(args: Args) -> Result<ExitCode, String> {
    if args.kinds {
        out!("{}", diff::render::kinds(args.format));
        return Ok(ExitCode::SUCCESS);
    }
    let diffs = match &args.git {
        Some(rev) => from_git(&args, rev)?,
        None => {
            let (Some(old), Some(new)) = (&args.old, &args.new) else {
                return Err("give two map files, or --git <rev> [map]".into());
            };
            let ctx = context_for(new);
            vec![diff::compare(&read(old, &ctx)?, &read(new, &ctx)?)]
        }
    };
    let out = match args.format {
        Format::Text => {
            let color = std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none();
            diff::render::text(&diffs, color)
        }
        Format::Md => diff::render::markdown(&diffs),
    };
    out!("{out}");
    let breaking = diffs.iter().any(|d| d.breaking() > 0);
    Ok(if breaking {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn yaml_names(dir: &Path) -> BTreeSet<String> {
    drivemap_codegen::find_maps(dir)
        .unwrap_or_default()
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect()
}

fn from_git(args: &Args, rev: &str) -> Result<Vec<DriveDiff>, String> {
    // A map is named by path (it may be gone from the working tree) or by drive id.
    let (dir, names): (PathBuf, Option<Vec<String>>) = match &args.old {
        Some(map) => {
            let text = map.to_string_lossy();
            let is_path =
                map.components().count() > 1 || text.ends_with(".yaml") || text.ends_with(".yml");
            if is_path {
                let dir = map
                    .parent()
                    .filter(|p| !p.as_os_str().is_empty())
                    .unwrap_or(Path::new("."))
                    .to_path_buf();
                let name = map
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .ok_or_else(|| format!("{}: not a map file", map.display()))?;
                (dir, Some(vec![name]))
            } else {
                (args.dir.maps.clone(), Some(vec![format!("{text}.yaml")]))
            }
        }
        None => (args.dir.maps.clone(), None),
    };
    let then = diff::git::maps_at(&dir, rev)?;
    let names: Vec<String> = match names {
        Some(n) => n,
        None => yaml_names(&dir)
            .union(&yaml_names(then.path()))
            .cloned()
            .collect(),
    };
    let ctx = context_for(&dir.join("x.yaml"));
    let mut diffs = Vec::new();
    for name in names {
        let (old, new) = (then.path().join(&name), dir.join(&name));
        let diff = match (old.is_file(), new.is_file()) {
            (true, true) => diff::compare(&read(&old, &ctx)?, &read(&new, &ctx)?),
            (false, true) => diff::added(&read(&new, &ctx)?),
            (true, false) => diff::removed(&read(&old, &ctx)?),
            (false, false) => {
                return Err(format!(
                    "{name} is neither in {} nor at revision {rev}",
                    dir.display()
                ));
            }
        };
        diffs.push(diff);
    }
    Ok(diffs)
}
