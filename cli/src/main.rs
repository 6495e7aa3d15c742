//! `drivemap`: check, export, document and diff drive maps; simulate a drive; read, write and
//! poll live drives by register name.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[macro_use]
mod output;

mod commands;
mod describe;
mod diff;
mod drive_doc;
mod duration;
mod live;
mod maps;

#[derive(Parser)]
#[command(
    name = "drivemap",
    version,
    about = "Register maps of industrial AC drives: check, export, simulate, talk to drives by name"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate maps; print every error with file:line:column; exit 1 if any.
    Check(commands::check::Args),
    /// Print a map as JSON (drivemap-export/1).
    Export(commands::export::Args),
    /// Serve a simulated drive built from its map over Modbus TCP, RTU over TCP or a serial port.
    Simulate(commands::simulate::Args),
    /// Run a simulated drive on loopback and drive it through the generated typed API.
    Demo(commands::demo::Args),
    /// Write a drive's Markdown reference: protocol, register tables by group, codes, bits, citations.
    Doc(commands::doc::Args),
    /// Compare two maps: every change classified breaking or compatible, with citations; exit 1 if any breaks.
    Diff(commands::diff::Args),
    /// Read registers of a live drive by name, decoded by its map.
    Read(commands::read::Args),
    /// Write registers of a live drive by name, in engineering units, range-checked first.
    Write(commands::write::Args),
    /// Poll registers of a live drive by name as a live-updating table.
    Poll(commands::poll::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(a) => commands::check::run(a),
        Command::Export(a) => commands::export::run(a),
        Command::Simulate(a) => commands::simulate::run(a),
        Command::Demo(a) => commands::demo::run(a),
        Command::Doc(a) => commands::doc::run(a),
        Command::Diff(a) => commands::diff::run(a),
        Command::Read(a) => commands::read::run(a),
        Command::Write(a) => commands::write::run(a),
        Command::Poll(a) => commands::poll::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("drivemap: {e}");
            ExitCode::from(2)
        }
    }
}
