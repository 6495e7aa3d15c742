//! `drivemap check <map>...`: validation, then review of every citation against the manuals.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_codegen::review::{self, Manuals, Verdict};
use drivemap_codegen::{Diagnostics, Drive};

use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Map files to check (default: every map of --maps, else every built-in map).
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub dir: MapsDir,
    /// Treat citations whose line does not mention the cited item as errors.
    #[arg(long)]
    pub strict: bool,
}

/// Counts of a map's citation review.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CitationCounts {
    pub verified: usize,
    pub indirect: usize,
    pub unverified: usize,
    pub unchecked: usize,
}

impl CitationCounts {
    pub fn of(checks: &[review::CitationCheck]) -> CitationCounts {
        let mut c = CitationCounts::default();
        for check in checks {
            match check.verdict {
                Verdict::Verified | Verdict::VerifiedRow(_) => c.verified += 1,
                Verdict::Indirect(_) => c.indirect += 1,
                Verdict::Unverified { .. } => c.unverified += 1,
                Verdict::Unchecked => c.unchecked += 1,
            }
        }
        c
    }
}

impl std::fmt::Display for CitationCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let total = self.verified + self.indirect + self.unverified + self.unchecked;
        write!(
            f,
            "citations: {} of {total} verified, {} indirect, {} unverified",
            self.verified, self.indirect, self.unverified
        )?;
        if self.unchecked > 0 {
            write!(f, ", {} unchecked (manual not at hand)", self.unchecked)?;
        }
        Ok(())
    }
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    // (name shown, map read, manuals directory for its citations)
    type Checked = (String, Result<Drive, Diagnostics>, Option<PathBuf>);
    let from_file = |f: &PathBuf| -> Checked {
        (
            f.display().to_string(),
            args.dir.read(f),
            crate::maps::manuals_dir_for(f),
        )
    };
    let files: Vec<Checked> = if !args.files.is_empty() {
        args.files.iter().map(from_file).collect()
    } else if let Some(dir) = &args.dir.maps {
        drivemap_codegen::find_maps(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .iter()
            .map(from_file)
            .collect()
    } else {
        // The built-in maps; their manuals are found from the current directory.
        crate::maps::BUILTIN_MAPS
            .iter()
            .map(|(id, text)| {
                (
                    format!("<built-in>/{id}.yaml"),
                    args.dir.read_builtin(id, text),
                    drivemap_codegen::default_manuals_dir(Path::new(".")),
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
                    drive.meta.id,
                    drive.registers.len()
                );
                let mut unverified = 0;
                let mut manuals = manuals_dir.as_deref().map(Manuals::new);
                if let Some(m) = manuals.as_mut() {
                    m.load_for(drive);
                }
                let manuals = manuals.filter(Manuals::any);
                if manuals.is_none() && args.strict {
                    // Strict means every citation read against its manual.
                    eprintln!(
                        "{file}: error: --strict, but none of the map's manuals is at hand (set DRIVEMAP_MANUALS)"
                    );
                    unverified += 1;
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
                    unverified = counts.unverified;
                    summary.push_str(&format!("; {counts}"));
                }
                summary.push(')');
                if args.strict && unverified > 0 {
                    failed += 1;
                    errors += unverified;
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
