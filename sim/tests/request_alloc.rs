//! The simulator's request path allocates nothing once warm: reads and writes through
//! `Simulator::handle`, the drive model's tick included, counted with a global allocator that
//! counts the allocations of the current thread.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use drivemap_runtime::pdu::Request;
use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::{rtu, tcp};
use drivemap_sim::{SimOptions, Simulator};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

fn simulator(id: &str) -> Simulator {
    let path = format!("{}/../maps/{id}.yaml", env!("CARGO_MANIFEST_DIR"));
    let drive = drivemap_codegen::read_map(path.as_ref(), &Default::default()).unwrap();
    Simulator::new(drive, SimOptions::default()).unwrap()
}

/// Allocations per request over 100 requests, after 10 to warm up; every request answered
/// without an exception.
fn per_request(sim: &mut Simulator, request: Request<'_>) -> f64 {
    let mut frame = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(sim.slave(), &request, &mut frame).unwrap();
    let mut out = [0u8; tcp::MAX_FRAME];
    let mut run = |sim: &mut Simulator| {
        let h = sim.handle(TransportKind::Rtu, &frame[..n], &mut out);
        let reply = h.reply.expect("a reply");
        assert_eq!(out[1], request.function(), "{:02X?}", &out[..reply]);
    };
    for _ in 0..10 {
        run(sim);
    }
    let before = allocations();
    for _ in 0..100 {
        run(sim);
    }
    (allocations() - before) as f64 / 100.0
}

#[test]
fn reads_allocate_nothing() {
    for (id, address) in [
        ("ptlk-tds-v8", 0x0020),
        ("yaskawa-v7", 0x0020),
        ("yaskawa-j7", 0x0020),
        ("yaskawa-gpd515", 0x0020),
        ("automationdirect-acn", 0x0300),
    ] {
        let mut sim = simulator(id);
        let quantity = sim.profile().max_read.min(16);
        let per = per_request(&mut sim, Request::ReadHolding { address, quantity });
        assert_eq!(
            per, 0.0,
            "{id}: {per} allocations per {quantity}-register read"
        );
    }
}

#[test]
fn writes_allocate_nothing() {
    // TDS-V8 Bn-01 (0200h) = 10.0 s; V7 frequency reference (0002h) = 0.
    for (id, address, value) in [("ptlk-tds-v8", 0x0200, 100), ("yaskawa-v7", 0x0002, 0)] {
        let mut sim = simulator(id);
        let per = per_request(&mut sim, Request::WriteSingle { address, value });
        assert_eq!(per, 0.0, "{id}: {per} allocations per write");
    }
}
