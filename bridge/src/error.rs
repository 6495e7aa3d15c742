//! Why the bridge cannot start, and why a write through it is refused: each names the option,
//! file, address or register it is about.

use std::net::SocketAddr;
use std::path::PathBuf;

use drivemap_live::lookup::NotFound;

/// Why the bridge cannot start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No drive was given.
    #[error("no drives to bridge")]
    NoDrives,
    /// `--mqtt` is not `mqtt://` or `mqtts://`.
    #[error("--mqtt {url}: give mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (TLS)")]
    MqttScheme {
        /// The URL given.
        url: String,
    },
    /// `--mqtt`'s port is not a number from 0 to 65535.
    #[error("--mqtt {url}: `{port}` is not a port")]
    MqttPort {
        /// The URL given.
        url: String,
        /// The port as written.
        port: String,
    },
    /// `--mqtt` carries a user name or password (`mqtt://user:pass@host`): never taken from
    /// the command line, where every process and shell history can read it.
    #[error(
        "--mqtt {url}: credentials in the URL are refused (the command line is readable by every process); give DRIVEMAP_MQTT_USERNAME and DRIVEMAP_MQTT_PASSWORD or --mqtt-credentials FILE"
    )]
    MqttUserinfo {
        /// The URL without its credentials.
        url: String,
    },
    /// `--mqtt-topic` or `--discovery-prefix` is not a topic to publish under.
    #[error("{option} {root}: {why}")]
    TopicRoot {
        /// The option.
        option: &'static str,
        /// The value, quoted.
        root: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// `--command-rate` is not a finite positive number.
    #[error("--command-rate {rate}: give a finite number of commands per second above 0")]
    CommandRate {
        /// The rate given.
        rate: f64,
    },
    /// More links than the bridge serves.
    #[error(
        "{links} links: the bridge serves at most {max} (one thread each); put the drives of a line on one link"
    )]
    TooManyLinks {
        /// Links given.
        links: usize,
        /// The most served.
        max: usize,
    },
    /// `--mqtt` has no host.
    #[error("--mqtt {url}: no host")]
    MqttHost {
        /// The URL given.
        url: String,
    },
    /// `mqtts://` without `--mqtt-ca`.
    #[error("--mqtt {url}: TLS needs the CA certificate the broker's chains to: --mqtt-ca FILE")]
    NoCa {
        /// The URL given.
        url: String,
    },
    /// `--mqtt-ca` with `mqtt://`.
    #[error("--mqtt-ca given for {url}, which is not TLS: use mqtts://")]
    CaWithoutTls {
        /// The URL given.
        url: String,
    },
    /// The CA file cannot be read, or holds a certificate rustls refuses.
    #[error("--mqtt-ca {}: {message}", path.display())]
    Ca {
        /// The file.
        path: PathBuf,
        /// What the PEM reader or rustls said.
        message: String,
    },
    /// The CA file holds no certificate.
    #[error("--mqtt-ca {}: no certificate in it", path.display())]
    NoCertificate {
        /// The file.
        path: PathBuf,
    },
    /// rustls refused its own default protocol versions with the ring provider.
    #[error("TLS: {0}")]
    Tls(#[from] rustls::Error),
    /// The tokio runtime could not be started.
    #[error("cannot start the runtime: {0}")]
    Runtime(#[source] std::io::Error),
    /// SIGTERM cannot be watched.
    #[error("cannot watch SIGTERM: {0}")]
    Signal(#[source] std::io::Error),
    /// The `/metrics` listener cannot bind.
    #[error("cannot listen for /metrics on {addr}: {source}")]
    Metrics {
        /// The address asked.
        addr: SocketAddr,
        /// Why not.
        source: std::io::Error,
    },
    /// The proxy's listener cannot bind.
    #[error("cannot listen for Modbus TCP masters on {addr}: {source}")]
    Proxy {
        /// The address asked.
        addr: SocketAddr,
        /// Why not.
        source: std::io::Error,
    },
    /// Registers asked for a link that are not there or cannot be read on it, one line each.
    #[error("{}", lines(.0))]
    Registers(Vec<RegisterProblem>),
    /// The link has nothing to poll.
    #[error("{link}: no readable registers on this link")]
    NothingReadable {
        /// The drive's name on the link.
        link: String,
    },
}

fn lines(problems: &[RegisterProblem]) -> String {
    let text: Vec<String> = problems.iter().map(ToString::to_string).collect();
    text.join("\n")
}

/// A register asked for (`registers:` of a drive) that cannot be polled.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RegisterProblem {
    /// The map has no register of that name.
    #[error("{link}: {source}")]
    NotFound {
        /// The drive's name on the link.
        link: String,
        /// The lookup's answer (with suggestions).
        source: NotFound,
    },
    /// A poll period names nothing that is polled.
    #[error(
        "{link}: the period of {what}: no polled register is that (a register, role, group of the map, `status`, `monitors` or `parameters`)"
    )]
    NoPeriodTarget {
        /// The drive's name on the link.
        link: String,
        /// What was named, quoted.
        what: String,
    },
    /// It exists but is write-only, broadcast-only or not on this transport.
    #[error("{link}: {register} cannot be read on this link")]
    Unreadable {
        /// The drive's name on the link.
        link: String,
        /// The register, described.
        register: String,
    },
}

/// Why a write through the bridge is refused before it reaches the drive.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refused {
    /// The register named is not on the drive.
    #[error(transparent)]
    NotFound(#[from] NotFound),
    /// The bridge was not started with `--allow-writes` naming it (`what`, quoted).
    #[error("not allowed: the bridge was not started with --allow-writes naming {what}")]
    NotAllowed {
        /// What would have to be named.
        what: String,
    },
    /// A button command (`run`, `stop`, `fault_reset`) whose payload is not `PRESS`.
    #[error("command/{command} takes the payload PRESS (a Home Assistant button), not {payload}")]
    NotPress {
        /// The command topic's last level.
        command: &'static str,
        /// The payload, quoted.
        payload: String,
    },
    /// A message with the retain flag on a command topic: a command is carried out once, when
    /// it is sent, never again on a (re)connection.
    #[error(
        "retained messages are never carried out on command topics (publish commands with retain off; clear the retained one with an empty retained message)"
    )]
    Retained,
    /// The drive's map is a draft and the bridge was not started with `--draft`: nothing is
    /// written through it, not even a stop (its run register's address is what a reader made of
    /// the manual's text).
    #[error("{why}")]
    Draft {
        /// The refusal, naming the map.
        why: String,
    },
    /// Over the drive's rate of runs, references and sets (a stop is never limited).
    #[error(
        "over the rate limit of {rate} command(s) per second for {drive} (stops are never limited)"
    )]
    RateLimit {
        /// Commands per second, as given.
        rate: String,
        /// The drive's name.
        drive: String,
    },
    /// The drive did not answer its last poll (link down or drive silent): a run, reference,
    /// set or reset is not kept for later.
    #[error(
        "{drive} did not answer its last poll (link down or drive silent): commands other than stop are not kept for later"
    )]
    NotAnswering {
        /// The drive's name.
        drive: String,
    },
    /// A later command replaced this one before it was carried out.
    #[error("superseded by a later {by} before it was carried out")]
    Superseded {
        /// The later command (`stop`, `run`, ...).
        by: &'static str,
    },
}

/// A new connection of a link could not be made (what the link's `Connect` answers: the
/// CLI's [`drivemap_live::link::LinkError`], a transport's I/O error).
pub type ConnectError = Box<dyn std::error::Error + Send + Sync>;

/// Why a register of a polled drive cannot be read this cycle, or its reads not planned.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PollFailure {
    /// Its address moves with a setting the bridge has not read yet.
    #[error("{register}: its address depends on {setting}, which is not known yet")]
    AddressUnknown {
        /// The register, described.
        register: String,
        /// The setting (parameter number when printed).
        setting: &'static str,
    },
    /// The runtime's planner refused the registers.
    #[error(transparent)]
    Plan(#[from] drivemap_runtime::planner::PlanError),
    /// The read failed on the wire.
    #[error(transparent)]
    Read(#[from] drivemap_runtime::error::Error),
}

/// Why a command through the bridge wrote nothing (published on the drive's `error` topic).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CommandFailure {
    /// The register named is not on the drive.
    #[error(transparent)]
    NotFound(#[from] NotFound),
    /// An empty payload.
    #[error("no value given for {register}")]
    NoValue {
        /// The register, described.
        register: String,
    },
    /// The write gate refused it (not writable on this link, broadcast only, ...).
    #[error("{register}: {source}")]
    Refused {
        /// The register, described.
        register: String,
        /// The gate's refusal.
        source: drivemap_runtime::error::Refusal,
    },
    /// The parameter its limit depends on could not be read.
    #[error("reading {register}, which the limit depends on: {source}")]
    Dependency {
        /// The parameter, described.
        register: String,
        /// Why not.
        source: Box<PollFailure>,
    },
    /// The payload is not a value of the register.
    #[error(transparent)]
    Input(#[from] drivemap_live::codec::InputError),
    /// Fields given for a register without fields.
    #[error("{register} has no fields")]
    NoFields {
        /// The register, described.
        register: String,
    },
    /// The register's other fields could not be read to keep them.
    #[error("reading {id} to keep its other fields: {source}")]
    OtherFields {
        /// The register's id.
        id: String,
        /// Why not.
        source: Box<PollFailure>,
    },
    /// The value does not convert.
    #[error(transparent)]
    Value(#[from] drivemap_runtime::core::scale::ValueError),
    /// The register's address is not known yet.
    #[error(transparent)]
    Address(PollFailure),
    /// The drive or the line failed the write or the drive command.
    #[error(transparent)]
    Drive(#[from] drivemap_runtime::error::Error),
    /// The command names a drive index the link does not poll.
    #[error("no such drive on this link")]
    NoSuchDrive,
    /// A reference that is not a frequency.
    #[error("{value} is not a frequency in Hz")]
    NotAFrequency {
        /// The payload, quoted.
        value: String,
    },
    /// The drive's map is a draft and the bridge was not started with `--draft`.
    #[error("{why}")]
    Draft {
        /// The refusal, naming the map.
        why: String,
    },
    /// The command waited past its deadline (the link busy, down, or its drive silent).
    #[error("expired after {} ms waiting for the link (deadline {} ms): not carried out late", waited.as_millis(), deadline.as_millis())]
    Expired {
        /// How long it waited.
        waited: std::time::Duration,
        /// The deadline.
        deadline: std::time::Duration,
    },
    /// A fault reset for a drive that reports no fault.
    #[error("the drive reports no fault{}: nothing to reset", if *running { " and is running" } else { "" })]
    NoFault {
        /// It reports running.
        running: bool,
    },
    /// A fault reset for a running drive whose map gives no fault status.
    #[error(
        "the drive is running and its map gives no fault status: a reset is not sent to a running drive"
    )]
    RunningWithoutFaultRole,
}

impl CommandFailure {
    /// Whether a stop that failed this way is worth sending again: the line or the drive did
    /// not answer (a refusal of the gate or the drive's exception is final).
    pub fn retryable(&self) -> bool {
        use drivemap_runtime::error::Error as E;
        match self {
            CommandFailure::Drive(e) => {
                !matches!(e, E::Refused(_) | E::Value(_) | E::Exception { .. })
            }
            CommandFailure::Dependency { source, .. }
            | CommandFailure::OtherFields { source, .. } => {
                matches!(&**source, PollFailure::Read(e) if !matches!(e, E::Refused(_) | E::Value(_) | E::Exception { .. }))
            }
            _ => false,
        }
    }
}

/// Why a drive cannot be exported for a tool on the link given (`drivemap export --format
/// home-assistant | node-red | telegraf`).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The drive does not have the link's transport.
    #[error(transparent)]
    Link(#[from] drivemap_live::link::LinkError),
    /// No link given.
    #[error("give the link the tool connects to: --tcp, --gateway, --rtu-tcp or --serial")]
    NoLink,
    /// A link address without a port.
    #[error("`{addr}` is not HOST:PORT")]
    NotHostPort {
        /// The address given.
        addr: String,
    },
    /// A link address whose port is not a TCP port.
    #[error("`{addr}`: `{port}` is not a TCP port")]
    NotPort {
        /// The address given.
        addr: String,
        /// What stands for the port.
        port: String,
    },
    /// A link address without a host.
    #[error("`{addr}` has no host")]
    NoHost {
        /// The address given.
        addr: String,
    },
    /// The runtime's planner cannot plan the reads.
    #[error(transparent)]
    Plan(drivemap_runtime::planner::PlanError),
    /// A planned read starts outside the link's address space.
    #[error("a planned read at {address:04X}h is outside 0..=FFFFh on this link")]
    ReadOutside {
        /// The read's address, as the manual prints it.
        address: u16,
    },
    /// No planned read covers a register.
    #[error("no planned read covers {register} at {address:04X}h")]
    NotCovered {
        /// The register's id.
        register: String,
        /// Its address.
        address: u16,
    },
}
