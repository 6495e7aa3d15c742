//! The MQTT side (MQTT 5): state topics per drive, Home Assistant MQTT discovery, and command
//! topics whose messages become intents on the [`Board`] only when `--allow-writes` names them
//! and, but for a stop, the drive's rate limit lets them through; the link carries them out
//! through the write gate or the drive trait, and every refusal is published on the drive's
//! error topic.
//!
//! A command is carried out when it is sent, never again: command topics are subscribed with
//! MQTT 5's "do not send retained messages" and "retain as published", and every message that
//! arrives with the retain flag (one published retained while the bridge is connected) is
//! refused. `run`, `stop` and `fault_reset` take the payload `PRESS` only (an
//! `OFF`, a `0` or the empty payload that clears a retained message start nothing). The
//! broker is told the largest packet the bridge takes ([`MAX_PACKET`]): MQTT 5 brokers drop a
//! larger message for this client instead of sending it, so an oversized message cannot make
//! the connection fail over and over.
//!
//! Topics (`<t>` is `--mqtt-topic`, default `drivemap`; `<name>` the drive's name):
//! - `<t>/bridge/availability`: `online` / `offline` (the connection's last will);
//! - `<t>/<name>/availability`: `online` while the drive answers, else `offline`;
//! - `<t>/<name>/<object>`: a value (retained): a number in the map's unit, a code's
//!   meaning, `1`/`0` for a one-bit field;
//! - `<t>/<name>/set/<register>`: write a register (payload: the value as `drivemap write`
//!   takes it);
//! - `<t>/<name>/command/<run|stop|fault_reset>`: the drive trait's commands, payload `PRESS`;
//!   `<t>/<name>/command/reference`: the frequency reference in Hz;
//! - `<t>/<name>/error`: a refused, expired, superseded or failed command, JSON `{"topic",
//!   "payload", "error", "outcome", "written": false}` (topic and payload shortened).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::Refused;
use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::core::plan::{RegisterPlan, ValueShape};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::roles::Role;
use rumqttc::v5::mqttbytes::QoS;
use rumqttc::v5::mqttbytes::v5::{Filter, LastWill, Packet, RetainForwardRule};
use rumqttc::v5::{AsyncClient, ConnectionError, Event, EventLoop, MqttOptions};
use serde_json::{Value as Json, json};
use tokio::sync::mpsc::Receiver;

use crate::command::Board;
use crate::link::{Action, Command, Update};
use crate::log::{Limiter, quote, shorten};
use crate::metrics::Metrics;
use crate::points::home_assistant::{device_class, unit};
use crate::points::{self, Meaning, Point, slug};

/// How to reach the broker and what to publish.
#[derive(Debug, Clone)]
pub struct Options {
    /// `mqtt://host[:1883]` or `mqtts://host[:8883]` (TLS).
    pub url: String,
    /// CA certificate (PEM) the broker's certificate must chain to, for `mqtts://`.
    pub ca: Option<PathBuf>,
    /// User name and password (from the environment or a file, never the command line).
    pub credentials: Option<(String, String)>,
    /// The client id.
    pub client_id: String,
    /// Root of the state and command topics.
    pub topic: String,
    /// Home Assistant's discovery prefix.
    pub discovery_prefix: String,
    /// What commands may write: register ids, parameter numbers or printed names, role ids
    /// (`frequency_reference`, `run`, `fault_reset`), `stop`.
    pub allow: Vec<String>,
    /// Runs, references, sets and fault resets per second per drive (a burst of as many is
    /// let through at once); stops are never limited.
    pub rate: f64,
}

/// The largest MQTT packet the bridge takes (told to the broker when connecting): commands
/// are short, and a larger message is dropped by an MQTT 5 broker for this client.
pub const MAX_PACKET: u32 = 64 * 1024;

/// A drive as the MQTT side knows it.
pub struct DriveInfo {
    /// Its name (topics).
    pub name: String,
    /// Its map.
    pub drive: &'static Map,
    /// Slave address.
    pub slave: u8,
    /// Its link's kind.
    pub kind: TransportKind,
    /// The link's index, for its command queue.
    pub link: usize,
    /// Its points.
    pub points: Vec<Point<'static>>,
    /// Whether writes may go through its map when it is a draft.
    pub draft: drivemap_live::draft::DraftWrites,
}

/// Splits `mqtt[s]://host[:port]`.
pub fn parse_url(url: &str) -> Result<(bool, String, u16), crate::Error> {
    let (tls, rest) = if let Some(r) = url.strip_prefix("mqtts://") {
        (true, r)
    } else if let Some(r) = url.strip_prefix("mqtt://") {
        (false, r)
    } else {
        return Err(crate::Error::MqttScheme {
            url: url.to_owned(),
        });
    };
    let rest = rest.trim_end_matches('/');
    if let Some((_, host)) = rest.rsplit_once('@') {
        // Never printed: the URL is named without what stood before the `@`.
        let scheme = if tls { "mqtts" } else { "mqtt" };
        return Err(crate::Error::MqttUserinfo {
            url: format!("{scheme}://…@{host}"),
        });
    }
    let (host, port) = match rest.rsplit_once(':') {
        Some((h, p)) => (
            h,
            p.parse::<u16>().map_err(|_| crate::Error::MqttPort {
                url: url.to_owned(),
                port: p.to_owned(),
            })?,
        ),
        None => (rest, if tls { 8883 } else { 1883 }),
    };
    if host.is_empty() {
        return Err(crate::Error::MqttHost {
            url: url.to_owned(),
        });
    }
    Ok((tls, host.trim_matches(['[', ']']).to_owned(), port))
}

/// Checks a topic root or discovery prefix given on the command line (`option` names it): one
/// or more topic levels to publish under and subscribe below, so no wildcard (`+`, `#`), no
/// empty level, no NUL, not a broker's `$` topic, at most 512 bytes.
pub fn check_topic_root(option: &'static str, root: &str) -> Result<(), crate::Error> {
    let why = if root.is_empty() {
        Some("it is empty")
    } else if root.len() > 512 {
        Some("it is longer than 512 bytes")
    } else if root.contains(['+', '#']) {
        Some("MQTT wildcards (+, #) cannot be published to")
    } else if root.starts_with('$') {
        Some("topics starting with $ are the broker's")
    } else if root.contains('\0') {
        Some("it contains a NUL character")
    } else if root.split('/').any(str::is_empty) {
        Some("it has an empty level (a leading, trailing or double /)")
    } else {
        None
    };
    match why {
        Some(why) => Err(crate::Error::TopicRoot {
            option,
            root: quote(root),
            why,
        }),
        None => Ok(()),
    }
}

/// Whether `allow` lets `action` be written on `info` (`register` resolved for a set).
pub fn allowed(info: &DriveInfo, allow: &[String], action: &Action) -> Result<(), Refused> {
    let has = |name: &str| allow.iter().any(|a| a.eq_ignore_ascii_case(name));
    let ok = match action {
        Action::Set { register } => {
            let r = points::find(info.drive, register)?;
            has(r.id())
                || r.param().is_some_and(has)
                || has(r.name())
                || points::register_role(info.drive, r, info.kind)
                    .is_some_and(|role| has(role.id()))
        }
        Action::Run => has("run"),
        Action::Stop => has("stop") || has("run"),
        Action::Reference => has("frequency_reference") || has("reference"),
        Action::FaultReset => has("fault_reset"),
    };
    if ok {
        Ok(())
    } else {
        Err(Refused::NotAllowed {
            what: match action {
                Action::Set { register } => format!("`{register}`"),
                Action::Run => "`run`".into(),
                Action::Stop => "`stop` (or `run`)".into(),
                Action::Reference => "`frequency_reference`".into(),
                Action::FaultReset => "`fault_reset`".into(),
            },
        })
    }
}

/// Parses a command topic `<t>/<name>/set/<register>` or `<t>/<name>/command/<what>`.
pub fn parse_command(topic_root: &str, topic: &str) -> Option<(String, Action)> {
    let rest = topic.strip_prefix(topic_root)?.strip_prefix('/')?;
    let mut parts = rest.split('/');
    let name = parts.next()?.to_owned();
    let kind = parts.next()?;
    let what = parts.next()?;
    if parts.next().is_some() {
        return None;
    }
    let action = match (kind, what) {
        ("set", r) if !r.is_empty() => Action::Set {
            register: r.to_owned(),
        },
        ("command", "run") => Action::Run,
        ("command", "stop") => Action::Stop,
        ("command", "reference") => Action::Reference,
        ("command", "fault_reset") => Action::FaultReset,
        _ => return None,
    };
    Some((name, action))
}

/// A token bucket: `rate` per second, as many at once.
pub struct Bucket {
    tokens: f64,
    at: Instant,
}

impl Bucket {
    /// A full bucket for `rate` per second.
    pub fn new(rate: f64) -> Bucket {
        Bucket {
            tokens: rate.max(1.0),
            at: Instant::now(),
        }
    }

    /// Takes a token if there is one.
    pub fn take(&mut self, rate: f64) -> bool {
        let now = Instant::now();
        let cap = rate.max(1.0);
        self.tokens = (self.tokens + now.duration_since(self.at).as_secs_f64() * rate).min(cap);
        self.at = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

fn device(info: &DriveInfo) -> Json {
    let meta = info.drive.meta();
    json!({
        "identifiers": [format!("drivemap_{}", slug(&info.name))],
        "name": info.name,
        "manufacturer": meta.vendor,
        "model": meta.models.first().cloned().unwrap_or_else(|| meta.id.clone()),
        "sw_version": format!("drivemap map {}", meta.id),
    })
}

fn availability(root: &str, info: &DriveInfo) -> Json {
    json!([
        {"topic": format!("{root}/bridge/availability")},
        {"topic": format!("{root}/{}/availability", info.name)},
    ])
}

/// The Home Assistant discovery messages of a drive: `(topic, payload)`.
pub fn discovery(options: &Options, info: &DriveInfo) -> Vec<(String, Json)> {
    let root = &options.topic;
    let node = format!("drivemap_{}", slug(&info.name));
    let mut out = Vec::new();
    let base = |object: &str, name: &str| {
        json!({
            "name": name,
            "unique_id": format!("{node}_{object}"),
            "object_id": format!("{node}_{object}"),
            "availability": availability(root, info),
            "availability_mode": "all",
            "device": device(info),
        })
    };
    let writes = drivemap_live::draft::check_write(info.drive, info.draft).is_ok();
    let allow_set = |r: RegisterRef<'_>| {
        writes
            && r.writable()
            && !r.broadcast_only()
            && r.plan().transports.contains(info.kind)
            && allowed(
                info,
                &options.allow,
                &Action::Set {
                    register: r.id().to_owned(),
                },
            )
            .is_ok()
    };
    for p in &info.points {
        let r = p.register;
        let state = format!("{root}/{}/{}", info.name, p.object());
        let mut c = base(&p.object(), &p.name());
        c["state_topic"] = json!(state);
        let writable = p.field().is_none() && allow_set(r);
        let component = match &p.meaning {
            Meaning::Number(_) | Meaning::Word => {
                if !p.unit().is_empty() {
                    c["unit_of_measurement"] = json!(unit(p.unit()));
                }
                if let Some(dc) = device_class(p.unit()) {
                    c["device_class"] = json!(dc);
                }
                if writable {
                    c["command_topic"] = json!(format!("{root}/{}/set/{}", info.name, p.id()));
                    c["mode"] = json!("box");
                    let bounds = r.input_bounds();
                    c["min"] = json!(bounds.min);
                    c["max"] = json!(bounds.max);
                    c["step"] = json!(bounds.step);
                    "number"
                } else {
                    c["state_class"] = json!("measurement");
                    "sensor"
                }
            }
            Meaning::Code(_) => {
                let options = select_options(p.plan);
                if writable && !options.is_empty() {
                    c["command_topic"] = json!(format!("{root}/{}/set/{}", info.name, p.id()));
                    c["options"] = json!(options);
                    "select"
                } else {
                    c["device_class"] = json!("enum");
                    if !options.is_empty() {
                        c["options"] = json!(options);
                    }
                    "sensor"
                }
            }
            Meaning::Field { field, .. } if field.width == 1 => {
                c["payload_on"] = json!("1");
                c["payload_off"] = json!("0");
                match p.role {
                    Some(Role::Fault | Role::Alarm) => c["device_class"] = json!("problem"),
                    Some(Role::Running) => c["device_class"] = json!("running"),
                    _ => {}
                }
                "binary_sensor"
            }
            // Text is not bridged (`points::polled` leaves strings out); a sensor if it were.
            Meaning::Field { .. } | Meaning::Bits(_) | Meaning::Text(_) => "sensor",
            Meaning::Bit => {
                c["payload_on"] = json!("1");
                c["payload_off"] = json!("0");
                match p.role {
                    Some(Role::Fault | Role::Alarm) => c["device_class"] = json!("problem"),
                    Some(Role::Running) => c["device_class"] = json!("running"),
                    _ => {}
                }
                if writable {
                    // A coil the bridge may set: a switch, its state the coil read back.
                    c["command_topic"] = json!(format!("{root}/{}/set/{}", info.name, p.id()));
                    c["state_on"] = json!("1");
                    c["state_off"] = json!("0");
                    "switch"
                } else {
                    "binary_sensor"
                }
            }
        };
        out.push((
            format!(
                "{}/{component}/{node}/{}/config",
                options.discovery_prefix,
                p.object()
            ),
            c,
        ));
    }
    // Writable registers allowed but not polled: numbers and selects without a state topic.
    for r in info.drive.registers() {
        if !allow_set(r) || info.points.iter().any(|p| p.register == r) {
            continue;
        }
        let plan = r.plan();
        if !plan.transports.contains(info.kind) {
            continue;
        }
        let object = slug(r.id());
        let mut c = base(&object, r.name());
        c["command_topic"] = json!(format!("{root}/{}/set/{}", info.name, r.id()));
        let component = match plan.conversion.shape() {
            // A coil: a switch whose state is what it was told (the coil is not polled).
            _ if plan.info.table.is_bits() => {
                c["payload_on"] = json!("1");
                c["payload_off"] = json!("0");
                c["optimistic"] = json!(true);
                "switch"
            }
            ValueShape::Codes(_) => {
                c["options"] = json!(select_options(plan));
                c["optimistic"] = json!(true);
                "select"
            }
            // Text is read-only: nothing to command.
            ValueShape::Bits { .. } | ValueShape::Text { .. } => continue,
            ValueShape::Word { .. } | ValueShape::Number => {
                if !plan.unit.is_empty() {
                    c["unit_of_measurement"] = json!(unit(plan.unit));
                }
                if let Some(dc) = device_class(plan.unit) {
                    c["device_class"] = json!(dc);
                }
                let bounds = r.input_bounds();
                c["min"] = json!(bounds.min);
                c["max"] = json!(bounds.max);
                c["step"] = json!(bounds.step);
                c["mode"] = json!("box");
                c["optimistic"] = json!(true);
                "number"
            }
        };
        out.push((
            format!(
                "{}/{component}/{node}/{object}/config",
                options.discovery_prefix
            ),
            c,
        ));
    }
    // The drive trait's commands: buttons, and the reference as a number.
    let roles = info.drive.plan().roles;
    let role_on_link = |role: Role| roles.of(role).any(|p| p.transports.contains(info.kind));
    for (what, role, label) in [
        ("run", Role::Run, "Run"),
        ("stop", Role::Run, "Stop"),
        ("fault_reset", Role::FaultReset, "Fault reset"),
    ] {
        let action = match what {
            "run" => Action::Run,
            "stop" => Action::Stop,
            _ => Action::FaultReset,
        };
        let has_role = role_on_link(role) || (role == Role::Run && role_on_link(Role::RunForward));
        if !writes || !has_role || allowed(info, &options.allow, &action).is_err() {
            continue;
        }
        let object = format!("command_{what}");
        let mut c = base(&object, label);
        c["command_topic"] = json!(format!("{root}/{}/command/{what}", info.name));
        c["payload_press"] = json!("PRESS");
        out.push((
            format!("{}/button/{node}/{object}/config", options.discovery_prefix),
            c,
        ));
    }
    if writes
        && role_on_link(Role::FrequencyReference)
        && allowed(info, &options.allow, &Action::Reference).is_ok()
    {
        let object = "command_reference";
        let mut c = base(object, "Frequency reference");
        c["command_topic"] = json!(format!("{root}/{}/command/reference", info.name));
        c["unit_of_measurement"] = json!("Hz");
        c["device_class"] = json!("frequency");
        c["mode"] = json!("box");
        c["optimistic"] = json!(true);
        if let Some(r) = roles
            .of(Role::FrequencyReference)
            .find_map(|p| p.target.row())
            .and_then(|row| info.drive.register_of_row(usize::from(row)))
        {
            let bounds = r.input_bounds();
            c["min"] = json!(bounds.min);
            c["max"] = json!(bounds.max);
            c["step"] = json!(bounds.step);
        }
        out.push((
            format!("{}/number/{node}/{object}/config", options.discovery_prefix),
            c,
        ));
    }
    out
}

/// The options of a select: an enumeration's codes as the bridge publishes them.
fn select_options(plan: &RegisterPlan) -> Vec<String> {
    match plan.conversion.shape() {
        ValueShape::Codes(values) => values
            .iter()
            .map(|v| crate::link::option_text(v.code, Some(v.id), Some(v.name)))
            .collect(),
        ValueShape::Word { .. }
        | ValueShape::Number
        | ValueShape::Bits { .. }
        | ValueShape::Text { .. } => Vec::new(),
    }
}

/// Connects and serves until `stop`: publishes discovery and availability on each connection,
/// state updates as they come, and offers allowed commands to the [`Board`].
// The task's inputs, each owned by it for its whole life (options, drives, channels,
// shared flags and counters, TLS); `lib.rs` builds them once and hands them over.
#[allow(clippy::too_many_arguments)]
pub async fn run(
    options: Options,
    drives: Vec<DriveInfo>,
    mut updates: Receiver<Update>,
    board: Arc<Board>,
    metrics: Arc<Metrics>,
    stop: Arc<AtomicBool>,
    republish: Vec<Arc<AtomicBool>>,
    tls: Option<rumqttc::TlsConfiguration>,
) {
    let Ok((secure, host, port)) = parse_url(&options.url) else {
        return;
    };
    let mut mo = MqttOptions::new(options.client_id.clone(), host, port);
    mo.set_keep_alive(Duration::from_secs(15));
    mo.set_max_packet_size(Some(MAX_PACKET));
    let bridge_availability = format!("{}/bridge/availability", options.topic);
    mo.set_last_will(LastWill::new(
        &bridge_availability,
        "offline",
        QoS::AtLeastOnce,
        true,
        None,
    ));
    if let Some((user, password)) = &options.credentials {
        mo.set_credentials(user.clone(), password.clone());
    }
    if secure && let Some(t) = tls {
        mo.set_transport(rumqttc::Transport::Tls(t));
    }
    let (client, mut eventloop): (AsyncClient, EventLoop) = AsyncClient::new(mo, 1024);
    let by_name: BTreeMap<String, usize> = drives
        .iter()
        .enumerate()
        .map(|(i, d)| (d.name.clone(), i))
        .collect();
    let mut buckets: Vec<Bucket> = drives.iter().map(|_| Bucket::new(options.rate)).collect();
    let mut log = Limiter::default();
    let mut refused_logged = false;
    let mut connected = false;
    let mut wait = Duration::from_millis(500);
    loop {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        tokio::select! {
            event = eventloop.poll() => match event {
                Ok(Event::Incoming(Packet::ConnAck(_))) => {
                    eprintln!("bridge: MQTT connected to {}", options.url);
                    refused_logged = false;
                    wait = Duration::from_millis(500);
                    connected = true;
                    // The subscriptions, availability and discovery wait for room in the
                    // client's queue (never dropped); then every value again (the broker may
                    // have lost them).
                    let all: Vec<(String, Json)> = drives.iter().flat_map(|d| discovery(&options, d)).collect();
                    let client = client.clone();
                    let root = options.topic.clone();
                    let online = bridge_availability.clone();
                    tokio::spawn(async move {
                        // Retained messages are never sent for the command topics.
                        let filters = [format!("{root}/+/set/+"), format!("{root}/+/command/+")]
                            .map(|f| {
                                let mut f = Filter::new(f, QoS::AtLeastOnce);
                                f.retain_forward_rule = RetainForwardRule::Never;
                                // A retained message published while connected keeps its flag
                                // (retain as published), so it is refused too.
                                f.preserve_retain = true;
                                f
                            });
                        if client.subscribe_many(filters).await.is_err() {
                            return;
                        }
                        if client.publish(online, QoS::AtLeastOnce, true, "online").await.is_err() {
                            return;
                        }
                        for (topic, payload) in all {
                            if client.publish(topic, QoS::AtLeastOnce, true, payload.to_string()).await.is_err() {
                                return;
                            }
                        }
                    });
                    for r in &republish {
                        r.store(true, Ordering::Relaxed);
                    }
                }
                Ok(Event::Incoming(Packet::Publish(p))) => {
                    let topic = String::from_utf8_lossy(&p.topic).into_owned();
                    let payload = String::from_utf8_lossy(&p.payload).into_owned();
                    let Some((name, action)) = parse_command(&options.topic, &topic) else { continue };
                    let Some(&index) = by_name.get(&name) else { continue };
                    let info = &drives[index];
                    let command = Command { drive: index, action: action.clone(), topic, payload };
                    match accept(info, &options, &mut buckets[index], &board, &command, p.retain) {
                        Err(why) => {
                            refuse(&client, &options.topic, info, &command, &why.to_string(), "refused", &metrics, &mut log);
                        }
                        Ok(key) => {
                            let gone = board.offer(command.clone(), &key, Instant::now());
                            for g in gone.0 {
                                let why = crate::Refused::Superseded { by: command.action.name() };
                                refuse(&client, &options.topic, info, &g.command, &why.to_string(), "superseded", &metrics, &mut log);
                            }
                        }
                    }
                }
                Ok(_) => {}
                Err(e) => {
                    connected = false;
                    let text = match &e {
                        ConnectionError::ConnectionRefused(code) => refused_why(*code),
                        other => other.to_string(),
                    };
                    if !refused_logged {
                        eprintln!("bridge: MQTT {}: {text}; trying again", options.url);
                        refused_logged = true;
                    }
                    let mut l = vec![("link".to_owned(), "mqtt".to_owned())];
                    l.push(("kind".into(), "connect".into()));
                    metrics.errors.get_or_create(&l).inc();
                    tokio::time::sleep(wait).await;
                    wait = (wait * 2).min(Duration::from_secs(10));
                }
            },
            update = updates.recv() => match update {
                None => break,
                Some(Update::State { .. }) if !connected => {
                    // Not queued while the broker is away: every value is sent again on
                    // connecting.
                    metrics.mqtt_dropped.get_or_create(&Vec::new()).inc();
                }
                Some(Update::State { drive, values }) => {
                    let info = &drives[drive];
                    for (pi, text) in values {
                        let topic = format!("{}/{}/{}", options.topic, info.name, info.points[pi].object());
                        if client.try_publish(topic, QoS::AtMostOnce, true, text).is_err() {
                            metrics.mqtt_dropped.get_or_create(&Vec::new()).inc();
                        }
                    }
                }
                Some(Update::Availability { drive, online }) => {
                    let info = &drives[drive];
                    let topic = format!("{}/{}/availability", options.topic, info.name);
                    let _ = client.try_publish(topic, QoS::AtLeastOnce, true, if online { "online" } else { "offline" });
                }
                Some(Update::Outcome { command, result, outcome }) => {
                    if let Err(why) = result {
                        publish_error(&client, &options.topic, &drives[command.drive], &command, &why.to_string(), outcome);
                    }
                }
            },
            _ = tokio::time::sleep(Duration::from_millis(200)) => {}
        }
    }
    // Going away: the drives the links marked offline, the bridge's availability, then a
    // clean disconnect (bounded).
    while let Ok(update) = updates.try_recv() {
        if let Update::Availability { drive, online } = update {
            let topic = format!("{}/{}/availability", options.topic, drives[drive].name);
            let _ = client.try_publish(
                topic,
                QoS::AtLeastOnce,
                true,
                if online { "online" } else { "offline" },
            );
        }
    }
    let _ = client.try_publish(&bridge_availability, QoS::AtLeastOnce, true, "offline");
    let _ = client.try_disconnect();
    let _ = tokio::time::timeout(Duration::from_secs(2), async {
        while let Ok(e) = eventloop.poll().await {
            if matches!(e, Event::Outgoing(rumqttc::Outgoing::Disconnect)) {
                break;
            }
        }
    })
    .await;
}

/// Why the broker refused the connection, with what to check.
fn refused_why(code: rumqttc::v5::mqttbytes::v5::ConnectReturnCode) -> String {
    use rumqttc::v5::mqttbytes::v5::ConnectReturnCode as C;
    let check = match code {
        C::BadUserNamePassword | C::NotAuthorized | C::BadAuthenticationMethod => {
            "check the user name and password"
        }
        C::RefusedProtocolVersion | C::UnsupportedProtocolVersion => {
            "the bridge speaks MQTT 5 (command topics without retained messages); use a broker that does (mosquitto 1.6 or later)"
        }
        C::ClientIdentifierNotValid | C::BadClientId => "check --mqtt-client-id",
        _ => "see the broker's log",
    };
    format!("the broker refused the connection: {code:?} ({check})")
}

/// Whether a command message is taken as an intent: not retained, allowed, a press for a
/// button, within the rate (but a stop), its drive answering (but for a stop). Returns the
/// key it is kept under (the register's id for a set).
pub fn accept(
    info: &DriveInfo,
    options: &Options,
    bucket: &mut Bucket,
    board: &Board,
    command: &Command,
    retained: bool,
) -> Result<String, crate::Refused> {
    if retained {
        return Err(crate::Refused::Retained);
    }
    allowed(info, &options.allow, &command.action)?;
    if let Err(why) = drivemap_live::draft::check_write(info.drive, info.draft) {
        return Err(crate::Refused::Draft { why });
    }
    let press = match &command.action {
        Action::Run | Action::Stop | Action::FaultReset => Some(command.action.name()),
        _ => None,
    };
    if let Some(name) = press
        && command.payload.trim() != "PRESS"
    {
        return Err(crate::Refused::NotPress {
            command: name,
            payload: quote(&command.payload),
        });
    }
    if command.action == Action::Stop {
        return Ok(String::new());
    }
    if !bucket.take(options.rate) {
        return Err(crate::Refused::RateLimit {
            rate: options.rate.to_string(),
            drive: info.name.clone(),
        });
    }
    if !board.answering(command.drive) {
        return Err(crate::Refused::NotAnswering {
            drive: info.name.clone(),
        });
    }
    Ok(match &command.action {
        Action::Set { register } => points::find(info.drive, register)?.id().to_owned(),
        _ => String::new(),
    })
}

// The refusal's parts, each needed: where to publish, what, and the two counters.
#[allow(clippy::too_many_arguments)]
fn refuse(
    client: &AsyncClient,
    root: &str,
    info: &DriveInfo,
    command: &Command,
    why: &str,
    outcome: &'static str,
    metrics: &Metrics,
    log: &mut Limiter,
) {
    let (ok, held) = log.allow(Instant::now());
    if let Some(n) = held {
        eprintln!("bridge: {n} more command refusal(s) not logged");
    }
    if ok {
        eprintln!(
            "bridge: command on {} ({}) {outcome}, nothing written: {why}",
            quote(&command.topic),
            quote(&command.payload)
        );
        publish_error(client, root, info, command, why, outcome);
    }
    metrics
        .commands
        .get_or_create(&vec![
            ("name".to_owned(), info.name.clone()),
            ("outcome".to_owned(), outcome.to_owned()),
        ])
        .inc();
}

fn publish_error(
    client: &AsyncClient,
    root: &str,
    info: &DriveInfo,
    command: &Command,
    why: &str,
    outcome: &str,
) {
    let payload = json!({
        "topic": shorten(&command.topic, 256),
        "payload": shorten(&command.payload, 64),
        "error": why,
        "outcome": outcome,
        "written": false,
    });
    let _ = client.try_publish(
        format!("{root}/{}/error", info.name),
        QoS::AtLeastOnce,
        false,
        payload.to_string(),
    );
}

/// A rustls client configuration trusting only the CA certificates in `ca` (PEM).
pub fn tls_config(ca: &std::path::Path) -> Result<rumqttc::TlsConfiguration, crate::Error> {
    use rustls::pki_types::CertificateDer;
    use rustls::pki_types::pem::PemObject;
    let bad = |e: &dyn std::fmt::Display| crate::Error::Ca {
        path: ca.to_owned(),
        message: e.to_string(),
    };
    let mut roots = rustls::RootCertStore::empty();
    let certs: Vec<CertificateDer<'static>> = CertificateDer::pem_file_iter(ca)
        .map_err(|e| bad(&e))?
        .collect::<Result<_, _>>()
        .map_err(|e| bad(&e))?;
    if certs.is_empty() {
        return Err(crate::Error::NoCertificate {
            path: ca.to_owned(),
        });
    }
    for c in certs {
        roots.add(c).map_err(|e| bad(&e))?;
    }
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let config = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()?
        .with_root_certificates(roots)
        .with_no_client_auth();
    Ok(rumqttc::TlsConfiguration::Rustls(Arc::new(config)))
}

/// The register a name means on `drive`, for messages.
pub fn describe_register(map: &Map, name: &str) -> String {
    points::find(map, name)
        .map(|r| r.label())
        .unwrap_or_else(|_| name.to_owned())
}
