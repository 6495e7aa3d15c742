//! `drivemap export (<map.yaml> | --drive <id>) [--format json|home-assistant|node-red|telegraf]`

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args as ClapArgs, ValueEnum};

use crate::error::Error;
use crate::maps::MapsDir;
use drivemap_bridge::points::export::{self, Export};
use drivemap_bridge::points::{home_assistant, node_red, telegraf};
use drivemap_live::link::{Link, ParityParser};
use drivemap_live::session::{SettingsArgs, find_all};
use drivemap_map::{Diagnostics, Map};
use drivemap_runtime::core::profile::Parity;

/// What to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Format {
    /// The map as JSON (drivemap-export/1).
    Json,
    /// What every printer says of each register, as JSON: the facts view
    /// (`drivemap_map::facts`), rows of label, value and citation per register.
    Facts,
    /// Home Assistant's `modbus:` YAML: a hub and a sensor per register.
    HomeAssistant,
    /// A Node-RED flow for node-red-contrib-modbus (JSON to import or run).
    NodeRed,
    /// Telegraf's `inputs.modbus` configuration in the request style.
    Telegraf,
}

#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// Map file to export.
    #[arg(conflicts_with = "drive", required_unless_present = "drive")]
    pub(crate) file: Option<PathBuf>,
    /// Drive id: a built-in map, or `<maps>/<id>.yaml`.
    #[arg(long)]
    pub(crate) drive: Option<String>,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
    /// What to write: the map as JSON, or a poller's configuration (which then needs the link).
    #[arg(long, value_enum, default_value_t = Format::Json)]
    pub(crate) format: Format,
    /// Registers to poll, by id, parameter number, printed name or address (repeat, or
    /// comma-separated; default: the registers the map's roles name and every read-only one).
    #[arg(long = "register", value_delimiter = ',', value_name = "NAME")]
    pub(crate) registers: Vec<String>,
    /// Poll every readable register of the map.
    #[arg(long, conflicts_with = "registers")]
    pub(crate) all: bool,
    /// How often the tool polls (default 1 s; 5 s for Home Assistant, which warns below 5 s).
    #[arg(long, value_parser = drivemap_live::duration::positive)]
    pub(crate) interval: Option<Duration>,
    /// The name of the hub, entities and measurement (default: the drive id).
    #[arg(long)]
    pub(crate) name: Option<String>,
    /// The drive's own Modbus TCP interface the tool connects to (`192.168.1.10:502`).
    #[arg(long, value_name = "HOST:PORT")]
    pub(crate) tcp: Option<String>,
    /// A Modbus TCP to RTU gateway with the drive on its serial line (the map's RTU addresses).
    #[arg(long, value_name = "HOST:PORT")]
    pub(crate) gateway: Option<String>,
    /// RTU frames over TCP through a transparent serial gateway.
    #[arg(long = "rtu-tcp", value_name = "HOST:PORT")]
    pub(crate) rtu_tcp: Option<String>,
    /// Serial port speaking Modbus RTU.
    #[arg(long, value_name = "PATH")]
    pub(crate) serial: Option<String>,
    /// Baud rate (default: the map's default, else 9600).
    #[arg(long)]
    pub(crate) baud: Option<u32>,
    /// Parity (default: the map's default, else none).
    #[arg(long, value_parser = ParityParser)]
    pub(crate) parity: Option<Parity>,
    /// Stop bits (default: the map's for the parity).
    #[arg(long = "stop-bits", value_parser = clap::value_parser!(u8).range(1..=2))]
    pub(crate) stop_bits: Option<u8>,
    /// Slave address (default: the map's default, else 1).
    #[arg(long)]
    pub(crate) slave: Option<u8>,
    /// What conversions and addresses depend on (`--set n152=1`): a scale another parameter
    /// selects is exported only when given.
    #[command(flatten)]
    pub(crate) settings: SettingsArgs,
}

impl Args {
    fn link(&self) -> Link {
        Link {
            tcp: self.tcp.clone(),
            gateway: self.gateway.clone(),
            rtu_tcp: self.rtu_tcp.clone(),
            serial: self.serial.clone(),
            ascii: false,
            data_bits: None,
            baud: self.baud,
            parity: self.parity,
            stop_bits: self.stop_bits,
            slave: self.slave,
            timeout: None,
            retries: 2,
            request_gap: None,
        }
    }

    fn link_given(&self) -> usize {
        [&self.tcp, &self.gateway, &self.rtu_tcp, &self.serial]
            .iter()
            .filter(|l| l.is_some())
            .count()
    }
}

pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = match load(&args)? {
        Ok(drive) => drive,
        Err(diags) => {
            eprintln!("{diags}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let (text, left_out) = render(&drive, &args)?;
    out!("{text}");
    for line in left_out {
        eprintln!("drivemap: {line}");
    }
    Ok(ExitCode::SUCCESS)
}

/// The map the arguments name: the file, or the drive by id (built in or under `--maps`);
/// `Ok(Err(_))` when it does not validate.
pub(crate) fn load(args: &Args) -> Result<Result<Map, Diagnostics>, Error> {
    match (&args.file, &args.drive) {
        (Some(f), _) => Ok(args.dir.read(f)),
        (None, Some(id)) => Ok(Ok(args.dir.load(id)?)),
        (None, None) => Err(Error::Refused("give a map file or --drive <id>".into())),
    }
}

/// What `drivemap export` writes of `drive` (loaded by [`load`]) on standard output, and the
/// registers left out, one line each, that it says on standard error.
pub(crate) fn render(drive: &Map, args: &Args) -> Result<(String, Vec<String>), Error> {
    if matches!(args.format, Format::Json | Format::Facts) {
        if args.link_given() > 0 || !args.registers.is_empty() || args.all {
            return Err(
                "the JSON export is the whole map: --register, --all and a link go with --format home-assistant, node-red or telegraf".into(),
            );
        }
        let json = match args.format {
            Format::Facts => serde_json::to_value(drive.facts())?,
            _ => drive.export(),
        };
        return Ok((
            format!("{}\n", serde_json::to_string_pretty(&json)?),
            Vec::new(),
        ));
    }
    if args.link_given() != 1 {
        return Err(
            "give one link the tool connects to: --tcp HOST:PORT, --gateway HOST:PORT, --rtu-tcp HOST:PORT or --serial PATH".into(),
        );
    }
    let given = args.settings.resolve(drive)?;
    let regs = if args.all {
        drive.registers().filter(|r| r.readable()).collect()
    } else if args.registers.is_empty() {
        export::default_registers(drive)
    } else {
        find_all(drive, &args.registers)?
    };
    let interval = args.interval.unwrap_or(Duration::from_secs(
        if args.format == Format::HomeAssistant {
            5
        } else {
            1
        },
    ));
    let period_ms = u64::try_from(interval.as_millis()).unwrap_or(u64::MAX);
    let points = Export::build(
        drive,
        &regs,
        &args.link(),
        &given.settings,
        period_ms,
        args.name.as_deref(),
    )?;
    let text = match args.format {
        Format::HomeAssistant => home_assistant::render(&points),
        Format::Telegraf => telegraf::render(&points),
        Format::NodeRed => {
            serde_json::to_string_pretty(&node_red::render(&points)).map_err(|e| e.to_string())?
                + "\n"
        }
        Format::Json | Format::Facts => return Ok((String::new(), Vec::new())),
    };
    Ok((text, points.left_out_lines()))
}
