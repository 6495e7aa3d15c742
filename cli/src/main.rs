//! `drivemap`: check, export, document and diff drive maps; simulate a drive; read, write and
//! poll live drives by register name. The commands live in the library (`src/lib.rs`).

fn main() -> std::process::ExitCode {
    drivemap_cli::main()
}
