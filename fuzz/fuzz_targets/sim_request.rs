//! The simulator's request handling must never panic, whatever frame arrives, on any shipped
//! map and either framing; every reply it writes must fit the buffer and be a well-formed frame.
#![no_main]

use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::{crc, tcp};
use drivemap_sim::{clock::ManualClock, SimOptions, Simulator};
use libfuzzer_sys::fuzz_target;

const MAPS: [&str; 5] = [
    "ptlk-tds-v8",
    "yaskawa-v7",
    "yaskawa-j7",
    "yaskawa-gpd515",
    "automationdirect-acn",
];

struct Sims {
    clock: ManualClock,
    sims: Vec<Mutex<Simulator>>,
}

fn sims() -> &'static Sims {
    static SIMS: OnceLock<Sims> = OnceLock::new();
    SIMS.get_or_init(|| {
        let clock = ManualClock::new();
        let sims = MAPS
            .iter()
            .map(|id| {
                let path = format!("{}/../maps/{id}.yaml", env!("CARGO_MANIFEST_DIR"));
                let drive = drivemap_map::Loader::new()
                    .load(path.as_ref())
                    .expect("shipped map");
                let sim = Simulator::new(drive, SimOptions::new().clock(Arc::new(clock.clone())))
                    .expect("simulator of a shipped map");
                Mutex::new(sim)
            })
            .collect();
        Sims { clock, sims }
    })
}

fuzz_target!(|data: &[u8]| {
    // Byte 0: map and framing; then frames, each prefixed by its length byte. Frames run one
    // after another against the same simulator, so a write can change what a later read sees.
    let [sel, rest @ ..] = data else {
        return;
    };
    let sims = sims();
    let mut sim = match sims.sims[usize::from(sel % 5)].lock() {
        Ok(g) => g,
        Err(p) => p.into_inner(),
    };
    let kind = match (sel / 5) % 3 {
        0 => TransportKind::Rtu,
        1 => TransportKind::RtuOverTcp,
        _ => TransportKind::Tcp,
    };
    let mut rest = rest;
    let mut out = [0u8; tcp::MAX_FRAME];
    while let [len, tail @ ..] = rest {
        let n = usize::from(*len).min(tail.len());
        let (frame, next) = tail.split_at(n);
        rest = next;
        let handled = sim.handle(kind, frame, &mut out);
        if let Some(m) = handled.reply {
            assert!(m <= out.len());
            if kind.is_rtu_framed() {
                assert!(m >= 5, "an RTU reply holds slave, function, data and CRC");
                assert!(crc::check(&out[..m]).is_ok(), "reply CRC");
                assert_eq!(out[0], frame[0], "reply from the slave addressed");
            } else {
                let h = tcp::Header::parse(&out[..m]).ok().flatten().expect("reply header");
                assert_eq!(h.frame_len(), m, "MBAP length agrees with the reply");
                assert_eq!(&out[..2], &frame[..2], "transaction id echoed");
            }
        }
        sims.clock.advance(Duration::from_millis(u64::from(*len % 8) * 100));
        sim.tick();
    }
});
