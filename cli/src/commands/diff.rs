//! `drivemap diff <old.yaml> <new.yaml>` and `drivemap diff --git <rev> [map]`

use std::collections::BTreeSet;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_map::Map;
use drivemap_review::diff::{self, DriveDiff, render};
use drivemap_review::review::Manuals;

use crate::error::Error;
use crate::git;
use crate::maps::{MapsDir, loader_for};

/// Output format of `drivemap diff` (see [`render::Format`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Format {
    /// Plain text for a terminal.
    Text,
    /// Markdown, for pasting into a review; quotes the manual line each side cites.
    Md,
    /// GitHub workflow annotations on the changed lines of the map (`::error` for breaking
    /// changes, `::warning` for the rest).
    Github,
    /// JSON for tools: every change with its kind, severity, both sides, both citations and
    /// the manual lines they point at.
    Json,
}

impl From<Format> for render::Format {
    fn from(f: Format) -> render::Format {
        match f {
            Format::Text => render::Format::Text,
            Format::Md => render::Format::Md,
            Format::Github => render::Format::Github,
            Format::Json => render::Format::Json,
        }
    }
}

/// Arguments of `drivemap diff`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// The old map file; with `--git`, the map to compare (a file or a drive id; every map of
    /// the maps directory when omitted).
    pub(crate) old: Option<PathBuf>,
    /// The new map file.
    #[arg(conflicts_with = "git")]
    pub(crate) new: Option<PathBuf>,
    /// Compare the working tree with this git revision (`HEAD`, `main`, `HEAD~3`).
    #[arg(long, value_name = "REV")]
    pub(crate) git: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    pub(crate) format: Format,
    /// Print every kind of change with its classification (breaking or compatible) and why.
    #[arg(long, conflicts_with_all = ["old", "new", "git"])]
    pub(crate) kinds: bool,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
}

fn read(path: &Path, manuals_near: &Path) -> Result<Map, Error> {
    let drive = loader_for(manuals_near)
        .load(path)
        .map_err(|d| format!("{d}"))?;
    warn_schema(&drive, None);
    Ok(drive)
}

/// Prints what reading a map of an earlier schema version changed (the map is compared by its
/// meaning all the same); `rename` shows a temporary directory as the revision it holds.
fn warn_schema(drive: &Map, rename: Option<(&Path, &str)>) {
    let show = |text: String| match rename {
        Some((tmp, shown)) => text.replace(&tmp.display().to_string(), shown),
        None => text,
    };
    // The file's warning says what changed; the values read so are listed by `check`.
    if let Some(first) = drive.warnings().first() {
        eprintln!("{}", show(first.as_warning()));
    }
    if drive.warnings().len() > 1 {
        eprintln!(
            "{}: note: {} address(es) and code(s) of it are written in decimal; `drivemap check` \
             lists them",
            show(drive.file().display().to_string()),
            drive.warnings().len() - 1
        );
    }
}

/// Reads a map of revision `rev` written to the temporary directory `tmp`, naming it
/// `rev:dir/name` in errors and warnings instead of the temporary path.
fn read_at_rev(path: &Path, manuals_near: &Path, tmp: &Path, shown: &str) -> Result<Map, Error> {
    let drive = loader_for(manuals_near)
        .load(path)
        .map_err(|d| format!("{d}").replace(&tmp.display().to_string(), shown))?;
    warn_schema(&drive, Some((tmp, shown)));
    Ok(drive)
}

/// Compares maps and prints the changes; exits 1 when any is breaking.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    if args.kinds {
        out!("{}", render::kinds(args.format.into()));
        return Ok(ExitCode::SUCCESS);
    }
    let diffs = match &args.git {
        Some(rev) => from_git(&args, rev)?,
        None => {
            let (Some(old), Some(new)) = (&args.old, &args.new) else {
                return Err(Error::Refused(
                    "give two map files, or --git <rev> [map]".into(),
                ));
            };
            let read = |path: &Path| {
                let drive = loader_for(new)
                    .any_file_name()
                    .load(path)
                    .map_err(|d| format!("{d}"))?;
                warn_schema(&drive, None);
                Ok::<_, String>(drive)
            };
            vec![diff::compare(&read(old)?, &read(new)?)]
        }
    };
    let manuals = manuals_for(&args, &diffs);
    let out = match args.format {
        Format::Text => {
            let color = std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none();
            render::text(&diffs, color)
        }
        Format::Md => render::markdown(&diffs, manuals.as_ref()),
        Format::Github => render::github(&diffs, manuals.as_ref()),
        Format::Json => render::json(&diffs, manuals.as_ref()),
    };
    out!("{out}");
    let breaking = diffs.iter().any(|d| d.breaking() > 0);
    Ok(if breaking {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// The manuals the changes cite, read from the manuals directory found from the new map, the
/// old map or the maps directory, when there is one.
fn manuals_for(args: &Args, diffs: &[DriveDiff]) -> Option<Manuals> {
    let maps = args
        .dir
        .maps
        .clone()
        .unwrap_or_else(|| PathBuf::from("maps"))
        .join("x.yaml");
    let candidates = [
        args.new.as_deref(),
        args.old.as_deref(),
        Some(maps.as_path()),
    ];
    let dir = candidates
        .into_iter()
        .flatten()
        .find_map(crate::maps::manuals_dir_for)?;
    let mut manuals = Manuals::new(&dir);
    for c in diffs.iter().flat_map(|d| d.changes.iter()) {
        for s in [&c.old_source, &c.new_source].into_iter().flatten() {
            if let Some((file, _)) = drivemap_map::facts::parse_citation(s) {
                manuals.load(file);
            }
        }
    }
    Some(manuals)
}

fn yaml_names(dir: &Path) -> BTreeSet<String> {
    drivemap_map::find_maps(dir)
        .unwrap_or_default()
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect()
}

fn from_git(args: &Args, rev: &str) -> Result<Vec<DriveDiff>, Error> {
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
                (args.dir.dir(), Some(vec![format!("{text}.yaml")]))
            }
        }
        None => (args.dir.dir(), None),
    };
    let then = git::maps_at(&dir, rev)?;
    let names: Vec<String> = match names {
        Some(n) => n,
        None => yaml_names(&dir)
            .union(&yaml_names(then.path()))
            .cloned()
            .collect(),
    };
    let near = dir.join("x.yaml");
    let shown = format!("{rev}:{}", dir.display());
    let old_read = |p: &Path| read_at_rev(p, &near, then.path(), &shown);
    let mut diffs = Vec::new();
    for name in names {
        let (old, new) = (then.path().join(&name), dir.join(&name));
        let diff = match (old.is_file(), new.is_file()) {
            (true, true) => diff::compare(&old_read(&old)?, &read(&new, &near)?),
            (false, true) => diff::added(&read(&new, &near)?),
            (true, false) => diff::removed(&old_read(&old)?),
            (false, false) => {
                return Err(Error::Refused(format!(
                    "{name} is neither in {} nor at revision {rev}",
                    dir.display()
                )));
            }
        };
        diffs.push(diff);
    }
    Ok(diffs)
}
