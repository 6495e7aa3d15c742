//! One 16-register read, end to end without a link: encode the 03h request, decode the RTU
//! response, convert the 16 words to engineering values (0.1 scale). Ours (protocol core, and
//! the whole blocking client over an instant in-memory link) against rmodbus's client codec in
//! the same run. tokio-modbus keeps its codec private (`mod codec`), so it cannot be measured
//! at this level.
//!
//! Heap allocations per transaction are counted with a counting global allocator and printed
//! before the timings.
//!
//! Run: `cargo bench -p drivemap-runtime --bench read16`

use drivemap_test_support::alloc_count::{self, Counting};
use std::hint::black_box;
use std::io;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::core::scale::{Decimal, decode_decimal};
use drivemap_runtime::pdu::{Request, Response, Words};
use drivemap_runtime::reply::{Framing, ReplyBuffer};
use drivemap_runtime::rtu;
use drivemap_runtime::transport::Transport;

#[global_allocator]
static GLOBAL: Counting = Counting;

const SLAVE: u8 = 1;
const ADDRESS: u16 = 0x0020;
const SCALE: Decimal = Decimal::new(1, 1);

fn response_frame() -> Vec<u8> {
    let words: Vec<u16> = (0..16).map(|i| 6000 + i).collect();
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_response(
        SLAVE,
        0x03,
        &Response::Registers(Words::Native(&words)),
        &mut buf,
    )
    .unwrap();
    buf[..n].to_vec()
}

/// Ours, protocol core: what the client does per transaction, without a link.
fn ours(reply: &[u8], tx: &mut [u8; rtu::MAX_FRAME], rx: &mut ReplyBuffer, out: &mut [f64; 16]) {
    let request = Request::ReadHolding {
        address: ADDRESS,
        quantity: 16,
    };
    let n = rtu::encode_request(SLAVE, &request, tx).unwrap();
    black_box(&tx[..n]);
    rx.clear();
    rx.push(reply);
    let range = rx.scan(Framing::Rtu { slave: SLAVE }, &request).unwrap();
    let Ok(Response::Registers(words)) = rtu::decode_response(SLAVE, &request, rx.frame(range))
    else {
        panic!("not decoded");
    };
    let mut raw = [0u16; 16];
    words.copy_to(&mut raw);
    for (v, r) in out.iter_mut().zip(raw) {
        *v = decode_decimal(r, false, SCALE);
    }
}

/// rmodbus's client codec with reused buffers.
fn rmodbus(reply: &[u8], request: &mut Vec<u8>, words: &mut Vec<u16>, out: &mut [f64; 16]) {
    use rmodbus::{ModbusProto, client::ModbusRequest};
    let mut mreq = ModbusRequest::new(SLAVE, ModbusProto::Rtu);
    request.clear();
    mreq.generate_get_holdings(ADDRESS, 16, request).unwrap();
    black_box(&request[..]);
    words.clear();
    mreq.parse_u16(reply, words).unwrap();
    for (v, r) in out.iter_mut().zip(words.iter()) {
        *v = decode_decimal(*r, false, SCALE);
    }
}

/// A link that answers every request at once with the canned reply.
struct Instant16 {
    reply: Vec<u8>,
    pending: bool,
}

impl Transport for Instant16 {
    fn kind(&self) -> TransportKind {
        TransportKind::Rtu
    }
    fn send(&mut self, _: &[u8]) -> io::Result<()> {
        self.pending = true;
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], _: Instant) -> io::Result<usize> {
        if !self.pending {
            return Ok(0);
        }
        self.pending = false;
        let n = self.reply.len().min(buf.len());
        buf[..n].copy_from_slice(&self.reply[..n]);
        Ok(n)
    }
}

static PROFILE: Profile = Profile {
    max_read: 16,
    ..Profile::GENERIC
};

fn client_read(client: &mut Client<Instant16>, out: &mut [f64; 16]) {
    let mut raw = [0u16; 16];
    client.read_holding(SLAVE, ADDRESS, &mut raw).unwrap();
    for (v, r) in out.iter_mut().zip(raw) {
        *v = decode_decimal(r, false, SCALE);
    }
}

fn allocations_per(iterations: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm up: buffers that grow once are not per-transaction.
    let before = alloc_count::all_threads();
    for _ in 0..iterations {
        f();
    }
    (alloc_count::all_threads() - before) as f64 / iterations as f64
}

fn bench(c: &mut Criterion) {
    let reply = response_frame();
    let mut tx = [0u8; rtu::MAX_FRAME];
    let mut rx = ReplyBuffer::new();
    let mut out = [0f64; 16];
    let mut request = Vec::new();
    let mut words = Vec::new();
    let mut client = Client::with_options(
        Instant16 {
            reply: reply.clone(),
            pending: false,
        },
        &PROFILE,
        ClientOptions::default(),
    );

    // Sanity: all three agree.
    let mut a = [0f64; 16];
    let mut b = [0f64; 16];
    let mut d = [0f64; 16];
    ours(&reply, &mut tx, &mut rx, &mut a);
    rmodbus(&reply, &mut request, &mut words, &mut b);
    client_read(&mut client, &mut d);
    assert_eq!(a, b);
    assert_eq!(a, d);
    assert_eq!(a[0], 600.0);

    let n = 10_000;
    println!(
        "heap allocations per 16-register read: drivemap core {:.2}, drivemap Client {:.2}, rmodbus (reused Vec buffers) {:.2}, rmodbus (fresh Vec buffers) {:.2}",
        allocations_per(n, || ours(&reply, &mut tx, &mut rx, &mut out)),
        allocations_per(n, || client_read(&mut client, &mut out)),
        allocations_per(n, || rmodbus(&reply, &mut request, &mut words, &mut out)),
        allocations_per(n, || rmodbus(
            &reply,
            &mut Vec::new(),
            &mut Vec::new(),
            &mut out
        )),
    );

    let mut g = c.benchmark_group("read 16 registers: encode, decode, typed");
    g.bench_function("drivemap core", |bch| {
        bch.iter(|| ours(black_box(&reply), &mut tx, &mut rx, &mut out))
    });
    g.bench_function("drivemap Client (instant link)", |bch| {
        bch.iter(|| client_read(&mut client, &mut out))
    });
    g.bench_function("rmodbus", |bch| {
        bch.iter(|| rmodbus(black_box(&reply), &mut request, &mut words, &mut out))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
