//! The serial line at its speed: the emulated line's analysis finds every broken timing rule
//! (property test with faults injected into a correct record), and drivemap's planned poller,
//! polling the V7's monitor registers through an emulated 9600-baud line against a simulated
//! V7 that keeps its manual's response time, breaks none of them and stays within 10 % of the
//! bus-time model (the short form of `examples/line_report.rs`; the full table is in
//! `docs/performance.md`).

#![cfg(unix)]

use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::client::ClientOptions;
use drivemap_test_support::line::{Char, Direction, Violation, analyse};
use drivemap_tests::line_bench;
use proptest::prelude::*;
use std::time::Duration;

/// The tests on an emulated line run one at a time.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A read of `quantity` registers from slave 1 and its reply, as the wire carries them.
fn read_frames(quantity: u16) -> (Vec<u8>, Vec<u8>) {
    let mut request = vec![1, 3, 0, 0x20, 0, quantity as u8];
    let crc = drivemap_runtime::crc::crc_bytes(&request);
    request.extend_from_slice(&crc);
    let mut reply = vec![1, 3, (2 * quantity) as u8];
    reply.extend(std::iter::repeat_n(0u8, 2 * usize::from(quantity)));
    let crc = drivemap_runtime::crc::crc_bytes(&reply);
    reply.extend_from_slice(&crc);
    (request, reply)
}

/// Characters of `bytes` in `direction` back to back from `start` (ns), each `char_ns` long,
/// with `extra[i]` ns of silence before character i.
fn chars(
    bytes: &[u8],
    direction: Direction,
    start: f64,
    char_ns: f64,
    extra: &[f64],
) -> (Vec<Char>, f64) {
    let mut t = start;
    let mut out = Vec::new();
    for (i, &byte) in bytes.iter().enumerate() {
        t += extra.get(i).copied().unwrap_or(0.0);
        out.push(Char {
            direction,
            byte,
            start_ns: t.round() as u64,
            end_ns: (t + char_ns).round() as u64,
        });
        t += char_ns;
    }
    (out, t)
}

/// A V7 model (24 bits + 10 ms before the reply, 24 bits + 10 ms after it) at `baud`.
fn v7(baud: u32) -> BusModel {
    BusModel::new(
        &drivemap_drives::yaskawa_v7::PROFILE,
        SerialConfig::new(baud),
    )
}

#[derive(Debug, Clone, Copy)]
enum Fault {
    None,
    /// The request after transaction `k` starts this fraction of the required gap early.
    EarlyRequest(usize, f64),
    /// Character `i` of request `k` comes this many character times late (> 1.5).
    GapInRequest(usize, usize, f64),
    /// The reply to request `k` starts this fraction of a character before the request ends.
    Collision(usize, f64),
}

fn fault() -> impl Strategy<Value = Fault> {
    prop_oneof![
        Just(Fault::None),
        (0usize..4, 0.05f64..0.95).prop_map(|(k, f)| Fault::EarlyRequest(k, f)),
        (0usize..5, 1usize..8, 1.6f64..3.0).prop_map(|(k, i, c)| Fault::GapInRequest(k, i, c)),
        (0usize..5, 0.1f64..4.0).prop_map(|(k, f)| Fault::Collision(k, f)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Five transactions laid on the wire with the silences the rules require (plus random
    /// slack), then one fault injected: the analysis reports exactly that fault, and nothing
    /// on the correct record; the transactions' times are those laid.
    #[test]
    fn the_analysis_finds_each_broken_rule(
        baud in prop::sample::select(vec![1200u32, 4800, 9600, 19_200, 38_400]),
        quantities in prop::collection::vec(1u16..=8, 5),
        slack in prop::collection::vec(0f64..5e6, 10),
        fault in fault(),
    ) {
        let model = v7(baud);
        let char_ns = model.serial.char_ns();
        let mut record = Vec::new();
        let mut t = 1e6;
        let mut starts = Vec::new();
        for (k, &q) in quantities.iter().enumerate() {
            let (request, reply) = read_frames(q);
            if k > 0 {
                let gap = model.turnaround_ns().ceil() + slack[2 * k];
                t += match fault {
                    Fault::EarlyRequest(e, f) if e + 1 == k => gap - slack[2 * k] - f * model.turnaround_ns(),
                    _ => gap,
                };
            }
            let mut extra = vec![0.0; request.len()];
            if let Fault::GapInRequest(g, i, c) = fault && g == k {
                extra[i] = c * char_ns;
            }
            starts.push(t.round() as u64);
            let (chars_out, end) = chars(&request, Direction::ToDrive, t, char_ns, &extra);
            record.extend(chars_out);
            let latency = match fault {
                Fault::Collision(c, f) if c == k => -f * char_ns,
                _ => model.latency_ns().ceil() + slack[2 * k + 1],
            };
            let (reply_chars, reply_end) = chars(&reply, Direction::ToMaster, end + latency, char_ns, &[]);
            record.extend(reply_chars);
            t = reply_end;
        }
        record.sort_by_key(|c| c.start_ns);
        let report = analyse(&record, &model);
        match fault {
            Fault::None => {
                prop_assert!(report.violations.is_empty(), "{:?}", report.violations);
                prop_assert_eq!(report.transactions.len(), 5);
                for (t, s) in report.transactions.iter().zip(&starts) {
                    prop_assert_eq!(t.start_ns, *s);
                    prop_assert!(t.reply_end_ns.is_some());
                }
            }
            Fault::EarlyRequest(..) => {
                prop_assert_eq!(report.violations.len(), 1, "{:?}", report.violations);
                let is_early = matches!(
                    report.violations[0],
                    Violation::EarlyFrame { direction: Direction::ToDrive, .. }
                );
                prop_assert!(is_early, "{:?}", report.violations);
            }
            Fault::GapInRequest(..) => {
                prop_assert!(!report.violations.is_empty());
                let gap = report.violations.iter().any(|v| matches!(
                    v,
                    Violation::GapInFrame { direction: Direction::ToDrive, .. }
                ));
                prop_assert!(gap, "{:?}", report.violations);
            }
            Fault::Collision(..) => {
                let collision = report.violations.iter().any(|v| matches!(v, Violation::Collision { .. }));
                prop_assert!(collision, "{:?}", report.violations);
            }
        }
    }
}

/// The short form of the line report: the V7's monitor registers, all once and four random
/// halves, at 9600 baud: no rule broken, every register read, the cycle on the wire within
/// 10 % of the model, and the client asleep while the line is busy.
#[test]
fn the_planned_poller_keeps_the_v7s_timing_within_10_percent_of_the_model() {
    let m = line_bench::monitors()
        .into_iter()
        .find(|m| m.id == "yaskawa-v7")
        .expect("the V7 map");
    let line = line_bench::line_for(m.profile, 9600);
    let mut sets = vec![m.wanted.clone()];
    sets.extend(line_bench::halves(&m.wanted, 4, 0xB05_7173));
    let _one = ONE_AT_A_TIME.lock();
    let (measured, realtime) =
        line_bench::on_realtime_thread(|| line_bench::planned(&m, line, &sets));
    let measured = measured.expect("the emulated line");
    println!(
        "V7 9600 (real-time priority: {realtime}): {} cycles, {} requests, measured {:.1} ms, model {:.1} ms, ratio {:.3}, client CPU {:.0} µs/cycle, relay late up to {:.2} ms",
        measured.cycles,
        measured.requests,
        measured.measured_ns as f64 / 1e6,
        measured.model_ns as f64 / 1e6,
        measured.ratio(),
        measured.cpu_us_per_cycle(),
        measured.relay_max_late_ns as f64 / 1e6
    );
    assert_eq!(measured.errors, 0, "every wanted register read");
    assert!(
        measured.violations.is_empty(),
        "timing rules broken: {:#?}",
        measured.violations
    );
    assert!(
        measured.ratio() >= 1.0,
        "faster than the model: {}",
        measured.ratio()
    );
    assert!(
        measured.ratio() <= 1.10,
        "{:.3} × the model",
        measured.ratio()
    );
    // The simulated V7 answers after 24 bits + n156 (10 ms), not sooner.
    assert!(measured.latency_ns >= measured.model_latency_ns);
    // It sleeps: its CPU time is a small part of the cycle.
    assert!(
        (measured.client_cpu_ns as f64) < 0.05 * measured.measured_ns as f64,
        "client CPU {} ns of {} ns",
        measured.client_cpu_ns,
        measured.measured_ns
    );
}

/// A client that keeps no request gap (the V7 asks 24 bits + 10 ms after each reply) is caught
/// on the line: every request after a reply is a frame inside the required silence.
#[test]
fn a_client_that_keeps_no_request_gap_is_caught_on_the_line() {
    let m = line_bench::monitors()
        .into_iter()
        .find(|m| m.id == "yaskawa-v7")
        .expect("the V7 map");
    let line = line_bench::line_for(m.profile, 19_200);
    let sets = vec![m.wanted.clone()];
    let _one = ONE_AT_A_TIME.lock();
    let measured = line_bench::planned_with(&m, line, &sets, |o| ClientOptions {
        request_gap: Duration::ZERO,
        ..o
    })
    .expect("the emulated line");
    let early = measured
        .violations
        .iter()
        .filter(|v| {
            matches!(
                v,
                Violation::EarlyFrame {
                    direction: Direction::ToDrive,
                    ..
                }
            )
        })
        .count();
    assert!(
        early >= measured.requests,
        "{early} early requests of {}: {:#?}",
        measured.requests,
        measured.violations
    );
    // Not asserted: that the cycle is shorter than the model's. It is on an idle machine (the
    // rules' silences left out), but a wall-clock figure; on a loaded one the scheduler adds
    // the time back, and the test failed so (CI, load average 12) with every early request
    // caught. What the line shows, frame by frame, is the claim; speed is docs/performance.md's.
}
