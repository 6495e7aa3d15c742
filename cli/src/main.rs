//! `drivemap`: check, export, document and diff drive maps; simulate a drive; read, write and
//! poll live drives by register name.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod commands;
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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(a) => commands::check::run(a),
        Command::Export(a) => commands::export::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("drivemap: {e}");
            ExitCode::from(2)
        }
    }
}
