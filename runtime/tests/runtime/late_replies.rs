//! One reply per request on every RTU-framed link (issue 23, item 2). RTU frames carry no
//! transaction id: a reply that arrives after the client's timeout looks exactly like the answer
//! to the next request of the same shape. Against a slave that answers one request in
//! [`EVERY`] just after the timeout, 1,000 reads of different registers of the same shape
//! (holding register `a` holds `a`) must give 0 misattributed values, over RTU over TCP and a
//! real serial line (a socat pseudo-terminal pair), with the blocking and the async client.
//! Before the fix each late reply was taken as the next read's answer.
//!
//! A Modbus TCP gateway link (Modbus TCP framing, transaction ids) is checked the same way, and
//! so is Modbus ASCII on the serial line (no transaction id either).

use std::time::{Duration, Instant};

use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::error::Error;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_test_support::hostile_peer::{HostilePeer, Script};

static PROFILE: Profile = Profile {
    max_read: 16,
    ..Profile::GENERIC
};

/// The client's reply timeout: short, so 1,000 reads stay within seconds.
const TIMEOUT: Duration = Duration::from_millis(100);
/// How late the slave answers one request in [`EVERY`]: just after the timeout (with room
/// for the socket timeout's kernel tick and the scheduler, so that it is after the timeout).
/// The client's wait for silence covers a reply up to twice the timeout after its request:
/// 90 ms to spare for a loaded machine (socat relays the pseudo-terminal's bytes in a process
/// of its own).
const LATE: Duration = Duration::from_millis(110);
/// One request in this many is answered late.
const EVERY: u32 = 25;
/// Reads per run.
const READS: u16 = 1000;

fn options() -> ClientOptions {
    ClientOptions {
        timeout: TIMEOUT,
        retries: 0,
        ..ClientOptions::generic()
    }
}

/// What 1,000 reads gave.
#[derive(Debug, Default)]
struct Tally {
    right: u32,
    /// Values that belong to another register's request.
    misattributed: Vec<(u16, u16)>,
    timeouts: u32,
    /// Timeouts whose error says the next request waits for silence.
    timeouts_saying_they_wait: u32,
    /// Reads that first waited for silence and threw a late reply away.
    settled_with_bytes: u32,
    other: Vec<String>,
}

impl Tally {
    fn take(&mut self, address: u16, result: Result<u16, Error>) {
        match result {
            Ok(v) if v == address => self.right += 1,
            Ok(v) => self.misattributed.push((address, v)),
            Err(e @ Error::Timeout { .. }) => {
                self.timeouts += 1;
                if e.to_string().contains(&format!(
                    "the next request to slave 1 waits until the line has been silent for {} ms",
                    TIMEOUT.as_millis()
                )) {
                    self.timeouts_saying_they_wait += 1;
                }
            }
            Err(e) => self.other.push(e.to_string()),
        }
    }

    /// 0 misattributed values; the late requests time out (and say that the next request
    /// waits) and their replies are thrown away by the next request's wait; most reads succeed.
    fn check(&self, what: &str, rtu_framed: bool) {
        assert!(
            self.misattributed.is_empty(),
            "{what}: {} value(s) taken from another request's reply (register, value): {:?}",
            self.misattributed.len(),
            &self.misattributed[..self.misattributed.len().min(10)]
        );
        assert!(self.other.is_empty(), "{what}: {:?}", self.other);
        let late = u32::from(READS).div_ceil(EVERY);
        // Most late replies come after the timeout (a stalled client may still catch one).
        assert!(
            self.timeouts >= late / 2,
            "{what}: {} timeouts, {late} late replies: {self:?}",
            self.timeouts
        );
        assert!(
            self.right >= u32::from(READS) / 2,
            "{what}: only {} right: {self:?}",
            self.right
        );
        if rtu_framed {
            assert_eq!(self.timeouts_saying_they_wait, self.timeouts, "{what}");
            assert!(
                self.settled_with_bytes >= late / 2,
                "{what}: the wait for silence discarded a late reply only {} times: {self:?}",
                self.settled_with_bytes
            );
        }
    }
}

fn reads_blocking<T: Transport>(client: &mut Client<T>) -> Tally {
    let mut tally = Tally::default();
    for i in 0..READS {
        let address = i % 64;
        let mut word = [0u16; 1];
        let result = client.read_holding(1, address, &mut word).map(|()| word[0]);
        if client.settled().is_some_and(|s| s.bytes > 0) {
            tally.settled_with_bytes += 1;
        }
        tally.take(address, result);
    }
    tally
}

#[test]
fn blocking_rtu_over_tcp_never_takes_a_late_reply_for_the_next_answer() {
    let peer = HostilePeer::start(
        TransportKind::RtuOverTcp,
        &PROFILE,
        Script::Late {
            every: EVERY,
            by_us: LATE.as_micros() as u64,
        },
    );
    let link = RtuOverTcpTransport::connect(peer.addr, Duration::from_secs(1)).unwrap();
    let mut client = Client::with_options(link, &PROFILE, options());
    let started = Instant::now();
    let tally = reads_blocking(&mut client);
    tally.check("blocking, RTU over TCP", true);
    // The waits cost about one timeout per late reply, not more.
    assert!(
        started.elapsed() < Duration::from_secs(30),
        "{:?}",
        started.elapsed()
    );
}

/// Through a Modbus TCP gateway the transaction id tells replies apart: a late reply is
/// discarded without any wait.
#[test]
fn blocking_modbus_tcp_gateway_never_takes_a_late_reply_for_the_next_answer() {
    let peer = HostilePeer::start(
        TransportKind::TcpGateway,
        &PROFILE,
        Script::Late {
            every: EVERY,
            by_us: LATE.as_micros() as u64,
        },
    );
    let link = TcpTransport::connect_gateway(peer.addr, Duration::from_secs(1)).unwrap();
    let mut client = Client::with_options(link, &PROFILE, options());
    let tally = reads_blocking(&mut client);
    tally.check("blocking, Modbus TCP gateway", false);
    assert_eq!(
        tally.settled_with_bytes, 0,
        "no wait for silence with transaction ids"
    );
}

/// A slave on a real serial line (pseudo-terminal pair) answering just after the timeout.
#[cfg(all(unix, feature = "serial"))]
mod serial {
    use super::*;
    use drivemap_runtime::transport::serial::{SerialOptions, SerialTransport};
    use drivemap_test_support::late_slave::{numbered, serve_late};
    use drivemap_test_support::pty_pair::PtyPair;
    use std::thread;

    fn line(path: &str) -> SerialOptions {
        SerialOptions::new(path, 115_200).with_profile(&PROFILE)
    }

    /// Serves the drive's end until `for_how_long` has passed.
    fn drive(path: &str, for_how_long: Duration) -> thread::JoinHandle<u32> {
        let mut link = SerialTransport::open(line(path)).expect("opening the drive's end");
        thread::spawn(move || {
            serve_late(
                &mut link,
                &mut numbered(&PROFILE),
                EVERY,
                LATE,
                Instant::now() + for_how_long,
            )
        })
    }

    #[test]
    fn blocking_serial_never_takes_a_late_reply_for_the_next_answer() {
        let pty = PtyPair::new();
        let server = drive(&pty.paths[1], Duration::from_secs(60));
        let link = SerialTransport::open(line(&pty.paths[0])).expect("opening the client's end");
        let mut client = Client::with_options(link, &PROFILE, options());
        let tally = reads_blocking(&mut client);
        tally.check("blocking, serial", true);
        drop(client);
        drop(pty);
        let _ = server.join();
    }

    /// Modbus ASCII on the same line: the same guarantee, no late reply taken for an answer.
    #[test]
    fn blocking_ascii_serial_never_takes_a_late_reply_for_the_next_answer() {
        let ascii = |path: &str| line(path).ascii(7).expect("7 data bits");
        let pty = PtyPair::new();
        let mut drive_end = SerialTransport::open(ascii(&pty.paths[1])).expect("the drive's end");
        let server = thread::spawn(move || {
            serve_late(
                &mut drive_end,
                &mut numbered(&PROFILE),
                EVERY,
                LATE,
                Instant::now() + Duration::from_secs(60),
            )
        });
        let link = SerialTransport::open(ascii(&pty.paths[0])).expect("opening the client's end");
        assert_eq!(link.kind(), TransportKind::Ascii);
        let mut client = Client::with_options(link, &PROFILE, options());
        let tally = reads_blocking(&mut client);
        tally.check("blocking, ASCII serial", true);
        drop(client);
        drop(pty);
        let _ = server.join();
    }

    #[cfg(feature = "tokio")]
    #[test]
    fn async_serial_never_takes_a_late_reply_for_the_next_answer() {
        use drivemap_runtime::async_client::{AsyncClient, BlockingTransport};
        let pty = PtyPair::new();
        let server = drive(&pty.paths[1], Duration::from_secs(60));
        let link = SerialTransport::open(line(&pty.paths[0])).expect("opening the client's end");
        let tally = super::asynchronous::runtime().block_on(async move {
            let mut client =
                AsyncClient::with_options(BlockingTransport::new(link), &PROFILE, options());
            super::asynchronous::reads(&mut client).await
        });
        tally.check("async, serial", true);
        drop(pty);
        let _ = server.join();
    }
}

#[cfg(feature = "tokio")]
mod asynchronous {
    use super::*;
    use drivemap_runtime::async_client::{AsyncClient, AsyncTcpTransport, AsyncTransport};

    pub(super) fn runtime() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap()
    }

    pub(super) async fn reads<T: AsyncTransport>(client: &mut AsyncClient<T>) -> Tally {
        let mut tally = Tally::default();
        for i in 0..READS {
            let address = i % 64;
            let mut word = [0u16; 1];
            let result = client
                .read_holding(1, address, &mut word)
                .await
                .map(|()| word[0]);
            if client.settled().is_some_and(|s| s.bytes > 0) {
                tally.settled_with_bytes += 1;
            }
            tally.take(address, result);
        }
        tally
    }

    #[test]
    fn async_rtu_over_tcp_never_takes_a_late_reply_for_the_next_answer() {
        let peer = HostilePeer::start(
            TransportKind::RtuOverTcp,
            &PROFILE,
            Script::Late {
                every: EVERY,
                by_us: LATE.as_micros() as u64,
            },
        );
        let addr = peer.addr;
        let tally = runtime().block_on(async move {
            let link =
                AsyncTcpTransport::connect(addr, TransportKind::RtuOverTcp, Duration::from_secs(1))
                    .await
                    .unwrap();
            let mut client = AsyncClient::with_options(link, &PROFILE, options());
            reads(&mut client).await
        });
        tally.check("async, RTU over TCP", true);
    }

    /// Through a Modbus TCP gateway the async client matches by transaction id, no wait.
    #[test]
    fn async_modbus_tcp_gateway_never_takes_a_late_reply_for_the_next_answer() {
        let peer = HostilePeer::start(
            TransportKind::TcpGateway,
            &PROFILE,
            Script::Late {
                every: EVERY,
                by_us: LATE.as_micros() as u64,
            },
        );
        let addr = peer.addr;
        let tally = runtime().block_on(async move {
            let link =
                AsyncTcpTransport::connect(addr, TransportKind::TcpGateway, Duration::from_secs(1))
                    .await
                    .unwrap();
            let mut client = AsyncClient::with_options(link, &PROFILE, options());
            reads(&mut client).await
        });
        tally.check("async, Modbus TCP gateway", false);
        assert_eq!(tally.settled_with_bytes, 0);
    }
}
