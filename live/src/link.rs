//! The link to a live drive: which transport, which slave, how long to wait.
//!
//! [`Link`] is what the `drivemap` command's `--tcp`, `--gateway`, `--rtu-tcp`, `--serial`,
//! `--ascii` and timing options give (with the `clap` feature it is those options); a program fills it in
//! and opens a [`crate::session::Session`] on it.

use std::time::Duration;

use drivemap_map::Map;

use crate::draft::DraftWrites;
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::core::profile::Parity;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::ascii_over_tcp::AsciiOverTcpTransport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::serial::{
    Parity as PortParity, SerialOptions, SerialTransport, StopBits,
};
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{client::Client, client::ClientOptions};

/// `--parity none|even|odd` as a clap value parser for [`Parity`] (the vocabulary crate has
/// no clap): the possible values are listed in `--help` and a wrong one is refused naming them.
#[cfg(feature = "clap")]
#[derive(Debug, Clone, Copy, Default)]
pub struct ParityParser;

#[cfg(feature = "clap")]
impl ParityParser {
    fn possible() -> impl Iterator<Item = clap::builder::PossibleValue> {
        Parity::ALL.into_iter().map(|p| {
            clap::builder::PossibleValue::new(p.name()).help(match p {
                Parity::None => "No parity bit",
                Parity::Even => "Even parity",
                Parity::Odd => "Odd parity",
            })
        })
    }
}

#[cfg(feature = "clap")]
impl clap::builder::TypedValueParser for ParityParser {
    type Value = Parity;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<Parity, clap::Error> {
        let name = clap::builder::PossibleValuesParser::new(Self::possible())
            .parse_ref(cmd, arg, value)?;
        Parity::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| clap::Error::new(clap::error::ErrorKind::InvalidValue).with_cmd(cmd))
    }

    fn possible_values(
        &self,
    ) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(Self::possible()))
    }
}

/// Why a link cannot be opened; each names the address or port.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// `--tcp` to a drive whose map lists no Modbus TCP interface.
    #[error(
        "{drive} has no Modbus TCP interface (its map's protocol.transports is [{transports}]), so --tcp {addr} cannot reach it: for the drive on the serial line of a Modbus TCP to RTU gateway give --gateway {addr} (Modbus TCP frames, the drive's RTU addressing and timing), for a transparent gateway --rtu-tcp {addr}"
    )]
    NoTcp {
        /// The drive's id.
        drive: String,
        /// The transports its map lists.
        transports: String,
        /// The address given.
        addr: String,
    },
    /// The connection or port could not be opened.
    #[error("cannot {what} {addr}: {source}")]
    Open {
        /// What was tried: "connect to Modbus TCP server", "open serial port", ...
        what: &'static str,
        /// The address or port.
        addr: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// `--ascii` to a drive whose map does not list Modbus ASCII.
    #[error(
        "{drive}'s map does not list Modbus ASCII (its protocol.transports is [{transports}]), so --ascii would send frames the drive does not read: leave --ascii out for RTU, or add `ascii` to the map's transports with the manual's citation"
    )]
    NoAscii {
        /// The drive's id.
        drive: String,
        /// The transports its map lists.
        transports: String,
    },
    /// RTU framing to a drive whose map lists Modbus ASCII and not RTU.
    #[error(
        "{drive} speaks Modbus ASCII, not RTU (its map's protocol.transports is [{transports}]): add --ascii"
    )]
    NoRtu {
        /// The drive's id.
        drive: String,
        /// The transports its map lists.
        transports: String,
    },
    /// `--ascii` with a link that carries no serial frames, or data bits a line cannot have.
    #[error("{0}")]
    Ascii(String),
    /// The serial format is not one the map lists.
    #[error(transparent)]
    Format(#[from] drivemap_runtime::error::Refusal),
    /// No transport was given.
    #[error("give --tcp, --gateway, --rtu-tcp or --serial")]
    NoTransport,
}

/// How to reach the drive: one of `tcp`, `gateway`, `rtu_tcp` or `serial`, and the line's
/// settings (each `None` takes the map's default).
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(group(clap::ArgGroup::new("link").required(true).args(["tcp", "gateway", "rtu_tcp", "serial"]))))]
pub struct Link {
    /// The drive's own Modbus TCP interface (`192.168.1.10:502`); refused for a map whose
    /// `protocol.transports` lacks `tcp` (reach such a drive with --gateway or --rtu-tcp).
    #[cfg_attr(feature = "clap", arg(long, value_name = "ADDR"))]
    pub tcp: Option<String>,
    /// A Modbus TCP to RTU gateway with the drive on its serial line (`192.168.1.20:502`):
    /// Modbus TCP frames, the map's RTU addressing, RTU registers and RTU timing (--baud and
    /// --parity are the serial line's behind the gateway, for the timing).
    #[cfg_attr(feature = "clap", arg(long, value_name = "HOST:PORT"))]
    pub gateway: Option<String>,
    /// RTU frames over TCP through a transparent serial gateway (`192.168.1.20:4001`).
    #[cfg_attr(feature = "clap", arg(long = "rtu-tcp", value_name = "ADDR"))]
    pub rtu_tcp: Option<String>,
    /// Serial port speaking Modbus RTU (`/dev/ttyUSB0`), or Modbus ASCII with --ascii.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PATH"))]
    pub serial: Option<String>,
    /// Modbus ASCII (`:` ... LRC CR LF) instead of RTU: on --serial, or over TCP through a
    /// transparent gateway with --rtu-tcp. Refused for a map whose `protocol.transports`
    /// lacks `ascii`.
    #[cfg_attr(feature = "clap", arg(long, conflicts_with_all = ["tcp", "gateway"]))]
    pub ascii: bool,
    /// Data bits of an ASCII line, 7 or 8 (default: the map's `serial.data_bits`); RTU lines
    /// have 8.
    #[cfg_attr(feature = "clap", arg(long = "data-bits", requires = "ascii", value_parser = clap::value_parser!(u8).range(7..=8)))]
    pub data_bits: Option<u8>,
    /// Baud rate (default: the map's default, else 9600).
    #[cfg_attr(feature = "clap", arg(long))]
    pub baud: Option<u32>,
    /// Parity (default: the map's default, else none).
    #[cfg_attr(feature = "clap", arg(long, value_parser = ParityParser))]
    pub parity: Option<Parity>,
    /// Stop bits (default: the map's for the parity when its formats give only one, else 1;
    /// 2 without parity where the map fixes 11-bit characters). A map that lists its serial
    /// formats (`serial.formats`) refuses any other parity and stop bits.
    #[cfg_attr(feature = "clap", arg(long = "stop-bits", value_parser = clap::value_parser!(u8).range(1..=2)))]
    pub stop_bits: Option<u8>,
    /// Slave address (default: the map's default, else 1; 0 broadcasts a write).
    #[cfg_attr(feature = "clap", arg(long))]
    pub slave: Option<u8>,
    /// How long to wait for each reply (default: 1 s plus the map's response time and
    /// response-delay default).
    #[cfg_attr(feature = "clap", arg(long, value_parser = crate::duration::positive))]
    pub timeout: Option<Duration>,
    /// Further attempts after a timeout.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 2))]
    pub retries: u8,
    /// Least pause between a reply and the next request (default on RTU links: the map's
    /// `timing.request_gap`, V7/J7 24 bit times + 10 ms, at least the 3.5-character frame gap;
    /// none on Modbus TCP).
    #[cfg_attr(feature = "clap", arg(long = "request-gap", value_parser = crate::duration::parse))]
    pub request_gap: Option<Duration>,
}

/// A client over whichever transport was chosen.
pub type LiveClient = Client<Box<dyn Transport>>;

impl Link {
    /// A link with the map's defaults and two retries (as the command line's): connect with
    /// `tcp`, `gateway`, `rtu_tcp` or `serial` set through the constructors below.
    fn with(
        tcp: Option<String>,
        gateway: Option<String>,
        rtu_tcp: Option<String>,
        serial: Option<String>,
    ) -> Link {
        Link {
            tcp,
            gateway,
            rtu_tcp,
            serial,
            ascii: false,
            data_bits: None,
            baud: None,
            parity: None,
            stop_bits: None,
            slave: None,
            timeout: None,
            retries: 2,
            request_gap: None,
        }
    }

    /// The drive's own Modbus TCP interface at `addr` (`192.168.1.10:502`).
    pub fn tcp(addr: impl Into<String>) -> Link {
        Link::with(Some(addr.into()), None, None, None)
    }

    /// A Modbus TCP to RTU gateway at `addr` with the drive on its serial line.
    pub fn gateway(addr: impl Into<String>) -> Link {
        Link::with(None, Some(addr.into()), None, None)
    }

    /// RTU frames over TCP through a transparent serial gateway at `addr`.
    pub fn rtu_over_tcp(addr: impl Into<String>) -> Link {
        Link::with(None, None, Some(addr.into()), None)
    }

    /// A serial port speaking Modbus RTU (`/dev/ttyUSB0`).
    pub fn serial(path: impl Into<String>) -> Link {
        Link::with(None, None, None, Some(path.into()))
    }

    /// The same link speaking Modbus ASCII (a serial port, or a transparent gateway over TCP).
    pub fn with_ascii(self) -> Link {
        Link {
            ascii: true,
            ..self
        }
    }

    /// The slave address to talk to.
    pub fn slave(&self, drive: &Map) -> u8 {
        self.slave
            .or(drive.protocol().slave_address.default)
            .unwrap_or(1)
    }

    /// The transport kind the link will have, before connecting.
    pub fn kind(&self) -> TransportKind {
        if self.tcp.is_some() {
            TransportKind::Tcp
        } else if self.gateway.is_some() {
            TransportKind::TcpGateway
        } else if self.rtu_tcp.is_some() {
            if self.ascii {
                TransportKind::AsciiOverTcp
            } else {
                TransportKind::RtuOverTcp
            }
        } else if self.ascii {
            TransportKind::Ascii
        } else {
            TransportKind::Rtu
        }
    }

    /// Data bits of the serial line: 8 on RTU; on ASCII as given, else the map's
    /// `serial.data_bits`.
    pub fn data_bits(&self, drive: &Map) -> u8 {
        if !self.ascii {
            return 8;
        }
        self.data_bits
            .or(drive.protocol().serial.as_ref().map(|s| s.data_bits))
            .unwrap_or(8)
    }

    /// Baud rate, parity and stop bits of the serial line: as given, else the map's defaults
    /// (9600, no parity); 2 stop bits without parity where the map fixes 11-bit characters.
    pub fn line(&self, drive: &Map) -> (u32, Parity, u8) {
        serial_line(drive, self.baud, self.parity, self.stop_bits)
    }

    /// The line as the bus-time model of the runtime's read planner sees it (serial links; a
    /// TCP link is planned as the default 9600 baud line, which only the relative costs matter
    /// for).
    pub fn bus_line(&self, drive: &Map) -> SerialConfig {
        if self.serial.is_none() && self.gateway.is_none() {
            return SerialConfig::default();
        }
        self.serial_config(drive)
    }

    /// The serial line's baud rate and framing ([`Link::line`]) as the runtime counts bit
    /// and character times.
    fn serial_config(&self, drive: &Map) -> SerialConfig {
        let (baud, parity, stop_bits) = self.line(drive);
        let mut config = SerialConfig::new(baud).parity(parity).stop_bits(stop_bits);
        config.data_bits = self.data_bits(drive);
        if let Some(bits) = drive.serial_defaults().char_bits {
            config = config.fixed_char_bits(bits);
        }
        config
    }

    /// The client's options: the map's timing ([`ClientOptions::for_line`] on the line's baud
    /// rate and framing), with what was given on the command line in its place. On Modbus TCP
    /// the serial line's request gap does not apply (the drive's network card keeps its own
    /// line), so none is kept unless given; through a gateway (`--gateway`) the drive is on a
    /// serial line and its timing applies.
    pub fn client_options(&self, drive: &Map, profile: &Profile) -> ClientOptions {
        let mut options = if self.kind().reaches_rtu_side() {
            ClientOptions::for_line(profile, self.serial_config(drive))
        } else {
            ClientOptions {
                request_gap: Duration::ZERO,
                ..ClientOptions::for_profile(profile)
            }
        };
        if let Some(t) = self.timeout {
            options.timeout = t;
        }
        if let Some(g) = self.request_gap {
            options.request_gap = g;
        }
        options.retries = self.retries;
        options
    }

    /// Refuses `--tcp` for a drive whose map does not list Modbus TCP among its transports: a
    /// serial drive behind a Modbus TCP gateway is addressed on its RTU side, which `--gateway`
    /// does (Modbus TCP addressing would put every register of a drive with an RTU address
    /// offset one off).
    pub fn check_transport(&self, drive: &Map) -> Result<(), LinkError> {
        use drivemap_map::facts::TransportName;
        let listed = &drive.protocol().transports;
        let transports = || {
            listed
                .iter()
                .map(|t| t.word())
                .collect::<Vec<_>>()
                .join(", ")
        };
        if self.ascii {
            if self.tcp.is_some() || self.gateway.is_some() {
                return Err(LinkError::Ascii(
                    "--ascii goes with --serial or --rtu-tcp (a transparent gateway): --tcp and --gateway carry Modbus TCP frames".into(),
                ));
            }
            if !listed.contains(&TransportName::Ascii) {
                return Err(LinkError::NoAscii {
                    drive: drive.id().to_owned(),
                    transports: transports(),
                });
            }
            if !matches!(self.data_bits(drive), 7 | 8) {
                return Err(LinkError::Ascii(format!(
                    "{} data bits: an ASCII line has 7 or 8",
                    self.data_bits(drive)
                )));
            }
        } else if (self.serial.is_some() || self.rtu_tcp.is_some())
            && listed.contains(&TransportName::Ascii)
            && !listed.contains(&TransportName::Rtu)
        {
            return Err(LinkError::NoRtu {
                drive: drive.id().to_owned(),
                transports: transports(),
            });
        }
        let Some(addr) = &self.tcp else {
            return Ok(());
        };
        if drive.protocol().transports.contains(&TransportName::Tcp) {
            return Ok(());
        }
        Err(LinkError::NoTcp {
            drive: drive.id().to_owned(),
            addr: addr.clone(),
            transports: drive
                .protocol()
                .transports
                .iter()
                .map(|t| t.word())
                .collect::<Vec<_>>()
                .join(", "),
        })
    }

    /// Opens the link and makes a client for `profile`. Returns the client and a description
    /// of the link for headers. Through a draft map (`draft:`) the client's writes are refused
    /// unsent ([`crate::draft`]): [`Link::connect_as`] with [`DraftWrites::Allowed`] lets them
    /// through.
    pub fn connect(
        &self,
        drive: &Map,
        profile: &'static Profile,
    ) -> Result<(LiveClient, String), LinkError> {
        self.connect_as(drive, profile, DraftWrites::Refused)
    }

    /// [`Link::connect`], with writes through a draft map refused or allowed as `draft` says
    /// (the command line's `--draft`); a reviewed map's writes are not affected.
    pub fn connect_as(
        &self,
        drive: &Map,
        profile: &'static Profile,
        draft: DraftWrites,
    ) -> Result<(LiveClient, String), LinkError> {
        let options = self.client_options(drive, profile);
        let connect_timeout = options.timeout.max(Duration::from_secs(1));
        let (transport, what): (Box<dyn Transport>, String) = if let Some(addr) = &self.tcp {
            let t = TcpTransport::connect(addr.as_str(), connect_timeout).map_err(|source| {
                LinkError::Open {
                    what: "connect to Modbus TCP server",
                    addr: addr.clone(),
                    source,
                }
            })?;
            (Box::new(t), format!("Modbus TCP {addr}"))
        } else if let Some(addr) = &self.gateway {
            let t = TcpTransport::connect_gateway(addr.as_str(), connect_timeout).map_err(
                |source| LinkError::Open {
                    what: "connect to Modbus TCP gateway",
                    addr: addr.clone(),
                    source,
                },
            )?;
            (
                Box::new(t),
                format!("Modbus TCP gateway {addr} (drive on RTU)"),
            )
        } else if let Some(addr) = self.rtu_tcp.as_ref().filter(|_| !self.ascii) {
            let t =
                RtuOverTcpTransport::connect(addr.as_str(), connect_timeout).map_err(|source| {
                    LinkError::Open {
                        what: "connect to RTU gateway",
                        addr: addr.clone(),
                        source,
                    }
                })?;
            (Box::new(t), format!("RTU over TCP {addr}"))
        } else if let Some(addr) = self.rtu_tcp.as_ref().filter(|_| self.ascii) {
            let t = AsciiOverTcpTransport::connect(addr.as_str(), connect_timeout).map_err(
                |source| LinkError::Open {
                    what: "connect to ASCII gateway",
                    addr: addr.clone(),
                    source,
                },
            )?;
            (Box::new(t), format!("ASCII over TCP {addr}"))
        } else if let Some(path) = &self.serial {
            let (baud, parity, stops) = self.line(drive);
            let stop_bits = if stops == 2 {
                StopBits::Two
            } else {
                StopBits::One
            };
            let mut options = SerialOptions::new(path.as_str(), baud)
                .parity(port_parity(parity))
                .stop_bits(stop_bits)
                .with_profile(profile);
            if self.ascii {
                options = options
                    .ascii(self.data_bits(drive))
                    .map_err(|e| LinkError::Ascii(e.to_string()))?;
            }
            options.check_format()?;
            let t = SerialTransport::open(options).map_err(|source| LinkError::Open {
                what: "open serial port",
                addr: path.clone(),
                source,
            })?;
            let parity = format!("{parity:?}").to_lowercase();
            let framing = if self.ascii {
                format!("ASCII ({} data bits)", self.data_bits(drive))
            } else {
                "RTU".to_owned()
            };
            (
                Box::new(t),
                format!("{framing} {path} {baud} baud, parity {parity}, {stops} stop bit(s)"),
            )
        } else {
            return Err(LinkError::NoTransport);
        };
        let transport = crate::draft::guard(drive, draft, transport);
        let client = Client::with_options(transport, profile, options);
        Ok((client, format!("{what}, slave {}", self.slave(drive))))
    }
}

/// Baud rate, parity and stop bits of a serial line to `drive`: what is given, else the map's
/// defaults ([`drivemap_map::facts::SerialDefaults`]: 9600, no parity unless the map says
/// otherwise; the stop bits of the map's formats for the parity when they give only one, else
/// 2 without parity where the map fixes 11-bit characters, else 1). For `read`/`write`/`poll`
/// and for `simulate --serial`; whether the map lists the combination is checked when the port
/// is opened ([`SerialOptions::check_format`]).
pub fn serial_line(
    drive: &Map,
    baud: Option<u32>,
    parity: Option<Parity>,
    stop_bits: Option<u8>,
) -> (u32, Parity, u8) {
    let defaults = drive.serial_defaults();
    let parity = parity.unwrap_or(defaults.parity);
    let stop_bits = stop_bits.unwrap_or(defaults.stop_bits_for(parity));
    (baud.unwrap_or(defaults.baud), parity, stop_bits)
}

/// The serial port crate's parity for a line's.
pub fn port_parity(parity: Parity) -> PortParity {
    match parity {
        Parity::None => PortParity::None,
        Parity::Even => PortParity::Even,
        Parity::Odd => PortParity::Odd,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(link: &str) -> Link {
        Link {
            tcp: (link == "tcp").then(|| "127.0.0.1:502".to_owned()),
            gateway: (link == "gateway").then(|| "127.0.0.1:5020".to_owned()),
            rtu_tcp: (link == "rtu-tcp").then(|| "127.0.0.1:4001".to_owned()),
            serial: (link == "serial").then(|| "/dev/null".to_owned()),
            ascii: false,
            data_bits: None,
            baud: None,
            parity: None,
            stop_bits: None,
            slave: None,
            timeout: None,
            retries: 2,
            request_gap: None,
        }
    }

    /// The request gap defaults to the map's (V7: 24 bits at its default 9600 baud + 10 ms) on
    /// RTU links, follows `--baud`, and `--request-gap`/`--timeout` override it.
    #[test]
    fn client_timing_defaults_come_from_the_map() {
        let path = drivemap_test_support::paths::shipped_map("yaskawa-v7");
        let drive = drivemap_map::Loader::new().load(&path).expect("the V7 map");
        let profile = crate::leak_profile(&drive);
        let gap = |a: &Link| a.client_options(&drive, profile).request_gap;
        assert_eq!(gap(&args("serial")), Duration::from_micros(12_500));
        assert_eq!(gap(&args("rtu-tcp")), Duration::from_micros(12_500));
        // Behind a Modbus TCP gateway the drive is on a serial line: its timing applies.
        assert_eq!(gap(&args("gateway")), Duration::from_micros(12_500));
        assert_eq!(gap(&args("tcp")), Duration::ZERO);
        let slow = Link {
            baud: Some(4800),
            ..args("serial")
        };
        assert_eq!(gap(&slow), Duration::from_millis(15));
        let given = Link {
            request_gap: Some(Duration::from_millis(50)),
            timeout: Some(Duration::from_millis(300)),
            ..args("serial")
        };
        let o = given.client_options(&drive, profile);
        assert_eq!(
            (o.request_gap, o.timeout),
            (Duration::from_millis(50), Duration::from_millis(300))
        );
    }
}
