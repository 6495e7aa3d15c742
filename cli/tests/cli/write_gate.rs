//! Nothing reaches the wire that the map does not allow there, whatever `drivemap write` is
//! asked.
//!
//! Every register of every shipped map, by every name form the CLI accepts (id, parameter
//! number, printed name) and every value form (number, number with unit, enumeration id, code
//! and printed meaning, bit fields by name, `field=value`, raw hex), legal and illegal values,
//! to slave 1 and to slave 0 (broadcast), over Modbus TCP and RTU over TCP, through the CLI's own
//! write command in-process (the same code as the binary; one map load per map instead of one
//! per case). A simulated drive that executes every write it receives records what arrived; each
//! arrival is checked against the map by rules written here from the map's keys as it writes
//! them (`RegisterRef::written`, not the plan the gate is built from), not by the gate, and
//! so is each refusal: a write the map allows on that link and that needs no setting from the
//! drive must arrive, exactly once. The rules cover every construct the schema documents: a
//! 32-bit pair arrives as its two words at its address and the next, its 32-bit value in range;
//! an address chosen by a setting, the transport or the variant arrives at the one the drive's
//! settings select (as the simulated drive holds them); `broadcast: {unknown}` sends nothing to
//! slave 0. Every map of `maps/` is swept, and `a_new_map_is_swept_with_no_test_edit` sweeps a
//! copy with a map added.
//!
//! `write_gate_repros_as_reported` runs the binary itself on the three cases of the report.

use drivemap_test_support::paths;

use drivemap_map::{Map, RegisterRef};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Condvar, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_map::facts::field_span;
use drivemap_map::facts::{BitField, EnumValue, Scale, TransportName};
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::core::scale::{Decimal, RawRange, raw_of};
use drivemap_runtime::core::width::{Width, WordOrder};
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_sim::SimulatedSlave;

use crate::common;
use crate::new_map;
mod safe_live;

use common::repo;

/// The maps of a `maps/` directory.
fn maps_in(dir: &Path) -> Vec<PathBuf> {
    drivemap_map::find_maps(dir).expect("maps/")
}

/// A simulated drive on loopback that executes every write it receives, legal or not.
struct Wire {
    addr: String,
    kind: TransportKind,
    slave: Arc<Mutex<SimulatedSlave>>,
    /// Client ports of the connections served to their end, in order of arrival; notified at
    /// each.
    served: Arc<(Mutex<Vec<u16>>, Condvar)>,
}

impl Wire {
    fn start(profile: &'static Profile, kind: TransportKind) -> Wire {
        let slave = Arc::new(Mutex::new(SimulatedSlave::new(1, profile)));
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let shared = Arc::clone(&slave);
        let served = Arc::new((Mutex::new(Vec::new()), Condvar::new()));
        let done = Arc::clone(&served);
        thread::spawn(move || {
            for stream in listener.incoming() {
                let Ok(stream) = stream else { continue };
                let port = stream.peer_addr().map(|a| a.port()).unwrap_or(0);
                let until = Instant::now() + Duration::from_secs(30);
                let mut s = shared.lock().unwrap();
                let _ = match kind {
                    TransportKind::Tcp => {
                        s.serve(&mut TcpTransport::from_stream(stream).unwrap(), until)
                    }
                    TransportKind::TcpGateway => s.serve(
                        &mut TcpTransport::from_gateway_stream(stream).unwrap(),
                        until,
                    ),
                    _ => s.serve(
                        &mut RtuOverTcpTransport::from_stream(stream).unwrap(),
                        until,
                    ),
                };
                drop(s);
                done.0.lock().unwrap().push(port);
                done.1.notify_all();
            }
        });
        Wire {
            addr,
            kind,
            slave,
            served,
        }
    }

    /// Waits until every connection made so far has been served: a broadcast gets no reply, so
    /// the client may return before the drive has read it. Connections are served in order,
    /// so once an empty connection made now is served, all before it were.
    fn settle(&self) {
        let barrier = std::net::TcpStream::connect(&self.addr).unwrap();
        let port = barrier.local_addr().unwrap().port();
        drop(barrier);
        let deadline = Instant::now() + Duration::from_secs(10);
        let (served, done) = &*self.served;
        let mut served = served.lock().unwrap();
        while !served.contains(&port) {
            let left = deadline.saturating_duration_since(Instant::now());
            assert!(!left.is_zero(), "the simulated drive stopped serving");
            served = done.wait_timeout(served, left).unwrap().0;
        }
    }

    fn flag(&self) -> &'static str {
        match self.kind {
            TransportKind::Tcp => "--tcp",
            TransportKind::TcpGateway => "--gateway",
            _ => "--rtu-tcp",
        }
    }

    fn writes(&self) -> usize {
        self.slave.lock().unwrap().writes.len()
    }

    fn writes_since(&self, n: usize) -> Vec<(u16, u16)> {
        self.slave.lock().unwrap().writes[n..].to_vec()
    }

    /// The word the drive holds at a PDU address.
    fn holding(&self, pdu: u16) -> u16 {
        self.slave.lock().unwrap().holding(pdu)
    }
}

/// What a register's word means as the map writes it: bit fields, else codes, else a scale,
/// else a unit, else a plain word.
enum ValueKind<'m> {
    Word,
    Quantity(&'m Scale),
    UnitQuantity,
    Enum(&'m [EnumValue]),
    Bits(&'m [BitField]),
}

fn value_kind<'m>(r: RegisterRef<'m>) -> ValueKind<'m> {
    let w = r.written();
    if !w.fields.is_empty() {
        ValueKind::Bits(w.fields)
    } else if !w.values.is_empty() {
        ValueKind::Enum(w.values)
    } else if let Some(scale) = w.scale {
        ValueKind::Quantity(scale)
    } else if w.unit.is_some() {
        ValueKind::UnitQuantity
    } else {
        ValueKind::Word
    }
}

/// The decimal factor of a fixed-scale register as written (1 for unit quantities and words).
fn factor(r: RegisterRef<'_>) -> Option<Decimal> {
    match value_kind(r) {
        ValueKind::Quantity(Scale::Factor(f)) => Decimal::from_f64(*f),
        ValueKind::Quantity(_) => None,
        _ => Some(Decimal::ONE),
    }
}

/// Raw limits for engineering limits at a fixed decimal factor; missing limits are the word's
/// own. `None` when a limit is not a whole number of increments.
fn raw_limits(
    r: RegisterRef<'_>,
    factor: Decimal,
    min: Option<f64>,
    max: Option<f64>,
) -> Option<RawRange> {
    let word = r.width().range(r.signed());
    let raw = |m: f64| raw_of(m, factor).and_then(|r| i64::try_from(r).ok());
    let min = match min {
        Some(m) => raw(m)?,
        None => word.min,
    };
    let max = match max {
        Some(m) => raw(m)?,
        None => word.max,
    };
    Some(RawRange { min, max })
}

/// The address at which the map puts `r` on this link, given the settings the drive holds
/// now (`address_alternatives` chosen by a setting's code, the transport or the model variant,
/// which is the base one here), as the map writes them: the first alternative whose condition
/// holds, else its own address.
fn selected_address(drive: &Map, r: RegisterRef<'_>, kind: TransportKind, wire: &Wire) -> i32 {
    let (rtu, tcp) = drive.address_offsets();
    let offset = if kind == TransportKind::Tcp { tcp } else { rtu };
    for alt in r.address_alternatives() {
        let when = &alt.when;
        // The sweep writes as the base variant: the first option of every axis.
        let in_variant = when.variant.as_ref().is_none_or(|v| {
            drive
                .variants()
                .iter()
                .any(|axis| axis.options.first().is_some_and(|o| o.id == *v))
        });
        let on_transport = when
            .transport
            .is_none_or(|t| (t == TransportName::Tcp) == (kind == TransportKind::Tcp));
        let setting_holds = when.setting.as_deref().is_none_or(|s| {
            let setting = drive
                .register(s)
                .expect("the setting is a register of the map");
            let pdu = i32::from(setting.address()) + offset;
            when.is.contains(&wire.holding(pdu as u16))
        });
        if in_variant && on_transport && setting_holds {
            return i32::from(alt.address);
        }
    }
    i32::from(r.address())
}

/// `drivemap write` in-process: the arguments parsed by the binary's own parser.
fn run_write(
    drive: &Map,
    profile: &'static Profile,
    wire: &Wire,
    slave: u8,
    assignment: &str,
) -> Result<ExitCode, String> {
    let maps = paths::maps();
    let slave = slave.to_string();
    let argv = [
        "drivemap",
        "write",
        "--drive",
        drive.id(),
        "--maps",
        maps.to_str().unwrap(),
        wire.flag(),
        &wire.addr,
        "--slave",
        &slave,
        "--timeout",
        "500ms",
        "--retries",
        "0",
        assignment,
    ];
    let result = drivemap_cli::write_in_process(&argv, drive, profile);
    if let Err(e) = &result {
        // A command line clap refuses is the test's mistake, not a refusal of the write.
        assert!(
            !e.starts_with("error: "),
            "the test's own arguments parse: {e}"
        );
    }
    result
}

/// The register's `transports` as written in the map (`rtu`, `tcp`): this oracle reads the
/// map's text form, not the plan the gate is built from.
fn on_transport(r: RegisterRef<'_>, kind: TransportKind) -> bool {
    let name = if kind == TransportKind::Tcp {
        "tcp"
    } else {
        "rtu"
    };
    r.written().transports.is_none_or(|list| {
        serde_json::to_value(list)
            .ok()
            .and_then(|v| v.as_array().cloned())
            .is_some_and(|names| names.iter().any(|n| n == name))
    })
}

/// The form of the register's `scale` as written: `factor`, `relative` or `selected`.
fn scale_form(r: RegisterRef<'_>) -> Option<&'static str> {
    let v = serde_json::to_value(r.written().scale?).ok()?;
    Some(if v.get("selected_by").is_some() {
        "selected"
    } else if v.get("relative_to").is_some() {
        "relative"
    } else {
        "factor"
    })
}

/// Whether the map lets `r` be written to `slave` (0: broadcast) on `kind`, as it writes it. A
/// drive whose map lists no `tcp` transport has no Modbus TCP interface: `--tcp` reaches
/// nothing of it (a serial drive behind a gateway is `--gateway`, its RTU side).
fn allowed_on_link(drive: &Map, r: RegisterRef<'_>, kind: TransportKind, slave: u8) -> bool {
    let has_tcp = serde_json::to_value(&drive.protocol().transports)
        .ok()
        .and_then(|v| v.as_array().cloned())
        .is_some_and(|names| names.iter().any(|n| n == "tcp"));
    if kind == TransportKind::Tcp && !has_tcp {
        return false;
    }
    if !r.writable() || !on_transport(r, kind) {
        return false;
    }
    let commands = drive
        .protocol()
        .commands
        .iter()
        .flat_map(|c| c.writes.iter().map(|w| w.address));
    if commands.clone().any(|a| a == r.address()) {
        return false; // ENTER/ACCEPT/save: only through --persist
    }
    if slave != 0 {
        return !r.broadcast_only();
    }
    let Some(b) = &drive.protocol().broadcast else {
        return false;
    };
    if b.unknown.is_some() {
        // `broadcast: {unknown: ...}`: the manual names a broadcast but not its rules, so
        // nothing is sent to slave 0.
        return false;
    }
    let named = b
        .registers
        .iter()
        .any(|n| drive.register(n).is_some_and(|x| x.id() == r.id()));
    r.broadcast_only() || named || drive.broadcast_addresses().is_empty()
}

/// Whether a conversion of `r` needs a setting read from the drive (a selected or relative
/// scale, an address chosen by a setting, limits per variant, a limit through another
/// parameter or quantity).
fn needs_settings(r: RegisterRef<'_>) -> bool {
    let w = r.written();
    matches!(scale_form(r), Some("selected" | "relative"))
        || w.address_alternatives
            .iter()
            .any(|a| a.when.setting.is_some())
        || !w.by_variant.is_empty()
        || w.max_relative.is_some()
}

fn field_mask(r: RegisterRef<'_>) -> Option<u16> {
    match value_kind(r) {
        ValueKind::Bits(fields) => Some(
            fields
                .iter()
                .filter_map(field_span)
                .fold(0u16, |m, (lsb, w)| m | ((((1u32 << w) - 1) << lsb) as u16)),
        ),
        _ => None,
    }
}

/// Whether the words that arrived (PDU address, word) for one write of `r` are what the map
/// allows for it on this link: one word at the register's address (or an alternative), or the
/// two words of a 32-bit pair at it and the next address, the value in range either way.
fn legal_arrival(
    drive: &Map,
    r: RegisterRef<'_>,
    kind: TransportKind,
    slave: u8,
    wire: &Wire,
    arrived: &[(u16, u16)],
) -> Result<(), String> {
    if !allowed_on_link(drive, r, kind, slave) {
        return Err("the map does not allow this register on this link".into());
    }
    let order = match r.width() {
        Width::Word => None,
        Width::Pair(order) => Some(order),
        Width::Text(_) => return Err("a string (text) is never written".into()),
    };
    let words = if order.is_some() { 2 } else { 1 };
    if arrived.len() != words {
        return Err(format!(
            "{} words arrived; one write of the register is {words}",
            arrived.len()
        ));
    }
    let (rtu, tcp) = drive.address_offsets();
    let offset = if kind == TransportKind::Tcp { tcp } else { rtu };
    let address = i32::from(arrived[0].0) - offset;
    let selected = selected_address(drive, r, kind, wire);
    if address != selected {
        return Err(format!(
            "arrived at {address:04X}h, the map puts the register at {selected:04X}h now"
        ));
    }
    if words == 2 && arrived[1].0 != arrived[0].0.wrapping_add(1) {
        return Err(format!(
            "the second word of the pair arrived at {:04X}h, not the next address",
            arrived[1].0
        ));
    }
    let (first, second) = (
        u32::from(arrived[0].1),
        arrived.get(1).map_or(0, |a| u32::from(a.1)),
    );
    let (raw, unsigned): (i128, u32) = match order {
        None => {
            let w = arrived[0].1;
            (
                if r.signed() {
                    i128::from(w as i16)
                } else {
                    i128::from(w)
                },
                u32::from(w),
            )
        }
        Some(order) => {
            let v = match order {
                WordOrder::HighFirst => (first << 16) | second,
                WordOrder::LowFirst => (second << 16) | first,
            };
            (
                if r.signed() {
                    i128::from(v as i32)
                } else {
                    i128::from(v)
                },
                v,
            )
        }
    };
    if let Some(mask) = field_mask(r)
        && unsigned & !u32::from(mask) != 0
    {
        return Err(format!(
            "reserved bits {:04X}h set",
            unsigned & !u32::from(mask)
        ));
    }
    let w = r.written();
    let plain = matches!(value_kind(r), ValueKind::Word | ValueKind::UnitQuantity)
        || (matches!(value_kind(r), ValueKind::Quantity(_)) && scale_form(r) == Some("factor"));
    if plain && w.by_variant.is_empty() {
        let factor = factor(r).expect("fixed factor");
        if let Some(l) = raw_limits(r, factor, w.min, w.max)
            && (raw < i128::from(l.min) || raw > i128::from(l.max))
        {
            return Err(format!("raw {raw} outside {} ..= {}", l.min, l.max));
        }
    }
    if let ValueKind::Enum(values) = value_kind(r) {
        let listed = values.iter().any(|v| u32::from(v.value) == unsigned);
        let in_range = (w.min.is_some() || w.max.is_some())
            && w.min.is_none_or(|m| f64::from(unsigned) >= m)
            && w.max.is_none_or(|m| f64::from(unsigned) <= m);
        if !listed && !in_range {
            return Err(format!("code {unsigned} not listed"));
        }
    }
    Ok(())
}

/// The names the CLI accepts for `r` that resolve to it.
fn names(drive: &Map, r: RegisterRef<'_>) -> Vec<String> {
    let mut out = vec![r.id().to_owned()];
    for n in [r.param().map(str::to_owned), Some(r.name().to_owned())]
        .into_iter()
        .flatten()
    {
        if !out.contains(&n)
            && drivemap_live::lookup::find(drive, &n).is_ok_and(|x| x.id() == r.id())
        {
            out.push(n);
        }
    }
    out
}

fn number(v: f64) -> String {
    format!("{v}")
}

/// Values in every form the CLI accepts: `(text, legal)`. Legal ones are in range for the base
/// variant; illegal ones are out of range, unlisted codes or reserved bits.
fn values(r: RegisterRef<'_>) -> Vec<(String, bool)> {
    let unit = r.unit().map(str::to_owned).unwrap_or_default();
    let w = r.written();
    match value_kind(r) {
        ValueKind::Bits(fields) => {
            let mask = field_mask(r).unwrap_or(0);
            let f = &fields[0];
            let (lsb, _) = field_span(f).unwrap_or((0, 1));
            let mut v = vec![
                (f.id.clone(), true),
                (format!("{}=1", f.id), true),
                (format!("0x{:04X}", 1u16 << lsb), true),
            ];
            if mask != 0xFFFF {
                v.push(("0xFFFF".to_owned(), false));
            }
            v
        }
        ValueKind::Enum(list) => {
            let first = &list[0];
            let mut v = vec![
                (first.id.clone(), true),
                (first.value.to_string(), true),
                (first.name.clone(), true),
                (format!("0x{:04X}", first.value), true),
            ];
            let unlisted = (0..=u16::MAX).rev().find(|c| {
                !list.iter().any(|e| e.value == *c) && w.max.is_none_or(|m| f64::from(*c) > m)
            });
            if let Some(c) = unlisted {
                v.push((c.to_string(), false));
            }
            v
        }
        _ => {
            let legal = r
                .default_value()
                .filter(|d| w.min.is_none_or(|m| *d >= m) && w.max.is_none_or(|m| *d <= m))
                .or(w.min)
                .unwrap_or(0.0);
            let mut v = vec![(number(legal), true)];
            if !unit.is_empty() {
                v.push((format!("{} {unit}", number(legal)), true));
            }
            if let (Some(max), Some(factor)) = (w.max, factor(r)) {
                let step = factor.mantissa as f64 / 10f64.powi(factor.exponent as i32);
                v.push((number(max + 10.0 * step), false));
            }
            if let (Some(min), Some(factor)) = (w.min, factor(r)) {
                let step = factor.mantissa as f64 / 10f64.powi(factor.exponent as i32);
                if !r.signed() && min - 10.0 * step < 0.0 {
                    v.push((number(min - 10.0 * step), false));
                }
            }
            v
        }
    }
}

#[derive(Default)]
struct Tally {
    cases: usize,
    arrived: usize,
    refused: usize,
}

fn sweep(path: &Path, kind: TransportKind) -> Tally {
    let drive = drivemap_map::Loader::new().load(path).expect("shipped map");
    let profile = drivemap_live::leak_profile(&drive);
    let wire = Wire::start(profile, kind);
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for r in drive.registers() {
        let names = names(&drive, r);
        for slave in [1u8, 0] {
            for (ni, name) in names.iter().enumerate() {
                for (vi, (value, legal)) in values(r).into_iter().enumerate() {
                    // Every name form with the first value form; every value form by id.
                    if ni > 0 && vi > 0 {
                        continue;
                    }
                    let case = format!("{} {:?} slave {slave}: {name}={value}", drive.id(), kind);
                    tally.cases += 1;
                    let before = wire.writes();
                    let result =
                        run_write(&drive, profile, &wire, slave, &format!("{name}={value}"));
                    wire.settle();
                    let arrived = wire.writes_since(before);
                    if !arrived.is_empty()
                        && let Err(why) = legal_arrival(&drive, r, kind, slave, &wire, &arrived)
                    {
                        let words: Vec<String> = arrived
                            .iter()
                            .map(|(pdu, word)| format!("{pdu:04X}h = {word:04X}h"))
                            .collect();
                        failures.push(format!(
                            "{case}: {} reached the wire: {why}",
                            words.join(", ")
                        ));
                    }
                    let sent = !arrived.is_empty();
                    match (&result, sent) {
                        (Ok(code), true) if *code == ExitCode::SUCCESS => tally.arrived += 1,
                        (Ok(_), true) | (Err(_), true) => {
                            failures.push(format!("{case}: reported failure but a write arrived"))
                        }
                        (Ok(code), false) if *code == ExitCode::SUCCESS && slave != 0 => {
                            failures.push(format!("{case}: reported success but nothing arrived"))
                        }
                        _ => tally.refused += 1,
                    }
                    let must_arrive = legal
                        && allowed_on_link(&drive, r, kind, slave)
                        && !needs_settings(r)
                        && !r
                            .address_alternatives()
                            .iter()
                            .any(|a| a.when.variant.is_some() || a.when.transport.is_some());
                    if must_arrive && !sent {
                        failures.push(format!(
                            "{case}: allowed by the map but not written: {result:?}"
                        ));
                    }
                    if !legal && sent {
                        failures.push(format!("{case}: an illegal value was written"));
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases wrong:\n{}",
        failures.len(),
        tally.cases,
        failures
            .iter()
            .take(40)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
    // A drive without Modbus TCP refuses every write over --tcp (none arrived, checked above);
    // every other sweep exercises both outcomes.
    let reachable = drive
        .registers()
        .any(|r| allowed_on_link(&drive, r, kind, 1));
    assert!(
        tally.refused > 0 && (tally.arrived > 0 || !reachable),
        "the sweep exercised both outcomes"
    );
    tally
}

/// The sweep over every map of a `maps/` directory on one transport.
fn sweep_all(dir: &Path, kind: TransportKind) {
    for map in maps_in(dir) {
        let t = sweep(&map, kind);
        eprintln!(
            "{}: {} cases, {} written, {} refused",
            map.display(),
            t.cases,
            t.arrived,
            t.refused
        );
    }
}

#[test]
fn every_register_of_every_map_over_modbus_tcp() {
    assert!(maps_in(&paths::maps()).len() >= 5, "the shipped maps");
    sweep_all(&paths::maps(), TransportKind::Tcp);
}

#[test]
fn every_register_of_every_map_over_rtu_over_tcp() {
    sweep_all(&paths::maps(), TransportKind::RtuOverTcp);
}

/// A map added to `maps/` is swept by the same code with no edit (here the fixture drive,
/// which uses every construct the schema documents: `broadcast: {unknown}`, 32-bit pairs, an
/// address or scale selected by a setting). RTU framing, where slave 0 is a broadcast.
#[test]
fn a_new_map_is_swept_with_no_test_edit() {
    let n = new_map::NewMap::new("write-gate");
    sweep_all(&n.root.join("maps"), TransportKind::RtuOverTcp);
}

/// Through a Modbus TCP to RTU gateway: Modbus TCP frames, the map's RTU addresses and RTU
/// registers.
#[test]
fn every_register_of_every_map_through_a_modbus_tcp_gateway() {
    sweep_all(&paths::maps(), TransportKind::TcpGateway);
}

/// The three writes of the report, with the binary: each is refused before connecting and
/// nothing reaches the simulated V7.
#[test]
fn write_gate_repros_as_reported() {
    let path = repo().join("maps/yaskawa-v7.yaml");
    let drive = drivemap_map::Loader::new().load(&path).unwrap();
    let profile = drivemap_live::leak_profile(&drive);
    let cases: [(TransportKind, &[&str], &str); 3] = [
        // The TCP option card's digital inputs over an RTU link: 0001h there is the run command.
        (
            TransportKind::RtuOverTcp,
            &["tcp_digital_input_command=terminal_s1"],
            "does not exist on RtuOverTcp",
        ),
        // The RTU run command over Modbus TCP: 0001h there switches terminal S5.
        (
            TransportKind::Tcp,
            &["digital_input_command=run_command"],
            "does not exist on Tcp",
        ),
        // An ordinary register to slave 0 lands in the broadcast space (bit 2: external fault).
        (
            TransportKind::RtuOverTcp,
            &["--slave", "0", "digital_input_command=0x0004"],
            "does not accept digital_input_command in a broadcast",
        ),
    ];
    for (kind, args, expected) in cases {
        let wire = Wire::start(profile, kind);
        let mut all = vec![
            "write",
            "--drive",
            "yaskawa-v7",
            wire.flag(),
            wire.addr.as_str(),
        ];
        all.extend_from_slice(args);
        let out = common::command()
            .args(&all)
            .arg("--maps")
            .arg(paths::maps())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(expected) && err.contains("nothing written"),
            "{args:?}: {err}"
        );
        wire.settle();
        assert_eq!(wire.writes(), 0, "{args:?} reached the wire");
        assert_eq!(
            wire.slave.lock().unwrap().executed,
            0,
            "{args:?} sent a request"
        );
    }
}
