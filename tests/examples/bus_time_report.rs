//! Bus time of reading every readable monitor register of every shipped drive, planned against
//! one request per register and against contiguous runs only (what Telegraf's Modbus input and
//! Home Assistant's modbus integration do: merge strictly consecutive wanted addresses, split at
//! the drive's maximum). A model, not a measurement: `drivemap_runtime::bus_time`.
//!
//! Run: `cargo run -p drivemap-tests --example bus_time_report [--release] [BAUD]`
//!
//! - **Drives**: every entry of `drivemap_drives::DRIVES`, with the generated `PROFILE` and
//!   `REGISTERS` of its module; the map (`maps/<id>.yaml`, loaded with `drivemap_map::Loader`)
//!   supplies what the generated code does not carry: groups, transports, the fixed character
//!   length.
//! - **Monitor registers**: the registers of the map's *monitor groups*, the groups whose every
//!   register is read-only (`access: r`) — the manuals' status/monitor tables (V7/J7/GPD 515
//!   "Monitor Registers", TDS-V8 "Monitor data registers", ACN "Drive monitoring area"). Of those,
//!   the ones readable on Modbus RTU and not broadcast-only.
//! - **May be read**: a register of the map that is readable on RTU and not broadcast-only;
//!   reserved, unmapped and write-only addresses are never read.
//! - **Line**: 9600 baud, 8N1 (10-bit characters), or the drive's fixed character (TDS-V8: 11
//!   bits); the response-delay parameters at their manual defaults.

use drivemap_test_support::paths;

use std::collections::BTreeMap;

use drivemap_drives as drives;
use drivemap_map::RegisterRef;
use drivemap_map::facts::TransportName;
use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::core::plan::RegisterPlan;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::register::Access;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::planner::{
    Read, ReadableSet, plan_contiguous, plan_cost, plan_reads, plan_single,
};
use drivemap_test_support::rng::SplitMix;

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

/// Random subsets per drive for the second table.
const SUBSETS: usize = 1000;

/// Requests and bus time (ns) of the three strategies for one set of wanted registers.
#[derive(Debug, Default, Clone, Copy)]
struct Outcome {
    registers: usize,
    planned: (usize, u64),
    bridged: usize,
    contiguous: (usize, u64),
    single: (usize, u64),
}

impl Outcome {
    fn add(&mut self, o: &Outcome) {
        self.registers += o.registers;
        self.planned = (self.planned.0 + o.planned.0, self.planned.1 + o.planned.1);
        self.bridged += o.bridged;
        self.contiguous = (
            self.contiguous.0 + o.contiguous.0,
            self.contiguous.1 + o.contiguous.1,
        );
        self.single = (self.single.0 + o.single.0, self.single.1 + o.single.1);
    }
}

fn evaluate(
    wanted: &BTreeMap<u8, Vec<u16>>,
    readable: &BTreeMap<u8, ReadableSet>,
    max_read: u16,
    model: &BusModel,
) -> Outcome {
    let cost = |q: u16| model.read_ns(q);
    let mut o = Outcome::default();
    for (t, w) in wanted {
        let p =
            plan_reads(w, &readable[t], max_read, cost).expect("monitor registers are readable");
        let s = plan_single(w);
        let c = plan_contiguous(w, max_read);
        let read: usize = p.iter().map(|r: &Read| usize::from(r.quantity)).sum();
        o.add(&Outcome {
            registers: s.len(),
            planned: (p.len(), plan_cost(&p, cost)),
            bridged: read - s.len(),
            contiguous: (c.len(), plan_cost(&c, cost)),
            single: (s.len(), plan_cost(&s, cost)),
        });
    }
    o
}

struct Row {
    drive: String,
    groups: Vec<String>,
    max_read: u16,
    char_bits: u32,
    request_ms: f64,
    all: Outcome,
    subsets: Outcome,
}

fn ms(ns: u64) -> f64 {
    ns as f64 / 1e6
}

fn main() {
    let baud: u32 = std::env::args()
        .nth(1)
        .map(|b| b.parse().expect("BAUD must be a number"))
        .unwrap_or(9600);
    let maps_dir = paths::maps();
    let ctx = drivemap_map::Loader::new().default_manuals(&maps_dir);
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    for &(drive_id, module) in drives::DRIVES {
        let Some((profile, registers)) = generated(module) else {
            eprintln!(
                "error: module `{module}` of drivemap_drives::DRIVES is not listed in this report"
            );
            std::process::exit(1);
        };
        let path = maps_dir.join(format!("{drive_id}.yaml"));
        let drive = ctx.load(&path).unwrap_or_else(|e| {
            eprintln!("error: {}: {e}", path.display());
            std::process::exit(1);
        });
        assert_eq!(drive.id(), drive_id);

        let on_rtu = |r: RegisterRef<'_>| {
            r.data()
                .transports
                .as_ref()
                .is_none_or(|t| t.contains(&TransportName::Rtu))
        };
        let generated_readable = [
            ReadableSet::from_registers(registers, Table::Holding),
            ReadableSet::from_registers(registers, Table::Input),
        ];
        let mut readable: BTreeMap<u8, Vec<u16>> = BTreeMap::new();
        let mut wanted: BTreeMap<u8, Vec<u16>> = BTreeMap::new();
        for r in drive.registers() {
            if !(r.readable() && !r.broadcast_only() && on_rtu(r)) {
                continue;
            }
            let t = r.plan().info.table;
            let ti = u8::from(t == Table::Input);
            assert!(
                generated_readable[usize::from(ti)].contains(r.address()),
                "{drive_id}: {} at {:04X}h is readable in the map but not in REGISTERS",
                r.id(),
                r.address()
            );
            readable.entry(ti).or_default().push(r.address());
            if r.group_access() == Some(Access::Read) {
                wanted.entry(ti).or_default().push(r.address());
            }
        }

        let protocol = drive.protocol();
        let mut serial = SerialConfig::new(baud);
        if let Some(bits) = protocol.serial.as_ref().and_then(|s| s.char_bits) {
            serial = serial.fixed_char_bits(bits);
        }
        let model = BusModel::new(profile, serial);
        let sets: BTreeMap<u8, ReadableSet> = readable
            .iter()
            .map(|(&t, a)| (t, ReadableSet::new(a.iter().copied())))
            .collect();
        let all = evaluate(&wanted, &sets, profile.max_read, &model);
        // Subsets: each monitor register wanted with probability 1/2, fixed seed.
        let mut rng = SplitMix(0xB05_7173);
        let mut sum = Outcome::default();
        for _ in 0..SUBSETS {
            let subset: BTreeMap<u8, Vec<u16>> = wanted
                .iter()
                .map(|(&t, w)| {
                    (
                        t,
                        w.iter()
                            .copied()
                            .filter(|_| rng.next_u64() & 1 == 1)
                            .collect(),
                    )
                })
                .collect();
            sum.add(&evaluate(&subset, &sets, profile.max_read, &model));
        }
        // The turnaround terms the model takes from the map.
        let t = &profile.timing;
        let opt = |v: Option<u32>| v.map_or("-".to_string(), |v| v.to_string());
        notes.push(format!(
            "{drive_id}: before the reply {} bits + {} µs + {} ({} µs by default); after it {} bits + {} µs",
            opt(t.response_delay_bits),
            opt(t.response_delay_us),
            t.response_delay_param.unwrap_or("no delay parameter"),
            opt(t.response_delay_param_default_us),
            opt(t.request_gap_bits),
            opt(t.request_gap_us),
        ));
        // Monitor groups: the groups the map declares read-only (`access: r`).
        let mut groups: Vec<String> = drive
            .groups()
            .iter()
            .filter(|g| drive.group_access(g) == Some(Access::Read))
            .map(|g| g.id.clone())
            .collect();
        groups.sort();
        rows.push(Row {
            drive: drive_id.to_string(),
            groups,
            max_read: profile.max_read,
            char_bits: serial.bits_per_char(),
            request_ms: ms(model.read_ns(1)),
            all,
            subsets: sum,
        });
    }

    println!(
        "All readable monitor registers, one poll, {baud} baud, 8N1 or the drive's fixed character (model: drivemap_runtime::bus_time)\n"
    );
    print_table(&rows, |r| r.all, 1);
    println!(
        "\nRandom halves of the monitor registers ({SUBSETS} subsets per drive, each register wanted with probability 1/2, fixed seed), mean per poll\n"
    );
    print_table(&rows, |r| r.subsets, SUBSETS);
    println!("\nTurnaround terms from each map's protocol timing:");
    for n in notes {
        println!("- {n}");
    }
}

fn print_table(rows: &[Row], pick: impl Fn(&Row) -> Outcome, n: usize) {
    let n = n as f64;
    println!(
        "| drive | monitor groups | registers | max_read | bits/char | 1-register read | planned: requests (bridged registers) | planned | contiguous runs: requests | contiguous runs | one per register: requests | one per register | contiguous ÷ planned | one per register ÷ planned |"
    );
    println!("|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|");
    let mut total = Outcome::default();
    for r in rows {
        let o = pick(r);
        println!(
            "| {} | {} | {:.1} | {} | {} | {:.1} ms | {:.1} ({:.1}) | {:.1} ms | {:.1} | {:.1} ms | {:.1} | {:.1} ms | {:.2} | {:.2} |",
            r.drive,
            r.groups.join(", "),
            o.registers as f64 / n,
            r.max_read,
            r.char_bits,
            r.request_ms,
            o.planned.0 as f64 / n,
            o.bridged as f64 / n,
            ms(o.planned.1) / n,
            o.contiguous.0 as f64 / n,
            ms(o.contiguous.1) / n,
            o.single.0 as f64 / n,
            ms(o.single.1) / n,
            o.contiguous.1 as f64 / o.planned.1 as f64,
            o.single.1 as f64 / o.planned.1 as f64,
        );
        total.add(&o);
    }
    println!(
        "| **all drives** | | {:.1} | | | | {:.1} ({:.1}) | {:.1} ms | {:.1} | {:.1} ms | {:.1} | {:.1} ms | {:.2} | {:.2} |",
        total.registers as f64 / n,
        total.planned.0 as f64 / n,
        total.bridged as f64 / n,
        ms(total.planned.1) / n,
        total.contiguous.0 as f64 / n,
        ms(total.contiguous.1) / n,
        total.single.0 as f64 / n,
        ms(total.single.1) / n,
        total.contiguous.1 as f64 / total.planned.1 as f64,
        total.single.1 as f64 / total.planned.1 as f64,
    );
}
