//! Live drives by register name (`drivemap read`, `write`, `poll`): the map is loaded at run
//! time ([`drivemap_live`]) and spoken over the runtime's transports; reads are planned by the
//! runtime's read planner ([`drivemap_runtime::planner`]).

pub(crate) mod output;
pub(crate) mod table;

pub(crate) use drivemap_live::{link, session};

use clap::Args as ClapArgs;
use drivemap_map::Map;

use crate::error::Error;
use crate::maps::MapsDir;

/// The drive to talk to: its map and how to reach it.
#[derive(ClapArgs, Debug, Clone)]
pub(crate) struct Target {
    /// Drive id: a built-in map, or `<maps>/<id>.yaml`.
    #[arg(long)]
    pub(crate) drive: String,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
    #[command(flatten)]
    pub(crate) link: link::Link,
    #[command(flatten)]
    pub(crate) settings: session::SettingsArgs,
    /// Write through a draft map (one marked `draft:`, as `drivemap import` writes it, not yet
    /// reviewed against its manual); without it such writes are refused, nothing sent. Every
    /// write made with it says it went through a draft.
    #[arg(long)]
    pub(crate) draft: bool,
}

impl Target {
    /// Reads and validates the drive's map, and refuses a link the drive does not have
    /// (`--tcp` to a drive without Modbus TCP: [`link::Link::check_transport`]) before
    /// anything else is looked at.
    /// A draft map (`draft:`) is loaded with a note saying so on standard error.
    pub(crate) fn load(&self) -> Result<Map, Error> {
        let drive = self.dir.load(&self.drive)?;
        self.link.check_transport(&drive)?;
        if let Some(note) = drivemap_live::draft::read_note(&drive) {
            eprintln!("note: {note}");
        }
        Ok(drive)
    }

    /// Whether writes through a draft map are allowed (`--draft`).
    pub(crate) fn draft_writes(&self) -> drivemap_live::draft::DraftWrites {
        drivemap_live::draft::DraftWrites::from_flag(self.draft)
    }
}
