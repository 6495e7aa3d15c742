//! A map-aware Modbus TCP proxy: many masters (a PLC, Home Assistant, a logger, a laptop) share
//! one link, whose link task is the only master on the line.
//!
//! - Requests from every master wait in one queue, in the order they came (each connection has
//!   at most one request in it: the next frame of a connection is read after its reply), so a
//!   master waiting for a slow drive does not hold the others back beyond its turn. The link
//!   task takes them between any two of its own requests, after the drives' pending commands (a
//!   stop first), with the line's timing and each drive's map (request gap, response time).
//! - Each reply goes back to the master that asked, with its transaction id. A request for a
//!   slave that is not on the link is answered with exception 0Bh (gateway target failed to
//!   respond) at once; one the line does not answer in time with 0Bh too, one the link cannot
//!   carry (closed, broken) with 0Ah (gateway path unavailable); the drive's own exceptions pass
//!   through.
//! - Every write is checked by the drive's write gate before the line sees it (access, range,
//!   function, broadcast, 32-bit pairs) and by its limits through other parameters, read first
//!   (the V7's reference against n011): refused with the exception the drive would answer (01h
//!   function, 02h address, 03h value) and logged with the master's address and why. Writes are
//!   off unless allowed; a write to a register holding a command role (run, stop, fault reset)
//!   only from the masters `--allow-commands` names.
//! - Reads pass through; with a cache age, a read answered from the same read of another master
//!   made within that age, so ten dashboards cost the line one read.
//! - Bounded: at most [`ProxyOptions::max_connections`] masters at once (more are closed at
//!   once), frames of at most the Modbus size, a master that waits more than
//!   [`ProxyOptions::timeout`] for the line gets 0Bh and its request is dropped.

use std::collections::{BTreeMap, VecDeque};
use std::net::{IpAddr, SocketAddr};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use drivemap_live::codec;
use drivemap_runtime::core::plan::ValueShape;
use drivemap_runtime::core::roles::RoleKind;
use drivemap_runtime::pdu::{self, Request, Response, Words};
use drivemap_runtime::tcp;
use drivemap_runtime::{error::Error as LineError, error::Refusal};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{Semaphore, oneshot};

use crate::command::Board;
use crate::commander::Commander;
use crate::link::LinkClient;
use crate::log::quote;
use crate::metrics::Metrics;

/// Exception 01h: illegal function.
pub const ILLEGAL_FUNCTION: u8 = 0x01;
/// Exception 02h: illegal data address.
pub const ILLEGAL_ADDRESS: u8 = 0x02;
/// Exception 03h: illegal data value.
pub const ILLEGAL_VALUE: u8 = 0x03;
/// Exception 04h: server device failure.
pub const DEVICE_FAILURE: u8 = 0x04;
/// Exception 0Ah: gateway path unavailable.
pub const PATH_UNAVAILABLE: u8 = 0x0A;
/// Exception 0Bh: gateway target device failed to respond.
pub const TARGET_FAILED: u8 = 0x0B;

/// What the proxy serves and lets through.
#[derive(Debug, Clone)]
pub struct ProxyOptions {
    /// Where masters connect (Modbus TCP).
    pub listen: SocketAddr,
    /// Writes are carried out at all (checked by the gate); off: every write is refused (01h).
    pub allow_writes: bool,
    /// The masters whose writes may touch a command register (run, stop, fault reset).
    pub allow_commands: Vec<Cidr>,
    /// Masters served at once; more are closed at once.
    pub max_connections: usize,
    /// A read answered from the same read made within this age (none: every read goes out).
    pub cache: Option<Duration>,
    /// How long a master's request may wait for the line before it is answered 0Bh.
    pub timeout: Duration,
}

/// An address or a network: `192.168.1.20`, `10.0.0.0/8`, `::1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cidr {
    net: IpAddr,
    prefix: u8,
}

impl Cidr {
    /// Parses `ADDR` or `ADDR/PREFIX`.
    pub fn parse(text: &str) -> Result<Cidr, String> {
        let (addr, prefix) = match text.split_once('/') {
            Some((a, p)) => (a, Some(p)),
            None => (text, None),
        };
        let net: IpAddr = addr
            .trim()
            .parse()
            .map_err(|_| format!("{} is not an IP address or network", quote(text)))?;
        let max = if net.is_ipv4() { 32 } else { 128 };
        let prefix = match prefix {
            Some(p) => p
                .trim()
                .parse::<u8>()
                .ok()
                .filter(|p| *p <= max)
                .ok_or_else(|| format!("{}: the prefix is not 0 to {max}", quote(text)))?,
            None => max,
        };
        Ok(Cidr { net, prefix })
    }

    /// Whether `ip` is in this network.
    pub fn contains(&self, ip: IpAddr) -> bool {
        let bits = |ip: IpAddr| -> u128 {
            match ip {
                IpAddr::V4(v) => u128::from(u32::from(v)),
                IpAddr::V6(v) => match v.to_ipv4_mapped() {
                    Some(v4) => u128::from(u32::from(v4)),
                    None => u128::from(v),
                },
            }
        };
        let width: u32 = if self.net.is_ipv4() { 32 } else { 128 };
        let ip4 = match ip {
            IpAddr::V6(v) => v.to_ipv4_mapped().is_some(),
            IpAddr::V4(_) => true,
        };
        if self.net.is_ipv4() != ip4 {
            return false;
        }
        let shift = width - u32::from(self.prefix);
        let mask = if shift >= 128 { 0 } else { u128::MAX << shift };
        let mask = if width == 32 {
            mask & 0xFFFF_FFFF
        } else {
            mask
        };
        bits(ip) & mask == bits(self.net) & mask
    }
}

/// A master's request waiting for the line.
pub struct Pending {
    /// The master.
    pub master: SocketAddr,
    /// The unit id (the slave on the line).
    pub unit: u8,
    /// The request PDU as the master sent it.
    pub pdu: Vec<u8>,
    /// When it came.
    pub received: Instant,
    /// The response PDU goes here.
    reply: oneshot::Sender<Vec<u8>>,
}

/// The requests of every master, in the order they came; shared by the server and the link.
pub struct Queue {
    waiting: Mutex<VecDeque<Pending>>,
    board: Arc<Board>,
}

impl Queue {
    /// An empty queue whose arrivals wake the link waiting on `board`.
    pub fn new(board: Arc<Board>) -> Queue {
        Queue {
            waiting: Mutex::new(VecDeque::new()),
            board,
        }
    }

    fn push(&self, p: Pending) {
        self.waiting
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push_back(p);
        self.board.ring();
    }

    /// The oldest request, taken out.
    pub fn pop(&self) -> Option<Pending> {
        self.waiting
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .pop_front()
    }

    /// Whether a request waits.
    pub fn is_empty(&self) -> bool {
        self.waiting
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .is_empty()
    }
}

/// An exception response PDU.
fn exception(function: u8, code: u8) -> Vec<u8> {
    vec![function | 0x80, code]
}

/// The exception a drive would answer for what the gate refused.
fn refusal_code(r: &Refusal) -> u8 {
    match r {
        Refusal::UnsupportedFunction { .. }
        | Refusal::FunctionNotAccepted { .. }
        | Refusal::BroadcastFunction { .. }
        | Refusal::BroadcastRead { .. }
        | Refusal::BroadcastLoopBack => ILLEGAL_FUNCTION,
        Refusal::TooManyRegisters { .. }
        | Refusal::NoRegisters { .. }
        | Refusal::RawOutOfRange { .. }
        | Refusal::ReservedBits { .. } => ILLEGAL_VALUE,
        _ => ILLEGAL_ADDRESS,
    }
}

/// The exception for what became of a request on the line.
fn line_code(e: &LineError) -> u8 {
    match e {
        LineError::Exception { exception, .. } => exception.code,
        LineError::Refused(r) => refusal_code(r),
        LineError::Value(_) => ILLEGAL_VALUE,
        LineError::Timeout { .. } => TARGET_FAILED,
        LineError::Io { .. } | LineError::Link(_) => PATH_UNAVAILABLE,
        _ => DEVICE_FAILURE,
    }
}

/// A read as a master asked it: unit, function, PDU address, quantity.
type ReadKey = (u8, u8, u16, u16);

/// What the link keeps for the proxy: its options and the reads it may answer again.
pub struct LineSide {
    options: ProxyOptions,
    queue: Arc<Queue>,
    metrics: Arc<Metrics>,
    cache: BTreeMap<ReadKey, (Instant, Vec<u8>)>,
}

impl LineSide {
    /// The link's side of a proxy.
    pub fn new(options: ProxyOptions, queue: Arc<Queue>, metrics: Arc<Metrics>) -> LineSide {
        LineSide {
            options,
            queue,
            metrics,
            cache: BTreeMap::new(),
        }
    }

    /// The next waiting request, if any.
    pub fn next(&self) -> Option<Pending> {
        self.queue.pop()
    }

    /// Whether a request waits.
    pub fn waiting(&self) -> bool {
        !self.queue.is_empty()
    }

    /// Carries out `p` on the line for the drive it names and answers its master.
    pub(crate) fn serve(&mut self, p: Pending, client: &mut LinkClient, drives: &mut [Commander]) {
        let function = p.pdu.first().copied().unwrap_or(0);
        let master = p.master;
        let (reply, refused) = if p.received.elapsed() > self.options.timeout {
            // The master was answered 0Bh already.
            return;
        } else {
            match drives.iter_mut().find(|d| d.slave == p.unit) {
                None => (
                    exception(function, TARGET_FAILED),
                    Some("no such slave".into()),
                ),
                Some(d) => self.carry_out(&p, client, d),
            }
        };
        let ip = master.ip().to_string();
        self.metrics
            .proxy_requests
            .get_or_create(&vec![("master".to_owned(), ip)])
            .inc();
        if let Some(why) = refused {
            let reason = why.split(':').next().unwrap_or("").to_owned();
            self.metrics
                .proxy_refusals
                .get_or_create(&vec![("reason".to_owned(), short_reason(&reason))])
                .inc();
            eprintln!(
                "proxy: {master} unit {} function {function:02X}h refused (exception {:02X}h): {why}",
                p.unit,
                reply.get(1).copied().unwrap_or(0)
            );
        }
        let _ = p.reply.send(reply);
    }

    fn carry_out(
        &mut self,
        p: &Pending,
        client: &mut LinkClient,
        d: &mut Commander,
    ) -> (Vec<u8>, Option<String>) {
        let request = match pdu::decode_request(&p.pdu) {
            Ok(r) => r,
            Err(e) => {
                let f = p.pdu.first().copied().unwrap_or(0);
                let code = match e {
                    pdu::RequestDecodeError::Malformed(_) => ILLEGAL_VALUE,
                    _ => ILLEGAL_FUNCTION,
                };
                return (exception(f, code), Some(e.to_string()));
            }
        };
        let f = request.function();
        client.switch_drive(d.drive.plan().profile, d.options);
        let profile = d.drive.plan().profile;
        let kind = d.kind;
        // The master sends what goes on the line: a PDU address. The client takes the map's
        // communication address and moves it by the map's offset for the link again.
        let comm = |pdu_address: u16| {
            profile
                .address_offsets
                .communication_address(pdu_address, kind)
        };
        let mut words = [0u16; 125];
        let result = match request {
            Request::ReadHolding { address, quantity }
            | Request::ReadInput { address, quantity } => {
                let key = (p.unit, f, address, quantity);
                if let (Some(age), Some((at, cached))) = (self.options.cache, self.cache.get(&key))
                    && at.elapsed() <= age
                {
                    return (cached.clone(), None);
                }
                let Some(a) = comm(address) else {
                    return (
                        exception(f, ILLEGAL_ADDRESS),
                        Some("address outside the map's addressing".into()),
                    );
                };
                let out = &mut words[..usize::from(quantity).min(125)];
                let read = if f == pdu::function::READ_HOLDING {
                    client.read_holding(d.slave, a, out)
                } else {
                    client.read_input(d.slave, a, out)
                };
                read.map(|()| {
                    let reply = encode(f, &Response::Registers(Words::Native(out)));
                    if self.options.cache.is_some() {
                        if self.cache.len() > 4096 {
                            self.cache.clear();
                        }
                        self.cache.insert(key, (Instant::now(), reply.clone()));
                    }
                    reply
                })
            }
            Request::WriteSingle { address, value } => {
                if let Err(refusal) = self.may_write(p, d, client, comm(address), &[value]) {
                    return refusal;
                }
                self.cache.clear();
                let Some(a) = comm(address) else {
                    unreachable!("checked by may_write")
                };
                client
                    .write_register(d.slave, a, value)
                    .map(|()| encode(f, &Response::WriteSingle { address, value }))
            }
            Request::WriteMultiple { address, values } => {
                let values: Vec<u16> = values.iter().collect();
                if let Err(refusal) = self.may_write(p, d, client, comm(address), &values) {
                    return refusal;
                }
                self.cache.clear();
                let Some(a) = comm(address) else {
                    unreachable!("checked by may_write")
                };
                let quantity = values.len() as u16;
                client
                    .write_registers(d.slave, a, &values)
                    .map(|()| encode(f, &Response::WriteMultiple { address, quantity }))
            }
            Request::LoopBack { data } => client
                .loop_back(d.slave, data)
                .map(|()| encode(f, &Response::LoopBack { data })),
            _ => {
                return (
                    exception(f, ILLEGAL_FUNCTION),
                    Some("function not carried".into()),
                );
            }
        };
        match result {
            Ok(reply) => (reply, None),
            Err(e) => {
                let why = match &e {
                    LineError::Exception { .. } => None,
                    other => Some(other.to_string()),
                };
                (exception(f, line_code(&e)), why)
            }
        }
    }

    /// Whether the master may write `values` from communication address `address` of `d`: writes
    /// allowed, a command register only from the masters allowed commands, every word within
    /// the limits in force (those through other parameters read now). The gate's own checks
    /// (access, range, function, pairs) follow in the client.
    fn may_write(
        &self,
        p: &Pending,
        d: &Commander,
        client: &mut LinkClient,
        address: Option<u16>,
        values: &[u16],
    ) -> Result<(), (Vec<u8>, Option<String>)> {
        let f = p.pdu.first().copied().unwrap_or(0);
        let refuse = |code: u8, why: String| Err((exception(f, code), Some(why)));
        if !self.options.allow_writes {
            return refuse(
                ILLEGAL_FUNCTION,
                "writes not allowed: the proxy was not started with --allow-writes".into(),
            );
        }
        if let Err(why) = &d.draft {
            return refuse(ILLEGAL_FUNCTION, why.clone());
        }
        let Some(address) = address else {
            return refuse(
                ILLEGAL_ADDRESS,
                "address outside the map's addressing".into(),
            );
        };
        let drive = d.drive;
        let plan = drive.plan();
        let view = d.settings.view(drive);
        for (k, &word) in values.iter().enumerate() {
            let at = address.wrapping_add(k as u16);
            // The register this word writes on this link to this slave (a broadcast register
            // may share its address).
            let Some((i, r)) = drive.registers().enumerate().find(|(_, r)| {
                let rp = r.plan();
                r.writable()
                    && !r.broadcast_only()
                    && rp.transports.contains(d.kind)
                    && rp.locate(&view, d.kind).ok() == Some(at)
            }) else {
                continue; // the gate refuses an address the map does not write
            };
            let row = u16::try_from(plan.order[i]).ok();
            let command = plan
                .roles
                .places
                .iter()
                .any(|pl| pl.role.kind() == RoleKind::Command && pl.target.row() == row);
            if command
                && !self
                    .options
                    .allow_commands
                    .iter()
                    .any(|c| c.contains(p.master.ip()))
            {
                return refuse(
                    ILLEGAL_FUNCTION,
                    format!(
                        "commands not allowed: {} holds command roles and {} is not in --allow-commands",
                        r.label(),
                        p.master.ip()
                    ),
                );
            }
            // Its scale and its limits through other parameters, with those parameters read
            // now: a word the drive would take for another value, or above a limit in force,
            // never reaches the line.
            let quantity = r.plan().conversion.shape() == ValueShape::Number;
            if !quantity {
                continue; // codes, fields and words: the gate's checks of the word
            }
            let settings = match d.settings_now(client, r) {
                Ok(s) => s,
                Err(why) => return refuse(DEVICE_FAILURE, why.to_string()),
            };
            let checked = codec::decode_written(drive, r, u32::from(word), &settings)
                .map_err(|e| e.to_string())
                .and_then(|v| v.as_f64().ok_or_else(|| "not a number".to_owned()))
                .and_then(|v| {
                    codec::encode(drive, r, v, &settings)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                });
            if let Err(why) = checked {
                return refuse(ILLEGAL_VALUE, why);
            }
        }
        Ok(())
    }
}

/// The first words of a refusal, for the `reason` label.
fn short_reason(why: &str) -> String {
    why.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
}

fn encode(function: u8, response: &Response<'_>) -> Vec<u8> {
    let mut out = vec![0u8; response.pdu_len()];
    match response.encode(function, &mut out) {
        Ok(n) => {
            out.truncate(n);
            out
        }
        Err(_) => exception(function, DEVICE_FAILURE),
    }
}

/// Serves masters on `listener` until `stop`: each connection's frames read one at a time,
/// checked, queued for the link that has `slaves`, answered with their transaction ids.
pub async fn serve(
    listener: TcpListener,
    queue: Arc<Queue>,
    slaves: Vec<u8>,
    options: ProxyOptions,
    stop: Arc<std::sync::atomic::AtomicBool>,
) {
    let places = Arc::new(Semaphore::new(options.max_connections));
    let slaves = Arc::new(slaves);
    loop {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            return;
        }
        let accepted = tokio::time::timeout(Duration::from_millis(200), listener.accept()).await;
        let Ok(Ok((stream, master))) = accepted else {
            continue;
        };
        let Ok(place) = Arc::clone(&places).try_acquire_owned() else {
            eprintln!(
                "proxy: {master} refused: {} masters connected already (--max-connections)",
                options.max_connections
            );
            drop(stream);
            continue;
        };
        let (queue, slaves, timeout, stop) = (
            Arc::clone(&queue),
            Arc::clone(&slaves),
            options.timeout,
            Arc::clone(&stop),
        );
        tokio::spawn(async move {
            connection(stream, master, queue, &slaves, timeout, &stop).await;
            drop(place);
        });
    }
}

async fn connection(
    mut stream: TcpStream,
    master: SocketAddr,
    queue: Arc<Queue>,
    slaves: &[u8],
    timeout: Duration,
    stop: &std::sync::atomic::AtomicBool,
) {
    let _ = stream.set_nodelay(true);
    let mut buf = vec![0u8; tcp::MAX_FRAME];
    loop {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            return;
        }
        // A frame: the header, then what it announces (at most the Modbus size). A master
        // silent for a minute is closed.
        let mut have = 0;
        loop {
            let need = match tcp::bytes_needed(&buf[..have]) {
                Ok(0) => break,
                Ok(n) => n,
                Err(_) => return, // out of step: close
            };
            let read = tokio::time::timeout(
                Duration::from_secs(60),
                stream.read(&mut buf[have..have + need]),
            )
            .await;
            match read {
                Ok(Ok(n)) if n > 0 => have += n,
                _ => return,
            }
        }
        let Ok(Some(header)) = tcp::Header::parse(&buf[..have]) else {
            return;
        };
        let pdu = buf[tcp::HEADER_LEN..have].to_vec();
        let function = pdu.first().copied().unwrap_or(0);
        let reply = if !slaves.contains(&header.unit) {
            exception(function, TARGET_FAILED)
        } else {
            let (tx, rx) = oneshot::channel();
            queue.push(Pending {
                master,
                unit: header.unit,
                pdu,
                received: Instant::now(),
                reply: tx,
            });
            match tokio::time::timeout(timeout, rx).await {
                Ok(Ok(reply)) => reply,
                _ => exception(function, TARGET_FAILED),
            }
        };
        let mut frame = Vec::with_capacity(tcp::HEADER_LEN + reply.len());
        frame.extend_from_slice(&header.transaction.to_be_bytes());
        frame.extend_from_slice(&0u16.to_be_bytes());
        frame.extend_from_slice(&((reply.len() + 1) as u16).to_be_bytes());
        frame.push(header.unit);
        frame.extend_from_slice(&reply);
        if stream.write_all(&frame).await.is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn networks_contain_their_addresses_only() {
        let lan = Cidr::parse("192.168.1.0/24").unwrap();
        assert!(lan.contains("192.168.1.77".parse().unwrap()));
        assert!(!lan.contains("192.168.2.1".parse().unwrap()));
        assert!(lan.contains("::ffff:192.168.1.5".parse().unwrap()));
        let one = Cidr::parse("127.0.0.1").unwrap();
        assert!(one.contains("127.0.0.1".parse().unwrap()));
        assert!(!one.contains("127.0.0.2".parse().unwrap()));
        assert!(
            Cidr::parse("0.0.0.0/0")
                .unwrap()
                .contains("8.8.8.8".parse().unwrap())
        );
        assert!(
            !Cidr::parse("::1")
                .unwrap()
                .contains("127.0.0.1".parse().unwrap())
        );
        assert!(Cidr::parse("10.0.0.0/33").is_err());
        assert!(Cidr::parse("plant").is_err());
    }
}
