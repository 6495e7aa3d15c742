//! Indexed access under injected faults: a value is never attributed to the wrong entry, and a
//! write never lands on another entry, whatever happens to the replies (lost, late, duplicated,
//! delayed past the timeout) and whatever another master or the keypad selects between calls.
//!
//! The drive is the fictional Tarrow TM-44 (`tests/fixtures/tarrow-tm44`: index in register 44,
//! value in 45), served by a [`SimulatedSlave`] with its pairs behind a [`FaultyLink`]. The
//! property runs on the client's `read_entry`/`write_entry`, and the same scenario is shown to
//! break a naive strategy that writes the index only when it believes another entry is selected.

use drivemap_test_support::paths;

use std::io;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use drivemap_map::MapPlan;
use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::indexed::{EntryRef, Indexed};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::error::Error;
use drivemap_runtime::transport::Transport;
use drivemap_sim::SimulatedSlave;
use drivemap_sim::{Fault, FaultyLink};
use proptest::prelude::*;

fn plan() -> &'static MapPlan {
    static PLAN: OnceLock<MapPlan> = OnceLock::new();
    PLAN.get_or_init(|| {
        let dir = paths::fixture("tarrow-tm44");
        let drive = drivemap_map::Loader::new()
            .manuals(dir.join("manuals"))
            .load(&dir.join("tarrow-tm44.yaml"))
            .unwrap_or_else(|d| panic!("{d}"));
        drive.plan().clone()
    })
}

fn pair() -> &'static Indexed {
    &plan().indexed[0]
}

fn entry(i: usize) -> EntryRef {
    let pair = pair();
    EntryRef {
        pair,
        entry: &pair.entries[i],
    }
}

/// The link with another master on the line: after the client's next write to the index
/// register reaches the drive, it selects `meddle` there (between the two requests of a call).
struct Line {
    link: FaultyLink,
    meddle: Option<u16>,
}

impl Line {
    fn slave(&mut self) -> &mut SimulatedSlave {
        &mut self.link.slave
    }
}

impl Transport for Line {
    fn kind(&self) -> TransportKind {
        self.link.kind()
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.link.send(frame)?;
        let pdu = if self.kind() == TransportKind::Tcp {
            &frame[7..]
        } else {
            &frame[1..]
        };
        let index = pair().index_address.to_be_bytes();
        if pdu[0] == 0x06
            && pdu[1..3] == index
            && let Some(other) = self.meddle.take()
        {
            self.link.slave.set_holding(pair().index_address, other);
        }
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.link.recv(buf, deadline)
    }
    fn inter_char_timeout(&self) -> Option<Duration> {
        self.link.inter_char_timeout()
    }
    fn discard_input(&mut self) -> io::Result<()> {
        self.link.discard_input()
    }
}

fn client(kind: TransportKind, retries: u8) -> Client<Line> {
    let plan = plan();
    let slave = SimulatedSlave::new(1, plan.profile).with_indexed(plan.indexed);
    let options = ClientOptions {
        timeout: Duration::from_millis(25),
        retries,
        request_gap: Duration::ZERO,
        ..ClientOptions::default()
    };
    let line = Line {
        link: FaultyLink::new(kind, slave),
        meddle: None,
    };
    Client::with_options(line, plan.profile, options)
}

/// What one step does.
#[derive(Debug, Clone)]
enum Op {
    /// Read entry `n` (an index into the listed entries).
    Read(usize),
    /// Write the raw word `raw` (kept inside the entry's range) to entry `n`.
    Write(usize, u16),
    /// Another master or the keypad selects index `i` in register 44.
    Select(u16),
    /// The keypad changes entry `n`'s value to `raw`.
    Keypad(usize, u16),
    /// Another master selects index `i` right after the next index write of the client.
    SelectDuring(u16),
}

/// Faults for the requests of the next call, in order (`None`: a clean reply).
type Faults = Vec<Option<Fault>>;

fn fault() -> impl Strategy<Value = Option<Fault>> {
    prop_oneof![
        3 => Just(None),
        1 => Just(Some(Fault::Drop)),
        1 => Just(Some(Fault::LateReply)),
        1 => Just(Some(Fault::Duplicate)),
        1 => Just(Some(Fault::Delay(Duration::from_millis(40)))),
        1 => Just(Some(Fault::Delay(Duration::from_millis(5)))),
    ]
}

fn op() -> impl Strategy<Value = Op> {
    let n = pair().entries.len();
    prop_oneof![
        4 => (0..n).prop_map(Op::Read),
        3 => (0..n, any::<u16>()).prop_map(|(e, r)| Op::Write(e, r)),
        1 => (1u16..=12).prop_map(Op::Select),
        1 => (0..n, any::<u16>()).prop_map(|(e, r)| Op::Keypad(e, r)),
        1 => (1u16..=12).prop_map(Op::SelectDuring),
    ]
}

/// A raw word inside entry `n`'s range.
fn in_range(n: usize, raw: u16) -> u16 {
    let r = pair().entries[n].range;
    let span = (r.max - r.min + 1) as u64;
    (r.min + (u64::from(raw) % span) as i64) as u16
}

/// How a strategy reaches an entry.
trait Access {
    fn read(&mut self, c: &mut Client<Line>, n: usize) -> Result<f64, Error>;
    fn write(&mut self, c: &mut Client<Line>, n: usize, value: f64) -> Result<(), Error>;
}

/// The client's own calls.
struct OneCall;

impl Access for OneCall {
    fn read(&mut self, c: &mut Client<Line>, n: usize) -> Result<f64, Error> {
        c.read_entry(1, entry(n))
    }
    fn write(&mut self, c: &mut Client<Line>, n: usize, value: f64) -> Result<(), Error> {
        c.write_entry(1, entry(n), value)
    }
}

/// The naive strategy: remembers the index it last wrote successfully and writes the index only
/// when another entry is wanted; never reads the index back.
#[derive(Default)]
struct Cached {
    selected: Option<u16>,
}

impl Cached {
    fn select(&mut self, c: &mut Client<Line>, index: u16) -> Result<(), Error> {
        if self.selected != Some(index) {
            c.write_register(1, pair().index_address, index)?;
            self.selected = Some(index);
        }
        Ok(())
    }
}

impl Access for Cached {
    fn read(&mut self, c: &mut Client<Line>, n: usize) -> Result<f64, Error> {
        let e = entry(n).entry;
        self.select(c, e.index)?;
        let mut w = [0u16; 1];
        c.read_holding(1, pair().value_address, &mut w)?;
        Ok(e.decode(w[0]))
    }
    fn write(&mut self, c: &mut Client<Line>, n: usize, value: f64) -> Result<(), Error> {
        let e = entry(n).entry;
        let raw = e.encode(value)?;
        self.select(c, e.index)?;
        c.write_rule(1, &e.rule, pair().value_address, u32::from(raw))
    }
}

fn held(c: &mut Client<Line>, index: u16) -> u16 {
    c.transport()
        .slave()
        .indexed
        .value(pair().register, index)
        .unwrap_or(0)
}

/// Runs `ops`, each with its faults; `Err` names the first value attributed to the wrong entry
/// or the first write that changed another entry.
fn run(access: &mut dyn Access, c: &mut Client<Line>, ops: &[(Op, Faults)]) -> Result<(), String> {
    let entries = pair().entries;
    for (step, (op, faults)) in ops.iter().enumerate() {
        for f in faults {
            // A clean reply is a fault with nothing to add.
            c.transport()
                .link
                .inject(f.clone().unwrap_or(Fault::Noise(Vec::new())));
        }
        let before: Vec<u16> = entries.iter().map(|e| held(c, e.index)).collect();
        match *op {
            Op::Read(n) => {
                let got = access.read(c, n);
                if let Ok(v) = got {
                    let truth = entries[n].decode(before[n]);
                    if v != truth {
                        return Err(format!(
                            "step {step}: read {v} as {} whose value is {truth}",
                            entries[n].id
                        ));
                    }
                }
            }
            Op::Write(n, raw) => {
                let raw = in_range(n, raw);
                let value = entries[n].decode(raw);
                let result = access.write(c, n, value);
                for (k, e) in entries.iter().enumerate() {
                    let now = held(c, e.index);
                    if k != n && now != before[k] {
                        return Err(format!(
                            "step {step}: writing {} changed {} ({} -> {now})",
                            entries[n].id, e.id, before[k]
                        ));
                    }
                }
                if result.is_ok() && held(c, entries[n].index) != raw {
                    return Err(format!("step {step}: {} not written", entries[n].id));
                }
            }
            Op::Select(i) => c.transport().slave().set_holding(pair().index_address, i),
            Op::SelectDuring(i) => c.transport().meddle = Some(i),
            Op::Keypad(n, raw) => {
                let raw = in_range(n, raw);
                c.transport()
                    .slave()
                    .indexed
                    .set(pair().register, entries[n].index, raw);
            }
        }
        // Faults the call did not use (it was refused, or ended early) are dropped.
        c.transport().link.clear_faults();
        // Late and delayed replies still on their way arrive before the next step.
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn a_value_is_never_attributed_to_the_wrong_entry(
        tcp in any::<bool>(),
        retries in 0u8..2,
        ops in prop::collection::vec((op(), prop::collection::vec(fault(), 0..3)), 1..14),
    ) {
        let kind = if tcp { TransportKind::Tcp } else { TransportKind::Rtu };
        let mut c = client(kind, retries);
        let outcome = run(&mut OneCall, &mut c, &ops);
        prop_assert!(outcome.is_ok(), "{}", outcome.unwrap_err());
    }
}

/// A lost reply to an index write: the drive selected the entry, the naive strategy believes
/// the previous one still is and reads the other entry's value as its own; the client writes the
/// index before every access and verifies it, and reads right.
#[test]
fn a_lost_reply_to_the_index_write_misleads_a_naive_strategy_only() {
    let scenario = vec![
        (Op::Keypad(0, 50), vec![]),
        (Op::Keypad(1, 70), vec![]),
        (Op::Read(0), vec![]),
        // The reply to the index write (2) is lost: the drive shows deceleration time now.
        (Op::Read(1), vec![Some(Fault::Drop)]),
        (Op::Read(0), vec![]),
        (Op::Write(0, 123), vec![]),
    ];
    for kind in [TransportKind::Rtu, TransportKind::Tcp] {
        let mut c = client(kind, 0);
        assert_eq!(run(&mut OneCall, &mut c, &scenario), Ok(()), "{kind:?}");
        let mut c = client(kind, 0);
        let naive = run(&mut Cached::default(), &mut c, &scenario);
        assert_eq!(
            naive,
            Err("step 4: read 7.1 as acceleration_time whose value is 5.1".to_owned()),
            "{kind:?}"
        );
    }
}

/// Another master selects another entry between the index write and the value access: the
/// client refuses the read (it reads the index with the value, in one 03h request of registers
/// 44 and 45) and writes nothing (it reads the index back first); the naive strategy reads and
/// writes the other entry.
#[test]
fn another_selection_between_the_two_is_refused() {
    let scenario = vec![
        (Op::Keypad(0, 50), vec![]),
        (Op::Keypad(1, 70), vec![]),
        (Op::SelectDuring(2), vec![]),
        (Op::Read(0), vec![]),
        (Op::SelectDuring(2), vec![]),
        (Op::Write(0, 99), vec![]),
    ];
    let mut c = client(TransportKind::Rtu, 0);
    assert_eq!(run(&mut OneCall, &mut c, &scenario), Ok(()));
    let mut c = client(TransportKind::Rtu, 0);
    c.transport().slave().indexed.set(pair().register, 1, 50);
    c.transport().meddle = Some(2);
    let e = c.read_entry(1, entry(0)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "parameter_value: parameter_index shows index 2, not 1 as just written (another master or the keypad selected another entry); the value was not taken as entry 1's"
    );
    let last = c.transport().link.sent.last().unwrap().clone();
    assert_eq!(&last[1..6], &[0x03, 0x00, 44, 0x00, 2]);
    c.transport().meddle = Some(2);
    let (accel, decel) = (held(&mut c, 1), held(&mut c, 2));
    let e = c.write_entry(1, entry(0), 9.9).unwrap_err();
    assert!(
        matches!(
            e,
            Error::IndexChanged {
                selected: 1,
                shown: 2,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!((held(&mut c, 1), held(&mut c, 2)), (accel, decel));
    let mut c = client(TransportKind::Rtu, 0);
    let naive = run(&mut Cached::default(), &mut c, &scenario);
    assert!(naive.is_err(), "{naive:?}");
}

/// The gate checks both words before anything is sent: an index outside the index register's
/// range, a value outside the entry's range, and a write to a read-only entry are refused with
/// nothing on the wire.
#[test]
fn the_gate_checks_the_index_and_the_value() {
    let mut c = client(TransportKind::Rtu, 0);
    let hours = pair().entry("total_running_hours").unwrap();
    let hours = EntryRef {
        pair: pair(),
        entry: hours,
    };
    let max = entry(2);
    let e = c.write_entry(1, max, 61.0).unwrap_err();
    assert!(e.is_refusal(), "{e}");
    let e = c.write_entry(1, hours, 10.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "refused before sending: total_running_hours is read-only"
    );
    let e = c.read_indexed(1, pair(), 41).unwrap_err();
    assert_eq!(
        e.to_string(),
        "refused before sending: parameter_index: raw value 41 is outside 1 ..= 40, the map's range for it"
    );
    let e = c
        .write_indexed(1, pair(), &max.entry.rule, 3, 6001)
        .unwrap_err();
    assert!(e.is_refusal(), "{e}");
    assert!(c.transport().link.sent.is_empty());
    c.write_entry(1, max, 50.0).unwrap();
    assert_eq!(held(&mut c, 3), 5000);
    // The value read back through the pair, and an unlisted index by raw word.
    assert_eq!(c.read_entry(1, max).unwrap(), 50.0);
    assert_eq!(c.read_indexed(1, pair(), 5).unwrap(), 0);
}
