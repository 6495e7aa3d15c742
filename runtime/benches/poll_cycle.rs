//! CPU time and heap allocations of a planned poll cycle, and of planning itself.
//!
//! The drive is a `SimulatedSlave` behind an in-memory link that answers each request as it is
//! sent, so the figures are the client's and the poller's own work (encode, check, decode, copy
//! words out), not bus time: on a real line the bus dominates (see `bus_time_report`).
//!
//! The register set is V7-like: monitor registers 0020h-003Fh with reserved holes, 8 registers
//! per read; 18 of them wanted, the way a dashboard would.
//!
//! Heap allocations are counted with a counting global allocator and printed before the
//! timings.
//!
//! Run: `cargo bench -p drivemap-runtime --bench poll_cycle`

use drivemap_test_support::alloc_count::{self, Counting};
use drivemap_test_support::instant_link::InstantLink;
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use drivemap_runtime::client::Client;
use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::register::{Access, RegisterInfo, Table};
use drivemap_runtime::planner::{Poller, ReadableSet, plan_contiguous, plan_reads, plan_single};
use drivemap_sim::SimulatedSlave;

#[global_allocator]
static GLOBAL: Counting = Counting;

static PROFILE: Profile = Profile {
    drive_id: "yaskawa-v7",
    function_codes: &[0x03, 0x06, 0x08, 0x10],
    max_read: 8,
    max_write: 16,
    max_read_bits: drivemap_runtime::core::stated::MODBUS_MAX_READ_BITS,
    max_write_bits: drivemap_runtime::core::stated::MODBUS_MAX_WRITE_BITS,
    ..Profile::GENERIC
};

/// Readable monitor addresses 0020h-003Fh except the reserved 0029h-002Ah, 0030h, 0039h-003Ah.
fn registers() -> Vec<RegisterInfo> {
    (0x20u16..0x40)
        .filter(|a| ![0x29, 0x2A, 0x30, 0x39, 0x3A].contains(a))
        .map(|address| RegisterInfo {
            id: "monitor",
            param: None,
            name: "monitor",
            address,
            access: Access::Read,
            table: Table::Holding,
            width: drivemap_runtime::core::width::Width::Word,
            broadcast_only: false,
            source: "",
        })
        .collect()
}

/// 18 wanted registers, scattered.
const WANTED: [u16; 18] = [
    0x20, 0x21, 0x23, 0x24, 0x26, 0x27, 0x2B, 0x2C, 0x2D, 0x2F, 0x31, 0x32, 0x34, 0x37, 0x38, 0x3B,
    0x3D, 0x3F,
];

fn client() -> Client<InstantLink> {
    let mut drive = SimulatedSlave::new(1, &PROFILE);
    for a in 0x20..0x40 {
        drive.set_holding(a, a * 3);
    }
    // The generic options: no request gap. `Client::new` keeps the drive's timing on an RTU
    // link (the frame gap after each reply, 3.6 ms at 9600 8N1), which would make this a
    // measure of sleeping, not of the client's and the poller's own work.
    Client::with_options(InstantLink::new(drive), &PROFILE, ClientOptions::generic())
}

fn allocations_per(iterations: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm up: buffers that grow once are not per cycle.
    let before = alloc_count::all_threads();
    for _ in 0..iterations {
        f();
    }
    (alloc_count::all_threads() - before) as f64 / iterations as f64
}

/// A cycle of raw reads following `reads` (for the baselines), values summed.
fn raw_cycle(client: &mut Client<InstantLink>, reads: &[drivemap_runtime::planner::Read]) -> u32 {
    let mut words = [0u16; 8];
    let mut sum = 0u32;
    for r in reads {
        let out = &mut words[..usize::from(r.quantity)];
        client.read_holding(1, r.address, out).unwrap();
        sum += out.iter().map(|&w| u32::from(w)).sum::<u32>();
    }
    sum
}

fn bench(c: &mut Criterion) {
    let registers: &'static [RegisterInfo] = Box::leak(registers().into_boxed_slice());
    let wanted: Vec<(Table, u16)> = WANTED.iter().map(|&a| (Table::Holding, a)).collect();
    let mut poller = Poller::new(&PROFILE, registers, wanted.clone()).unwrap();
    let mut client = client();
    let contiguous = plan_contiguous(&WANTED, PROFILE.max_read);
    let single = plan_single(&WANTED);

    // Sanity: every wanted register read, with its value.
    let stats = poller.poll(&mut client, 1);
    for (i, a) in WANTED.iter().enumerate() {
        assert_eq!(poller.value(i).unwrap().unwrap(), a * 3);
    }
    println!(
        "plan: {} requests for {} registers (contiguous runs: {}, one per register: {}); modelled bus time {:.1} ms at 9600 8N1",
        stats.requests,
        WANTED.len(),
        contiguous.len(),
        single.len(),
        poller.plan_ns() as f64 / 1e6
    );

    let n = 10_000;
    println!(
        "heap allocations: per planned poll cycle {:.2}, per contiguous-runs cycle {:.2}, per one-per-register cycle {:.2}, per Poller::new (planning) {:.1}",
        allocations_per(n, || {
            black_box(poller.poll(&mut client, 1));
        }),
        allocations_per(n, || {
            black_box(raw_cycle(&mut client, &contiguous));
        }),
        allocations_per(n, || {
            black_box(raw_cycle(&mut client, &single));
        }),
        allocations_per(1000, || {
            black_box(Poller::new(&PROFILE, registers, wanted.clone()).unwrap());
        }),
    );

    let mut g = c.benchmark_group("poll cycle, 18 of 27 V7-like monitor registers");
    g.bench_function("planned (Poller::poll)", |b| {
        b.iter(|| black_box(poller.poll(&mut client, 1)))
    });
    g.bench_function("contiguous runs (raw reads)", |b| {
        b.iter(|| black_box(raw_cycle(&mut client, &contiguous)))
    });
    g.bench_function("one request per register (raw reads)", |b| {
        b.iter(|| black_box(raw_cycle(&mut client, &single)))
    });
    g.finish();

    let mut g = c.benchmark_group("planning");
    g.bench_function("Poller::new, 18 wanted", |b| {
        b.iter(|| black_box(Poller::new(&PROFILE, registers, wanted.clone()).unwrap()))
    });
    // A large map: 2000 readable addresses in runs of 50, every third wanted, 16 per read.
    let big = ReadableSet::new((0u16..2400).filter(|a| a % 60 < 50));
    let big_wanted: Vec<u16> = big.addresses().iter().copied().step_by(3).collect();
    let model = drivemap_runtime::bus_time::BusModel::new(
        &PROFILE,
        drivemap_runtime::bus_time::SerialConfig::new(9600),
    );
    g.bench_function("plan_reads, 667 wanted of 2000, max_read 16", |b| {
        b.iter(|| black_box(plan_reads(&big_wanted, &big, 16, |q| model.read_ns(q)).unwrap()))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(30);
    targets = bench
}
criterion_main!(benches);
