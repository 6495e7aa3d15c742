//! `drivemap import --manual FILE... --id ID`: a draft map from a manual's own text, every row
//! cited, nothing invented (the reader is `drivemap-import`); `--merge MAP` sets the manual's rows
//! against an existing map instead: rows the map lacks, and fields where the two disagree.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args as ClapArgs;

use crate::error::Error;
use crate::maps::MapsDir;

/// Arguments of `drivemap import`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// A manual's text (OCR text as in shared/manuals) or a PDF (its text is extracted with
    /// poppler's `pdftotext -layout` and kept beside the draft as `<name>.txt`, which the draft
    /// cites); repeat for a drive with several manuals. Citations name the file by its file name.
    #[arg(long = "manual", value_name = "FILE", required = true)]
    pub manuals: Vec<PathBuf>,
    /// The drive id of the draft (`acme-vf2`); the draft's file should be `<id>.yaml`.
    #[arg(long, value_name = "ID", required_unless_present = "merge")]
    pub id: Option<String>,
    /// Read rows only from this line on (1-based, in every manual).
    #[arg(long, value_name = "N")]
    pub start_line: Option<usize>,
    /// Read rows only up to this line (inclusive).
    #[arg(long, value_name = "M")]
    pub end_line: Option<usize>,
    /// Write the draft (or the merge report) here instead of standard output.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Write the report of lines not used as rows (with why) and of what to confirm here.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Compare with this map (a file, or a drive id): propose only rows it lacks and report the
    /// rows where it and the manual disagree.
    #[arg(long, value_name = "MAP")]
    pub merge: Option<PathBuf>,
    /// Name the columns of the table whose header is on line LINE, left to right (the report
    /// names the tables and columns the reader could not decide): `--columns
    /// 12:address,name,min,max,default,unit`. Roles: address, reference, param, name, access,
    /// unit, resolution, factor, exponent, range, min, max, default, type, size, description,
    /// skip. Repeat for several tables.
    #[arg(long = "columns", value_name = "LINE:ROLES")]
    pub columns: Vec<String>,
    /// Where `--merge` looks a drive id up.
    #[command(flatten)]
    pub dir: MapsDir,
}

/// Runs `drivemap import`.
pub fn run(a: Args) -> Result<ExitCode, Error> {
    let mut columns = std::collections::BTreeMap::new();
    for c in &a.columns {
        let (line, roles) = c.split_once(':').ok_or_else(|| {
            Error::Refused(format!(
                "--columns {c}: write the header's line and the roles, `12:address,name,unit`"
            ))
        })?;
        let line: usize = line
            .trim()
            .parse()
            .map_err(|_| Error::Refused(format!("--columns {c}: `{line}` is not a line number")))?;
        let roles = drivemap_import::columns::parse_roles(roles)
            .map_err(|e| Error::Refused(format!("--columns {c}: {e}")))?;
        columns.insert(line, roles);
    }
    let mut texts = Vec::new();
    for path in &a.manuals {
        let is_pdf = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("pdf"));
        let (file, text) = if is_pdf {
            pdf_text(path, a.output.as_deref())?
        } else {
            let text = std::fs::read_to_string(path).map_err(Error::io(path.display()))?;
            let file = path
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .ok_or_else(|| format!("{}: not a file", path.display()))?;
            (file, text)
        };
        texts.push((file, text));
    }
    let lines = match (a.start_line, a.end_line) {
        (None, None) => None,
        (s, e) => {
            let (s, e) = (s.unwrap_or(1), e.unwrap_or(usize::MAX));
            if s == 0 || e < s {
                return Err(Error::Refused(format!(
                    "--start-line {s} --end-line {e}: not a range of lines (1-based, start <= end)"
                )));
            }
            Some((s, e))
        }
    };
    let manuals: Vec<drivemap_import::Manual<'_>> = texts
        .iter()
        .map(|(file, text)| drivemap_import::Manual { file, text })
        .collect();
    let command = std::env::args()
        .skip(1)
        .map(|a| if a.contains(' ') { format!("'{a}'") } else { a })
        .collect::<Vec<_>>()
        .join(" ");
    let id = match (&a.id, &a.merge) {
        (Some(id), _) => id.clone(),
        (None, Some(m)) => m
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        (None, None) => unreachable!("clap requires --id or --merge"),
    };
    let import = drivemap_import::import_with(
        &id,
        &manuals,
        lines,
        &columns,
        &format!("drivemap {command}"),
    );
    if let Some(report) = &a.report {
        std::fs::write(report, drivemap_import::report(&import))
            .map_err(Error::io(report.display()))?;
    }
    let out = match &a.merge {
        Some(map) => {
            let drive = a.dir.read(map).map_err(|d| format!("{d}"))?;
            let known = drivemap_import::known::registers(drive.ir());
            drivemap_import::merge(&import, &known).render(&map.display().to_string())
        }
        None => import.yaml.clone(),
    };
    // The draft's registers (rows refused by the front end, coils, the other word of a pair
    // and reserved rows are reported, not counted).
    let proposed = import.registers.len();
    let reported: usize = import.readings.iter().map(|(r, _)| r.unread.len()).sum();
    match &a.output {
        Some(path) => std::fs::write(path, &out).map_err(Error::io(path.display()))?,
        None => print!("{out}"),
    }
    eprintln!(
        "drivemap import: {proposed} rows proposed from {} manual(s); {reported} lines reported; {} items to confirm{}",
        import.readings.len(),
        import.to_confirm.len(),
        a.report
            .as_ref()
            .map(|r| format!("; report in {}", r.display()))
            .unwrap_or_default()
    );
    Ok(ExitCode::SUCCESS)
}

/// The text of a PDF manual, extracted with poppler's `pdftotext -layout` and kept beside the
/// draft (the directory of `-o`, else the PDF's own) as `<name>.txt`: the file the draft cites.
fn pdf_text(
    path: &std::path::Path,
    output: Option<&std::path::Path>,
) -> Result<(String, String), Error> {
    let stem = path
        .file_stem()
        .map(|f| f.to_string_lossy().into_owned())
        .ok_or_else(|| format!("{}: not a file", path.display()))?;
    let out = std::process::Command::new("pdftotext")
        .arg("-layout")
        .arg("-enc")
        .arg("UTF-8")
        .arg(path)
        .arg("-")
        .output()
        .map_err(|e| {
            Error::Refused(format!(
                "{}: a PDF manual needs poppler's pdftotext, which could not be run ({e}); install poppler-utils (apt-get install poppler-utils) or give the manual's text",
                path.display()
            ))
        })?;
    if !out.status.success() {
        return Err(Error::Refused(format!(
            "{}: pdftotext failed ({}): {}",
            path.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr)
                .chars()
                .take(300)
                .collect::<String>()
                .escape_debug()
        )));
    }
    // Page breaks (form feeds) become blank lines: line numbers stay those of the text file.
    let text = String::from_utf8_lossy(&out.stdout).replace('\u{c}', "\n");
    let file = format!("{stem}.txt");
    let dir = output
        .and_then(|o| o.parent())
        .filter(|d| !d.as_os_str().is_empty())
        .or_else(|| path.parent())
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    let kept = dir.join(&file);
    std::fs::write(&kept, &text).map_err(Error::io(kept.display()))?;
    eprintln!(
        "drivemap import: the text of {} is in {} (the draft cites it)",
        path.display(),
        kept.display()
    );
    Ok((file, text))
}
