//! The `drivemap` command: check, export, document and diff drive maps; simulate a drive; read,
//! write and poll live drives by register name.
//!
//! A library for one reason only, and with three items: `src/main.rs` is [`main`],
//! [`write_in_process`] runs `drivemap write` in-process for the write-gate sweeps
//! (`tests/cli/write_gate.rs`, `tests/cli/safe_live`), which write every register of every map in every
//! name and value form, thousands of cases per map: a process per case would load and validate
//! the map each time; and [`export_in_process`] runs `drivemap export` for the export sweeps
//! (`tests/cli/export_formats.rs`: every map on every link in every format), loading each map
//! once. Both parse the command line with the binary's parser and run its command's code; the
//! sweeps compare a case of each format with the binary's output. Every other test drives the
//! binary, as users do. The commands' modules are private; nothing here is an API.

#![warn(missing_docs, unreachable_pub, unnameable_types)]
#![doc = include_str!("../README.md")]

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[macro_use]
mod output;

mod commands;
mod error;
mod git;
mod live;
mod maps;

/// The command line.
#[derive(Parser)]
#[command(
    name = "drivemap",
    version,
    about = "Register maps of industrial AC drives: check, export, simulate, talk to drives by name"
)]
struct Cli {
    /// What to do.
    #[command(subcommand)]
    command: Command,
}

/// The commands.
#[derive(Subcommand)]
enum Command {
    /// Validate maps; print every error with file:line:column; exit 1 if any.
    Check(commands::check::Args),
    /// Print a map as JSON (drivemap-export/1), or a Home Assistant, Node-RED or Telegraf configuration polling it.
    Export(commands::export::Args),
    /// Serve a simulated drive built from its map over Modbus TCP, RTU over TCP or a serial port.
    Simulate(commands::simulate::Args),
    /// Run a simulated drive on loopback and drive it through the one drive API (any map with roles).
    Demo(commands::demo::Args),
    /// Write a drive's Markdown reference: protocol, register tables by group, codes, bits, citations.
    Doc(commands::doc::Args),
    /// Compare two maps: every change classified breaking or compatible, with citations; exit 1 if any breaks.
    Diff(commands::diff::Args),
    /// Rewrite maps of an earlier schema version in the current one, keeping their meaning.
    Migrate(commands::migrate::Args),
    /// List the rows of a map's manuals that no item cites, with a summary per table.
    Coverage(commands::coverage::Args),
    /// Draft a map from a manual's text: every register row read with its citation, nothing invented.
    Import(commands::import::Args),
    /// Read registers of a live drive by name, decoded by its map.
    Read(commands::read::Args),
    /// Write registers of a live drive by name, in engineering units, range-checked first.
    Write(commands::write::Args),
    /// Poll registers of a live drive by name as a live-updating table (reconnects over TCP).
    Poll(commands::poll::Args),
    /// Save every setting of a live drive to a parameter set file (YAML, the map's order).
    Save(commands::save::Args),
    /// Compare parameter sets, live drives and the map's defaults; exit 1 if any setting differs.
    Compare(commands::compare::Args),
    /// Restore a parameter set to a live drive: validated first, what differs written in dependency order, stored, read back.
    Restore(commands::restore::Args),
    /// Read every readable register of a drive against its map (never writes); report what disagrees; exit 1 if anything does.
    Probe(commands::probe::Args),
    /// Poll drives into Prometheus (/metrics) and MQTT / Home Assistant; commands over MQTT through the write gate.
    Bridge(Box<commands::bridge::Args>),
    /// Let many Modbus TCP masters share one link: requests serialised onto the line, every write checked by the drive's map.
    Proxy(commands::proxy::Args),
    /// Find the slaves on a line: which addresses answer, at which baud rate and parity, and which maps fit them.
    Scan(commands::scan::Args),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(Completions),
}

/// Arguments of `drivemap completions`.
#[derive(clap::Args, Debug)]
struct Completions {
    /// The shell.
    #[arg(value_enum)]
    shell: clap_complete::Shell,
}

/// Parses the command line and runs the command; errors go to standard error, exit status 2.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(a) => commands::check::run(a),
        Command::Export(a) => commands::export::run(a),
        Command::Simulate(a) => commands::simulate::run(a),
        Command::Demo(a) => commands::demo::run(a),
        Command::Doc(a) => commands::doc::run(a),
        Command::Diff(a) => commands::diff::run(a),
        Command::Coverage(a) => commands::coverage::run(a),
        Command::Import(a) => commands::import::run(a),
        Command::Migrate(a) => commands::migrate::run(a),
        Command::Read(a) => commands::read::run(a),
        Command::Write(a) => commands::write::run(a),
        Command::Poll(a) => commands::poll::run(a),
        Command::Save(a) => commands::save::run(a),
        Command::Compare(a) => commands::compare::run(a),
        Command::Restore(a) => commands::restore::run(a),
        Command::Probe(a) => commands::probe::run(a),
        Command::Scan(a) => commands::scan::run(a),
        Command::Bridge(a) => commands::bridge::run(*a),
        Command::Proxy(a) => commands::proxy::run(a),
        Command::Completions(a) => {
            use clap::CommandFactory;
            let mut cmd = Cli::command();
            clap_complete::generate(a.shell, &mut cmd, "drivemap", &mut std::io::stdout());
            Ok(ExitCode::SUCCESS)
        }
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("drivemap: {e}");
            ExitCode::from(2)
        }
    }
}

/// Parses a command line with the binary's own parser (`Cli::try_parse_from`'s parse), built
/// once per thread and reused: building clap's whole command tree costs more than a write
/// (a sweep runs thousands). A command line clap refuses is its message (`error: ...`).
fn parse_in_process(argv: &[&str]) -> Result<Command, String> {
    thread_local! {
        static PARSER: std::cell::RefCell<Option<clap::Command>> =
            const { std::cell::RefCell::new(None) };
    }
    let cli = PARSER.with(|parser| {
        use clap::{CommandFactory, FromArgMatches};
        let mut parser = parser.borrow_mut();
        let cmd = parser.get_or_insert_with(Cli::command);
        let mut matches = cmd.try_get_matches_from_mut(argv)?;
        Cli::from_arg_matches_mut(&mut matches).map_err(|e| e.format(cmd))
    });
    cli.map(|cli| cli.command).map_err(|e| e.to_string())
}

/// `drivemap write` in-process on a map already loaded: `argv` is the command line (`drivemap
/// write --drive <id> --tcp <addr> ... <register>=<value>`), `drive` and `profile` the map it
/// names, read once by the caller. What the binary prints on standard error before exit status
/// 2 is the error's text.
pub fn write_in_process(
    argv: &[&str],
    drive: &drivemap_map::Map,
    profile: &'static drivemap_runtime::core::profile::Profile,
) -> Result<ExitCode, String> {
    let Command::Write(args) = parse_in_process(argv)? else {
        return Err("not a `drivemap write` command line".to_owned());
    };
    commands::write::execute(drive, profile, &args).map_err(|e| e.to_string())
}

/// `drivemap export` in-process: `argv` is the command line (`drivemap export --drive <id>
/// --format home-assistant --tcp <addr> ...`); the result is what the binary writes on
/// standard output (exit status 0), or the text of its error (a map that does not validate,
/// refused arguments). The map is loaded as the binary loads it, once per thread for each
/// distinct way of naming it (file or id, and `--maps`): the export sweeps export every map on
/// every link in every format.
pub fn export_in_process(argv: &[&str]) -> Result<String, String> {
    type Loaded = std::collections::HashMap<String, std::rc::Rc<drivemap_map::Map>>;
    thread_local! {
        static LOADED: std::cell::RefCell<Loaded> = std::cell::RefCell::new(Loaded::new());
    }
    let Command::Export(args) = parse_in_process(argv)? else {
        return Err("not a `drivemap export` command line".to_owned());
    };
    let key = format!("{:?} {:?} {:?}", args.file, args.drive, args.dir.maps);
    let cached = LOADED.with(|l| l.borrow().get(&key).cloned());
    let drive = match cached {
        Some(drive) => drive,
        None => {
            let drive = match commands::export::load(&args).map_err(|e| e.to_string())? {
                Ok(drive) => std::rc::Rc::new(drive),
                Err(diags) => return Err(diags.to_string()),
            };
            LOADED.with(|l| l.borrow_mut().insert(key, drive.clone()));
            drive
        }
    };
    commands::export::render(&drive, &args)
        .map(|(text, _)| text)
        .map_err(|e| e.to_string())
}
