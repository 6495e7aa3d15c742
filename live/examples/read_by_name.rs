//! Reads registers of a drive by name over Modbus TCP, decoded by its map: the
//! [`drivemap_live::session::Session`] that `drivemap read` is built on, used by another program.
//!
//! ```text
//! cargo run -p drivemap-live --example read_by_name -- maps/yaskawa-v7.yaml 192.168.1.10:502 n019 output_current
//! ```
//!
//! Each name is an id, a parameter number, a printed name or an address as the manual prints
//! it; the parameters that select a register's scale (V7 n018 for n019) are read first.

use std::collections::BTreeSet;
use std::error::Error;
use std::path::Path;

use drivemap_live::LiveSettings;
use drivemap_live::link::Link;
use drivemap_live::session::{Session, find_all};

/// A register's id and its decoded value, or why it has none.
pub type Reading = (String, Result<String, Box<dyn Error>>);

/// Reads `names` from the drive whose map is `map` at Modbus TCP `addr`.
pub fn read_by_name(
    map: &Path,
    addr: &str,
    names: &[String],
) -> Result<Vec<Reading>, Box<dyn Error>> {
    let drive = drivemap_map::Loader::new().load(map)?;
    let regs = find_all(&drive, names)?;
    let mut session = Session::open(&drive, &Link::tcp(addr), LiveSettings::default())?;
    for warning in session.load_dependencies(&regs, &BTreeSet::new()) {
        eprintln!("warning: {warning}");
    }
    let words = session.read_words(&regs)?;
    Ok(regs
        .iter()
        .zip(words)
        .map(|(&r, word)| {
            let value = word
                .map_err(Box::<dyn Error>::from)
                .and_then(|raw| Ok(session.decode(r, raw)?.to_string()));
            (r.id().to_owned(), value)
        })
        .collect())
}

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [map, addr, names @ ..] = args.as_slice() else {
        eprintln!("usage: read_by_name <map.yaml> <host:port> <register>...");
        return std::process::ExitCode::from(2);
    };
    match read_by_name(Path::new(map), addr, names) {
        Ok(values) => {
            for (id, value) in values {
                match value {
                    Ok(v) => println!("{id} = {v}"),
                    Err(e) => println!("{id}: error: {e}"),
                }
            }
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("read_by_name: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
