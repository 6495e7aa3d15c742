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

use crate::commands::bridge::{LineArgs, ProxyArgs, link};
use crate::error::Error;
use crate::live::session::SettingsArgs;
use crate::maps::MapsDir;

/// Arguments of `drivemap proxy`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// Where masters connect (Modbus TCP; loopback unless another address is given).
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:5020")]
    pub(crate) listen: SocketAddr,
    /// A drive on the link: its map's id and slave address (`yaskawa-v7@1`); repeat per drive.
    #[arg(long = "drive", value_name = "ID@SLAVE", required = true)]
    pub(crate) drives: Vec<String>,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
    #[command(flatten)]
    pub(crate) line: LineArgs,
    #[command(flatten)]
    pub(crate) proxy: ProxyArgs,
    /// Carry out writes to drives whose map is marked `draft:` (not reviewed against its
    /// manual); without it they are refused (01h).
    #[arg(long)]
    pub(crate) draft: bool,
    /// Where Prometheus scrapes the proxy's `/metrics` (requests per master, refusals).
    #[arg(long, value_name = "ADDR")]
    pub(crate) metrics: Option<SocketAddr>,
}

/// Serves masters until SIGTERM or SIGINT.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let la = args.line.link()?;
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
