//! `drivemap doc (<map.yaml> | --drive <id>) [-o file.md]`

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;

use crate::error::Error;
use crate::maps::{MapSource, MapsDir};
use drivemap_review::reference;

/// Arguments of `drivemap doc`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// Map file to document.
    #[arg(conflicts_with = "drive", required_unless_present = "drive")]
    pub(crate) file: Option<PathBuf>,
    /// Drive id: a built-in map, or `<maps>/<id>.yaml`.
    #[arg(long)]
    pub(crate) drive: Option<String>,
    /// Write the Markdown here instead of standard output.
    #[arg(short = 'o', long = "output")]
    pub(crate) output: Option<PathBuf>,
    /// Regenerate every generated document of the map under DIR (the repository's `docs`): the
    /// reference `DIR/drives/<id>.md` and the generated section of `DIR/coverage/<id>.md`
    /// (created with a title when new; the text around the section is kept). The tests compare
    /// both with the map.
    #[arg(long, value_name = "DIR", conflicts_with = "output")]
    pub(crate) docs: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
}

/// Writes the Markdown reference of one map.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
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
        (None, None) => return Err(Error::Refused("give a map file or --drive <id>".into())),
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
    if let Some(docs) = &args.docs {
        return write_docs(docs, &path, &drive, &text, &args);
    }
    match &args.output {
        Some(out) => {
            std::fs::write(out, &text).map_err(Error::io(out.display()))?;
            eprintln!(
                "wrote {}: {} registers, {} lines",
                out.display(),
                drive.registers().len(),
                text.lines().count()
            );
        }
        None => out!("{text}"),
    }
    Ok(ExitCode::SUCCESS)
}

/// `--docs DIR`: the reference and the coverage section of one map.
fn write_docs(
    docs: &std::path::Path,
    path: &std::path::Path,
    drive: &drivemap_map::Map,
    reference: &str,
    args: &Args,
) -> Result<ExitCode, Error> {
    use crate::commands::coverage;
    let id = &drive.id();
    if !path.is_file() {
        return Err(Error::Refused(format!(
            "{}: not a file; the coverage document is made from the map's text beside its \
             manuals (give --maps DIR)",
            path.display()
        )));
    }
    let write = |file: PathBuf, text: &str| -> Result<PathBuf, Error> {
        if let Some(dir) = file.parent() {
            std::fs::create_dir_all(dir).map_err(Error::io(dir.display()))?;
        }
        if std::fs::read_to_string(&file).ok().as_deref() != Some(text) {
            std::fs::write(&file, text).map_err(Error::io(file.display()))?;
        }
        Ok(file)
    };
    let refpath = write(docs.join("drives").join(format!("{id}.md")), reference)?;
    outln!(
        "{}: {} registers, {} lines",
        refpath.display(),
        drive.registers().len(),
        reference.lines().count()
    );
    let report = coverage::report_for(path, &args.dir)?;
    let covpath = docs.join("coverage").join(format!("{id}.md"));
    let old = std::fs::read_to_string(&covpath).unwrap_or_else(|_| {
        format!(
            "# Coverage: {} {} (`maps/{id}.yaml`)\n\n",
            drive.meta().vendor,
            drive.meta().models.join(" / ")
        )
    });
    let covpath = write(
        covpath,
        &coverage::splice(&old, &coverage::markdown(&report)),
    )?;
    outln!("{}: {}", covpath.display(), coverage::totals(&report));
    Ok(ExitCode::SUCCESS)
}
