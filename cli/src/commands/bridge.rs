//! `drivemap bridge --drive ID@SLAVE... (--tcp | --gateway | --rtu-tcp | --serial) ...
//! [--metrics ADDR] [--mqtt URL] [--config FILE]`: the drives polled into Prometheus and MQTT /
//! Home Assistant ([`drivemap_bridge`]).

use std::collections::{BTreeMap, BTreeSet};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use clap::Args as ClapArgs;
use drivemap_bridge::link::{DriveSpec, LinkSpec};
use drivemap_bridge::mqtt;
use drivemap_map::Map;
use serde::Deserialize;

use crate::error::Error;
use crate::live::link::{Link as LinkArgs, ParityParser};
use crate::live::session::SettingsArgs;
use crate::maps::MapsDir;
use drivemap_runtime::core::profile::Parity;

/// Arguments of `drivemap bridge`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// A drive on the link given by --tcp/--gateway/--rtu-tcp/--serial: its map's id and its
    /// slave address (`yaskawa-v7@1`). Repeat for every drive on that link; more links go in
    /// --config.
    #[arg(long = "drive", value_name = "ID@SLAVE")]
    pub(crate) drives: Vec<String>,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
    #[command(flatten)]
    pub(crate) line: LineArgs,
    /// Variants and values given instead of read, for every --drive (`--set n011=60`).
    #[command(flatten)]
    pub(crate) settings: SettingsArgs,
    /// Time between the starts of two poll cycles of each link.
    #[arg(long, default_value = "1s", value_parser = drivemap_live::duration::positive)]
    pub(crate) period: Duration,
    /// A longer period for some registers of the command line's drives: `WHAT=PERIOD`, WHAT a
    /// register, a role, a group of the map, `status`, `monitors` or `parameters`
    /// (`--period-of parameters=60s`); repeat for more. The rest every --period.
    #[arg(long = "period-of", value_name = "WHAT=PERIOD", value_parser = period_of)]
    pub(crate) period_of: Vec<(String, Duration)>,
    /// Where Prometheus scrapes `/metrics` (loopback unless an address is given).
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:9187")]
    pub(crate) metrics: SocketAddr,
    /// No `/metrics` endpoint.
    #[arg(long = "no-metrics", conflicts_with = "metrics")]
    pub(crate) no_metrics: bool,
    /// The MQTT broker: `mqtt://HOST[:1883]`, or `mqtts://HOST[:8883]` with --mqtt-ca.
    #[arg(long, value_name = "URL")]
    pub(crate) mqtt: Option<String>,
    /// CA certificate (PEM) the broker's TLS certificate must chain to.
    #[arg(long = "mqtt-ca", value_name = "FILE")]
    pub(crate) mqtt_ca: Option<PathBuf>,
    /// A file whose first line is `USER:PASSWORD` for the broker (else the environment's
    /// DRIVEMAP_MQTT_USERNAME and DRIVEMAP_MQTT_PASSWORD; never on the command line).
    #[arg(long = "mqtt-credentials", value_name = "FILE")]
    pub(crate) mqtt_credentials: Option<PathBuf>,
    /// Root of the state and command topics.
    #[arg(long = "mqtt-topic", default_value = "drivemap")]
    pub(crate) mqtt_topic: String,
    /// Home Assistant's MQTT discovery prefix.
    #[arg(long = "discovery-prefix", default_value = "homeassistant")]
    pub(crate) discovery_prefix: String,
    /// The MQTT client id (default: `drivemap-bridge-PID`).
    #[arg(long = "mqtt-client-id")]
    pub(crate) mqtt_client_id: Option<String>,
    /// What MQTT commands may write, comma-separated: register ids, parameter numbers or
    /// printed names, roles (`frequency_reference`, `accel_time`), `run` (run and stop),
    /// `stop`, `fault_reset`. Without it every command is refused.
    #[arg(long = "allow-writes", value_name = "LIST", value_delimiter = ',')]
    pub(crate) allow_writes: Vec<String>,
    /// Runs, references, sets and fault resets per second per drive over MQTT (as many at
    /// once); more are refused. A stop is never limited.
    #[arg(long = "command-rate", default_value_t = 2.0)]
    pub(crate) command_rate: f64,
    /// How long a run, reference, set or fault reset may wait for its link (busy, down, its
    /// drive silent) before it is refused as expired; never carried out later. A stop waits
    /// until it is delivered or a later run replaces it.
    #[arg(long = "command-deadline", default_value = "3s", value_parser = drivemap_live::duration::positive)]
    pub(crate) command_deadline: Duration,
    /// More links and drives, in YAML (see the README, "Into Prometheus / Home Assistant").
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    /// Write through maps marked `draft:` (not reviewed against their manuals): without it, the
    /// drives of a draft map are read (with a note) and nothing is written to them, not even a
    /// stop. With it every command through a draft says so.
    #[arg(long)]
    pub(crate) draft: bool,
    /// Serve Modbus TCP masters on this address for the drives of the command line's link,
    /// through the bridge's one master on the line (see `drivemap proxy`).
    #[arg(long = "serve-modbus", value_name = "ADDR")]
    pub(crate) serve_modbus: Option<SocketAddr>,
    #[command(flatten)]
    pub(crate) proxy: ProxyArgs,
}

/// What Modbus TCP masters served by the proxy may do (`drivemap proxy`, `bridge --serve-modbus`).
#[derive(ClapArgs, Debug, Clone)]
pub(crate) struct ProxyArgs {
    /// Carry out the masters' writes (each checked by the drive's write gate and its limits);
    /// without it every write is refused with exception 01h.
    #[arg(long = "proxy-writes")]
    pub(crate) writes: bool,
    /// The masters (addresses or networks, `192.168.1.20`, `10.0.0.0/8`) whose writes may touch
    /// a command register (run, stop, fault reset); others get exception 01h.
    #[arg(long = "allow-commands", value_name = "CIDR", value_delimiter = ',')]
    pub(crate) allow_commands: Vec<String>,
    /// Answer a read from the same read of another master made within this age.
    #[arg(long, value_name = "AGE", value_parser = drivemap_live::duration::positive)]
    pub(crate) cache: Option<Duration>,
    /// Masters served at once; more are closed at once.
    #[arg(long = "max-connections", default_value_t = 16, value_parser = clap::value_parser!(u16).range(1..=1024))]
    pub(crate) max_connections: u16,
    /// How long a master's request may wait for the line before it is answered 0Bh.
    #[arg(long = "proxy-timeout", id = "proxy_timeout", default_value = "5s", value_parser = drivemap_live::duration::positive)]
    pub(crate) wait: Duration,
}

impl ProxyArgs {
    /// The proxy's options on `listen`.
    pub(crate) fn options(
        &self,
        listen: SocketAddr,
    ) -> Result<drivemap_bridge::proxy::ProxyOptions, Error> {
        let allow_commands = self
            .allow_commands
            .iter()
            .map(|c| {
                drivemap_bridge::proxy::Cidr::parse(c).map_err(|e| format!("--allow-commands {e}"))
            })
            .collect::<Result<_, _>>()?;
        Ok(drivemap_bridge::proxy::ProxyOptions {
            listen,
            allow_writes: self.writes,
            allow_commands,
            max_connections: usize::from(self.max_connections),
            cache: self.cache,
            timeout: self.wait,
        })
    }
}

/// The link of the command line's drives (`drivemap bridge`, `drivemap proxy`).
#[derive(ClapArgs, Debug, Clone)]
pub(crate) struct LineArgs {
    /// The drives' own Modbus TCP interface (`192.168.1.10:502`).
    #[arg(long, value_name = "HOST:PORT")]
    pub(crate) tcp: Option<String>,
    /// A Modbus TCP to RTU gateway with the drives on its serial line.
    #[arg(long, value_name = "HOST:PORT")]
    pub(crate) gateway: Option<String>,
    /// RTU frames over TCP through a transparent serial gateway.
    #[arg(long = "rtu-tcp", value_name = "HOST:PORT")]
    pub(crate) rtu_tcp: Option<String>,
    /// Serial port speaking Modbus RTU (`/dev/ttyUSB0`), or Modbus ASCII with --ascii.
    #[arg(long, value_name = "PATH")]
    pub(crate) serial: Option<String>,
    /// Modbus ASCII instead of RTU, on --serial or through a transparent gateway (--rtu-tcp).
    #[arg(long, conflicts_with_all = ["tcp", "gateway"])]
    pub(crate) ascii: bool,
    /// Data bits of an ASCII line, 7 or 8 (default: the map's).
    #[arg(long = "data-bits", requires = "ascii", value_parser = clap::value_parser!(u8).range(7..=8))]
    pub(crate) data_bits: Option<u8>,
    /// Baud rate of the serial line (default: the first drive's map's default).
    #[arg(long)]
    pub(crate) baud: Option<u32>,
    /// Parity of the serial line (default: the map's).
    #[arg(long, value_parser = ParityParser)]
    pub(crate) parity: Option<Parity>,
    /// How long to wait for each reply (default: from the map).
    #[arg(long, value_parser = drivemap_live::duration::positive)]
    pub(crate) timeout: Option<Duration>,
    /// Further attempts after a timeout.
    #[arg(long, default_value_t = 1)]
    pub(crate) retries: u8,
}

impl LineArgs {
    /// Whether a link was given.
    fn given(&self) -> bool {
        self.tcp.is_some()
            || self.gateway.is_some()
            || self.rtu_tcp.is_some()
            || self.serial.is_some()
    }

    /// The link, checked.
    pub(crate) fn link(&self) -> Result<LinkArgs, Error> {
        link_args(
            self.tcp.clone(),
            self.gateway.clone(),
            self.rtu_tcp.clone(),
            self.serial.clone(),
            self.baud,
            self.parity,
            self.timeout,
            self.retries,
            self.ascii,
            self.data_bits,
        )
    }
}

/// `--config` file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Config {
    links: Vec<ConfigLink>,
}

/// One link of the `--config` file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfigLink {
    tcp: Option<String>,
    gateway: Option<String>,
    rtu_tcp: Option<String>,
    serial: Option<String>,
    baud: Option<u32>,
    timeout_ms: Option<u64>,
    /// Modbus ASCII instead of RTU on `serial` or `rtu_tcp`.
    #[serde(default)]
    ascii: bool,
    /// Data bits of an ASCII line.
    data_bits: Option<u8>,
    /// `ID@SLAVE`.
    drives: Vec<String>,
    /// Longer periods for some registers: `{parameters: 60s, output_current: 5s}`.
    #[serde(default)]
    periods: BTreeMap<String, String>,
}

/// `WHAT=PERIOD` of `--period-of`.
fn period_of(text: &str) -> Result<(String, Duration), String> {
    let (what, period) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}` is not WHAT=PERIOD (`parameters=60s`)"))?;
    let period = drivemap_live::duration::positive(period.trim()).map_err(|e| e.to_string())?;
    Ok((what.trim().to_owned(), period))
}

/// Reads `--config` with the map loader's limits (size, nesting depth, aliases: untrusted
/// text is never read whole or expanded without bound), every error naming the file and line.
fn read_config(path: &std::path::Path) -> Result<Config, Error> {
    use drivemap_map::{MAX_YAML_BYTES, parse_yaml, too_large};
    use std::io::Read;
    let shown = path.display();
    let mut text = String::new();
    let file = std::fs::File::open(path).map_err(|e| format!("--config {shown}: {e}"))?;
    // At most one byte past the limit, so a huge file (or a device) is never read whole.
    file.take(MAX_YAML_BYTES as u64 + 1)
        .read_to_string(&mut text)
        .map_err(|e| format!("--config {shown}: {e}"))?;
    let name = format!("{shown}");
    if text.len() > MAX_YAML_BYTES {
        return Err(format!("{}", too_large(&name, text.len())).into());
    }
    let tree = parse_yaml(&name, &text).map_err(|d| format!("--config {d}"))?;
    serde_yaml::from_value(tree.to_value()).map_err(|e| format!("--config {shown}: {e}").into())
}

/// Splits `ID@SLAVE`.
fn drive_slave(text: &str) -> Result<(String, u8), Error> {
    let (id, slave) = text
        .rsplit_once('@')
        .ok_or_else(|| format!("`{text}` is not ID@SLAVE (`yaskawa-v7@1`)"))?;
    let slave: u8 = slave
        .parse()
        .ok()
        .filter(|s| (1..=247).contains(s))
        .ok_or_else(|| format!("`{text}`: the slave address `{slave}` is not 1 to 247"))?;
    Ok((id.trim().to_owned(), slave))
}

// One parameter per command-line option of a link (clap's fields), checked together.
#[allow(clippy::too_many_arguments)]
pub(crate) fn link_args(
    tcp: Option<String>,
    gateway: Option<String>,
    rtu_tcp: Option<String>,
    serial: Option<String>,
    baud: Option<u32>,
    parity: Option<Parity>,
    timeout: Option<Duration>,
    retries: u8,
    ascii: bool,
    data_bits: Option<u8>,
) -> Result<LinkArgs, Error> {
    let given = [&tcp, &gateway, &rtu_tcp, &serial]
        .iter()
        .filter(|x| x.is_some())
        .count();
    if given != 1 {
        return Err("give one of --tcp, --gateway, --rtu-tcp, --serial for the drives".into());
    }
    Ok(LinkArgs {
        tcp,
        gateway,
        rtu_tcp,
        serial,
        ascii,
        data_bits,
        baud,
        parity,
        stop_bits: None,
        slave: None,
        timeout,
        retries,
        request_gap: None,
    })
}

/// Builds a link of the bridge: its drives' maps loaded, their clients' timing, its connection.
pub(crate) fn link(
    dir: &MapsDir,
    args: LinkArgs,
    drives: &[String],
    settings: &SettingsArgs,
    draft: bool,
    names: &mut BTreeSet<String>,
    loaded: &mut BTreeMap<String, &'static Map>,
) -> Result<LinkSpec, Error> {
    if drives.is_empty() {
        return Err("a link without drives: give --drive ID@SLAVE".into());
    }
    let mut specs = Vec::new();
    let mut first: Option<&'static Map> = None;
    for text in drives {
        let (id, slave) = drive_slave(text)?;
        // Each map is read once, however many drives use it (1,000 drives of five maps).
        let drive: &'static Map = match loaded.get(&id) {
            Some(d) => d,
            None => {
                let d: &'static Map = Box::leak(Box::new(dir.load(&id)?));
                loaded.insert(id.clone(), d);
                d
            }
        };
        args.check_transport(drive)?;
        first.get_or_insert(drive);
        let given = settings.resolve(drive)?;
        // The bridge reads what conversions depend on from the drive every cycle: a `--set`
        // of a register it can read would replace what the drive holds by what was assumed.
        for g in given.given.iter().filter(|g| !g.external) {
            if let Some(r) = drive.register_by_id(&g.id)
                && r.readable()
                && !r.broadcast_only()
                && r.plan().transports.contains(args.kind())
            {
                return Err(format!(
                    "--set {}={}: the bridge reads {} from the drive every cycle; --set is for what the drive does not give (an external quantity, a setting it cannot read on this link)",
                    drivemap_live::codec::shorten(&g.name),
                    drivemap_live::codec::shorten(&g.value),
                    r.label()
                )
                .into());
            }
        }
        let profile = drive.plan().profile;
        let mut name = format!("{id}-{slave}");
        let mut n = 2;
        while !names.insert(name.clone()) {
            name = format!("{id}-{slave}-{n}");
            n += 1;
        }
        specs.push(DriveSpec {
            drive,
            slave,
            name,
            options: args.client_options(drive, profile),
            settings: given.settings,
            fixed: given.fixed,
            registers: Vec::new(),
            periods: Vec::new(),
            draft: drivemap_live::draft::DraftWrites::from_flag(draft),
        });
    }
    let Some(first) = first else {
        return Err("a link without drives".into());
    };
    let profile = first.plan().profile;
    let kind = args.kind();
    let line = args.bus_line(first);
    let shown = if let Some(a) = &args.tcp {
        format!("tcp {a}")
    } else if let Some(a) = &args.gateway {
        format!("gateway {a}")
    } else if let Some(a) = &args.rtu_tcp {
        format!("rtu-tcp {a}")
    } else {
        format!("serial {}", args.serial.clone().unwrap_or_default())
    };
    // Each drive's commands are checked against its own map being a draft (`DriveSpec::draft`):
    // the link's transport is shared, so it is not guarded by the first drive's map.
    let connect = Box::new(move || {
        args.connect_as(first, profile, drivemap_live::draft::DraftWrites::Allowed)
            .map(|(client, _)| client.into_transport())
            .map_err(Into::into)
    });
    Ok(LinkSpec {
        name: shown,
        kind,
        line,
        connect,
        drives: specs,
        poll: true,
        proxy: None,
    })
}

/// The broker's user name and password: from `--mqtt-credentials FILE` (`USER:PASSWORD`), else
/// the environment.
fn credentials(file: Option<&PathBuf>) -> Result<Option<(String, String)>, Error> {
    if let Some(f) = file {
        let text = std::fs::read_to_string(f)
            .map_err(Error::io(format!("--mqtt-credentials {}", f.display())))?;
        let line = text.lines().next().unwrap_or("").trim_end();
        let (user, password) = line.split_once(':').ok_or_else(|| {
            format!(
                "--mqtt-credentials {}: line 1 is not USER:PASSWORD",
                f.display()
            )
        })?;
        return Ok(Some((user.to_owned(), password.to_owned())));
    }
    match (
        std::env::var("DRIVEMAP_MQTT_USERNAME"),
        std::env::var("DRIVEMAP_MQTT_PASSWORD"),
    ) {
        (Ok(u), Ok(p)) => Ok(Some((u, p))),
        (Ok(_), Err(_)) | (Err(_), Ok(_)) => Err(
            "give both DRIVEMAP_MQTT_USERNAME and DRIVEMAP_MQTT_PASSWORD, or --mqtt-credentials FILE"
                .into(),
        ),
        _ => Ok(None),
    }
}

/// Runs the bridge until SIGTERM or SIGINT.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let mut names = BTreeSet::new();
    let mut loaded = BTreeMap::new();
    let mut links = Vec::new();
    if !args.drives.is_empty() {
        let la = args.line.link()?;
        let mut l = link(
            &args.dir,
            la,
            &args.drives,
            &args.settings,
            args.draft,
            &mut names,
            &mut loaded,
        )?;
        for d in &mut l.drives {
            d.periods = args.period_of.clone();
        }
        l.proxy = args
            .serve_modbus
            .map(|addr| args.proxy.options(addr))
            .transpose()?;
        links.push(l);
    } else if args.serve_modbus.is_some() {
        return Err("--serve-modbus serves the drives of the command line's link: give --drive ID@SLAVE with a link".into());
    } else if args.line.given() {
        return Err("a link without drives: give --drive ID@SLAVE".into());
    }
    if let Some(path) = &args.config {
        let config = read_config(path)?;
        for (i, l) in config.links.into_iter().enumerate() {
            let la = link_args(
                l.tcp,
                l.gateway,
                l.rtu_tcp,
                l.serial,
                l.baud,
                None,
                l.timeout_ms.map(Duration::from_millis),
                args.line.retries,
                l.ascii,
                l.data_bits,
            )
            .map_err(|e| format!("--config {}: links[{i}]: {e}", path.display()))?;
            let mut spec = link(
                &args.dir,
                la,
                &l.drives,
                &SettingsArgs::default(),
                args.draft,
                &mut names,
                &mut loaded,
            )
            .map_err(|e| format!("--config {}: links[{i}]: {e}", path.display()))?;
            let periods = l
                .periods
                .iter()
                .map(|(what, p)| {
                    drivemap_live::duration::positive(p.trim())
                        .map(|d| (what.clone(), d))
                        .map_err(|e| {
                            format!(
                                "--config {}: links[{i}].periods.{what}: {e}",
                                path.display()
                            )
                        })
                })
                .collect::<Result<Vec<_>, _>>()?;
            for d in &mut spec.drives {
                d.periods = periods.clone();
            }
            links.push(spec);
        }
    }
    if links.is_empty() {
        return Err("no drives: give --drive ID@SLAVE with a link, or --config FILE".into());
    }
    if links.len() > drivemap_bridge::MAX_LINKS {
        return Err(drivemap_bridge::Error::TooManyLinks {
            links: links.len(),
            max: drivemap_bridge::MAX_LINKS,
        }
        .into());
    }
    let mqtt = match &args.mqtt {
        Some(url) => {
            mqtt::parse_url(url)?;
            let topic = args.mqtt_topic.trim_end_matches('/').to_owned();
            let prefix = args.discovery_prefix.trim_end_matches('/').to_owned();
            mqtt::check_topic_root("--mqtt-topic", &topic)?;
            mqtt::check_topic_root("--discovery-prefix", &prefix)?;
            if !(args.command_rate.is_finite() && args.command_rate > 0.0) {
                return Err(drivemap_bridge::Error::CommandRate {
                    rate: args.command_rate,
                }
                .into());
            }
            Some(mqtt::Options {
                url: url.clone(),
                ca: args.mqtt_ca.clone(),
                credentials: credentials(args.mqtt_credentials.as_ref())?,
                client_id: args
                    .mqtt_client_id
                    .clone()
                    .unwrap_or_else(|| format!("drivemap-bridge-{}", std::process::id())),
                topic,
                discovery_prefix: prefix,
                allow: args
                    .allow_writes
                    .iter()
                    .map(|s| s.trim().to_owned())
                    .collect(),
                rate: args.command_rate,
            })
        }
        None if !args.allow_writes.is_empty() => {
            return Err("--allow-writes is for MQTT commands: give --mqtt too".into());
        }
        None => None,
    };
    if args.no_metrics && mqtt.is_none() && args.serve_modbus.is_none() {
        return Err("nothing to serve: --no-metrics without --mqtt or --serve-modbus".into());
    }
    let options = drivemap_bridge::Options {
        period: args.period,
        metrics: (!args.no_metrics).then_some(args.metrics),
        mqtt,
        deadline: args.command_deadline,
    };
    drivemap_bridge::run(links, options, Arc::new(AtomicBool::new(false)))?;
    Ok(ExitCode::SUCCESS)
}
