//! The proxy in-process: a simulated V7 on a line whose one master is the link task, Modbus TCP
//! masters on loopback (plain sockets speaking MBAP, as any master does).

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use drivemap_bridge::command::{Board, DEFAULT_DEADLINE};
use drivemap_bridge::link::{self, LinkSpec};
use drivemap_bridge::proxy::{self, Cidr, ProxyOptions};
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};
use drivemap_test_support::rng::SplitMix;

use super::{connect_to, metrics_for, spec, v7};

/// A proxy in front of a simulated V7 (slave 1) on an RTU-over-TCP line.
struct Proxied {
    sim: drivemap_sim::server::SharedSim,
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    link: Option<std::thread::JoinHandle<()>>,
    server: Option<TcpServer>,
    _runtime: tokio::runtime::Runtime,
}

impl Proxied {
    fn start(options: impl FnOnce(SocketAddr) -> ProxyOptions) -> Proxied {
        let drive = v7();
        let sim_options = SimOptions::new().network_source(TransportKind::RtuOverTcp);
        let sim = drivemap_sim::server::shared(Simulator::new(drive.clone(), sim_options).unwrap());
        let server = TcpServer::spawn(
            Arc::clone(&sim),
            "127.0.0.1:0",
            TcpFraming::RtuOverTcp,
            None,
        )
        .unwrap();
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let listener = runtime
            .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
            .unwrap();
        let addr = listener.local_addr().unwrap();
        let options = options(addr);
        let board = Arc::new(Board::new(1, DEFAULT_DEADLINE));
        let queue = Arc::new(proxy::Queue::new(Arc::clone(&board)));
        let stop = Arc::new(AtomicBool::new(false));
        let metrics = metrics_for(drive);
        runtime.spawn(proxy::serve(
            listener,
            Arc::clone(&queue),
            vec![1],
            options.clone(),
            Arc::clone(&stop),
        ));
        let line_side = proxy::LineSide::new(options.clone(), queue, Arc::clone(&metrics));
        let l = LinkSpec {
            name: "proxied".into(),
            kind: TransportKind::RtuOverTcp,
            line: SerialConfig::default(),
            connect: connect_to(server.local_addr().to_string()),
            drives: vec![spec(drive)],
            poll: false,
            proxy: Some(options),
        };
        let s = Arc::clone(&stop);
        let link = std::thread::spawn(move || {
            link::run(
                l,
                0,
                Duration::from_millis(100),
                metrics,
                None,
                board,
                s,
                Arc::new(AtomicBool::new(false)),
                Some(line_side),
            )
        });
        Proxied {
            sim,
            addr,
            stop,
            link: Some(link),
            server: Some(server),
            _runtime: runtime,
        }
    }

    fn raw(&self, name: &str) -> u32 {
        drivemap_sim::server::lock(&self.sim).raw(name).unwrap()
    }
}

impl Drop for Proxied {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(l) = self.link.take() {
            let _ = l.join();
        }
        if let Some(s) = self.server.take() {
            s.stop();
        }
    }
}

fn options(addr: SocketAddr) -> ProxyOptions {
    ProxyOptions {
        listen: addr,
        allow_writes: true,
        allow_commands: vec![Cidr::parse("127.0.0.2").unwrap()],
        max_connections: 16,
        cache: None,
        timeout: Duration::from_secs(10),
    }
}

/// A master: one connection, requests one at a time.
struct Master(TcpStream);

impl Master {
    fn connect(addr: SocketAddr) -> Master {
        let s = TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(15))).unwrap();
        Master(s)
    }

    /// Sends `pdu` to `unit` with `transaction`; the reply's transaction, unit and PDU.
    fn ask(&mut self, transaction: u16, unit: u8, pdu: &[u8]) -> (u16, u8, Vec<u8>) {
        let mut frame = Vec::new();
        frame.extend_from_slice(&transaction.to_be_bytes());
        frame.extend_from_slice(&[0, 0]);
        frame.extend_from_slice(&((pdu.len() + 1) as u16).to_be_bytes());
        frame.push(unit);
        frame.extend_from_slice(pdu);
        self.0.write_all(&frame).unwrap();
        let mut head = [0u8; 7];
        self.0.read_exact(&mut head).unwrap();
        let len = usize::from(u16::from_be_bytes([head[4], head[5]])) - 1;
        let mut body = vec![0u8; len];
        self.0.read_exact(&mut body).unwrap();
        (u16::from_be_bytes([head[0], head[1]]), head[6], body)
    }
}

fn read_pdu(address: u16, quantity: u16) -> Vec<u8> {
    let mut p = vec![0x03];
    p.extend_from_slice(&address.to_be_bytes());
    p.extend_from_slice(&quantity.to_be_bytes());
    p
}

fn write_pdu(address: u16, value: u16) -> Vec<u8> {
    let mut p = vec![0x06];
    p.extend_from_slice(&address.to_be_bytes());
    p.extend_from_slice(&value.to_be_bytes());
    p
}

/// Four masters at once, each asking random reads of its own (address, quantity) with random
/// transaction ids: every reply carries its request's transaction id and unit, and holds the
/// words the drive holds at that address (read directly beforehand) — none lost, none given to
/// another master.
#[test]
fn every_reply_goes_to_the_master_that_asked() {
    let p = Proxied::start(options);
    let drive = v7();
    // Parameters (nothing changes them here) by address: what each master reads.
    let mut held = std::collections::BTreeMap::new();
    for name in [
        "accel_time_1",
        "decel_time_1",
        "max_output_frequency",
        "frequency_reference",
    ] {
        let r = drive.register_by_id(name).unwrap();
        held.insert(r.address(), p.raw(name) as u16);
    }
    let held = Arc::new(held);
    let addr = p.addr;
    let masters: Vec<_> = (0..4u64)
        .map(|m| {
            let held = Arc::clone(&held);
            std::thread::spawn(move || {
                let mut rng = SplitMix(m + 1);
                let mut master = Master::connect(addr);
                let mut answered = 0;
                for _ in 0..25 {
                    let (&address, &word) = held
                        .iter()
                        .nth(rng.below(held.len() as u64) as usize)
                        .unwrap();
                    let t = rng.next_u64() as u16;
                    let (rt, unit, body) = master.ask(t, 1, &read_pdu(address, 1));
                    assert_eq!((rt, unit), (t, 1), "master {m}");
                    assert_eq!(
                        body,
                        vec![0x03, 2, (word >> 8) as u8, word as u8],
                        "master {m} at {address:04X}h"
                    );
                    answered += 1;
                }
                answered
            })
        })
        .collect();
    let answered: usize = masters.into_iter().map(|t| t.join().unwrap()).sum();
    assert_eq!(answered, 100);
}

/// Writes through the proxy are the map's: above the limit n011 sets (03h, the drive never
/// sees it), to a command register from a master not in --allow-commands (01h), to a read-only
/// register (refused before the line); an allowed write reaches the drive; a slave not on the
/// line is answered 0Bh at once; without writes allowed every write is 01h.
#[test]
fn writes_are_checked_by_the_map_before_the_line() {
    let p = Proxied::start(options);
    let drive = v7();
    let address = |name: &str| drive.register_by_id(name).unwrap().address();
    let mut m = Master::connect(p.addr);
    let reference = address("frequency_reference");
    let max = p.raw("max_output_frequency");
    let before = p.raw("frequency_reference");
    // n011 in 0.1 Hz; the reference in 0.1 Hz too (n152 = 0 at the factory): max + 10 is
    // 1 Hz above it.
    let above = (max + 10) as u16;
    let (_, _, body) = m.ask(1, 1, &write_pdu(reference, above));
    assert_eq!(body, vec![0x86, 0x03], "above n011");
    assert_eq!(p.raw("frequency_reference"), before, "the drive saw it");
    let (_, _, body) = m.ask(2, 1, &write_pdu(reference, 250));
    assert_eq!(body, write_pdu(reference, 250));
    assert_eq!(p.raw("frequency_reference"), 250);
    let (_, _, body) = m.ask(3, 1, &write_pdu(address("digital_input_command"), 1));
    assert_eq!(
        body,
        vec![0x86, 0x01],
        "a run from a master not allowed commands"
    );
    assert_eq!(p.raw("digital_input_command"), 0);
    let (_, _, body) = m.ask(4, 1, &write_pdu(address("output_frequency"), 1));
    assert_eq!(body[0], 0x86, "a read-only register: {body:?}");
    let (_, unit, body) = m.ask(5, 7, &read_pdu(reference, 1));
    assert_eq!(
        (unit, body),
        (7, vec![0x83, 0x0B]),
        "a slave not on the line"
    );
    drop(m);
    drop(p);
    let p = Proxied::start(|a| ProxyOptions {
        allow_writes: false,
        ..options(a)
    });
    let mut m = Master::connect(p.addr);
    let (_, _, body) = m.ask(6, 1, &write_pdu(reference, 250));
    assert_eq!(body, vec![0x86, 0x01], "writes not allowed");
}

/// Four masters reading as fast as they can through the proxy onto a 9600-baud emulated line:
/// the line keeps its rules (no timing violation in the line's record), each master's share of
/// the answered requests is within 20 % of the others', and the line carries what the bus-time
/// model allows (the ratio printed for the notes, not asserted: speed is for benchmarks).
#[cfg(unix)]
#[test]
fn four_masters_share_a_9600_baud_line_fairly() {
    use drivemap_runtime::bus_time::BusModel;
    use drivemap_runtime::client::ClientOptions;
    use drivemap_runtime::transport::Transport;
    use drivemap_runtime::transport::serial::{self, SerialOptions, SerialTransport};
    use drivemap_sim::server::SerialServer;
    use drivemap_sim::timed::DriveLine;
    use drivemap_test_support::line::{EmulatedLine, analyse};

    let drive = v7();
    let profile = drive.plan().profile;
    let serial_line = SerialConfig::new(9600);
    let emulated = EmulatedLine::new(serial_line).unwrap();
    let options_for = |path: &str| {
        SerialOptions::new(path, 9600)
            .line(profile, serial::Parity::None, Some(serial::StopBits::One))
            .unwrap()
    };
    let sim =
        drivemap_sim::server::shared(Simulator::new(drive.clone(), SimOptions::new()).unwrap());
    let server = SerialServer::spawn_on_line(
        Arc::clone(&sim),
        options_for(emulated.drive_path()),
        None,
        Some(DriveLine {
            serial: serial_line,
            pace: false,
        }),
    )
    .unwrap();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .unwrap();
    let addr = listener.local_addr().unwrap();
    let opts = options(addr);
    let board = Arc::new(Board::new(1, DEFAULT_DEADLINE));
    let queue = Arc::new(proxy::Queue::new(Arc::clone(&board)));
    let stop = Arc::new(AtomicBool::new(false));
    let metrics = metrics_for(drive);
    runtime.spawn(proxy::serve(
        listener,
        Arc::clone(&queue),
        vec![1],
        opts.clone(),
        Arc::clone(&stop),
    ));
    let master_path = options_for(emulated.master_path());
    let mut s = spec(drive);
    s.options = ClientOptions::for_line(profile, serial_line);
    let l = LinkSpec {
        name: "9600".into(),
        kind: TransportKind::Rtu,
        line: serial_line,
        connect: Box::new(move || {
            SerialTransport::open(master_path.clone())
                .map(|t| Box::new(t) as Box<dyn Transport>)
                .map_err(Into::into)
        }),
        drives: vec![s],
        poll: false,
        proxy: Some(opts.clone()),
    };
    let line_side = proxy::LineSide::new(opts, queue, Arc::clone(&metrics));
    let st = Arc::clone(&stop);
    let link = std::thread::spawn(move || {
        link::run(
            l,
            0,
            Duration::from_millis(100),
            metrics,
            None,
            board,
            st,
            Arc::new(AtomicBool::new(false)),
            Some(line_side),
        )
    });
    // Warm up (the link opened, one request), then a clean record.
    Master::connect(addr).ask(0, 1, &read_pdu(0x0020, 4));
    drop(emulated.take_record());
    let run_for = Duration::from_secs(4);
    let began = std::time::Instant::now();
    let masters: Vec<_> = (0..4)
        .map(|m| {
            std::thread::spawn(move || {
                let mut master = Master::connect(addr);
                let mut n = 0u32;
                while began.elapsed() < run_for {
                    let (_, _, body) = master.ask(n as u16, 1, &read_pdu(0x0020, 4));
                    assert_eq!(body.len(), 10, "master {m}: {body:?}");
                    n += 1;
                }
                n
            })
        })
        .collect();
    let counts: Vec<u32> = masters.into_iter().map(|t| t.join().unwrap()).collect();
    let elapsed = began.elapsed();
    let record = emulated.take_record();
    stop.store(true, Ordering::Relaxed);
    link.join().unwrap();
    server.stop();
    let model = BusModel::new(profile, serial_line);
    let report = analyse(&record, &model);
    assert!(report.violations.is_empty(), "{:?}", report.violations);
    let total: u32 = counts.iter().sum();
    let (lo, hi) = (
        *counts.iter().min().unwrap() as f64,
        *counts.iter().max().unwrap() as f64,
    );
    assert!(lo >= 0.8 * hi, "shares {counts:?}");
    let allowed = elapsed.as_nanos() as f64 / model.read_ns(4) as f64;
    eprintln!(
        "4 masters through the proxy on 9600 baud: {counts:?} requests in {elapsed:?}; {:.2} of what the bus-time model allows ({allowed:.0} reads of 4 registers)",
        f64::from(total) / allowed
    );
}
