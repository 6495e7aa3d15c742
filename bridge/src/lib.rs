//! `drivemap bridge`: drives polled by their maps into the tools a plant already runs.
//!
//! - one blocking task per link ([`link::run`]), each polling its drives with the runtime's read
//!   planner every period, reconnecting with the client's back-off, reading what conversions
//!   depend on with every cycle and planning again when it changes;
//! - Prometheus: `/metrics` in the OpenMetrics text format ([`metrics`]);
//! - MQTT: state topics, Home Assistant discovery, command topics through the write gate and
//!   the drive trait, off unless allowed ([`mqtt`]);
//! - commands as intents with deadlines ([`command`]): a stop first and never refused for a
//!   rate or a queue, other commands carried out fresh or refused, never late; one drive object
//!   per drive for the bridge's life (`commander`).
//!
//! Bounded: a scrape reads atomics; MQTT updates go through a bounded queue offered without
//! waiting; commands are the latest wish per drive and register. SIGTERM (or SIGINT) stops
//! every link after the cycle in flight, publishes the drives and the bridge offline, and
//! returns.
//!
//! The bridge is not a safety function: a drive's own communication-loss stop (the V7's n151
//! Modbus time-out detection, the ACN's Pr.12 lost-command mode) is what stops a motor when the
//! bridge, the broker or the line is gone.
#![doc = include_str!("../README.md")]
#![warn(missing_docs, unreachable_pub, unnameable_types)]

pub mod command;
mod commander;
mod error;
pub mod link;
mod log;
pub mod metrics;
pub mod mqtt;
pub mod points;
pub mod proxy;

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

pub use error::{
    CommandFailure, ConnectError, Error, ExportError, PollFailure, Refused, RegisterProblem,
};

/// What the bridge serves.
pub struct Options {
    /// Time between the starts of two poll cycles of a link.
    pub period: Duration,
    /// Where `/metrics` listens (none: no Prometheus endpoint).
    pub metrics: Option<SocketAddr>,
    /// The broker (none: no MQTT).
    pub mqtt: Option<mqtt::Options>,
    /// How long a run, reference, set or fault reset may wait for its link.
    pub deadline: Duration,
}

/// Capacity of the queue of updates to the MQTT side.
pub const UPDATE_QUEUE: usize = 4096;
/// The most links one bridge serves (each is a thread).
pub const MAX_LINKS: usize = 1024;

/// Runs the bridge until SIGTERM or SIGINT, or until `stop` is set.
pub fn run(
    links: Vec<link::LinkSpec>,
    options: Options,
    stop: Arc<AtomicBool>,
) -> Result<(), Error> {
    if links.is_empty() {
        return Err(Error::NoDrives);
    }
    if links.len() > MAX_LINKS {
        return Err(Error::TooManyLinks {
            links: links.len(),
            max: MAX_LINKS,
        });
    }
    // The points of every drive, for the metric families and the MQTT side.
    let mut infos = Vec::new();
    let mut all_points = Vec::new();
    for (li, l) in links.iter().enumerate() {
        for d in &l.drives {
            let pts = link::points_of(d, l.kind)?;
            all_points.extend(pts.iter().cloned());
            infos.push(mqtt::DriveInfo {
                name: d.name.clone(),
                drive: d.drive,
                slave: d.slave,
                kind: l.kind,
                link: li,
                points: pts,
                draft: d.draft,
            });
            if let Some(note) = drivemap_live::draft::read_note(d.drive) {
                let writes = match drivemap_live::draft::check_write(d.drive, d.draft) {
                    Ok(_) => "its commands are written through it (--draft)",
                    Err(_) => "no command is written through it (give --draft to allow it)",
                };
                eprintln!("bridge: {}: {note}; {writes}", d.name);
            }
        }
    }
    let metrics = Arc::new(metrics::Metrics::new(&all_points));
    let board = Arc::new(command::Board::new(infos.len(), options.deadline));
    drop(all_points);
    let tls = match &options.mqtt {
        Some(m) => {
            let (secure, _, _) = mqtt::parse_url(&m.url)?;
            match (&m.ca, secure) {
                (Some(ca), true) => Some(mqtt::tls_config(ca)?),
                (None, true) => return Err(Error::NoCa { url: m.url.clone() }),
                (Some(_), false) => return Err(Error::CaWithoutTls { url: m.url.clone() }),
                (None, false) => None,
            }
        }
        None => None,
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .max_blocking_threads(links.len() + 4)
        .enable_all()
        .build()
        .map_err(Error::Runtime)?;
    runtime.block_on(async move {
        let listener = match options.metrics {
            Some(addr) => {
                let l = metrics::bind(addr).await?;
                eprintln!(
                    "bridge: metrics at http://{}/metrics",
                    l.local_addr().map(|a| a.to_string()).unwrap_or_default()
                );
                Some(l)
            }
            None => None,
        };
        let server = listener
            .map(|l| tokio::spawn(metrics::serve(l, Arc::clone(&metrics), Arc::clone(&stop))));
        let (tx, rx) = tokio::sync::mpsc::channel(UPDATE_QUEUE);
        let updates = options.mqtt.as_ref().map(|_| tx);
        let mut republish = Vec::new();
        let mut tasks = Vec::new();
        let mut servers = Vec::new();
        let mut first = 0;
        for l in links {
            let again = Arc::new(AtomicBool::new(false));
            republish.push(Arc::clone(&again));
            let n = l.drives.len();
            if l.poll {
                eprintln!(
                    "bridge: polling {n} drive(s) on {} every {} ms",
                    l.name,
                    options.period.as_millis()
                );
            }
            let proxy = match &l.proxy {
                Some(o) => {
                    let listener =
                        tokio::net::TcpListener::bind(o.listen)
                            .await
                            .map_err(|source| Error::Proxy {
                                addr: o.listen,
                                source,
                            })?;
                    let queue = Arc::new(proxy::Queue::new(Arc::clone(&board)));
                    let slaves = l.drives.iter().map(|d| d.slave).collect();
                    eprintln!(
                        "bridge: serving Modbus TCP masters on {} for {n} drive(s) on {}",
                        listener.local_addr().map_or(o.listen, |a| a),
                        l.name
                    );
                    servers.push(tokio::spawn(proxy::serve(
                        listener,
                        Arc::clone(&queue),
                        slaves,
                        o.clone(),
                        Arc::clone(&stop),
                    )));
                    Some(proxy::LineSide::new(o.clone(), queue, Arc::clone(&metrics)))
                }
                None => None,
            };
            let (m, u, s, p, b) = (
                Arc::clone(&metrics),
                updates.clone(),
                Arc::clone(&stop),
                options.period,
                Arc::clone(&board),
            );
            tasks.push(tokio::task::spawn_blocking(move || {
                link::run(l, first, p, m, u, b, s, again, proxy)
            }));
            first += n;
        }
        drop(updates);
        let mqtt_stop = Arc::new(AtomicBool::new(false));
        let mqtt_task = options.mqtt.map(|m| {
            tokio::spawn(mqtt::run(
                m,
                infos,
                rx,
                Arc::clone(&board),
                Arc::clone(&metrics),
                Arc::clone(&mqtt_stop),
                republish,
                tls,
            ))
        });
        let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
            .map_err(Error::Signal)?;
        loop {
            tokio::select! {
                _ = term.recv() => break,
                _ = tokio::signal::ctrl_c() => break,
                _ = tokio::time::sleep(Duration::from_millis(100)) => {
                    if stop.load(Ordering::Relaxed) { break; }
                }
            }
        }
        eprintln!("bridge: stopping after the cycle in flight");
        stop.store(true, Ordering::Relaxed);
        for t in tasks {
            let _ = t.await;
        }
        mqtt_stop.store(true, Ordering::Relaxed);
        if let Some(t) = mqtt_task {
            let _ = tokio::time::timeout(Duration::from_secs(5), t).await;
        }
        if let Some(s) = server {
            let _ = tokio::time::timeout(Duration::from_secs(1), s).await;
        }
        for s in servers {
            let _ = tokio::time::timeout(Duration::from_secs(1), s).await;
        }
        eprintln!("bridge: stopped");
        Ok::<(), Error>(())
    })?;
    runtime.shutdown_timeout(Duration::from_secs(1));
    Ok(())
}
