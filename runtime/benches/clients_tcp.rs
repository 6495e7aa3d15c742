//! Clients against peers, end to end over loopback TCP: 16-register reads (03h) from ONE
//! minimal in-process Modbus TCP server, by drivemap's blocking `Client` over `TcpTransport`,
//! drivemap's `AsyncClient` over `AsyncTcpTransport`, tokio-modbus and rmodbus (its codec over a
//! std `TcpStream`). Rounds are interleaved (each round runs every client once, in a rotating
//! order), and the median µs per read over the rounds is reported with its ratio to
//! tokio-modbus's, and the median of the per-round ratios (paired, so drift of the machine
//! between rounds cancels out). Heap allocations per request are counted with a counting global allocator.
//!
//! Run: `cargo bench -p drivemap-runtime --features tokio --bench clients_tcp`
//!
//! System calls per request (`strace -c -f`), one client at a time against a server in
//! another process: `scripts/clients-syscalls` (prints the calls per request of each client),
//! or by hand:
//!
//! ```sh
//! B=$(ls -t target/release/deps/clients_tcp-* | grep -v '\.d$' | head -1)
//! CLIENTS_TCP_SERVE=1 $B &          # prints the address it listens on
//! CLIENTS_TCP_ONLY=blocking CLIENTS_TCP_ADDR=127.0.0.1:PORT CLIENTS_TCP_READS=10000 \
//!     strace -c -f $B
//! ```

use drivemap_test_support::alloc_count::{self, Counting};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};

use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::async_client::{AsyncClient, AsyncTcpTransport};
use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::transport::tcp::TcpTransport;

#[global_allocator]
static GLOBAL: Counting = Counting;

static PROFILE: Profile = Profile {
    max_read: 16,
    ..Profile::GENERIC
};

const UNIT: u8 = 1;
const ADDRESS: u16 = 0x0020;
const QUANTITY: u16 = 16;
/// Reads per client per round.
const READS: usize = 1_000;
const ROUNDS: usize = 61;
/// The server's core: the clients run on CPU 0. `CLIENTS_TCP_SERVER_CPU=1` puts the server on
/// the other core.
static SERVER_CPU: std::sync::LazyLock<usize> = std::sync::LazyLock::new(|| {
    env("CLIENTS_TCP_SERVER_CPU")
        .and_then(|c| c.parse().ok())
        .unwrap_or(0)
});

/// The minimal server: answers every 03h request with 16 registers (6000 + i), nothing else.
/// One thread per connection; each connection ends when the client closes it.
fn serve(listener: TcpListener, lifetime: Duration) {
    pin(*SERVER_CPU);
    let until = Instant::now() + lifetime;
    listener.set_nonblocking(true).unwrap();
    while Instant::now() < until {
        match listener.accept() {
            Ok((stream, _)) => {
                thread::spawn(move || connection(stream));
            }
            Err(_) => thread::sleep(Duration::from_millis(5)),
        }
    }
}

/// Pins the calling thread to `cpu` where the machine has more than one, so every client meets
/// the server the same way. Left to the scheduler, some connections got their server thread on
/// the client's core and others on the other core, and ran at 20 or 50 µs a read for a whole
/// run, whichever client that was. By default the clients and the server share CPU 0 (a
/// request is a switch between two threads of one core; on this 2-vCPU machine, waking the
/// other core costs more than the whole exchange); `CLIENTS_TCP_SERVER_CPU=1` gives the server
/// CPU 1.
fn pin(cpu: usize) {
    #[cfg(target_os = "linux")]
    if thread::available_parallelism().is_ok_and(|n| n.get() > 1) {
        let mut set = rustix::thread::CpuSet::new();
        set.set(cpu);
        let _ = rustix::thread::sched_setaffinity(None, &set);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = cpu;
}

fn connection(mut s: TcpStream) {
    pin(*SERVER_CPU);
    s.set_nonblocking(false).unwrap();
    s.set_nodelay(true).unwrap();
    let mut answer = [0u8; 9 + 2 * QUANTITY as usize];
    answer[4..6].copy_from_slice(&(3 + 2 * QUANTITY).to_be_bytes());
    answer[6] = UNIT;
    answer[7] = 0x03;
    answer[8] = (2 * QUANTITY) as u8;
    for i in 0..QUANTITY {
        let at = 9 + 2 * usize::from(i);
        answer[at..at + 2].copy_from_slice(&(6000 + i).to_be_bytes());
    }
    let mut request = [0u8; 12];
    while s.read_exact(&mut request).is_ok() {
        answer[0..2].copy_from_slice(&request[0..2]);
        if s.write_all(&answer).is_err() {
            return;
        }
    }
}

fn check(words: &[u16]) {
    assert_eq!(words.len(), 16);
    assert_eq!(words[0], 6000);
    assert_eq!(words[15], 6015);
}

/// One of the compared clients, connected.
enum Peer {
    Blocking(Client<TcpTransport>),
    Async(tokio::runtime::Runtime, AsyncClient<AsyncTcpTransport>),
    TokioModbus(tokio::runtime::Runtime, tokio_modbus::client::Context),
    Rmodbus(TcpStream, Vec<u8>, Vec<u8>, Vec<u16>),
}

const NAMES: [&str; 4] = [
    "drivemap Client (blocking, TcpTransport)",
    "drivemap AsyncClient (AsyncTcpTransport)",
    "tokio-modbus 0.17",
    "rmodbus 0.13 over std TcpStream",
];

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

fn connect(which: usize, addr: SocketAddr) -> Peer {
    match which {
        0 => Peer::Blocking(Client::with_options(
            TcpTransport::connect(addr, Duration::from_secs(1)).unwrap(),
            &PROFILE,
            ClientOptions::default(),
        )),
        1 => {
            let rt = runtime();
            let link = rt
                .block_on(AsyncTcpTransport::connect(
                    addr,
                    TransportKind::Tcp,
                    Duration::from_secs(1),
                ))
                .unwrap();
            Peer::Async(
                rt,
                AsyncClient::with_options(link, &PROFILE, ClientOptions::default()),
            )
        }
        2 => {
            let rt = runtime();
            let ctx = rt
                .block_on(tokio_modbus::client::tcp::connect_slave(
                    addr,
                    tokio_modbus::Slave(UNIT),
                ))
                .unwrap();
            Peer::TokioModbus(rt, ctx)
        }
        _ => {
            let s = TcpStream::connect(addr).unwrap();
            s.set_nodelay(true).unwrap();
            Peer::Rmodbus(s, Vec::new(), Vec::new(), Vec::new())
        }
    }
}

impl Peer {
    /// `n` reads; checks the last.
    fn reads(&mut self, n: usize) {
        match self {
            Peer::Blocking(c) => {
                let mut words = [0u16; QUANTITY as usize];
                for _ in 0..n {
                    c.read_holding(UNIT, ADDRESS, &mut words).unwrap();
                }
                check(&words);
            }
            Peer::Async(rt, c) => rt.block_on(async {
                let mut words = [0u16; QUANTITY as usize];
                for _ in 0..n {
                    c.read_holding(UNIT, ADDRESS, &mut words).await.unwrap();
                }
                check(&words);
            }),
            Peer::TokioModbus(rt, ctx) => rt.block_on(async {
                use tokio_modbus::prelude::Reader;
                let mut last = Vec::new();
                for _ in 0..n {
                    last = ctx
                        .read_holding_registers(ADDRESS, QUANTITY)
                        .await
                        .unwrap()
                        .unwrap();
                }
                check(&last);
            }),
            Peer::Rmodbus(s, request, response, words) => {
                use rmodbus::{ModbusProto, client::ModbusRequest};
                let mut mreq = ModbusRequest::new(UNIT, ModbusProto::TcpUdp);
                for _ in 0..n {
                    request.clear();
                    mreq.generate_get_holdings(ADDRESS, QUANTITY, request)
                        .unwrap();
                    s.write_all(request).unwrap();
                    response.resize(6, 0);
                    s.read_exact(&mut response[..6]).unwrap();
                    let len = usize::from(u16::from_be_bytes([response[4], response[5]]));
                    response.resize(6 + len, 0);
                    s.read_exact(&mut response[6..]).unwrap();
                    words.clear();
                    mreq.parse_u16(response, words).unwrap();
                }
                check(words);
            }
        }
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        (v[m - 1] + v[m]) / 2.0
    }
}

fn allocations_per(peer: &mut Peer, n: usize) -> f64 {
    peer.reads(100); // warm up: buffers that grow once are not per request.
    let before = alloc_count::all_threads();
    peer.reads(n);
    (alloc_count::all_threads() - before) as f64 / n as f64
}

fn env(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.is_empty())
}

fn main() {
    // `CLIENTS_TCP_SERVE=1`: only the server, in its own process, for strace of a client.
    if env("CLIENTS_TCP_SERVE").is_some() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        println!("{}", listener.local_addr().unwrap());
        std::io::stdout().flush().unwrap();
        serve(listener, Duration::from_secs(300));
        return;
    }
    // `CLIENTS_TCP_ONLY=blocking|async|tokio-modbus|rmodbus`: one client, N reads.
    if let Some(only) = env("CLIENTS_TCP_ONLY") {
        let which = ["blocking", "async", "tokio-modbus", "rmodbus"]
            .iter()
            .position(|n| *n == only)
            .expect("CLIENTS_TCP_ONLY: blocking, async, tokio-modbus or rmodbus");
        let addr: SocketAddr = env("CLIENTS_TCP_ADDR")
            .expect("CLIENTS_TCP_ADDR of a CLIENTS_TCP_SERVE=1 server")
            .parse()
            .unwrap();
        let n: usize = env("CLIENTS_TCP_READS")
            .map(|n| n.parse().unwrap())
            .unwrap_or(10_000);
        let mut peer = connect(which, addr);
        let t = Instant::now();
        peer.reads(n);
        eprintln!(
            "{}: {n} reads, {:.1} µs/read",
            NAMES[which],
            t.elapsed().as_secs_f64() * 1e6 / n as f64
        );
        return;
    }

    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    thread::spawn(move || serve(listener, Duration::from_secs(600)));
    pin(0);
    let mut peers: Vec<Peer> = (0..NAMES.len()).map(|i| connect(i, addr)).collect();
    for p in &mut peers {
        p.reads(500); // warm up
    }
    let mut per_read: Vec<Vec<f64>> = vec![Vec::new(); NAMES.len()];
    for round in 0..ROUNDS {
        for k in 0..NAMES.len() {
            let i = (round + k) % NAMES.len();
            let t = Instant::now();
            peers[i].reads(READS);
            per_read[i].push(t.elapsed().as_secs_f64() * 1e6 / READS as f64);
        }
    }
    let allocs: Vec<f64> = peers
        .iter_mut()
        .map(|p| allocations_per(p, 10_000))
        .collect();
    // Paired: each client's time over tokio-modbus's in the same round, so drift of the
    // machine between rounds cancels out.
    let mut ratios: Vec<Vec<f64>> = (0..NAMES.len())
        .map(|i| {
            (0..ROUNDS)
                .map(|r| per_read[i][r] / per_read[2][r])
                .collect()
        })
        .collect();
    let ratio: Vec<f64> = ratios.iter_mut().map(|v| median(v)).collect();
    let medians: Vec<f64> = per_read.iter_mut().map(|v| median(v)).collect();
    let reference = medians[2];
    println!(
        "16-register reads (03h) over loopback TCP, one in-process server; {ROUNDS} interleaved rounds of {READS} reads per client; clients on CPU 0, server on CPU {}",
        *SERVER_CPU
    );
    println!();
    println!(
        "| client | median µs/read | min / max of rounds | median ÷ tokio-modbus's median | median of per-round ratios to tokio-modbus | heap allocations per request |"
    );
    println!("|---|--:|--:|--:|--:|--:|");
    for i in 0..NAMES.len() {
        let v = &per_read[i];
        let (lo, hi) = (v[0], v[v.len() - 1]);
        println!(
            "| {} | {:.1} | {:.1} / {:.1} | {:.2} | {:.2} | {:.2} |",
            NAMES[i],
            medians[i],
            lo,
            hi,
            medians[i] / reference,
            ratio[i],
            allocs[i]
        );
    }
}
