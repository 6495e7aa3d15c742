//! Polling a shipped drive's monitor registers through an emulated serial line
//! ([`drivemap_test_support::line`]) against a simulated drive that keeps the map's response
//! time, and measuring the cycle on the wire against the bus-time model
//! (`drivemap_runtime::bus_time`). Used by `examples/line_report.rs` (the full table) and
//! `tests/cross_crate/line_timing.rs` (one drive, one baud rate, in the test script).
//!
//! - **Monitor registers**: as `examples/bus_time_report.rs` takes them: the registers of the
//!   groups the map declares read-only (`access: r`), readable on RTU and not broadcast-only.
//! - **Sets**: all of them, and random halves (each register wanted with probability 1/2,
//!   SplitMix64 with the report's seed).
//! - **Cycle**: from the first character of a set's first request to the first character of
//!   the next set's first request, on the line's record; its model is the bus time the
//!   poller's model gives the requests it sent (`CycleStats::bus_ns`).

use std::collections::BTreeMap;
use std::io;
use std::path::PathBuf;
use std::time::Duration;

use drivemap_drives as drives;
use drivemap_map::Map;
use drivemap_map::facts::TransportName;
use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::core::plan::RegisterPlan;
use drivemap_runtime::core::profile::Parity;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Access;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::planner::{Poller, plan_contiguous, plan_cost};
use drivemap_runtime::transport::serial::{self, SerialOptions, SerialTransport};
use drivemap_runtime::{client::Client, client::ClientOptions};
use drivemap_sim::timed::DriveLine;
use drivemap_sim::{SimOptions, Simulator, server::SerialServer};
use drivemap_test_support::line::{EmulatedLine, LineReport, Violation, analyse};
pub use drivemap_test_support::rng::SplitMix;

/// A shipped drive and its monitor registers.
pub struct Monitors {
    pub id: String,
    pub drive: Map,
    pub profile: &'static Profile,
    pub registers: &'static [RegisterPlan],
    /// Wanted monitor registers: (table, communication address), in address order per table.
    pub wanted: Vec<(Table, u16)>,
}

/// The generated profile and register table of a module of `drivemap_drives`.
fn generated(module: &str) -> Option<(&'static Profile, &'static [RegisterPlan])> {
    macro_rules! modules {
        ($($m:ident),* $(,)?) => {
            match module {
                $(stringify!($m) => Some((&drives::$m::PROFILE, drives::$m::REGISTERS)),)*
                _ => None,
            }
        };
    }
    modules!(
        automationdirect_acn,
        ptlk_tds_v8,
        yaskawa_gpd515,
        yaskawa_j7,
        yaskawa_v7,
    )
}

/// Every shipped drive (`drivemap_drives::DRIVES`) with its monitor registers.
pub fn monitors() -> Vec<Monitors> {
    let maps_dir = crate::workspace().join("maps");
    let ctx = drivemap_map::Loader::new().default_manuals(&maps_dir);
    let mut out = Vec::new();
    for &(id, module) in drives::DRIVES {
        let (profile, registers) = generated(module)
            .unwrap_or_else(|| panic!("module `{module}` of DRIVES is not listed in line_bench"));
        let path: PathBuf = maps_dir.join(format!("{id}.yaml"));
        let drive = ctx
            .load(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut wanted: Vec<(Table, u16)> = drive
            .registers()
            .filter(|r| {
                r.readable()
                    && !r.broadcast_only()
                    && r.data()
                        .transports
                        .as_ref()
                        .is_none_or(|t| t.contains(&TransportName::Rtu))
                    && r.group_access() == Some(Access::Read)
            })
            .map(|r| (r.plan().info.table, r.address()))
            .collect();
        wanted.sort_by_key(|&(t, a)| (t == Table::Input, a));
        wanted.dedup();
        out.push(Monitors {
            id: id.to_string(),
            drive,
            profile,
            registers,
            wanted,
        });
    }
    out
}

/// `n` random halves of `wanted` (each register with probability 1/2; an empty draw is
/// drawn again).
pub fn halves(wanted: &[(Table, u16)], n: usize, seed: u64) -> Vec<Vec<(Table, u16)>> {
    let mut rng = SplitMix(seed);
    let mut sets = Vec::with_capacity(n);
    while sets.len() < n {
        let s: Vec<(Table, u16)> = wanted
            .iter()
            .copied()
            .filter(|_| rng.next_u64() & 1 == 1)
            .collect();
        if !s.is_empty() {
            sets.push(s);
        }
    }
    sets
}

/// The line a drive is polled on at `baud`: 8N1, or the map's fixed character (TDS-V8: 11
/// bits, 8N2).
pub fn line_for(profile: &Profile, baud: u32) -> SerialConfig {
    SerialConfig::for_profile(profile, baud, Parity::None, None).expect("8N1 or the map's format")
}

/// The serial port options of `path` for a line `line` to a drive of `profile`.
pub fn serial_options(path: &str, profile: &Profile, line: SerialConfig) -> SerialOptions {
    SerialOptions::new(path, line.baud)
        .line(
            profile,
            serial::Parity::None,
            Some(if line.stop_bits == 2 {
                serial::StopBits::Two
            } else {
                serial::StopBits::One
            }),
        )
        .expect("the map's format")
}

/// Runs `f` on a thread of its own at real-time priority where the system permits it
/// ([`drivemap_test_support::line::realtime`]; the line's relay and the simulated drive it
/// starts inherit it), and says whether it was granted.
pub fn on_realtime_thread<T: Send>(f: impl FnOnce() -> T + Send) -> (T, bool) {
    std::thread::scope(|s| {
        s.spawn(|| {
            let granted = drivemap_test_support::line::realtime();
            (f(), granted)
        })
        .join()
        .expect("the measuring thread")
    })
}

/// What one client did on the line.
#[derive(Debug, Clone, Default)]
pub struct Measured {
    /// Cycles measured (one per set).
    pub cycles: usize,
    /// Requests sent in them.
    pub requests: usize,
    /// Cycle time on the wire, summed.
    pub measured_ns: u64,
    /// The model's bus time of the same requests, summed.
    pub model_ns: u64,
    /// Timing rules broken on the line during the run.
    pub violations: Vec<Violation>,
    /// CPU time of the client's thread during the measured cycles.
    pub client_cpu_ns: u64,
    /// CPU time of the line's relay thread during the run.
    pub relay_cpu_ns: u64,
    /// The relay's latest hand-over after a character's end.
    pub relay_max_late_ns: u64,
    /// Reads that failed (none expected).
    pub errors: usize,
    /// Summed over the measured requests, on the wire: from the end of a request to the
    /// first character of its reply, and from the end of a reply to the next request.
    pub latency_ns: u64,
    pub turnaround_ns: u64,
    /// The same terms in the model.
    pub model_latency_ns: u64,
    pub model_turnaround_ns: u64,
}

impl Measured {
    /// Measured ÷ model.
    pub fn ratio(&self) -> f64 {
        self.measured_ns as f64 / self.model_ns.max(1) as f64
    }

    /// Mean cycle on the wire, in ms.
    pub fn cycle_ms(&self) -> f64 {
        self.measured_ns as f64 / 1e6 / self.cycles.max(1) as f64
    }

    /// Mean modelled cycle, in ms.
    pub fn model_ms(&self) -> f64 {
        self.model_ns as f64 / 1e6 / self.cycles.max(1) as f64
    }

    /// Client CPU time per cycle, in µs.
    pub fn cpu_us_per_cycle(&self) -> f64 {
        self.client_cpu_ns as f64 / 1e3 / self.cycles.max(1) as f64
    }
}

/// An emulated line at `line` with the simulated drive `m` on its far end, keeping the map's
/// response time. Returns the line, the simulator's server and the slave address.
pub fn drive_on_line(
    m: &Monitors,
    line: SerialConfig,
) -> io::Result<(EmulatedLine, SerialServer, u8)> {
    let emulated = EmulatedLine::new(line)?;
    let sim = Simulator::new(m.drive.clone(), SimOptions::new())
        .map_err(|e| io::Error::other(e.to_string()))?;
    let slave = sim.slave();
    let server = SerialServer::spawn_on_line(
        drivemap_sim::server::shared(sim),
        serial_options(emulated.drive_path(), m.profile, line),
        None,
        Some(DriveLine {
            serial: line,
            pace: false,
        }),
    )?;
    Ok((emulated, server, slave))
}

fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// Cycle times on the record: the cycles start at the transactions `starts` (indexes), the last
/// index closing the last cycle.
fn cycles_on_wire(report: &LineReport, starts: &[usize], model: &BusModel, out: &mut Measured) {
    out.measured_ns = starts
        .windows(2)
        .map(|w| report.transactions[w[1]].start_ns - report.transactions[w[0]].start_ns)
        .sum();
    let last = *starts.last().unwrap_or(&0);
    for pair in report.transactions[..=last].windows(2) {
        let t = &pair[0];
        if let (Some(rs), Some(re)) = (t.reply_start_ns, t.reply_end_ns) {
            out.latency_ns += rs.saturating_sub(t.request_end_ns);
            out.turnaround_ns += pair[1].start_ns.saturating_sub(re);
        }
    }
    out.model_latency_ns = (model.latency_ns() * last as f64) as u64;
    out.model_turnaround_ns = (model.turnaround_ns() * last as f64) as u64;
}

/// Polls each of `sets` once with drivemap's planned poller (`Client` over `SerialTransport`,
/// `ClientOptions::for_line`) through an emulated line at `line` to the simulated drive.
pub fn planned(
    m: &Monitors,
    line: SerialConfig,
    sets: &[Vec<(Table, u16)>],
) -> io::Result<Measured> {
    planned_with(m, line, sets, |o| o)
}

/// [`planned`] with the client's options changed by `options` (fault injection: a client that
/// keeps no request gap).
pub fn planned_with(
    m: &Monitors,
    line: SerialConfig,
    sets: &[Vec<(Table, u16)>],
    options: impl FnOnce(ClientOptions) -> ClientOptions,
) -> io::Result<Measured> {
    let (emulated, server, slave) = drive_on_line(m, line)?;
    let model = BusModel::new(m.profile, line);
    let transport = SerialTransport::open(serial_options(emulated.master_path(), m.profile, line))?;
    let mut client = Client::with_options(
        transport,
        m.profile,
        options(ClientOptions::for_line(m.profile, line)),
    );
    let mut pollers: Vec<Poller> = sets
        .iter()
        .map(|s| {
            Poller::new(m.profile, m.registers, s.iter().copied())
                .map(|p| p.with_model(model))
                .map_err(|e| io::Error::other(e.to_string()))
        })
        .collect::<io::Result<_>>()?;
    // A warm-up cycle, then every set once, then the first again to close the last cycle.
    pollers[0].poll(&mut client, slave);
    let skip = emulated.take_record();
    drop(skip);
    let mut out = Measured::default();
    let mut starts = vec![0usize];
    let cpu = thread_cpu_ns();
    for p in pollers.iter_mut() {
        let stats = p.poll(&mut client, slave);
        out.requests += stats.requests as usize;
        out.model_ns += stats.bus_ns;
        out.errors += (0..p.wanted().len())
            .filter(|&i| !matches!(p.value(i), Some(Ok(_))))
            .count();
        starts.push(out.requests);
    }
    out.client_cpu_ns = thread_cpu_ns() - cpu;
    pollers[0].poll(&mut client, slave);
    let record = emulated.take_record();
    let report = analyse(&record, &model);
    out.cycles = sets.len();
    if report.transactions.len() <= out.requests {
        return Err(io::Error::other(format!(
            "{} requests on the line, {} sent",
            report.transactions.len(),
            out.requests + 1
        )));
    }
    cycles_on_wire(&report, &starts, &model, &mut out);
    out.violations = report.violations;
    let relay = emulated.relay_stats();
    out.relay_cpu_ns = relay.cpu_ns;
    out.relay_max_late_ns = relay.max_late_ns;
    drop(client);
    server.stop();
    Ok(out)
}

/// The contiguous runs of a set per table (what Telegraf's Modbus input and Home Assistant do,
/// and what a tokio-modbus user writes): (table, wire address, quantity).
pub fn contiguous_requests(m: &Monitors, set: &[(Table, u16)]) -> Vec<(Table, u16, u16)> {
    let mut by_table: BTreeMap<bool, Vec<u16>> = BTreeMap::new();
    for &(t, a) in set {
        by_table.entry(t == Table::Input).or_default().push(a);
    }
    let mut out = Vec::new();
    for (input, addresses) in by_table {
        let t = if input { Table::Input } else { Table::Holding };
        for r in plan_contiguous(&addresses, m.profile.max_read) {
            let wire = m
                .profile
                .address_offsets
                .pdu_address(r.address, TransportKind::Rtu)
                .expect("a monitor register's RTU address");
            out.push((t, wire, r.quantity));
        }
    }
    out
}

/// The model's bus time of the contiguous runs of `set`.
pub fn contiguous_model_ns(m: &Monitors, line: SerialConfig, set: &[(Table, u16)]) -> u64 {
    let model = BusModel::new(m.profile, line);
    let mut by_table: BTreeMap<bool, Vec<u16>> = BTreeMap::new();
    for &(t, a) in set {
        by_table.entry(t == Table::Input).or_default().push(a);
    }
    by_table
        .values()
        .map(|a| {
            plan_cost(&plan_contiguous(a, m.profile.max_read), |q| {
                model.read_ns(q)
            })
        })
        .sum()
}

/// One read by tokio-modbus, within 2 s; whether it got the registers.
async fn read(ctx: &mut tokio_modbus::client::Context, t: Table, a: u16, q: u16) -> bool {
    use tokio_modbus::client::Reader;
    let within = Duration::from_secs(2);
    match t {
        Table::Holding => matches!(
            tokio::time::timeout(within, ctx.read_holding_registers(a, q)).await,
            Ok(Ok(Ok(_)))
        ),
        Table::Input => matches!(
            tokio::time::timeout(within, ctx.read_input_registers(a, q)).await,
            Ok(Ok(Ok(_)))
        ),
        Table::Coil => matches!(
            tokio::time::timeout(within, ctx.read_coils(a, q)).await,
            Ok(Ok(Ok(_)))
        ),
        Table::DiscreteInput => matches!(
            tokio::time::timeout(within, ctx.read_discrete_inputs(a, q)).await,
            Ok(Ok(Ok(_)))
        ),
    }
}

/// Polls each of `sets` once with tokio-modbus's RTU client over tokio-serial, one request per
/// contiguous run, through an emulated line at `line` to the simulated drive.
pub fn tokio_modbus(
    m: &Monitors,
    line: SerialConfig,
    sets: &[Vec<(Table, u16)>],
) -> io::Result<Measured> {
    use tokio_modbus::prelude::Slave;
    use tokio_serial::SerialPortBuilderExt;

    let (emulated, server, slave) = drive_on_line(m, line)?;
    let model = BusModel::new(m.profile, line);
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let requests: Vec<Vec<(Table, u16, u16)>> =
        sets.iter().map(|s| contiguous_requests(m, s)).collect();
    let mut out = Measured::default();
    let mut starts = vec![0usize];
    let result: io::Result<()> = runtime.block_on(async {
        let port = tokio_serial::new(emulated.master_path(), line.baud)
            .parity(tokio_serial::Parity::None)
            .stop_bits(if line.stop_bits == 2 {
                tokio_serial::StopBits::Two
            } else {
                tokio_serial::StopBits::One
            })
            .open_native_async()
            .map_err(io::Error::from)?;
        let mut ctx = tokio_modbus::client::rtu::attach_slave(port, Slave(slave));
        for &(t, a, q) in &requests[0] {
            read(&mut ctx, t, a, q).await;
        }
        drop(emulated.take_record());
        let cpu = thread_cpu_ns();
        for (set, reqs) in sets.iter().zip(&requests) {
            for &(t, a, q) in reqs {
                if !read(&mut ctx, t, a, q).await {
                    out.errors += 1;
                }
            }
            out.requests += reqs.len();
            out.model_ns += contiguous_model_ns(m, line, set);
            starts.push(out.requests);
        }
        out.client_cpu_ns = thread_cpu_ns() - cpu;
        for &(t, a, q) in &requests[0] {
            read(&mut ctx, t, a, q).await;
        }
        Ok(())
    });
    result?;
    let record = emulated.take_record();
    let report = analyse(&record, &model);
    out.cycles = sets.len();
    if report.transactions.len() <= out.requests {
        return Err(io::Error::other(format!(
            "{} requests on the line, {} sent",
            report.transactions.len(),
            out.requests + 1
        )));
    }
    cycles_on_wire(&report, &starts, &model, &mut out);
    out.violations = report.violations;
    let relay = emulated.relay_stats();
    out.relay_cpu_ns = relay.cpu_ns;
    out.relay_max_late_ns = relay.max_late_ns;
    drop(runtime);
    server.stop();
    Ok(out)
}
