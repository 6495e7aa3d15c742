//! `drivemap check <map>...`: validation, then review of every citation against the manuals.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_map::{Diagnostics, Loader, Map};
use drivemap_review::review::{self, Manuals, Verdict};

use crate::error::Error;
use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// Map files to check (default: every map of --maps, else every built-in map).
    pub(crate) files: Vec<PathBuf>,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
    /// Treat citations whose line does not mention the cited item as errors.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Fail when a map's citations cannot be verified: the manuals directory is not found
    /// (DRIVEMAP_MANUALS, or shared/manuals beside the repository) or lacks a text manual the
    /// map names (manuals cited by page are not expected there).
    #[arg(long)]
    pub(crate) require_manuals: bool,
}

/// Why some of a map's citations cannot be read against their manual, or `None` when every
/// text manual the map names is at hand (manuals cited by page have no text to read, so a map
/// citing only those needs no manuals directory).
fn not_verified(dir: Option<&Path>, manuals: &Manuals, drive: &Map) -> Option<String> {
    drive.meta().text_manuals().next()?;
    let Some(dir) = dir else {
        return Some(
            "no manuals directory found (set DRIVEMAP_MANUALS, or put the manuals in \
             shared/manuals beside the repository)"
                .to_owned(),
        );
    };
    if !dir.is_dir() {
        let from_env = std::env::var_os("DRIVEMAP_MANUALS").is_some_and(|v| Path::new(&v) == dir);
        return Some(if from_env {
            format!("DRIVEMAP_MANUALS={} is not a directory", dir.display())
        } else {
            format!("manuals directory {} not found", dir.display())
        });
    }
    let missing: Vec<&str> = drive
        .meta()
        .text_manuals()
        .filter(|f| manuals.lines(f).is_none())
        .collect();
    match missing.len() {
        0 => None,
        n if n == drive.meta().text_manuals().count() => Some(format!(
            "none of the map's manuals ({}) is in {}",
            missing.join(", "),
            dir.display()
        )),
        _ => Some(format!("{} not in {}", missing.join(", "), dir.display())),
    }
}

/// Counts of a map's citation review.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CitationCounts {
    pub(crate) verified: usize,
    pub(crate) indirect: usize,
    pub(crate) unverified: usize,
    pub(crate) unchecked: usize,
    /// Page citations of manuals with no text at hand: not verifiable by content.
    pub(crate) pages: usize,
}

impl CitationCounts {
    pub(crate) fn of(checks: &[review::CitationCheck]) -> CitationCounts {
        let mut c = CitationCounts::default();
        for check in checks {
            match check.verdict {
                Verdict::Verified | Verdict::VerifiedRow(_) => c.verified += 1,
                Verdict::Indirect(_) => c.indirect += 1,
                Verdict::Unverified { .. } => c.unverified += 1,
                Verdict::Unchecked => c.unchecked += 1,
                Verdict::Page => c.pages += 1,
            }
        }
        c
    }
}

impl std::fmt::Display for CitationCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let total = self.verified + self.indirect + self.unverified + self.unchecked + self.pages;
        write!(
            f,
            "citations: {} of {total} verified, {} indirect, {} unverified",
            self.verified, self.indirect, self.unverified
        )?;
        if self.unchecked > 0 {
            write!(f, ", {} unchecked (manual not at hand)", self.unchecked)?;
        }
        if self.pages > 0 {
            write!(
                f,
                ", {} page citations (not verifiable by content)",
                self.pages
            )?;
        }
        Ok(())
    }
}

/// Verified of each kind of citation outside the registers that can be read (not page
/// citations), as `roles 20 of 20, protocol 14 of 15, conflicts 30 of 32, gaps 6 of 6
/// verified`; empty when the map has none.
pub(crate) fn kinds_verified(checks: &[review::CitationCheck]) -> String {
    let mut parts = Vec::new();
    for (kind, label) in [
        ("role", "roles"),
        ("protocol", "protocol"),
        ("conflict", "conflicts"),
        ("gap", "gaps"),
        ("limit", "limits"),
        ("functions", "function codes"),
    ] {
        let of: Vec<&review::CitationCheck> = checks
            .iter()
            .filter(|c| matches!(&c.item, review::Item::Other { kind: k, .. } if *k == kind))
            .filter(|c| !matches!(c.verdict, Verdict::Page | Verdict::Unchecked))
            .collect();
        if !of.is_empty() {
            let verified = of.iter().filter(|c| c.verified()).count();
            parts.push(format!("{label} {verified} of {}", of.len()));
        }
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!("{} verified", parts.join(", "))
    }
}

pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    // (name shown, map read, manuals directory for its citations)
    type Checked = (String, Result<Map, Diagnostics>, Option<PathBuf>);
    // One cached loader for the files of each directory: a map's bases are read once, not
    // once per variant.
    let loaders: RefCell<Vec<(PathBuf, Loader<'_>)>> = RefCell::new(Vec::new());
    let from_file = |f: &PathBuf| -> Checked {
        let dir = f.parent().unwrap_or(Path::new(".")).to_path_buf();
        let mut loaders = loaders.borrow_mut();
        let i = match loaders.iter().position(|(d, _)| *d == dir) {
            Some(i) => i,
            None => {
                loaders.push((dir, args.dir.loader(f).cached()));
                loaders.len() - 1
            }
        };
        (
            f.display().to_string(),
            args.dir.read_with(&loaders[i].1, f),
            crate::maps::manuals_dir_for(f),
        )
    };
    let files: Vec<Checked> = if !args.files.is_empty() {
        args.files.iter().map(from_file).collect()
    } else if let Some(dir) = &args.dir.maps {
        let found = drivemap_map::find_maps(dir).map_err(Error::io(dir.display()))?;
        if found.is_empty() {
            return Err(Error::Refused(format!(
                "{}: no maps to check (no *.yaml or *.yml file in the directory)",
                dir.display()
            )));
        }
        found.iter().map(from_file).collect()
    } else if crate::maps::BUILTIN_MAPS.is_empty() {
        return Err("no maps to check: none built in; give map files or --maps DIR".into());
    } else {
        // The built-in maps; their manuals are found from the current directory.
        crate::maps::BUILTIN_MAPS
            .iter()
            .map(|(id, text)| {
                (
                    format!("<built-in>/{id}.yaml"),
                    args.dir.read_builtin(id, text),
                    drivemap_map::default_manuals_dir(Path::new(".")),
                )
            })
            .collect()
    };
    let mut failed = 0;
    let mut errors = 0;
    for (file, read, manuals_dir) in files.iter() {
        match read {
            Ok(drive) => {
                let mut summary = format!(
                    "{} ({}: {} registers",
                    file,
                    drive.id(),
                    drive.registers().len()
                );
                let mut map_errors = 0;
                // A map in an earlier schema version is read by its meaning, with warnings;
                // `--strict` wants it in the current one.
                for w in drive.warnings() {
                    let draft = drive.draft_warning().is_some_and(|d| w.message == d);
                    if args.strict && draft {
                        // Not a schema matter: a reviewer's.
                        eprintln!(
                            "{w} (--strict: review every row against the manual, confirm the items listed, then remove `draft:`)"
                        );
                        map_errors += 1;
                    } else if args.strict {
                        eprintln!("{w} (--strict: run `drivemap migrate`)");
                        map_errors += 1;
                    } else {
                        eprintln!("{}", w.as_warning());
                    }
                }
                for w in review::protocol_warnings(drive) {
                    eprintln!("{w}");
                }
                // The manual's example frames against the codec and the map.
                if !drive.examples().is_empty() {
                    let found = drivemap_live::examples::verify(drive);
                    for d in &found.errors {
                        eprintln!("{d}");
                    }
                    // One warning per frame whose contradiction the map records.
                    for r in &found.known {
                        eprintln!("{}", r.warning());
                    }
                    map_errors += found.errors.len();
                    let marked = drive
                        .examples()
                        .iter()
                        .filter(|e| e.conflict.is_some())
                        .count();
                    summary.push_str(&format!(
                        "; example frames: {} of {} verified",
                        found.clean,
                        drive.examples().len()
                    ));
                    if marked > 0 {
                        summary.push_str(&format!(", {marked} contradicting as recorded"));
                    }
                }
                let mut manuals = manuals_dir.as_deref().map(Manuals::new);
                if let Some(m) = manuals.as_mut() {
                    m.load_for(drive);
                }
                let why = not_verified(
                    manuals_dir.as_deref(),
                    manuals.as_ref().unwrap_or(&Manuals::default()),
                    drive,
                );
                if let (Some(why), true) = (&why, args.require_manuals) {
                    eprintln!(
                        "{file}: error: --require-manuals, but citations not verified: {why}"
                    );
                    map_errors += 1;
                }
                let text_manuals = drive.meta().text_manuals().next().is_some();
                // A map citing only pages is reviewed with no text: its citations are counted.
                let manuals = manuals
                    .filter(Manuals::any)
                    .or_else(|| (!text_manuals).then(Manuals::default));
                if manuals.is_none() && args.strict && !args.require_manuals {
                    // Strict means every citation read against its manual.
                    eprintln!(
                        "{file}: error: --strict, but none of the map's manuals is at hand (set DRIVEMAP_MANUALS)"
                    );
                    map_errors += 1;
                }
                if let Some(manuals) = manuals {
                    let checks = review::verify_citations(drive, &manuals);
                    let counts = CitationCounts::of(&checks);
                    for w in checks.iter().filter_map(|c| c.warning()) {
                        if args.strict {
                            eprintln!("{}", w.to_string().replacen(": warning", ": error", 1));
                        } else {
                            eprintln!("{w}");
                        }
                    }
                    if args.strict {
                        map_errors += counts.unverified;
                    }
                    let by_kind = kinds_verified(&checks);
                    if !by_kind.is_empty() {
                        summary.push_str(&format!("; {by_kind}"));
                    }
                    summary.push_str(&format!("; {counts}"));
                }
                if let Some(why) = &why {
                    summary.push_str(&format!("; citations not verified: {why}"));
                }
                summary.push(')');
                if map_errors > 0 {
                    failed += 1;
                    errors += map_errors;
                    outln!("FAIL {summary}");
                } else {
                    outln!("ok   {summary}");
                }
            }
            Err(diags) => {
                failed += 1;
                errors += diags.len();
                for d in diags.iter() {
                    eprintln!("{d}");
                }
                outln!(
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
