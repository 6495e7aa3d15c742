//! The guarantees the clients keep while being fast, over real loopback sockets, for the
//! blocking client (`TcpTransport`, `RtuOverTcpTransport`) and the async client
//! (`AsyncTcpTransport`, and `AsyncStreamTransport` over a TCP stream), Modbus TCP and RTU over
//! TCP:
//!
//! - a late reply to a timed-out request, already in the socket when the next request is
//!   sent, is flushed before that request (not taken as its answer, not even seen by the
//!   reply matching);
//! - input nobody asked for, arriving between two transactions, is flushed the same way, even
//!   a frame that would pass every check of the next request's reply;
//! - a late reply that arrives while the next request waits (after the flush) is discarded by
//!   its transaction id (Modbus TCP);
//! - the request gap is kept between the end of one transaction and the next request.
//!
//! The server is scripted step by step from the test and reports when it has written, so
//! nothing depends on how fast either side runs; the only clock readings are the server's, and
//! the gap is checked as a lower bound between causally ordered events.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::error::Error;
use drivemap_runtime::pdu::{Response, Words, function};
use drivemap_runtime::reply::Discarded;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{rtu, tcp};

static PROFILE: Profile = Profile {
    max_read: 16,
    ..Profile::GENERIC
};

const SLAVE: u8 = 1;
const ADDRESS: u16 = 0x0020;
const QUANTITY: usize = 4;
/// The reply timeout: short, since one test waits it out once.
const TIMEOUT: Duration = Duration::from_millis(150);
/// Longest the server waits for a request or a step, so a broken client fails the test
/// instead of hanging it.
const SERVER_WAIT: Duration = Duration::from_secs(10);
/// What the real answers hold: `GOOD + i`.
const GOOD: u16 = 6000;
/// What stale frames hold: `STALE + i`.
const STALE: u16 = 0xDEA0;
const KINDS: [TransportKind; 2] = [TransportKind::Tcp, TransportKind::RtuOverTcp];

/// What the server does next.
#[derive(Debug, Clone, Copy)]
enum Step {
    /// Reads one request and answers it with `GOOD + i`.
    Answer,
    /// Reads one request and does not answer it (yet).
    Swallow,
    /// Writes the answer to the last request read, with `STALE + i`: a late reply.
    Late,
    /// Writes a frame that answers the *next* request (its transaction id, for Modbus TCP),
    /// with `STALE + i`, before that request is sent: input nobody asked for.
    Unsolicited,
    /// Reads one request, writes the late reply to the one before it, then answers this one.
    LateThenAnswer,
}

/// When the server did what a step asked.
#[derive(Debug, Clone, Copy)]
struct Done {
    /// The request was read in full (steps that read one).
    read: Option<Instant>,
    /// Just before the first byte of the answer was written.
    writing: Instant,
}

/// A one-connection scripted server on 127.0.0.1.
struct Server {
    addr: SocketAddr,
    steps: mpsc::Sender<Step>,
    done: mpsc::Receiver<Done>,
}

impl Server {
    fn start(kind: TransportKind) -> Server {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let (steps, step_rx) = mpsc::channel();
        let (done_tx, done) = mpsc::channel();
        thread::spawn(move || {
            let Ok((stream, _)) = listener.accept() else {
                return;
            };
            serve(stream, kind, step_rx, done_tx);
        });
        Server { addr, steps, done }
    }

    /// Asks for `step`, without waiting for it.
    fn then(&self, step: Step) {
        self.steps.send(step).unwrap();
    }

    /// Waits until the server has done the step asked for.
    fn done(&self) -> Done {
        self.done
            .recv_timeout(SERVER_WAIT)
            .expect("the server did not finish its step")
    }
}

/// The request as read: its transaction id (Modbus TCP) and unit.
#[derive(Debug, Clone, Copy)]
struct Seen {
    transaction: u16,
}

fn serve(
    mut s: TcpStream,
    kind: TransportKind,
    steps: mpsc::Receiver<Step>,
    done: mpsc::Sender<Done>,
) {
    s.set_nodelay(true).unwrap();
    s.set_read_timeout(Some(SERVER_WAIT)).unwrap();
    let mut last: Option<Seen> = None;
    while let Ok(step) = steps.recv_timeout(SERVER_WAIT) {
        let outcome = match step {
            Step::Answer => read_request(&mut s, kind).map(|seen| {
                let read = Instant::now();
                last = Some(seen);
                let writing = Instant::now();
                write_answer(&mut s, kind, seen.transaction, GOOD);
                Done {
                    read: Some(read),
                    writing,
                }
            }),
            Step::Swallow => read_request(&mut s, kind).map(|seen| {
                last = Some(seen);
                Done {
                    read: Some(Instant::now()),
                    writing: Instant::now(),
                }
            }),
            Step::Late => {
                let seen = last.expect("a late reply needs a request before it");
                let writing = Instant::now();
                write_answer(&mut s, kind, seen.transaction, STALE);
                Some(Done {
                    read: None,
                    writing,
                })
            }
            Step::Unsolicited => {
                let seen = last.expect("the next transaction id follows the last one");
                let writing = Instant::now();
                write_answer(&mut s, kind, seen.transaction.wrapping_add(1), STALE);
                Some(Done {
                    read: None,
                    writing,
                })
            }
            Step::LateThenAnswer => {
                let before = last.expect("a late reply needs a request before it");
                read_request(&mut s, kind).map(|seen| {
                    let read = Instant::now();
                    last = Some(seen);
                    let writing = Instant::now();
                    write_answer(&mut s, kind, before.transaction, STALE);
                    write_answer(&mut s, kind, seen.transaction, GOOD);
                    Done {
                        read: Some(read),
                        writing,
                    }
                })
            }
        };
        let Some(d) = outcome else { return };
        if done.send(d).is_err() {
            return;
        }
    }
}

/// Reads one 03h request of `QUANTITY` registers (within the socket's read timeout).
fn read_request(s: &mut TcpStream, kind: TransportKind) -> Option<Seen> {
    let mut buf = [0u8; 12];
    let len = match kind {
        TransportKind::Tcp => 12,
        _ => 8,
    };
    s.read_exact(&mut buf[..len]).ok()?;
    let (transaction, pdu) = match kind {
        TransportKind::Tcp => (u16::from_be_bytes([buf[0], buf[1]]), &buf[7..12]),
        _ => (0, &buf[1..6]),
    };
    assert_eq!(pdu[0], function::READ_HOLDING, "{buf:02x?}");
    assert_eq!(
        usize::from(u16::from_be_bytes([pdu[3], pdu[4]])),
        QUANTITY,
        "{buf:02x?}"
    );
    Some(Seen { transaction })
}

fn write_answer(s: &mut TcpStream, kind: TransportKind, transaction: u16, base: u16) {
    let words: [u16; QUANTITY] = std::array::from_fn(|i| base + i as u16);
    let response = Response::Registers(Words::Native(&words));
    let mut frame = [0u8; tcp::MAX_FRAME];
    let n = match kind {
        TransportKind::Tcp => tcp::encode_response(
            transaction,
            SLAVE,
            function::READ_HOLDING,
            &response,
            &mut frame,
        ),
        _ => rtu::encode_response(SLAVE, function::READ_HOLDING, &response, &mut frame),
    }
    .unwrap();
    // The client may have closed the connection at the end of the test.
    let _ = s.write_all(&frame[..n]);
}

fn options(request_gap: Duration) -> ClientOptions {
    ClientOptions {
        timeout: TIMEOUT,
        retries: 0,
        request_gap,
        ..ClientOptions::default()
    }
}

fn good() -> [u16; QUANTITY] {
    std::array::from_fn(|i| GOOD + i as u16)
}

/// One of the clients under test, connected to a `Server`.
enum Under {
    Blocking(Client<Box<dyn Transport>>),
    #[cfg(feature = "tokio")]
    Async(
        tokio::runtime::Runtime,
        drivemap_runtime::async_client::AsyncClient<
            drivemap_runtime::async_client::AsyncTcpTransport,
        >,
    ),
    #[cfg(feature = "tokio")]
    AsyncStream(
        tokio::runtime::Runtime,
        drivemap_runtime::async_client::AsyncClient<
            drivemap_runtime::async_client::AsyncStreamTransport<tokio::net::TcpStream>,
        >,
    ),
}

impl Under {
    fn blocking(kind: TransportKind, addr: SocketAddr, gap: Duration) -> Under {
        let link: Box<dyn Transport> = match kind {
            TransportKind::Tcp => Box::new(TcpTransport::connect(addr, SERVER_WAIT).unwrap()),
            _ => Box::new(RtuOverTcpTransport::connect(addr, SERVER_WAIT).unwrap()),
        };
        Under::Blocking(Client::with_options(link, &PROFILE, options(gap)))
    }

    #[cfg(feature = "tokio")]
    fn asynchronous(kind: TransportKind, addr: SocketAddr, gap: Duration) -> Under {
        use drivemap_runtime::async_client::{AsyncClient, AsyncTcpTransport};
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        let link = rt
            .block_on(AsyncTcpTransport::connect(addr, kind, SERVER_WAIT))
            .unwrap();
        Under::Async(rt, AsyncClient::with_options(link, &PROFILE, options(gap)))
    }

    #[cfg(feature = "tokio")]
    fn asynchronous_stream(kind: TransportKind, addr: SocketAddr, gap: Duration) -> Under {
        use drivemap_runtime::async_client::{AsyncClient, AsyncStreamTransport};
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        let link = rt
            .block_on(AsyncStreamTransport::connect(addr, kind))
            .unwrap();
        Under::AsyncStream(rt, AsyncClient::with_options(link, &PROFILE, options(gap)))
    }

    fn read(&mut self) -> Result<[u16; QUANTITY], Error> {
        let mut words = [0u16; QUANTITY];
        match self {
            Under::Blocking(c) => c.read_holding(SLAVE, ADDRESS, &mut words)?,
            #[cfg(feature = "tokio")]
            Under::Async(rt, c) => rt.block_on(c.read_holding(SLAVE, ADDRESS, &mut words))?,
            #[cfg(feature = "tokio")]
            Under::AsyncStream(rt, c) => rt.block_on(c.read_holding(SLAVE, ADDRESS, &mut words))?,
        }
        Ok(words)
    }

    fn discarded(&self) -> Discarded {
        match self {
            Under::Blocking(c) => c.discarded(),
            #[cfg(feature = "tokio")]
            Under::Async(_, c) => c.discarded(),
            #[cfg(feature = "tokio")]
            Under::AsyncStream(_, c) => c.discarded(),
        }
    }
}

type Connect = fn(TransportKind, SocketAddr, Duration) -> Under;

/// The connectors of every client this build has.
fn clients() -> Vec<(&'static str, Connect)> {
    vec![
        ("blocking", Under::blocking),
        #[cfg(feature = "tokio")]
        ("async", Under::asynchronous),
        #[cfg(feature = "tokio")]
        ("async stream", Under::asynchronous_stream),
    ]
}

/// A request times out; its reply arrives afterwards and sits in the socket when the next
/// request is sent. The flush takes it: the next request gets its own answer, and the reply
/// matching never sees the late one (nothing discarded). Over RTU over TCP, where a reply
/// carries no transaction id, only the flush keeps the late reply (identical in form) from
/// being taken as the answer.
#[test]
fn late_reply_in_the_socket_is_flushed_before_the_next_request() {
    for (name, connect) in clients() {
        for kind in KINDS {
            let server = Server::start(kind);
            let mut c = connect(kind, server.addr, Duration::ZERO);
            server.then(Step::Answer);
            assert_eq!(c.read().unwrap(), good(), "{name} {kind:?}: first read");
            server.done();

            server.then(Step::Swallow);
            let e = c.read().unwrap_err();
            assert!(matches!(e, Error::Timeout { .. }), "{name} {kind:?}: {e:?}");
            server.done();
            server.then(Step::Late);
            server.done();

            server.then(Step::Answer);
            let words = c.read();
            assert_eq!(
                words.as_ref().ok(),
                Some(&good()),
                "{name} {kind:?}: the late reply was taken: {words:?}"
            );
            assert_eq!(
                c.discarded(),
                Discarded::default(),
                "{name} {kind:?}: the late reply reached the reply matching instead of being flushed"
            );
            server.done();
        }
    }
}

/// Between two transactions the peer sends a frame nobody asked for, one that would pass every
/// check of the next request's reply (for Modbus TCP it carries the next transaction id). It
/// is flushed before the request: the request gets its real answer.
#[test]
fn unsolicited_input_between_transactions_is_flushed() {
    for (name, connect) in clients() {
        for kind in KINDS {
            let server = Server::start(kind);
            let mut c = connect(kind, server.addr, Duration::ZERO);
            for round in 0..3 {
                server.then(Step::Answer);
                assert_eq!(c.read().unwrap(), good(), "{name} {kind:?} round {round}");
                server.done();
                server.then(Step::Unsolicited);
                server.done();
                server.then(Step::Answer);
                let words = c.read();
                assert_eq!(
                    words.as_ref().ok(),
                    Some(&good()),
                    "{name} {kind:?} round {round}: the unsolicited frame was taken"
                );
                assert_eq!(
                    c.discarded(),
                    Discarded::default(),
                    "{name} {kind:?} round {round}: the unsolicited frame was not flushed"
                );
                server.done();
            }
        }
    }
}

/// A late reply that arrives while the next request is already waiting (after the flush) is
/// told apart by its transaction id, discarded, and the real answer taken.
#[test]
fn late_reply_during_the_next_wait_is_discarded_by_transaction_id() {
    let kind = TransportKind::Tcp;
    for (name, connect) in clients() {
        let server = Server::start(kind);
        let mut c = connect(kind, server.addr, Duration::ZERO);
        server.then(Step::Swallow);
        let e = c.read().unwrap_err();
        assert!(matches!(e, Error::Timeout { .. }), "{name}: {e:?}");
        server.done();

        server.then(Step::LateThenAnswer);
        assert_eq!(
            c.read().unwrap(),
            good(),
            "{name}: the late reply was taken"
        );
        let d = c.discarded();
        assert_eq!(d.frames, 1, "{name}: {d:?}");
        server.done();
    }
}

/// With a request gap, the next request leaves no earlier than the gap after the previous
/// answer was written (the client reads the answer after that instant and waits the gap after
/// reading it, so the bound holds however slow either side is). Quick requests in a row keep
/// it every time.
#[test]
fn request_gap_is_kept_between_transactions() {
    let gap = Duration::from_millis(30);
    for (name, connect) in clients() {
        for kind in KINDS {
            let server = Server::start(kind);
            let mut c = connect(kind, server.addr, gap);
            let mut previous: Option<Done> = None;
            for i in 0..5 {
                server.then(Step::Answer);
                assert_eq!(c.read().unwrap(), good(), "{name} {kind:?} read {i}");
                let d = server.done();
                if let Some(p) = previous {
                    let between = d.read.unwrap() - p.writing;
                    assert!(
                        between >= gap,
                        "{name} {kind:?} read {i}: the request came {between:?} after the last answer, gap {gap:?}"
                    );
                }
                previous = Some(d);
            }
        }
    }
}
