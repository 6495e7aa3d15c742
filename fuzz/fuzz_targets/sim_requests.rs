//! The simulator's request handling and its RTU framer on arbitrary bytes, for every shipped
//! map: nothing panics, every reply fits its buffer and is a well-formed frame (RTU: CRC;
//! Modbus TCP: MBAP length), and the serving loop ends when the peer does.
#![no_main]

use std::io;
use std::sync::atomic::AtomicBool;
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{crc, tcp};
use drivemap_sim::{Limits, SharedSim, SimOptions, Simulator, serve_link, shared};
use libfuzzer_sys::fuzz_target;

const MAPS: [&str; 5] = [
    "automationdirect-acn",
    "ptlk-tds-v8",
    "yaskawa-gpd515",
    "yaskawa-j7",
    "yaskawa-v7",
];

fn sims() -> &'static [SharedSim] {
    static SIMS: OnceLock<Vec<SharedSim>> = OnceLock::new();
    SIMS.get_or_init(|| {
        MAPS.iter()
            .map(|id| {
                let path = format!("{}/../maps/{id}.yaml", env!("CARGO_MANIFEST_DIR"));
                let drive = drivemap_codegen::read_map(path.as_ref(), &Default::default())
                    .unwrap_or_else(|e| panic!("{id}: {e}"));
                shared(Simulator::new(drive, SimOptions::default()).expect("simulator"))
            })
            .collect()
    })
}

/// A link that delivers the input in chunks, then hangs up; checks every reply it is sent.
struct Scripted<'a> {
    kind: TransportKind,
    chunks: std::slice::Chunks<'a, u8>,
}

impl Transport for Scripted<'_> {
    fn kind(&self) -> TransportKind {
        self.kind
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        check_reply(self.kind, frame);
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], _deadline: Instant) -> io::Result<usize> {
        match self.chunks.next() {
            Some(c) => {
                let n = c.len().min(buf.len());
                buf[..n].copy_from_slice(&c[..n]);
                Ok(n)
            }
            None => Err(io::Error::new(io::ErrorKind::UnexpectedEof, "done")),
        }
    }
}

fn check_reply(kind: TransportKind, frame: &[u8]) {
    if kind.is_rtu_framed() {
        assert!(frame.len() >= 5, "RTU reply too short: {frame:02X?}");
        assert!(crc::check(frame).is_ok(), "RTU reply with a bad CRC: {frame:02X?}");
    } else {
        assert!(frame.len() >= tcp::HEADER_LEN + 2);
        let len = usize::from(u16::from_be_bytes([frame[4], frame[5]]));
        assert_eq!(len + 6, frame.len(), "MBAP length of the reply: {frame:02X?}");
    }
}

static LOG: Mutex<()> = Mutex::new(());

fuzz_target!(|data: &[u8]| {
    let [sel, chunk, rest @ ..] = data else {
        return;
    };
    let _one_at_a_time = LOG.lock().unwrap_or_else(|e| e.into_inner());
    let sim = &sims()[usize::from(*sel) % MAPS.len()];
    let kind = match (sel >> 4) % 3 {
        0 => TransportKind::Rtu,
        1 => TransportKind::RtuOverTcp,
        _ => TransportKind::Tcp,
    };
    // One frame handled directly.
    let mut out = [0u8; tcp::MAX_FRAME];
    let handled = drivemap_sim::server::lock(sim).handle(kind, rest, &mut out);
    if let Some(n) = handled.reply {
        assert!(n <= out.len());
        check_reply(kind, &out[..n]);
    }
    // The same bytes through the serving loop and its framer, in chunks of 1-32 bytes.
    let mut link = Scripted {
        kind,
        chunks: rest.chunks(usize::from(chunk % 32) + 1),
    };
    let stop = AtomicBool::new(false);
    let t = Instant::now();
    let _ = serve_link(sim, &mut link, &stop, None, Duration::from_millis(100), &Limits::default());
    assert!(t.elapsed() < Duration::from_secs(5), "serving {} bytes took {:?}", rest.len(), t.elapsed());
});
