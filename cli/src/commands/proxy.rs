//! `drivemap proxy --listen ADDR --drive ID@SLAVE... (--tcp | --gateway | --rtu-tcp | --serial)`:
//! many Modbus TCP masters share one link through one master on the line, every write checked
//! by the drive's map ([`drivemap_bridge::proxy`]).

use std::collections::{BTreeMap, BTreeSet};
use std::net::SocketAddr;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use clap::Args as ClapArgs;

use crate::commands::bridge::{ProxyArgs, link, link_args};
use crate::error::Error;
use crate::live::link::{Parity, ParityParser};
use crate::live::session::SettingsArgs;
use crate::maps::MapsDir;

/// Arguments of `drivemap proxy`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Where masters connect (Modbus TCP; loopback unless another address is given).
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:5020")]
    pub listen: SocketAddr,
    /// A drive on the link: its map's id and slave address (`yaskawa-v7@1`); repeat per drive.
    #[arg(long = "drive", value_name = "ID@SLAVE", required = true)]
    pub drives: Vec<String>,
    #[command(flatten)]
    pub dir: MapsDir,
    /// The drives' own Modbus TCP interface.
    #[arg(long, value_name = "HOST:PORT")]
    pub tcp: Option<String>,
    /// A Modbus TCP to RTU gateway with the drives on its serial line.
    #[arg(long, value_name = "HOST:PORT")]
    pub gateway: Option<String>,
    /// RTU frames over TCP through a transparent serial gateway.
    #[arg(long = "rtu-tcp", value_name = "HOST:PORT")]
    pub rtu_tcp: Option<String>,
    /// Serial port speaking Modbus RTU, or Modbus ASCII with --ascii.
    #[arg(long, value_name = "PATH")]
    pub serial: Option<String>,
    /// Modbus ASCII instead of RTU on the line (--serial, or --rtu-tcp through a transparent
    /// gateway); the masters still speak Modbus TCP to the proxy.
    #[arg(long, conflicts_with_all = ["tcp", "gateway"])]
    pub ascii: bool,
    /// Data bits of an ASCII line, 7 or 8 (default: the map's).
    #[arg(long = "data-bits", requires = "ascii", value_parser = clap::value_parser!(u8).range(7..=8))]
    pub data_bits: Option<u8>,
    /// Baud rate of the serial line (default: the first drive's map's).
    #[arg(long)]
    pub baud: Option<u32>,
    /// Parity of the serial line (default: the map's).
    #[arg(long, value_parser = ParityParser)]
    pub parity: Option<Parity>,
    /// How long to wait for each reply on the line (default: from the map).
    #[arg(long, value_parser = crate::duration::positive)]
    pub timeout: Option<Duration>,
    /// Further attempts after a timeout on the line.
    #[arg(long, default_value_t = 0)]
    pub retries: u8,
    #[command(flatten)]
    pub proxy: ProxyArgs,
    /// Carry out writes to drives whose map is marked `draft:` (not reviewed against its
    /// manual); without it they are refused (01h).
    #[arg(long)]
    pub draft: bool,
    /// Where Prometheus scrapes the proxy's `/metrics` (requests per master, refusals).
    #[arg(long, value_name = "ADDR")]
    pub metrics: Option<SocketAddr>,
}

/// Serves masters until SIGTERM or SIGINT.
pub fn run(args: Args) -> Result<ExitCode, Error> {
    let la = link_args(
        args.tcp,
        args.gateway,
        args.rtu_tcp,
        args.serial,
        args.baud,
        args.parity,
        args.timeout,
        args.retries,
        args.ascii,
        args.data_bits,
    )?;
    let settings = SettingsArgs::default();
    let mut l = link(
        &args.dir,
        la,
        &args.drives,
        &settings,
        args.draft,
        &mut BTreeSet::new(),
        &mut BTreeMap::new(),
    )?;
    l.poll = false;
    l.proxy = Some(args.proxy.options(args.listen)?);
    let options = drivemap_bridge::Options {
        period: Duration::from_secs(1),
        metrics: args.metrics,
        mqtt: None,
        deadline: drivemap_bridge::command::DEFAULT_DEADLINE,
    };
    drivemap_bridge::run(vec![l], options, Arc::new(AtomicBool::new(false)))?;
    Ok(ExitCode::SUCCESS)
}
