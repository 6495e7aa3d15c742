//! The bridge's bounds, in-process against a simulated V7: a broker side that never takes an
//! update does not hold polling back (the updates are dropped and counted, the cycles go on at
//! their period), a link that cannot be reached is tried again without end and without
//! blocking its stop, and a link stops within a cycle of being told to.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use drivemap_bridge::command::{Board, DEFAULT_DEADLINE};
use drivemap_bridge::link::{self, Action, Command, Connect, DriveSpec, LinkSpec, Update};
use drivemap_bridge::metrics::Metrics;
use drivemap_map::{Loader, Map};
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};

mod proxy;

fn v7() -> &'static Map {
    let path = paths::shipped_map("yaskawa-v7");
    Box::leak(Box::new(Loader::new().load(&path).unwrap()))
}

fn spec(drive: &'static Map) -> DriveSpec {
    let profile = drive.plan().profile;
    DriveSpec {
        drive,
        slave: 1,
        name: "v7".into(),
        options: ClientOptions {
            timeout: Duration::from_millis(200),
            retries: 0,
            ..ClientOptions::for_link(profile, TransportKind::RtuOverTcp)
        },
        settings: Default::default(),
        fixed: Default::default(),
        registers: Vec::new(),
        periods: Vec::new(),
        draft: Default::default(),
    }
}

fn connect_to(addr: String) -> Connect {
    Box::new(move || {
        RtuOverTcpTransport::connect(addr.as_str(), Duration::from_millis(300))
            .map(|t| Box::new(t) as Box<dyn Transport>)
            .map_err(Into::into)
    })
}

fn metrics_for(drive: &'static Map) -> Arc<Metrics> {
    let s = spec(drive);
    let pts = link::points_of(&s, TransportKind::RtuOverTcp).unwrap();
    Arc::new(Metrics::new(&pts))
}

fn value(text: &str, name: &str) -> f64 {
    text.lines()
        .filter(|l| l.starts_with(name))
        .filter_map(|l| l.rsplit(' ').next()?.parse::<f64>().ok())
        .sum()
}

/// An MQTT side that never takes an update (a queue of one, never read): polling goes on at
/// its period, updates beyond the queue are dropped and counted, and the link stops within a
/// cycle of being told to.
#[test]
fn a_stuck_broker_side_never_holds_polling_back() {
    let drive = v7();
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let server = TcpServer::spawn(sim, "127.0.0.1:0", TcpFraming::RtuOverTcp, None).unwrap();
    let addr = server.local_addr().to_string();
    let metrics = metrics_for(drive);
    let (tx, rx) = tokio::sync::mpsc::channel::<Update>(1);
    let commands = Arc::new(Board::new(1, DEFAULT_DEADLINE));
    let stop = Arc::new(AtomicBool::new(false));
    let l = LinkSpec {
        name: "sim".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(addr),
        drives: vec![spec(drive)],
        poll: true,
        proxy: None,
    };
    let (m, s) = (Arc::clone(&metrics), Arc::clone(&stop));
    let task = std::thread::spawn(move || {
        link::run(
            l,
            0,
            Duration::from_millis(50),
            m,
            Some(tx),
            commands,
            s,
            Arc::new(AtomicBool::new(false)),
            None,
        )
    });
    // The queue is full after the first update; the cycles go on (each is the V7's planned
    // reads with its request gap, a few hundred ms in a debug build).
    std::thread::sleep(Duration::from_millis(1500));
    let before = value(&metrics.encode(), "drivemap_bridge_cycles_total");
    std::thread::sleep(Duration::from_millis(1500));
    let text = metrics.encode();
    let cycles = value(&text, "drivemap_bridge_cycles_total");
    assert!(
        cycles >= before + 2.0,
        "{before} then {cycles} cycles:\n{text}"
    );
    assert!(
        value(&text, "drivemap_bridge_mqtt_dropped_total") >= 1.0,
        "{text}"
    );
    assert_eq!(value(&text, "drivemap_up{"), 1.0, "{text}");
    let asked = Instant::now();
    stop.store(true, Ordering::Relaxed);
    task.join().unwrap();
    assert!(
        asked.elapsed() < Duration::from_secs(1),
        "{:?}",
        asked.elapsed()
    );
    drop(rx);
    server.stop();
}

/// A link nobody listens on: connecting is tried again with a back-off and counted, and the
/// link still stops at once when told to.
#[test]
fn an_unreachable_link_is_retried_and_still_stops() {
    let drive = v7();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let metrics = metrics_for(drive);
    let commands = Arc::new(Board::new(1, DEFAULT_DEADLINE));
    let stop = Arc::new(AtomicBool::new(false));
    let l = LinkSpec {
        name: "nobody".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(format!("127.0.0.1:{port}")),
        drives: vec![spec(drive)],
        poll: true,
        proxy: None,
    };
    let (m, s) = (Arc::clone(&metrics), Arc::clone(&stop));
    let task = std::thread::spawn(move || {
        link::run(
            l,
            0,
            Duration::from_millis(50),
            m,
            None,
            commands,
            s,
            Arc::new(AtomicBool::new(false)),
            None,
        )
    });
    std::thread::sleep(Duration::from_millis(1500));
    let text = metrics.encode();
    // 100, 200, 400, 800 ms apart: 3 to 5 attempts in 1.5 s, not a tight loop.
    let attempts = value(
        &text,
        "drivemap_bridge_errors_total{link=\"nobody\",kind=\"connect\"}",
    );
    assert!((3.0..=5.0).contains(&attempts), "{attempts}:\n{text}");
    let asked = Instant::now();
    stop.store(true, Ordering::Relaxed);
    task.join().unwrap();
    assert!(
        asked.elapsed() < Duration::from_millis(500),
        "{:?}",
        asked.elapsed()
    );
}

/// A link of a simulated V7 (slave 1) and `silent` drives that never answer (slaves 2, ...), its commands
/// taken from `board`: the link thread, the shared simulator, the server.
struct Line {
    sim: drivemap_sim::server::SharedSim,
    server: Option<TcpServer>,
    board: Arc<Board>,
    stop: Arc<AtomicBool>,
    task: Option<std::thread::JoinHandle<()>>,
}

impl Line {
    fn start(silent: u8, deadline: Duration) -> Line {
        let drive = v7();
        let options = SimOptions::new().network_source(TransportKind::RtuOverTcp);
        let sim = drivemap_sim::server::shared(Simulator::new(drive.clone(), options).unwrap());
        let server = TcpServer::spawn(
            Arc::clone(&sim),
            "127.0.0.1:0",
            TcpFraming::RtuOverTcp,
            None,
        )
        .unwrap();
        let mut drives = vec![spec(drive)];
        for n in 0..silent {
            let mut s = spec(drive);
            s.slave = 2 + n;
            s.name = format!("silent-{n}");
            drives.push(s);
        }
        for d in &mut drives {
            d.options.timeout = Duration::from_millis(300);
            d.options.retries = 1;
        }
        let board = Arc::new(Board::new(drives.len(), deadline));
        let l = LinkSpec {
            name: "line".into(),
            kind: TransportKind::RtuOverTcp,
            line: SerialConfig::default(),
            connect: connect_to(server.local_addr().to_string()),
            drives,
            poll: true,
            proxy: None,
        };
        let stop = Arc::new(AtomicBool::new(false));
        let (m, s, b) = (metrics_for(drive), Arc::clone(&stop), Arc::clone(&board));
        let task = std::thread::spawn(move || {
            link::run(
                l,
                0,
                Duration::from_millis(50),
                m,
                None,
                b,
                s,
                Arc::new(AtomicBool::new(false)),
                None,
            )
        });
        let line = Line {
            sim,
            server: Some(server),
            board,
            stop,
            task: Some(task),
        };
        line.until(Duration::from_secs(20), "the V7 answering", |l| {
            l.board.answering(0)
        });
        line
    }

    fn state(&self) -> drivemap_sim::DriveState {
        drivemap_sim::server::lock(&self.sim).state().unwrap()
    }

    fn offer(&self, action: Action) {
        let command = Command {
            drive: 0,
            action,
            topic: "test".into(),
            payload: "PRESS".into(),
        };
        self.board.offer(command, "", Instant::now());
    }

    /// Waits until `what` holds; returns how long it took.
    fn until(&self, limit: Duration, what: &str, check: impl Fn(&Line) -> bool) -> Duration {
        let began = Instant::now();
        while !check(self) {
            assert!(began.elapsed() < limit, "{what}: not within {limit:?}");
            std::thread::sleep(Duration::from_millis(5));
        }
        began.elapsed()
    }
}

impl Drop for Line {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.task.take() {
            let _ = t.join();
        }
        if let Some(s) = self.server.take() {
            s.stop();
        }
    }
}

/// With three drives on the line that never answer (every request to one times out, with a
/// retry: 600 ms), a stop for the running V7 reaches it before the link's next request: within
/// two request times, never behind a cycle of timeouts (the bridge used to carry commands out
/// between cycles only, and a cycle of the silent drives' timeouts took seconds; without the
/// commands between requests a cycle here is still three timeouts, 1.8 s). The figures are
/// printed for the notes.
#[test]
fn a_stop_goes_out_before_the_next_request_with_a_silent_drive_on_the_line() {
    let line = Line::start(3, DEFAULT_DEADLINE);
    let mut took = Vec::new();
    for k in 0..8 {
        line.offer(Action::Run);
        line.until(Duration::from_secs(10), "the run", |l| {
            l.state().run_command
        });
        // At points spread over the cycle, where the silent drives' timeouts are.
        std::thread::sleep(Duration::from_millis(150 + 230 * k));
        line.offer(Action::Stop);
        took.push(line.until(Duration::from_secs(10), "the stop", |l| {
            !l.state().run_command
        }));
    }
    took.sort();
    eprintln!(
        "stop latency with a silent slave (request time 600 ms): median {:?}, max {:?}",
        took[took.len() / 2],
        took[took.len() - 1]
    );
    // Two request times of the silent drive (the one in flight, and one of the V7's own).
    for t in &took {
        assert!(*t < Duration::from_millis(1300), "{took:?}");
    }
}

/// `run` on a drive turning in reverse keeps it in reverse (the bridge used to build a fresh
/// drive object per command, which wrote the run word with the forward direction); a stop
/// keeps the direction too.
#[test]
fn run_keeps_the_direction_the_drive_turns_in() {
    let line = Line::start(0, DEFAULT_DEADLINE);
    {
        let mut sim = drivemap_sim::server::lock(&line.sim);
        // Run and reverse, as another master (or `drivemap write`) left them.
        sim.set_raw("digital_input_command", 0b11).unwrap();
    }
    line.until(Duration::from_secs(5), "the drive in reverse", |l| {
        let s = l.state();
        s.run_command && s.reverse_command
    });
    line.offer(Action::Stop);
    line.until(Duration::from_secs(5), "the stop", |l| {
        !l.state().run_command
    });
    assert!(
        line.state().reverse_command,
        "the stop changed the direction"
    );
    line.offer(Action::Run);
    line.until(Duration::from_secs(5), "the run", |l| l.state().run_command);
    assert!(line.state().reverse_command, "run reversed the drive");
}

/// While the link cannot be opened, a run waits at most its deadline and is then dropped:
/// when the drive comes back it does not start; a stop offered meanwhile is delivered.
#[test]
fn a_run_sent_while_the_link_is_down_expires_and_never_starts_the_drive() {
    let drive = v7();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let board = Arc::new(Board::new(1, Duration::from_millis(300)));
    let l = LinkSpec {
        name: "later".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(format!("127.0.0.1:{port}")),
        drives: vec![spec(drive)],
        poll: true,
        proxy: None,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let (m, s, b) = (metrics_for(drive), Arc::clone(&stop), Arc::clone(&board));
    let task = std::thread::spawn(move || {
        link::run(
            l,
            0,
            Duration::from_millis(50),
            m,
            None,
            b,
            s,
            Arc::new(AtomicBool::new(false)),
            None,
        )
    });
    let command = |action| Command {
        drive: 0,
        action,
        topic: "test".into(),
        payload: "PRESS".into(),
    };
    board.offer(command(Action::Run), "", Instant::now());
    std::thread::sleep(Duration::from_millis(800));
    // The gateway comes up with the drive.
    let options = SimOptions::new().network_source(TransportKind::RtuOverTcp);
    let sim = drivemap_sim::server::shared(Simulator::new(drive.clone(), options).unwrap());
    let server = TcpServer::spawn(
        Arc::clone(&sim),
        format!("127.0.0.1:{port}"),
        TcpFraming::RtuOverTcp,
        None,
    )
    .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    let state = drivemap_sim::server::lock(&sim).state().unwrap();
    assert!(!state.run_command, "a run that expired started the drive");
    assert!(board.idle(0, 1));
    stop.store(true, Ordering::Relaxed);
    task.join().unwrap();
    server.stop();
}

/// A `set/` of a field of the command word (a multi-function input) is written from what the
/// bridge told the drive, never from a word read back, and later runs and stops keep it (the
/// bridge used to clear it with the next run or stop, 0040h -> 0001h); the set itself carries
/// no run bit while the drive is stopped.
#[test]
fn a_set_of_a_command_field_is_kept_by_run_and_stop() {
    let line = Line::start(0, DEFAULT_DEADLINE);
    let word = |l: &Line| {
        drivemap_sim::server::lock(&l.sim)
            .raw("digital_input_command")
            .unwrap()
    };
    let set = |l: &Line, payload: &str| {
        let command = Command {
            drive: 0,
            action: Action::Set {
                register: "digital_input_command".into(),
            },
            topic: "test".into(),
            payload: payload.into(),
        };
        l.board
            .offer(command, "digital_input_command", Instant::now());
    };
    let s3 = 1 << 6;
    set(&line, "terminal_s3=1");
    line.until(Duration::from_secs(5), "the field written", |l| {
        word(l) & s3 != 0
    });
    assert_eq!(word(&line) & 1, 0, "the set sent a run bit");
    line.offer(Action::Run);
    line.until(Duration::from_secs(5), "the run", |l| l.state().run_command);
    assert_ne!(
        word(&line) & s3,
        0,
        "run cleared the field ({:04X}h)",
        word(&line)
    );
    line.offer(Action::Stop);
    line.until(Duration::from_secs(5), "the stop", |l| {
        !l.state().run_command
    });
    assert_ne!(
        word(&line) & s3,
        0,
        "stop cleared the field ({:04X}h)",
        word(&line)
    );
}

/// On a 9600-baud line (the test-support's emulated line, each character taking its time), the
/// V7 running: a stop reaches it before the link's next request, within two of the line's
/// request times. The figures are printed for the notes.
#[cfg(unix)]
#[test]
fn a_stop_on_a_9600_baud_line_waits_at_most_one_request() {
    use drivemap_runtime::transport::serial::{self, SerialOptions, SerialTransport};
    use drivemap_sim::server::SerialServer;
    use drivemap_sim::timed::DriveLine;
    use drivemap_test_support::line::EmulatedLine;

    let drive = v7();
    let profile = drive.plan().profile;
    let serial_line = SerialConfig::new(9600);
    let emulated = EmulatedLine::new(serial_line).unwrap();
    let options_for = |path: &str| {
        SerialOptions::new(path, 9600)
            .line(profile, serial::Parity::None, Some(serial::StopBits::One))
            .unwrap()
    };
    let options = SimOptions::new().network_source(TransportKind::Rtu);
    let sim = drivemap_sim::server::shared(Simulator::new(drive.clone(), options).unwrap());
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
    let master = options_for(emulated.master_path());
    let mut s = spec(drive);
    s.options = ClientOptions::for_line(profile, serial_line);
    let board = Arc::new(Board::new(1, DEFAULT_DEADLINE));
    let l = LinkSpec {
        name: "9600".into(),
        kind: TransportKind::Rtu,
        line: serial_line,
        connect: Box::new(move || {
            SerialTransport::open(master.clone())
                .map(|t| Box::new(t) as Box<dyn Transport>)
                .map_err(Into::into)
        }),
        drives: vec![s],
        poll: true,
        proxy: None,
    };
    let (stop, task) = spawn_link(l, Duration::from_millis(200), Arc::clone(&board));
    let mut took = stop_latencies(&board, &sim, 12, Duration::from_millis(37));
    took.sort();
    let model = drivemap_runtime::bus_time::BusModel::new(profile, serial_line);
    // The longest request of the V7's plan (16 registers) and a write, on the wire.
    let request = Duration::from_nanos(model.read_ns(16) + model.read_ns(1));
    eprintln!(
        "stop latency on a 9600-baud line: median {:?}, p90 {:?}, max {:?} (a 16-register read and a write take {:?} by the bus-time model)",
        took[took.len() / 2],
        took[took.len() * 9 / 10],
        took[took.len() - 1],
        request
    );
    for t in &took {
        assert!(*t < 2 * request + Duration::from_millis(100), "{took:?}");
    }
    stop.store(true, Ordering::Relaxed);
    task.join().unwrap();
    server.stop();
}

/// Runs link `l` in a thread of its own every `period`, its commands from `board`; the flag
/// that stops it and the thread.
fn spawn_link(
    l: LinkSpec,
    period: Duration,
    board: Arc<Board>,
) -> (Arc<AtomicBool>, std::thread::JoinHandle<()>) {
    let drive = l.drives[0].drive;
    let stop = Arc::new(AtomicBool::new(false));
    let (m, st) = (metrics_for(drive), Arc::clone(&stop));
    let task = std::thread::spawn(move || {
        link::run(
            l,
            0,
            period,
            m,
            None,
            board,
            st,
            Arc::new(AtomicBool::new(false)),
            None,
        )
    });
    (stop, task)
}

/// Once the simulated drive answers: `runs` times, a run, then after `k` x `spacing` a stop;
/// how long each stop took to reach the drive, sorted.
fn stop_latencies(
    board: &Board,
    sim: &drivemap_sim::server::SharedSim,
    runs: u64,
    spacing: Duration,
) -> Vec<Duration> {
    let running = || drivemap_sim::server::lock(sim).state().unwrap().run_command;
    let until = |what: &str, f: &dyn Fn() -> bool| {
        let began = Instant::now();
        while !f() {
            assert!(began.elapsed() < Duration::from_secs(15), "{what}");
            std::thread::sleep(Duration::from_millis(1));
        }
        began.elapsed()
    };
    until("the V7 answering", &|| board.answering(0));
    let command = |action| Command {
        drive: 0,
        action,
        topic: "test".into(),
        payload: "PRESS".into(),
    };
    let mut took = Vec::new();
    for k in 0..runs {
        board.offer(command(Action::Run), "", Instant::now());
        until("the run", &|| running());
        std::thread::sleep(spacing * k as u32);
        board.offer(command(Action::Stop), "", Instant::now());
        took.push(until("the stop", &|| !running()));
    }
    took.sort();
    took
}

/// Poll periods per class of register: with `parameters` every 2 s on a link polled every
/// 100 ms, the V7's status word is read every cycle and its acceleration time (a parameter) once
/// per 2 s, counted on the simulator's request log; the line's load is reported.
#[test]
fn parameters_are_read_at_their_period_and_status_every_cycle() {
    let drive = v7();
    let reads: Arc<std::sync::Mutex<Vec<(Instant, u16, usize)>>> = Arc::default();
    let log: drivemap_sim::server::Logger = {
        let reads = Arc::clone(&reads);
        Arc::new(move |r: &drivemap_sim::RequestRecord| {
            if let (Some(0x03), Some(a)) = (r.function, r.address) {
                reads.lock().unwrap().push((Instant::now(), a, r.quantity));
            }
        })
    };
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let server = TcpServer::spawn(sim, "127.0.0.1:0", TcpFraming::RtuOverTcp, Some(log)).unwrap();
    let mut s = spec(drive);
    s.periods = vec![("parameters".into(), Duration::from_secs(2))];
    let l = LinkSpec {
        name: "periods".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(server.local_addr().to_string()),
        drives: vec![s],
        poll: true,
        proxy: None,
    };
    let metrics = metrics_for(drive);
    let stop = Arc::new(AtomicBool::new(false));
    let (m, st) = (Arc::clone(&metrics), Arc::clone(&stop));
    let task = std::thread::spawn(move || {
        link::run(
            l,
            0,
            Duration::from_millis(100),
            m,
            None,
            Arc::new(Board::new(1, DEFAULT_DEADLINE)),
            st,
            Arc::new(AtomicBool::new(false)),
            None,
        )
    });
    // The first cycles read everything (and again when the settings they read change the
    // plan); counted from 1 s on, for 4 s.
    let from = Instant::now() + Duration::from_secs(1);
    std::thread::sleep(Duration::from_millis(5000));
    let to = from + Duration::from_secs(4);
    stop.store(true, Ordering::Relaxed);
    task.join().unwrap();
    server.stop();
    let at = |id: &str| drive.register_by_id(id).unwrap().address();
    let covering = |a: u16| {
        reads
            .lock()
            .unwrap()
            .iter()
            .filter(|(t, start, n)| {
                (from..to).contains(t) && *start <= a && usize::from(a - start) < *n
            })
            .count()
    };
    let (status, accel) = (
        covering(at("status_signal_1")),
        covering(at("accel_time_1")),
    );
    assert!(status >= 8, "status read {status} times in 4.5 s");
    assert!(
        (2..=3).contains(&accel),
        "accel_time_1 read {accel} times in 4.5 s"
    );
    let text = metrics.encode();
    assert!(text.contains("drivemap_bridge_line_load_ratio"), "{text}");
}

/// A poll period that names nothing polled is refused at start, naming it.
#[test]
fn a_period_of_nothing_is_refused() {
    let drive = v7();
    let mut s = spec(drive);
    s.periods = vec![("no_such_thing".into(), Duration::from_secs(1))];
    let e = match link::Polled::new(0, s, "x", TransportKind::RtuOverTcp) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted"),
    };
    assert!(e.contains("\"no_such_thing\""), "{e}");
}

/// A relay on loopback between the link and `to` that holds every reply back `late`.
fn late_relay(to: std::net::SocketAddr, late: Duration) -> std::net::SocketAddr {
    use std::io::{Read, Write};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        for master in listener.incoming() {
            let Ok(mut master) = master else { return };
            let Ok(mut drive) = std::net::TcpStream::connect(to) else {
                return;
            };
            let (mut m2, mut d2) = (master.try_clone().unwrap(), drive.try_clone().unwrap());
            // Requests straight through; replies after `late`.
            std::thread::spawn(move || {
                let mut buf = [0u8; 512];
                while let Ok(n) = m2.read(&mut buf) {
                    if n == 0 || d2.write_all(&buf[..n]).is_err() {
                        return;
                    }
                }
            });
            std::thread::spawn(move || {
                let mut buf = [0u8; 512];
                while let Ok(n) = drive.read(&mut buf) {
                    std::thread::sleep(late);
                    if n == 0 || master.write_all(&buf[..n]).is_err() {
                        return;
                    }
                }
            });
        }
    });
    addr
}

/// Every reply 100 ms late and a period shorter than a cycle (the bridge used to carry
/// commands out only in the time left before the next cycle, so with cycles back to back
/// they were never carried out): a stop reaches the running drive within two request times.
#[test]
fn a_stop_gets_out_when_every_reply_is_late_and_cycles_run_back_to_back() {
    let drive = v7();
    let options = SimOptions::new().network_source(TransportKind::RtuOverTcp);
    let sim = drivemap_sim::server::shared(Simulator::new(drive.clone(), options).unwrap());
    let server = TcpServer::spawn(
        Arc::clone(&sim),
        "127.0.0.1:0",
        TcpFraming::RtuOverTcp,
        None,
    )
    .unwrap();
    let late = Duration::from_millis(100);
    let relay = late_relay(server.local_addr(), late);
    let mut s = spec(drive);
    s.options.timeout = Duration::from_millis(400);
    let board = Arc::new(Board::new(1, DEFAULT_DEADLINE));
    let l = LinkSpec {
        name: "late".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(relay.to_string()),
        drives: vec![s],
        poll: true,
        proxy: None,
    };
    let (stop, task) = spawn_link(l, Duration::from_millis(50), Arc::clone(&board));
    let took = stop_latencies(&board, &sim, 6, Duration::from_millis(90));
    stop.store(true, Ordering::Relaxed);
    task.join().unwrap();
    server.stop();
    eprintln!(
        "stop latency with every reply 100 ms late, cycles back to back: median {:?}, max {:?}",
        took[took.len() / 2],
        took[took.len() - 1]
    );
    // The request in flight (its reply 100 ms late) and the stop's own.
    for t in &took {
        assert!(*t < 4 * late, "{took:?}");
    }
}
