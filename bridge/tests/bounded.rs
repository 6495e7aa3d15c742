//! The bridge's bounds, in-process against a simulated V7: a broker side that never takes an
//! update does not hold polling back (the updates are dropped and counted, the cycles go on at
//! their period), a link that cannot be reached is tried again without end and without
//! blocking its stop, and a link stops within a cycle of being told to.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use drivemap_bridge::link::{self, Connect, DriveSpec, LinkSpec, Update};
use drivemap_bridge::metrics::Metrics;
use drivemap_bridge::points;
use drivemap_map::Drive;
use drivemap_map::validate::Context;
use drivemap_runtime::ClientOptions;
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_sim::{SimOptions, Simulator, TcpFraming, TcpServer};

fn v7() -> &'static Drive {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps/yaskawa-v7.yaml");
    Box::leak(Box::new(
        drivemap_map::read_map(&path, &Context::default()).unwrap(),
    ))
}

fn spec(drive: &'static Drive) -> DriveSpec {
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
    }
}

fn connect_to(addr: String) -> Connect {
    Box::new(move || {
        RtuOverTcpTransport::connect(addr.as_str(), Duration::from_millis(300))
            .map(|t| Box::new(t) as Box<dyn Transport>)
            .map_err(Into::into)
    })
}

fn metrics_for(drive: &'static Drive) -> Arc<Metrics> {
    let s = spec(drive);
    let (regs, _) = link::choose(&s, TransportKind::RtuOverTcp).unwrap();
    let pts = points::points(drive, &regs, TransportKind::RtuOverTcp);
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
    let (_commands_tx, commands) = std::sync::mpsc::sync_channel(4);
    let stop = Arc::new(AtomicBool::new(false));
    let l = LinkSpec {
        name: "sim".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(addr),
        drives: vec![spec(drive)],
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
    let (_commands_tx, commands) = std::sync::mpsc::sync_channel(4);
    let stop = Arc::new(AtomicBool::new(false));
    let l = LinkSpec {
        name: "nobody".into(),
        kind: TransportKind::RtuOverTcp,
        line: SerialConfig::default(),
        connect: connect_to(format!("127.0.0.1:{port}")),
        drives: vec![spec(drive)],
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
