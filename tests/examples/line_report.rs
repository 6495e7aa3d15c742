//! Poll cycles measured on an emulated serial line against the bus-time model, and side by side
//! with tokio-modbus on the same line: every shipped drive's monitor registers (all, and random
//! halves), each character taking its time on the wire, a simulated drive keeping the map's
//! response time on the far end (`drivemap_tests::line_bench`).
//!
//! Run: `cargo run --release -p drivemap-tests --example line_report [-- OPTIONS]`
//!
//! - `--baud 9600,19200` (the default): the baud rates;
//! - `--halves N` (default 10): random halves per drive and baud rate;
//! - `--all N` (default 2): cycles of all monitor registers;
//! - `--drive ID`: one drive only (repeatable);
//! - `--no-peer`: drivemap alone, without tokio-modbus.
//!
//! Prints one Markdown table per baud rate. "Measured" is the cycle on the wire (first
//! character of a set's first request to that of the next set's); "model" is the bus time the
//! model gives the same requests; violations are the timing rules broken on the line (see
//! `drivemap_test_support::line::Violation`); CPU is the client thread's, per cycle, while it
//! polls (it sleeps while the line is busy).

use drivemap_tests::line_bench::{self, Measured, Monitors};

struct Options {
    bauds: Vec<u32>,
    halves: usize,
    all: usize,
    drives: Vec<String>,
    peer: bool,
}

fn options() -> Options {
    let mut o = Options {
        bauds: vec![9600, 19_200],
        halves: 10,
        all: 2,
        drives: Vec::new(),
        peer: true,
    };
    let mut args = std::env::args().skip(1);
    let usage =
        "usage: line_report [--baud B,B] [--halves N] [--all N] [--drive ID]... [--no-peer]";
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| panic!("{usage}"));
        match a.as_str() {
            "--baud" => {
                o.bauds = value()
                    .split(',')
                    .map(|b| b.parse().unwrap_or_else(|_| panic!("{usage}")))
                    .collect()
            }
            "--halves" => o.halves = value().parse().unwrap_or_else(|_| panic!("{usage}")),
            "--all" => o.all = value().parse().unwrap_or_else(|_| panic!("{usage}")),
            "--drive" => o.drives.push(value()),
            "--no-peer" => o.peer = false,
            _ => panic!("{usage}"),
        }
    }
    o
}

fn cell(m: &Measured) -> String {
    format!(
        "{:.1} ms | {:.1} ms | {:.3} | {}",
        m.cycle_ms(),
        m.model_ms(),
        m.ratio(),
        m.violations.len()
    )
}

fn main() {
    let o = options();
    let ((), realtime) = line_bench::on_realtime_thread(|| report(&o));
    println!(
        "\nReal-time priority (SCHED_FIFO 10) for the client, the line and the simulated drive: {}",
        if realtime {
            "granted"
        } else {
            "refused: figures include the machine's scheduling delays"
        }
    );
}

fn report(o: &Options) {
    let drives: Vec<Monitors> = line_bench::monitors()
        .into_iter()
        .filter(|m| o.drives.is_empty() || o.drives.contains(&m.id))
        .collect();
    for &baud in &o.bauds {
        println!(
            "\n{baud} baud, 8N1 or the drive's fixed character; drive's delays at the map's defaults\n"
        );
        println!(
            "| drive | set | cycles | requests/cycle | planned: measured | model | measured ÷ model | violations | client CPU/cycle | tokio-modbus (contiguous runs): measured | model | measured ÷ model | violations | planned ÷ tokio-modbus |"
        );
        println!("|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|");
        let mut totals: Vec<(&str, Measured, Measured)> = Vec::new();
        for m in &drives {
            let line = line_bench::line_for(m.profile, baud);
            let all = vec![m.wanted.clone(); o.all];
            let halves = line_bench::halves(&m.wanted, o.halves, 0xB05_7173);
            for (name, sets) in [("all", &all), ("halves", &halves)] {
                if sets.is_empty() {
                    continue;
                }
                let planned = line_bench::planned(m, line, sets)
                    .unwrap_or_else(|e| panic!("{} at {baud}: {e}", m.id));
                let peer = o.peer.then(|| {
                    line_bench::tokio_modbus(m, line, sets)
                        .unwrap_or_else(|e| panic!("{} at {baud} (tokio-modbus): {e}", m.id))
                });
                for v in planned.violations.iter().take(3) {
                    eprintln!("{} {baud} {name}: drivemap: {v}", m.id);
                }
                eprintln!(
                    "{} {baud} {name}: per request: latency {:.2} ms (model {:.2}), turnaround {:.2} ms (model {:.2}), relay late up to {:.2} ms",
                    m.id,
                    planned.latency_ns as f64 / 1e6 / planned.requests as f64,
                    planned.model_latency_ns as f64 / 1e6 / planned.requests as f64,
                    planned.turnaround_ns as f64 / 1e6 / planned.requests as f64,
                    planned.model_turnaround_ns as f64 / 1e6 / planned.requests as f64,
                    planned.relay_max_late_ns as f64 / 1e6,
                );
                if planned.errors > 0 {
                    eprintln!(
                        "{} {baud} {name}: {} register(s) not read",
                        m.id, planned.errors
                    );
                }
                let (peer_cells, versus) = match &peer {
                    Some(p) => (
                        cell(p),
                        format!("{:.2}", planned.measured_ns as f64 / p.measured_ns as f64),
                    ),
                    None => ("- | - | - | -".into(), "-".into()),
                };
                println!(
                    "| {} | {name} | {} | {:.1} | {} | {:.0} µs | {peer_cells} | {versus} |",
                    m.id,
                    planned.cycles,
                    planned.requests as f64 / planned.cycles as f64,
                    cell(&planned),
                    planned.cpu_us_per_cycle(),
                );
                if let Some(idx) = totals.iter().position(|t| t.0 == name) {
                    add(&mut totals[idx].1, &planned);
                    if let Some(p) = &peer {
                        add(&mut totals[idx].2, p);
                    }
                } else {
                    totals.push((name, planned, peer.unwrap_or_default()));
                }
            }
        }
        for (name, planned, peer) in &totals {
            let versus = if peer.measured_ns > 0 {
                format!(
                    "{:.2}",
                    planned.measured_ns as f64 / peer.measured_ns as f64
                )
            } else {
                "-".into()
            };
            println!(
                "| **all drives** | {name} | {} | {:.1} | {} | {:.0} µs | {} | {versus} |",
                planned.cycles,
                planned.requests as f64 / planned.cycles.max(1) as f64,
                cell(planned),
                planned.cpu_us_per_cycle(),
                if peer.cycles > 0 {
                    cell(peer)
                } else {
                    "- | - | - | -".into()
                },
            );
        }
        let relay_cpu: u64 = totals.iter().map(|t| t.1.relay_cpu_ns).sum();
        let late = totals
            .iter()
            .map(|t| t.1.relay_max_late_ns)
            .max()
            .unwrap_or(0);
        println!(
            "\nThe line's relay thread: {:.2} s of CPU for drivemap's runs; latest hand-over after a character's end {:.3} ms.",
            relay_cpu as f64 / 1e9,
            late as f64 / 1e6
        );
    }
}

fn add(total: &mut Measured, m: &Measured) {
    total.cycles += m.cycles;
    total.requests += m.requests;
    total.measured_ns += m.measured_ns;
    total.model_ns += m.model_ns;
    total.violations.extend(m.violations.iter().copied());
    total.client_cpu_ns += m.client_cpu_ns;
    total.relay_cpu_ns += m.relay_cpu_ns;
    total.relay_max_late_ns = total.relay_max_late_ns.max(m.relay_max_late_ns);
    total.errors += m.errors;
}
