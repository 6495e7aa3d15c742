//! `drivemap simulate --drive <id>[@SLAVE]... (--tcp ADDR | --gateway ADDR | --rtu-tcp ADDR | --serial PATH) [--slave N]`
//!
//! Serves a simulated drive (crate `drivemap-sim`) built from the drive's map, or a line of them
//! at their slave addresses (`--drive yaskawa-v7@1 --drive ptlk-tds-v8@2`: a [`Line`]), logging
//! each request in one line: time, slave, function, address, quantity, result or exception.

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use clap::{ArgGroup, Args as ClapArgs};
use drivemap_live::link::{ParityParser, port_parity};
use drivemap_map::Map;
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::core::profile::Parity;
use drivemap_runtime::transport::serial::{SerialOptions, StopBits};
use drivemap_sim::server::Logger;
use drivemap_sim::{
    Line, RequestRecord, SimOptions, Simulator, clock::SystemClock, server::SerialServer,
    server::TcpFraming, server::TcpServer,
};

use crate::error::Error;
use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
#[command(group(ArgGroup::new("link").required(true).args(["tcp", "gateway", "rtu_tcp", "serial"])))]
pub(crate) struct Args {
    /// Drive id: a built-in map, or `<maps>/<id>.yaml`; `ID@SLAVE` puts it at that slave
    /// address. Repeat for a line of several drives on the one link, each at its own address
    /// (`--drive yaskawa-v7@1 --drive ptlk-tds-v8@2`), as on an RS-485 line or behind a gateway.
    #[arg(long, required = true, value_name = "ID[@SLAVE]")]
    pub(crate) drive: Vec<String>,
    /// Serve Modbus TCP here: `PORT` (binds 127.0.0.1) or `HOST:PORT` (binds where told).
    #[arg(long, value_name = "ADDR")]
    pub(crate) tcp: Option<String>,
    /// Serve Modbus TCP as a Modbus TCP to RTU gateway with the drive on its serial line:
    /// the map's RTU addressing and RTU registers (`read --gateway` talks to it). `PORT` or
    /// `HOST:PORT`.
    #[arg(long, value_name = "ADDR")]
    pub(crate) gateway: Option<String>,
    /// Serve RTU frames over TCP, as a transparent serial gateway does: `PORT` or `HOST:PORT`.
    #[arg(long = "rtu-tcp", value_name = "ADDR")]
    pub(crate) rtu_tcp: Option<String>,
    /// Serve Modbus RTU on a serial port or pseudo-terminal (Modbus ASCII with --ascii).
    #[arg(long, value_name = "PATH")]
    pub(crate) serial: Option<PathBuf>,
    /// Serve Modbus ASCII (`:` ... LRC CR LF) instead of RTU: on --serial, or over TCP with
    /// --rtu-tcp (as a transparent gateway forwards an ASCII line). Refused for a map whose
    /// `protocol.transports` lacks `ascii`.
    #[arg(long, conflicts_with_all = ["tcp", "gateway"])]
    pub(crate) ascii: bool,
    /// Data bits of an ASCII serial line, 7 or 8 (default: the map's `serial.data_bits`).
    #[arg(long = "data-bits", requires = "ascii", value_parser = clap::value_parser!(u8).range(7..=8))]
    pub(crate) data_bits: Option<u8>,
    /// Baud rate for --serial (default: the map's default, else 9600).
    #[arg(long)]
    pub(crate) baud: Option<u32>,
    /// Parity for --serial (default: the map's default, else none).
    #[arg(long, value_parser = ParityParser)]
    pub(crate) parity: Option<Parity>,
    /// Stop bits for --serial (default: the map's for the parity when its formats give only
    /// one, else 1; 2 without parity where the map fixes 11-bit characters). A map that lists
    /// its serial formats refuses any other parity and stop bits.
    #[arg(long = "stop-bits", value_parser = clap::value_parser!(u8).range(1..=2))]
    pub(crate) stop_bits: Option<u8>,
    /// With --serial: keep the drive's timing on a line of this speed in bits per second, for a
    /// pseudo-terminal (socat), which delivers bytes at once: each request counts as taking a
    /// character time per byte, each reply waits for the drive's response time from its map
    /// (V7: 24 bits + n156 as the simulated drive holds it; TDS-V8: 5 ms) and is handed over
    /// when its last character would have left the wire at this speed.
    #[arg(long = "line-speed", value_name = "BAUD", requires = "serial", value_parser = clap::value_parser!(u32).range(50..=1_000_000))]
    pub(crate) line_speed: Option<u32>,
    /// Slave address of a single drive (default: the map's default, else 1); with several
    /// drives, give each its address as `--drive ID@SLAVE`.
    #[arg(long)]
    pub(crate) slave: Option<u8>,
    /// The drive's value of a register or an external quantity of the map, in engineering units
    /// (`--set n152=1`, `--set drive_rated_current=9.6`): a register starts with it, an
    /// external quantity is the drive's. The same `--set` tells read/write/poll the value
    /// instead of reading it. (`--external` is an older name for it.) On a line of several
    /// drives, `SLAVE:NAME=VALUE` (`--set 2:Cn-02=50`) sets it in the drive at that address
    /// only; without the prefix, in every drive.
    #[arg(long = "set", alias = "external", value_name = "NAME=VALUE")]
    pub(crate) set: Vec<String>,
    /// Power on with the settings of a parameter set (`drivemap save`), as if restored and
    /// stored; `--set` values go on top. On a line of several drives, `SLAVE:FILE` gives it to
    /// the drive at that address only; without the prefix, to every drive of the set's map.
    #[arg(long = "restore", value_name = "[SLAVE:]FILE")]
    pub(crate) restore: Vec<String>,
    /// Model variant: `--variant voltage_class=v440` (`SLAVE:AXIS=OPTION` for one drive of a
    /// line, as `--set`).
    #[arg(long, value_name = "AXIS=OPTION")]
    pub(crate) variant: Vec<String>,
    /// Simulated time runs this many times faster than real time (ramps finish sooner; 0.1 to 1000).
    #[arg(long = "time-scale", default_value_t = 1.0, value_parser = drivemap_live::duration::number(0.1, 1000.0))]
    pub(crate) time_scale: f64,
    /// Do not log requests.
    #[arg(long)]
    pub(crate) quiet: bool,
    /// Power on with the network selected as the source of run commands and the reference
    /// (the map's `command_source` / `reference_source`). Without it the simulated drive starts
    /// at the manual's factory setting and ignores network run commands and references until
    /// that parameter is set (`--set n003=2`, or written over the link).
    #[arg(long = "network-source")]
    pub(crate) network_source: bool,
    /// TCP: connections served at once. One more takes the place of the connection that has
    /// gone longest (at least 1 s) without a request to this drive; when every one is busy, it
    /// is closed as soon as it is accepted.
    #[arg(long = "max-connections", default_value_t = 64, value_parser = clap::value_parser!(u16).range(1..))]
    pub(crate) max_connections: u16,
    /// TCP: a connection that sends no request to this drive (a well-formed frame to its unit)
    /// this long is closed.
    #[arg(long = "idle-timeout", default_value = "60s", value_parser = drivemap_live::duration::positive)]
    pub(crate) idle_timeout: std::time::Duration,
    /// TCP: a connection whose started frame is not complete this long after its first byte is
    /// closed, Modbus TCP and RTU framing alike (a peer trickling bytes cannot hold it).
    #[arg(long = "frame-timeout", default_value = "1s", value_parser = drivemap_live::duration::positive)]
    pub(crate) frame_timeout: std::time::Duration,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
}

/// The map of a drive id: under `--maps` when there, else built in.
pub(crate) fn load_drive(dir: &MapsDir, id: &str) -> Result<Map, Error> {
    Ok(dir.load(id)?)
}

fn pair(text: &str, what: &str) -> Result<(String, String), Error> {
    text.split_once('=')
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .filter(|(k, v)| !k.is_empty() && !v.is_empty())
        .ok_or_else(|| Error::Refused(format!("`{text}` is not {what}")))
}

fn number(text: &str, v: &str) -> Result<f64, Error> {
    v.parse::<f64>()
        .map_err(|_| Error::Refused(format!("`{text}`: `{v}` is not a number")))
}

/// Simulator options from the command line. Each `--set NAME=VALUE` is the drive's value:
/// of an external quantity of the map when `NAME` is one (as `read --set` takes it first),
/// else the power-on value of the register `NAME` (an unknown register is refused when the
/// simulator starts).
pub(crate) fn options(
    drive: &Map,
    slave: Option<u8>,
    set: &[String],
    variant: &[String],
    time_scale: f64,
) -> Result<SimOptions, Error> {
    if !(time_scale.is_finite() && time_scale > 0.0) {
        return Err(Error::Refused(format!(
            "--time-scale {time_scale}: give a positive number"
        )));
    }
    let mut o = SimOptions::new().clock(Arc::new(SystemClock::scaled(time_scale)));
    o.slave = slave;
    let externals = drive.externals();
    for s in set {
        let (k, v) = pair(s, "NAME=VALUE")?;
        let value = match number(s, &v) {
            Ok(n) => n,
            // An enumeration's code or a bit-field word may be given as `read --set` takes
            // it (`run_source=rs485`, `command=run,reverse`): its word is its value.
            Err(e) => match drivemap_live::lookup::find(drive, &k) {
                Ok(r)
                    if matches!(
                        r.plan().conversion,
                        drivemap_runtime::core::plan::Conversion::Enum { .. }
                            | drivemap_runtime::core::plan::Conversion::Bits { .. }
                    ) =>
                {
                    drivemap_live::codec::parse_value(
                        drive,
                        r,
                        &v,
                        &drivemap_live::LiveSettings::default(),
                    )
                    .map(f64::from)
                    .map_err(|e| format!("`{s}`: {e}"))?
                }
                _ => return Err(e),
            },
        };
        o = if externals.iter().any(|q| q.external == k) {
            o.external(&k, value)
        } else {
            o.set(&k, value)
        };
    }
    for s in variant {
        let (k, v) = pair(s, "AXIS=OPTION")?;
        o = o.variant(&k, &v);
    }
    Ok(o)
}

/// The values of the parameter set in `file` for a simulated `drive`, as power-on values in
/// the order a restore writes them (what selects a scale first). A set of another map is
/// refused, unless on a line of several drives, where it is for the drives of its map.
fn restored_values(drive: &Map, file: &str, line: bool) -> Result<Vec<(String, f64)>, Error> {
    use drivemap_live::paramset;
    let set = super::compare::read_set(file)?;
    if set.drive != drive.id() {
        if line {
            return Ok(Vec::new());
        }
        return Err(Error::Refused(format!(
            "--restore {file}: a set of {}, not of {}",
            set.drive,
            drive.id()
        )));
    }
    let given = drivemap_live::LiveSettings::default();
    let validated = paramset::validate(drive, &set, &given, false)
        .map_err(|e| Error::Refused(format!("--restore {file}: {e}")))?;
    let mut out = Vec::new();
    for (r, text) in &validated.entries {
        let value = text
            .trim()
            .parse::<f64>()
            .ok()
            .or_else(|| {
                drivemap_runtime::core::ratio::Fraction::parse(text)
                    .map(|f| f.num as f64 / f.den as f64)
            })
            .ok_or_else(|| {
                Error::Refused(format!(
                    "--restore {file}: {}: `{text}` is not a number",
                    r.id()
                ))
            })?;
        out.push((r.id().to_owned(), value));
    }
    Ok(out)
}

/// `PORT` binds loopback; `HOST:PORT` binds where told.
fn bind_address(text: &str) -> Result<String, Error> {
    if let Ok(port) = text.parse::<u16>() {
        return Ok(format!("127.0.0.1:{port}"));
    }
    if text.parse::<SocketAddr>().is_ok() || text.rsplit_once(':').is_some() {
        return Ok(text.to_string());
    }
    Err(Error::Refused(format!(
        "`{text}` is neither PORT nor HOST:PORT"
    )))
}

/// Wall-clock time of day (UTC) with milliseconds.
pub(crate) fn time_of_day() -> String {
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    let s = now.as_secs() % 86_400;
    format!(
        "{:02}:{:02}:{:02}.{:03}",
        s / 3600,
        s / 60 % 60,
        s % 60,
        now.subsec_millis()
    )
}

fn logger() -> Logger {
    Arc::new(|r: &RequestRecord| {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "{}  {r}", time_of_day());
        let _ = out.flush();
    })
}

/// One `--drive ID[@SLAVE]`: the id and the address, if given.
pub(crate) fn drive_at(text: &str) -> Result<(&str, Option<u8>), Error> {
    match text.rsplit_once('@') {
        None => Ok((text, None)),
        Some((id, slave)) => match slave.parse::<u8>() {
            Ok(n) if !id.is_empty() && n >= 1 => Ok((id, Some(n))),
            _ => Err(Error::Refused(format!(
                "--drive `{text}`: give ID@SLAVE with a slave address 1-255 (`yaskawa-v7@1`)"
            ))),
        },
    }
}

/// The options of `--set` / `--variant` that are for the drive at `slave`: those with its
/// `SLAVE:` prefix (taken off) and those without one. Only a line of several drives takes
/// prefixes.
fn for_slave(list: &[String], slave: u8, line: bool) -> Result<Vec<String>, Error> {
    let mut out = Vec::new();
    for s in list {
        match s.split_once(':') {
            Some((n, rest)) if line && !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()) => {
                match n.parse::<u8>() {
                    Ok(n) if n == slave => out.push(rest.to_string()),
                    Ok(_) => {}
                    Err(_) => {
                        return Err(Error::Refused(format!(
                            "`{s}`: `{n}` is not a slave address"
                        )));
                    }
                }
            }
            _ => out.push(s.clone()),
        }
    }
    Ok(out)
}

pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    if args.line_speed.is_some() && args.serial.is_none() {
        return Err(Error::Refused(
            "--line-speed times the drive's side of a serial line: give it with --serial PATH"
                .into(),
        ));
    }
    let several = args.drive.len() > 1;
    if several && args.slave.is_some() {
        return Err(Error::Refused(
            "--slave is for a single drive; on a line give each drive its address as --drive ID@SLAVE"
                .into(),
        ));
    }
    let kind = if args.tcp.is_some() {
        drivemap_runtime::core::profile::TransportKind::Tcp
    } else if args.ascii {
        drivemap_runtime::core::profile::TransportKind::Ascii
    } else {
        drivemap_runtime::core::profile::TransportKind::Rtu
    };
    let mut data_bits = args.data_bits;
    let mut line = Line::new();
    let mut described = Vec::new();
    let mut models = Vec::new();
    let mut serial = None;
    for text in &args.drive {
        let (id, at) = drive_at(text)?;
        if several && at.is_none() {
            return Err(Error::Refused(format!(
                "--drive `{text}`: on a line of several drives give each its slave address (`{id}@1`)"
            )));
        }
        let drive = load_drive(&args.dir, id)?;
        // Served on a link the map does not list, it would answer requests the drive never
        // would (`read --tcp` refuses the same map).
        if let Some(addr) = &args.tcp
            && !drive
                .protocol()
                .transports
                .contains(&drivemap_map::facts::TransportName::Tcp)
        {
            return Err(Error::Refused(format!(
                "{id} has no Modbus TCP interface (its map's protocol.transports lacks tcp), so --tcp {addr} would serve what the drive never does: serve it behind a Modbus TCP to RTU gateway with --gateway {addr}, or RTU frames over TCP with --rtu-tcp {addr}"
            )));
        }
        // ASCII is served only for a map that lists it, RTU only for one that lists RTU or
        // does not list ASCII alone (`read --ascii` refuses the same).
        {
            use drivemap_map::facts::TransportName;
            let listed = &drive.protocol().transports;
            let words = || {
                listed
                    .iter()
                    .map(|t| t.word())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            if args.ascii && !listed.contains(&TransportName::Ascii) {
                return Err(Error::Refused(format!(
                    "{id}'s map does not list Modbus ASCII (its protocol.transports is [{}]): serve it without --ascii",
                    words()
                )));
            }
            if !args.ascii
                && (args.serial.is_some() || args.rtu_tcp.is_some())
                && listed.contains(&TransportName::Ascii)
                && !listed.contains(&TransportName::Rtu)
            {
                return Err(Error::Refused(format!(
                    "{id} speaks Modbus ASCII, not RTU (its map's protocol.transports is [{}]): add --ascii",
                    words()
                )));
            }
            if args.ascii && data_bits.is_none() {
                data_bits = drive.protocol().serial.as_ref().map(|s| s.data_bits);
            }
        }
        if let Some(note) = drivemap_live::draft::read_note(&drive) {
            eprintln!("note: {note}");
        }
        let slave = at.or(args.slave);
        let (set, variant) = match slave {
            Some(n) => (
                for_slave(&args.set, n, several)?,
                for_slave(&args.variant, n, several)?,
            ),
            None => (args.set.clone(), args.variant.clone()),
        };
        let mut options = options(&drive, slave, &set, &variant, args.time_scale).map_err(|e| {
            if several {
                Error::Refused(format!("{text}: {e}"))
            } else {
                e
            }
        })?;
        let files = match slave {
            Some(n) => for_slave(&args.restore, n, several)?,
            None => args.restore.clone(),
        };
        let mut restored = Vec::new();
        for file in &files {
            restored.extend(restored_values(&drive, file, several)?);
        }
        // The set's values first, in its restore order; `--set` on top.
        options.initial.splice(0..0, restored);
        if args.network_source {
            options.network_source = Some(kind);
        }
        // The serial line, should --serial be chosen: the flags, else the first map's defaults.
        if serial.is_none() {
            serial = Some(drivemap_live::link::serial_line(
                &drive,
                args.baud,
                args.parity,
                args.stop_bits,
            ));
        }
        let sim = Simulator::new(drive, options).map_err(|e| {
            if several {
                format!("{text}: {e}")
            } else {
                e.to_string()
            }
        })?;
        for w in sim.warnings() {
            eprintln!(
                "warning: {}{w}",
                if several {
                    format!("{text}: ")
                } else {
                    String::new()
                }
            );
        }
        let model = if sim.has_model() {
            "drive model on"
        } else {
            "no drive model: the map gives no `roles:`, so this is a register store"
        };
        let (id, slave) = (&sim.drive().id(), sim.slave());
        described.push(format!("{id} at slave {slave}"));
        models.push(if several {
            format!("slave {slave}: {model}")
        } else {
            model.to_string()
        });
        line.add(sim).map_err(|e| e.to_string())?;
    }
    let (baud, parity, stop_bits) = serial.ok_or_else(|| Error::Refused("give --drive".into()))?;
    let what_drives = described.join(", ");
    let models = models.join("; ");
    let log = (!args.quiet).then(logger);
    let time = if args.time_scale == 1.0 {
        String::new()
    } else {
        format!(", time x{}", args.time_scale)
    };
    if let Some(addr) = args
        .tcp
        .as_deref()
        .or(args.gateway.as_deref())
        .or(args.rtu_tcp.as_deref())
    {
        let framing = if args.tcp.is_some() {
            TcpFraming::ModbusTcp
        } else if args.gateway.is_some() {
            TcpFraming::Gateway
        } else if args.ascii {
            TcpFraming::AsciiOverTcp
        } else {
            TcpFraming::RtuOverTcp
        };
        let addr = bind_address(addr)?;
        let limits = drivemap_sim::server::ServerOptions {
            max_connections: usize::from(args.max_connections),
            idle_timeout: args.idle_timeout,
            frame_deadline: args.frame_timeout,
        };
        let server = TcpServer::spawn_with(line, addr.as_str(), framing, log, limits)
            .map_err(|e| format!("cannot listen on {addr}: {e}"))?;
        let what = match framing {
            TcpFraming::ModbusTcp => "Modbus TCP",
            TcpFraming::RtuOverTcp => "RTU over TCP",
            TcpFraming::Gateway => "Modbus TCP gateway to RTU",
            TcpFraming::AsciiOverTcp => "ASCII over TCP",
        };
        outln!(
            "simulating {what_drives} on {what} {} ({models}{time}); Ctrl-C stops",
            server.local_addr()
        );
        server.wait();
        return Ok(ExitCode::SUCCESS);
    }
    let Some(path) = &args.serial else {
        return Err(Error::Refused(
            "give --tcp, --gateway, --rtu-tcp or --serial".into(),
        ));
    };
    let mut options = SerialOptions::new(path.to_string_lossy(), baud)
        .parity(port_parity(parity))
        .stop_bits(if stop_bits == 2 {
            StopBits::Two
        } else {
            StopBits::One
        });
    if args.ascii {
        options = options
            .ascii(data_bits.unwrap_or(7))
            .map_err(|e| Error::Refused(e.to_string()))?;
    }
    // Every drive of the line must offer the line's character format.
    for d in line.drives() {
        let profile = drivemap_sim::server::lock(d).profile();
        options = options.with_profile(profile);
        options.check_format().map_err(|e| e.to_string())?;
    }
    let first = drivemap_sim::server::lock(&line.drives()[0]).profile();
    let options = options.with_profile(first);
    let framing = if options.ascii {
        format!("ASCII ({} data bits)", options.data_bits)
    } else {
        "RTU".to_owned()
    };
    // The drive's side of a line at --line-speed: its response time, its characters' time.
    let timed = args.line_speed.map(|speed| drivemap_sim::timed::DriveLine {
        serial: SerialConfig {
            baud: speed,
            ..options.serial_config()
        },
        pace: true,
    });
    let server = SerialServer::spawn_on_line(line, options, log, timed)
        .map_err(|e| format!("cannot open serial port {}: {e}", path.display()))?;
    let timing = match timed {
        Some(t) => format!(
            ", the drive's timing on a {} baud line of {}-bit characters",
            t.serial.baud,
            t.serial.bits_per_char()
        ),
        None => String::new(),
    };
    outln!(
        "simulating {what_drives} on {framing} {} {baud} baud, parity {}, {stop_bits} stop bit(s) ({models}{time}{timing}); Ctrl-C stops",
        path.display(),
        parity.name()
    );
    server
        .wait()
        .map_err(|e| format!("serial port {}: {e}", path.display()))?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_port_binds_loopback() {
        assert_eq!(bind_address("5020").unwrap(), "127.0.0.1:5020");
        assert_eq!(bind_address("0.0.0.0:502").unwrap(), "0.0.0.0:502");
        assert!(bind_address("nonsense").is_err());
    }

    #[test]
    fn options_are_parsed_with_clear_errors() {
        let v7 = MapsDir::default().load("yaskawa-v7").unwrap();
        assert!(options(&v7, None, &["n152=1".into()], &[], 1.0).is_ok());
        let e = options(&v7, None, &["n152".into()], &[], 1.0)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "`n152` is not NAME=VALUE");
        let e = options(&v7, None, &["n152=x".into()], &[], 1.0)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "`n152=x`: `x` is not a code of modbus_frequency_reference_unit_selection; expected a number or one of: 0 (unit_0_1_hz), 1 (unit_0_01_hz), 2 (full_scale_30000), 3 (unit_0_1_percent)"
        );
        let e = options(&v7, None, &["n019=x".into()], &[], 1.0)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "`n019=x`: `x` is not a number");
        assert!(options(&v7, None, &[], &[], 0.0).is_err());
    }

    /// `--set` is the drive's value of a register (its power-on value) or of an external
    /// quantity of the map (the drive's), as `read --set` takes it.
    #[test]
    fn set_gives_registers_and_external_quantities() {
        let gpd = MapsDir::default().load("yaskawa-gpd515").unwrap();
        let o = options(
            &gpd,
            None,
            &["drive_rated_current=12.5".into(), "b1-01=2".into()],
            &[],
            1.0,
        )
        .unwrap();
        let sim = Simulator::new(gpd, o).unwrap();
        assert_eq!(sim.externals().get("drive_rated_current"), Some(&12.5));
        assert_eq!(sim.raw("b1-01").unwrap(), 2);
        // An enumeration's id, as `read --set` takes it.
        let gpd = MapsDir::default().load("yaskawa-gpd515").unwrap();
        let o = options(&gpd, None, &["b1-01=option_board".into()], &[], 1.0).unwrap();
        assert_eq!(Simulator::new(gpd, o).unwrap().raw("b1-01").unwrap(), 3);
        // The older `--external` still parses, as `--set`.
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let cli = Cli::try_parse_from([
            "simulate",
            "--drive",
            "yaskawa-gpd515",
            "--tcp",
            "5020",
            "--external",
            "drive_rated_current=9.6",
            "--set",
            "b1-01=2",
        ])
        .unwrap();
        assert_eq!(cli.args.set, ["drive_rated_current=9.6", "b1-01=2"]);
    }

    #[test]
    fn time_of_day_is_hh_mm_ss_mmm() {
        let t = time_of_day();
        assert_eq!(t.len(), 12, "{t}");
        assert_eq!(&t[2..3], ":");
        assert_eq!(&t[8..9], ".");
    }
}
