//! `cargo bench -p drivemap-sim --bench sim_vs_minimal`
//!
//! The simulator's Modbus TCP server against a minimal Modbus TCP server with the same threading
//! (one thread per connection, registers behind one mutex), in-process on 127.0.0.1, in
//! interleaved rounds: 16-register reads (03h from 0020h, the TDS-V8 monitor block), 1 and 8
//! client connections, requests/s and the ratio. Then the heap allocations per request of the
//! simulator's request path (`Simulator::handle`), counted by a global allocator, and of a whole
//! TCP round (every thread of the process: clients, server, simulator).
//!
//! Environment: `SIM_BENCH_ROUNDS` (default 5), `SIM_BENCH_SECS` per round (default 1.5),
//! `SIM_BENCH_CPU=<n>`: every thread of the process (servers and clients) on CPU n, as the
//! clients' bench runs them, so a request is a switch between two threads of one core and the
//! scheduler's placement of threads on the two cores (which moved single rounds at 1 connection
//! by up to ±30 %) is out of the figure. Left unset, threads go where the scheduler puts them.

use drivemap_test_support::paths;

use drivemap_test_support::alloc_count::{self, Counting};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Barrier, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::pdu::Request;
use drivemap_runtime::tcp;
use drivemap_sim::{
    SimOptions, Simulator, clock::SystemClock, server::TcpFraming, server::TcpServer,
};

#[global_allocator]
static GLOBAL: Counting = Counting;

const REQUEST: [u8; 12] = [0, 0, 0, 0, 0, 6, 1, 0x03, 0x00, 0x20, 0x00, 0x10];
const REPLY_LEN: usize = 9 + 32;

/// A minimal Modbus TCP server: thread per connection, 03h only, registers behind a mutex.
struct Minimal {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
}

impl Minimal {
    fn spawn() -> Minimal {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        listener.set_nonblocking(true).unwrap();
        let addr = listener.local_addr().unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let regs = Arc::new(Mutex::new([0u16; 0x100]));
        let flag = stop.clone();
        thread::spawn(move || {
            while !flag.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((s, _)) => {
                        let (regs, flag) = (regs.clone(), flag.clone());
                        thread::spawn(move || minimal_connection(s, &regs, &flag));
                    }
                    Err(_) => thread::sleep(Duration::from_millis(5)),
                }
            }
        });
        Minimal { addr, stop }
    }
}

impl Drop for Minimal {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

fn minimal_connection(mut s: TcpStream, regs: &Mutex<[u16; 0x100]>, stop: &AtomicBool) {
    s.set_nonblocking(false).unwrap();
    s.set_nodelay(true).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let mut req = [0u8; 260];
    let mut out = [0u8; 260];
    while !stop.load(Ordering::Relaxed) {
        if s.read_exact(&mut req[..7]).is_err() {
            return;
        }
        let len = usize::from(u16::from_be_bytes([req[4], req[5]]));
        if !(2..=254).contains(&len) || s.read_exact(&mut req[7..6 + len]).is_err() {
            return;
        }
        let (f, addr, q) = (
            req[7],
            usize::from(u16::from_be_bytes([req[8], req[9]])),
            usize::from(u16::from_be_bytes([req[10], req[11]])),
        );
        out[..7].copy_from_slice(&req[..7]);
        out[7] = f;
        let n = if f == 3 && (1..=125).contains(&q) && addr + q <= 0x100 {
            let r = regs.lock().unwrap();
            out[8] = (2 * q) as u8;
            for k in 0..q {
                out[9 + 2 * k..11 + 2 * k].copy_from_slice(&r[addr + k].to_be_bytes());
            }
            9 + 2 * q
        } else {
            out[7] = f | 0x80;
            out[8] = 2;
            9
        };
        out[4..6].copy_from_slice(&((n - 6) as u16).to_be_bytes());
        if s.write_all(&out[..n]).is_err() {
            return;
        }
    }
}

/// `conns` clients each sending reads back to back for `secs`; requests/s over all.
fn round(addr: SocketAddr, conns: usize, secs: f64) -> (f64, u64) {
    let start = Arc::new(Barrier::new(conns + 1));
    let handles: Vec<_> = (0..conns)
        .map(|_| {
            let start = start.clone();
            thread::spawn(move || {
                let mut s = TcpStream::connect(addr).unwrap();
                s.set_nodelay(true).unwrap();
                s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
                let mut reply = [0u8; REPLY_LEN];
                let mut req = REQUEST;
                start.wait();
                let end = Instant::now() + Duration::from_secs_f64(secs);
                let mut n = 0u64;
                while Instant::now() < end {
                    req[..2].copy_from_slice(&(n as u16).to_be_bytes());
                    s.write_all(&req).unwrap();
                    s.read_exact(&mut reply).unwrap();
                    assert_eq!(reply[7], 0x03);
                    n += 1;
                }
                n
            })
        })
        .collect();
    start.wait();
    let t = Instant::now();
    let n: u64 = handles.into_iter().map(|h| h.join().unwrap()).sum();
    (n as f64 / t.elapsed().as_secs_f64(), n)
}

fn env<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn simulator() -> Simulator {
    let path = paths::shipped_map("ptlk-tds-v8");
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    Simulator::new(drive, SimOptions::new().clock(Arc::new(SystemClock::new()))).unwrap()
}

/// Pins the calling thread, and so every thread it starts afterwards, to CPU `cpu`.
fn pin(cpu: usize) {
    #[cfg(target_os = "linux")]
    {
        let mut set = rustix::thread::CpuSet::new();
        set.set(cpu);
        rustix::thread::sched_setaffinity(None, &set).expect("pin to the CPU given");
    }
    #[cfg(not(target_os = "linux"))]
    let _ = cpu;
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

fn main() {
    if let Some(cpu) = std::env::var("SIM_BENCH_CPU")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        pin(cpu);
        println!("every thread on CPU {cpu}");
    }
    // `cargo bench` passes `--bench`; `cargo test --benches` runs it once, briefly.
    let quick = !std::env::args().any(|a| a == "--bench");
    let rounds: usize = if quick { 1 } else { env("SIM_BENCH_ROUNDS", 5) };
    let secs: f64 = if quick {
        0.2
    } else {
        env("SIM_BENCH_SECS", 1.5)
    };

    // Allocations of the request path, on one thread.
    let mut sim = simulator();
    let mut frame = [0u8; tcp::MAX_FRAME];
    let read = Request::ReadHolding {
        address: 0x20,
        quantity: 16,
    };
    let n = tcp::encode_request(1, 1, &read, &mut frame).unwrap();
    let mut out = [0u8; tcp::MAX_FRAME];
    for _ in 0..100 {
        sim.handle(TransportKind::Tcp, &frame[..n], &mut out);
    }
    let before = alloc_count::all_threads();
    let calls = 100_000;
    let t = Instant::now();
    for _ in 0..calls {
        sim.handle(TransportKind::Tcp, &frame[..n], &mut out);
    }
    let handle_ns = t.elapsed().as_nanos() as f64 / f64::from(calls);
    let handle_allocs = (alloc_count::all_threads() - before) as f64 / f64::from(calls);

    let server = TcpServer::spawn(
        drivemap_sim::server::shared(sim),
        "127.0.0.1:0",
        TcpFraming::ModbusTcp,
        None,
    )
    .unwrap();
    let minimal = Minimal::spawn();
    println!("| connections | round | simulator req/s | minimal req/s | ratio |");
    println!("|--:|--:|--:|--:|--:|");
    let mut summary = Vec::new();
    let mut tcp_allocs = (0usize, 0u64);
    for conns in [1usize, 8] {
        let (mut sim_total, mut min_total) = (0.0, 0.0);
        let mut ratios = Vec::new();
        for r in 0..rounds {
            // Interleaved, and the order alternates so neither always runs first.
            let (s, m) = if r % 2 == 0 {
                let a0 = alloc_count::all_threads();
                let s = round(server.local_addr(), conns, secs);
                tcp_allocs.0 += alloc_count::all_threads() - a0;
                tcp_allocs.1 += s.1;
                (s.0, round(minimal.addr, conns, secs).0)
            } else {
                let m = round(minimal.addr, conns, secs).0;
                (round(server.local_addr(), conns, secs).0, m)
            };
            println!("| {conns} | {} | {s:.0} | {m:.0} | {:.2} |", r + 1, s / m);
            ratios.push(s / m);
            sim_total += s;
            min_total += m;
        }
        summary.push((
            conns,
            sim_total / rounds as f64,
            min_total / rounds as f64,
            median(ratios),
        ));
    }
    println!();
    println!(
        "| connections | simulator req/s (mean) | minimal req/s (mean) | simulator ÷ minimal (means) | median of per-round ratios |"
    );
    println!("|--:|--:|--:|--:|--:|");
    for (c, s, m, r) in summary {
        println!("| {c} | {s:.0} | {m:.0} | {:.2} | {r:.2} |", s / m);
    }
    println!();
    println!(
        "request path (`Simulator::handle`, 16-register read): {handle_allocs:.2} heap allocations per request, {handle_ns:.0} ns per request"
    );
    println!(
        "whole process during simulator rounds (clients' threads and connection set-up included): {:.3} allocations per request",
        tcp_allocs.0 as f64 / tcp_allocs.1.max(1) as f64
    );
}
