//! The Prometheus side: one registry of metric families (drive values and the bridge's own
//! health), updated by the link tasks and encoded on each scrape of `/metrics` in the
//! OpenMetrics text format (`prometheus-client`), served by a small HTTP/1 server (hyper).
//!
//! A scrape encodes what the families hold at that moment: it never waits for a poll, and a
//! slow scraper only holds its own connection (at most [`MAX_CONNECTIONS`] are served at once,
//! each with a header deadline).

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use http_body_util::Full;
use hyper::body::Bytes;
use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper::{Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use prometheus_client::encoding::text::encode;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::Histogram;
use prometheus_client::registry::{Registry, Unit};
use tokio::net::TcpListener;
use tokio::sync::Semaphore;

use crate::points::{Meaning, Point};

/// Label pairs, in the order given.
pub type Labels = Vec<(String, String)>;
/// A gauge family holding floating-point values.
pub type Gauges = Family<Labels, Gauge<f64, AtomicU64>>;
/// A counter family.
pub type Counters = Family<Labels, Counter>;
/// A histogram family (command latencies).
pub type Histograms = Family<Labels, Histogram, fn() -> Histogram>;

/// The buckets of command latencies (seconds): 5 ms to 20 s.
fn latency_histogram() -> Histogram {
    Histogram::new([
        0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 20.0,
    ])
}

/// Scrapes served at once; more wait for a free place.
pub const MAX_CONNECTIONS: usize = 16;

/// The metric families.
pub struct Metrics {
    registry: Registry,
    /// Drive value families by name (`drivemap_output_frequency` + unit suffix).
    values: BTreeMap<(String, String), Gauges>,
    /// Wall time of the link's last cycle.
    pub cycle_seconds: Gauges,
    /// The bus-time model of the requests of the link's last cycle.
    pub model_seconds: Gauges,
    /// Requests sent per link.
    pub requests: Counters,
    /// Poll cycles per link.
    pub cycles: Counters,
    /// Errors by link, drive and kind.
    pub errors: Counters,
    /// Unix time of the last cycle in which the drive answered.
    pub last_success: Gauges,
    /// 1 while the drive answered its last cycle.
    pub up: Gauges,
    /// MQTT messages not queued because the broker side was behind.
    pub mqtt_dropped: Counters,
    /// Commands by drive and outcome.
    pub commands: Counters,
    /// Time from a command's arrival to its write's reply, by drive and command.
    pub command_latency: Histograms,
    /// The poll period asked for each link (compare with the bus-time model).
    pub period_seconds: Gauges,
    /// The share of the line the link's reads take at their periods (bus-time model).
    pub line_load: Gauges,
    /// Requests of proxied masters, by master address.
    pub proxy_requests: Counters,
    /// Requests of proxied masters refused, by reason.
    pub proxy_refusals: Counters,
}

fn gauges(registry: &mut Registry, name: &str, help: &str, unit: Option<Unit>) -> Gauges {
    let f = Gauges::default();
    match unit {
        Some(u) => registry.register_with_unit(name, help, u, f.clone()),
        None => registry.register(name, help, f.clone()),
    }
    f
}

fn counters(registry: &mut Registry, name: &str, help: &str) -> Counters {
    let f = Counters::default();
    registry.register(name, help, f.clone());
    f
}

impl Metrics {
    /// The families of the bridge's health, and one per distinct value metric of `points`.
    pub fn new<'a, 'd: 'a>(points: impl IntoIterator<Item = &'a Point<'d>>) -> Metrics {
        let mut registry = Registry::default();
        let mut values = BTreeMap::new();
        for p in points {
            let suffix = p.metric_suffix();
            let key = (p.metric(), suffix.clone());
            if values.contains_key(&key) {
                continue;
            }
            let help = match (&p.meaning, p.role) {
                (Meaning::Number(_) | Meaning::Word, Some(r)) => {
                    format!("role {} of the drive's map", r.id())
                }
                (Meaning::Number(_) | Meaning::Word, None) => {
                    "a register without a role, by its map (labels register, param)".into()
                }
                (Meaning::Code(_) | Meaning::Bits(_), _) => {
                    "an enumeration register's code and meaning (value 1; labels code, value, meaning)".into()
                }
                (Meaning::Field { field, .. }, Some(r)) if field.width == 1 => {
                    format!("status role {} of the drive's map (0/1)", r.id())
                }
                (Meaning::Field { field, .. }, None) if field.width == 1 => {
                    "a one-bit field of a bit-field register (0/1)".into()
                }
                (Meaning::Field { .. }, _) => {
                    "a multi-bit field's code and meaning (value 1; labels code, meaning)".into()
                }
                (Meaning::Bit, Some(r)) => {
                    format!("role {} of the drive's map, a coil or discrete input (0/1)", r.id())
                }
                (Meaning::Bit, None) => format!("a {} without a role (0/1)", p.table().item()),
                // Not bridged: `points::polled` leaves strings out.
                (Meaning::Text(_), _) => "a string register (not bridged)".into(),
            };
            let unit = (!suffix.is_empty()).then(|| match suffix.as_str() {
                "seconds" => Unit::Seconds,
                "volts" => Unit::Volts,
                "amperes" => Unit::Amperes,
                "celsius" => Unit::Celsius,
                "ratio" => Unit::Other("ratio".into()),
                "joules" => Unit::Joules,
                other => Unit::Other(other.to_owned()),
            });
            values.insert(key, gauges(&mut registry, &p.metric(), &help, unit));
        }
        let cycle_seconds = gauges(
            &mut registry,
            "drivemap_bridge_cycle_duration",
            "wall time of the link's last poll cycle (every drive on it)",
            Some(Unit::Seconds),
        );
        let model_seconds = gauges(
            &mut registry,
            "drivemap_bridge_cycle_bus_model",
            "the bus-time model of the requests of the link's last cycle (the planner's)",
            Some(Unit::Seconds),
        );
        let requests = counters(&mut registry, "drivemap_bridge_requests", "requests sent");
        let cycles = counters(&mut registry, "drivemap_bridge_cycles", "poll cycles");
        let errors = counters(
            &mut registry,
            "drivemap_bridge_errors",
            "errors by kind: timeout, exception, io, refused, value, connect",
        );
        let last_success = gauges(
            &mut registry,
            "drivemap_bridge_last_success_timestamp",
            "Unix time of the last cycle in which the drive answered",
            Some(Unit::Seconds),
        );
        let up = gauges(
            &mut registry,
            "drivemap_up",
            "1 while the drive answered its last poll cycle",
            None,
        );
        let mqtt_dropped = counters(
            &mut registry,
            "drivemap_bridge_mqtt_dropped",
            "MQTT state messages not queued because the broker side was behind (sent later)",
        );
        let commands = counters(
            &mut registry,
            "drivemap_bridge_commands",
            "commands received over MQTT by outcome (done; refused, expired or superseded: nothing written; failed: the write failed on the line)",
        );
        let command_latency =
            Histograms::new_with_constructor(latency_histogram as fn() -> Histogram);
        registry.register_with_unit(
            "drivemap_bridge_command_latency",
            "from a command's arrival over MQTT to the reply to its last write, by drive and command",
            Unit::Seconds,
            command_latency.clone(),
        );
        let period_seconds = gauges(
            &mut registry,
            "drivemap_bridge_period",
            "the poll period asked for the link; above the bus-time model the cycles run back to back",
            Some(Unit::Seconds),
        );
        let line_load = gauges(
            &mut registry,
            "drivemap_bridge_line_load",
            "the share of the line the link's reads take at their periods by the bus-time model; above 1 the periods cannot be met",
            Some(Unit::Other("ratio".into())),
        );
        let proxy_requests = counters(
            &mut registry,
            "drivemap_proxy_requests",
            "requests of masters through the proxy, by master address",
        );
        let proxy_refusals = counters(
            &mut registry,
            "drivemap_proxy_refusals",
            "requests of masters refused by the proxy (answered with an exception), by reason",
        );
        Metrics {
            registry,
            values,
            cycle_seconds,
            model_seconds,
            requests,
            cycles,
            errors,
            last_success,
            up,
            mqtt_dropped,
            commands,
            command_latency,
            period_seconds,
            line_load,
            proxy_requests,
            proxy_refusals,
        }
    }

    /// The family a point's values go to.
    pub fn family(&self, p: &Point) -> &Gauges {
        &self.values[&(p.metric(), p.metric_suffix())]
    }

    /// The registry in the OpenMetrics text format.
    pub fn encode(&self) -> String {
        let mut out = String::new();
        // Writing to a String cannot fail.
        let _ = encode(&mut out, &self.registry);
        out
    }
}

/// Serves `GET /metrics` on `listener` until `stop` is set.
pub async fn serve(listener: TcpListener, metrics: Arc<Metrics>, stop: Arc<AtomicBool>) {
    let places = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    loop {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let accepted = tokio::time::timeout(Duration::from_millis(200), listener.accept()).await;
        let Ok(Ok((stream, _))) = accepted else {
            continue;
        };
        let Ok(place) = Arc::clone(&places).acquire_owned().await else {
            return;
        };
        let metrics = Arc::clone(&metrics);
        tokio::spawn(async move {
            let service = service_fn(move |req: Request<hyper::body::Incoming>| {
                let metrics = Arc::clone(&metrics);
                async move { Ok::<_, std::convert::Infallible>(respond(&req, &metrics)) }
            });
            let conn = http1::Builder::new()
                .timer(TokioTimer::new())
                .header_read_timeout(Duration::from_secs(5))
                .serve_connection(TokioIo::new(stream), service);
            // A connection kept longer than a minute is closed.
            let _ = tokio::time::timeout(Duration::from_secs(60), conn).await;
            drop(place);
        });
    }
}

fn respond(req: &Request<hyper::body::Incoming>, metrics: &Metrics) -> Response<Full<Bytes>> {
    let (status, kind, body) = match (req.method().as_str(), req.uri().path()) {
        ("GET", "/metrics") => (
            StatusCode::OK,
            "application/openmetrics-text; version=1.0.0; charset=utf-8",
            metrics.encode(),
        ),
        ("GET", "/") => (
            StatusCode::OK,
            "text/plain; charset=utf-8",
            "drivemap bridge: metrics at /metrics\n".to_owned(),
        ),
        ("GET", _) => (
            StatusCode::NOT_FOUND,
            "text/plain; charset=utf-8",
            "not found: the metrics are at /metrics\n".to_owned(),
        ),
        _ => (
            StatusCode::METHOD_NOT_ALLOWED,
            "text/plain; charset=utf-8",
            "only GET\n".to_owned(),
        ),
    };
    let mut resp = Response::new(Full::new(Bytes::from(body)));
    *resp.status_mut() = status;
    if let Ok(v) = hyper::header::HeaderValue::from_str(kind) {
        resp.headers_mut().insert(hyper::header::CONTENT_TYPE, v);
    }
    resp
}

/// Binds the metrics listener (loopback unless told otherwise: the caller decides).
pub async fn bind(addr: SocketAddr) -> Result<TcpListener, crate::Error> {
    TcpListener::bind(addr)
        .await
        .map_err(|source| crate::Error::Metrics { addr, source })
}
