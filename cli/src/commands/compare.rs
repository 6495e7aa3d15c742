//! `drivemap compare A [B] [--drive <id>] [link] [--format text|md|json]`: each side a set file,
//! `defaults` (the map's printed factory values) or `drive` / `drive@SLAVE` (a live drive on the
//! link given, saved first); one side given compares it with the drive.

use std::process::ExitCode;

use clap::{Args as ClapArgs, ValueEnum};
use drivemap_live::link::Link;
use drivemap_live::paramset::{self, Compared, ParameterSet, Side};
use drivemap_live::session::{Session, SettingsArgs};
use drivemap_map::Map;

use crate::error::Error;
use crate::live::output::now_rfc3339;
use crate::maps::MapsDir;

/// How the differences are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Format {
    /// One line per setting that differs.
    Text,
    /// A Markdown table.
    Md,
    /// JSON: the two sides, the differences, the settings without a printed default.
    Json,
}

/// Arguments of `drivemap compare`: the link is needed only for a `drive` side.
#[derive(ClapArgs, Debug)]
#[command(mut_group("link", |g| g.required(false)))]
pub(crate) struct Args {
    /// The sides: a set file (`drivemap save`), `defaults` (the map's printed factory
    /// values), `drive` (the drive on the link given, at --slave) or `drive@SLAVE` (another
    /// slave on the same link). One side alone is compared with `drive`.
    #[arg(required = true, num_args = 1..=2, value_name = "SIDE")]
    pub(crate) sides: Vec<String>,
    /// Drive id: a built-in map, or `<maps>/<id>.yaml` (default: the map the first set file
    /// names).
    #[arg(long)]
    pub(crate) drive: Option<String>,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
    #[command(flatten)]
    pub(crate) link: Link,
    #[command(flatten)]
    pub(crate) settings: SettingsArgs,
    /// Compare sides of different maps or variants (refused without it, naming what differs).
    #[arg(long)]
    pub(crate) other: bool,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    pub(crate) format: Format,
}

/// Reads a set file, naming it in every error.
pub(crate) fn read_set(path: &str) -> Result<ParameterSet, Error> {
    let meta = std::fs::metadata(path).map_err(|source| Error::Io {
        what: format!("reading {path}"),
        source,
    })?;
    if meta.len() > paramset::MAX_FILE as u64 {
        return Err(Error::Refused(format!(
            "{path}: {} bytes is more than a parameter set ({} bytes at most)",
            meta.len(),
            paramset::MAX_FILE
        )));
    }
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        what: format!("reading {path}"),
        source,
    })?;
    ParameterSet::from_yaml(path, &text).map_err(|e| Error::Refused(e.to_string()))
}

/// `drive` or `drive@N`: the slave (`None`: the link's).
fn drive_side(side: &str) -> Option<Option<&str>> {
    if side == "drive" {
        return Some(None);
    }
    side.strip_prefix("drive@").map(Some)
}

/// One side's values.
fn side(
    drive: &Map,
    text: &str,
    link: Option<&Link>,
    settings: &SettingsArgs,
    variant: &std::collections::BTreeMap<String, String>,
) -> Result<Side, Error> {
    if text == "defaults" {
        return Ok(Side::defaults(drive, variant));
    }
    if let Some(slave) = drive_side(text) {
        let Some(link) = link else {
            return Err(Error::Refused(format!(
                "`{text}`: give the link to the drive (--tcp, --gateway, --rtu-tcp or --serial)"
            )));
        };
        let mut link = link.clone();
        if let Some(s) = slave {
            link.slave = Some(s.parse::<u8>().map_err(|_| {
                Error::Refused(format!("`{text}`: `{s}` is not a slave address (0-255)"))
            })?);
        }
        link.check_transport(drive)?;
        let given = settings.resolve(drive)?;
        let mut session = Session::open(drive, &link, given.settings)?;
        let report = paramset::save(&mut session, &now_rfc3339())?;
        if let Some(why) = session.silence.report() {
            return Err(Error::Refused(format!(
                "{} did not answer: {why}",
                session.link
            )));
        }
        let label = format!("slave {} over {}", session.slave, session.link);
        return Ok(Side::set(label, report.set));
    }
    Ok(Side::set(text, read_set(text)?))
}

/// Prints the differences; exits 1 when any setting differs.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let mut sides = args.sides.clone();
    if sides.len() == 1 {
        sides.push("drive".to_owned());
    }
    let id = match &args.drive {
        Some(id) => id.clone(),
        None => {
            let file = sides
                .iter()
                .find(|s| *s != "defaults" && drive_side(s).is_none())
                .ok_or_else(|| {
                    Error::Refused("give the drive's map with --drive <id>".to_owned())
                })?;
            read_set(file)?.drive
        }
    };
    let drive = args.dir.load(&id)?;
    let given = args.settings.resolve(&drive)?;
    // The defaults are of the variant of the other side when it is a set, else of --variant.
    let mut variant = given.settings.variants.clone();
    for s in &sides {
        if s != "defaults" && drive_side(s).is_none() {
            let set = read_set(s)?;
            for (a, o) in set.variant {
                variant.entry(a).or_insert(o);
            }
        }
    }
    let given_link = [
        &args.link.tcp,
        &args.link.gateway,
        &args.link.rtu_tcp,
        &args.link.serial,
    ]
    .iter()
    .any(|l| l.is_some());
    let link = given_link.then_some(&args.link);
    let left = side(&drive, &sides[0], link, &args.settings, &variant)?;
    let right = side(&drive, &sides[1], link, &args.settings, &variant)?;
    let compared = paramset::compare(&drive, &left, &right, args.other).map_err(Error::Refused)?;
    for w in &compared.warnings {
        eprintln!("warning: {w}");
    }
    print(&compared, args.format)?;
    Ok(if compared.differences.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn print(c: &Compared, format: Format) -> Result<(), Error> {
    let or_none = |v: &Option<String>| v.clone().unwrap_or_else(|| "(none)".to_owned());
    match format {
        Format::Json => outln!("{}", serde_json::to_string_pretty(c)?),
        Format::Text => {
            outln!(
                "{} vs {}: {} differ, {} the same{}",
                c.left,
                c.right,
                c.differences.len(),
                c.same,
                if c.no_default.is_empty() {
                    String::new()
                } else {
                    format!(", {} without a printed default", c.no_default.len())
                }
            );
            for d in &c.differences {
                let mut line = format!("{}: {} -> {}", d.name, or_none(&d.left), or_none(&d.right));
                if let Some(why) = &d.why {
                    line.push_str(&format!(" ({why})"));
                }
                if let Some(s) = &d.source {
                    line.push_str(&format!("   [{s}]"));
                }
                outln!("{line}");
            }
            for n in &c.no_default {
                outln!("{n}: no printed default");
            }
        }
        Format::Md => {
            outln!(
                "**{}** vs **{}**: {} differ, {} the same\n",
                c.left,
                c.right,
                c.differences.len(),
                c.same
            );
            if !c.differences.is_empty() {
                outln!("| setting | {} | {} | source |", md(&c.left), md(&c.right));
                outln!("|---|---|---|---|");
                for d in &c.differences {
                    outln!(
                        "| {} | {} | {} | {} |",
                        md(&d.name),
                        md(&or_none(&d.left)),
                        md(&or_none(&d.right)),
                        md(d.source.as_deref().unwrap_or(""))
                    );
                }
            }
            if !c.no_default.is_empty() {
                outln!(
                    "\nWithout a printed default: {}",
                    md(&c.no_default.join(", "))
                );
            }
        }
    }
    Ok(())
}

/// Text for a Markdown table cell.
fn md(text: &str) -> String {
    text.replace('|', "\\|").replace('\n', " ")
}
