//! The simulator's framer must never panic, hold more than its budget, or hand over a frame
//! longer than what it holds, whatever bytes arrive, however they are split and timed.
#![no_main]

use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::TransportKind;
use drivemap_sim::server::{FrameLimits, Framer, Next};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // Byte 0: framing. Then chunks: [gap in 10 ms steps, length, bytes...].
    let [sel, rest @ ..] = data else {
        return;
    };
    let mut rest = rest;
    let kind = match sel % 3 {
        0 => TransportKind::Rtu,
        1 => TransportKind::RtuOverTcp,
        _ => TransportKind::Tcp,
    };
    let limits = FrameLimits {
        silence: Duration::from_millis(100),
        frame_deadline: Duration::from_secs(1),
        idle_timeout: None,
    };
    let mut now = Instant::now();
    let mut framer = Framer::new(kind, limits, now);
    let mut frames = 0usize;
    while let [gap, len, tail @ ..] = rest {
        let n = usize::from(*len).min(tail.len());
        let (bytes, next) = tail.split_at(n);
        rest = next;
        now += Duration::from_millis(u64::from(*gap) * 10);
        framer.push(bytes, now);
        assert!(framer.bytes().len() <= 2 * 260, "framer over its budget");
        loop {
            match framer.next(now) {
                Next::Frame(m) => {
                    assert!(m > 0 && m <= framer.bytes().len());
                    if kind == TransportKind::Tcp {
                        assert!(m <= 260);
                    }
                    framer.consume(m, now);
                    frames += 1;
                    assert!(frames <= data.len(), "a frame per byte at most");
                }
                Next::Wait => break,
                Next::Close => return,
            }
        }
    }
});
