//! A range chosen by a mode parameter (`limits: {selected_by}`, issue 38; the fictional
//! `tests/fixtures/lindgren-lg7`: P0640 is 10.0-400.0 % under V/f control, P1300 = 0 or 1, and
//! 10.0-150.0 % under vector control, P1300 = 20): nothing outside the range of the case the
//! drive's selector shows reaches the wire through `drivemap write`, whatever happens to the
//! selector's read.
//!
//! Property test through the CLI's own write command in-process (the code of the binary),
//! over Modbus TCP against a drive that executes every write it receives and records it with
//! the selector's code at that moment. Faults are injected on the selector: its reply lost
//! (the read times out), answered with an exception, or the selector changed by another master
//! after the read the value was converted with. The oracle's ranges come from the map's keys
//! as written (the YAML's `limits` cases), not from the plan the gate is built from; and every
//! write the case allows with no fault must arrive, once, so refusing everything fails.
//!
//! Measured: with `RegisterPlan::case` giving the union of the cases (the register's envelope)
//! instead of the selected case's range, and separately with `Session::confirm_selectors` not
//! called, this test fails (see the report of issue 38).

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use drivemap_map::Map;
use drivemap_runtime::core::profile::Profile;
use drivemap_sim::SimulatedSlave;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

use crate::common::repo;

const ID: &str = "lindgren-lg7";
const SELECTOR: u16 = 0x0100;

/// One register whose range the selector chooses, from the map as written.
#[derive(Debug, Clone)]
struct Ranged {
    name: String,
    address: u16,
    /// Raw units per engineering unit (1 / scale).
    per_unit: f64,
    /// (codes, raw min, raw max) per case.
    cases: Vec<(Vec<u16>, i64, i64)>,
}

impl Ranged {
    fn range(&self, code: u16) -> Option<(i64, i64)> {
        self.cases
            .iter()
            .find(|c| c.0.contains(&code))
            .map(|c| (c.1, c.2))
    }
}

/// The registers with `limits: {selected_by: P1300}` in the fixture, read from its YAML.
fn ranged() -> Vec<Ranged> {
    let text = std::fs::read_to_string(repo().join(format!("tests/fixtures/{ID}/{ID}.yaml")))
        .expect("fixture");
    let yaml: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let mut out = Vec::new();
    for g in yaml["groups"].as_sequence().unwrap() {
        for r in g["registers"].as_sequence().unwrap() {
            let Some(limits) = r.get("limits") else {
                continue;
            };
            let scale = r["scale"].as_f64().unwrap_or(1.0);
            let per_unit = (1.0 / scale).round();
            let address = match &r["address"] {
                serde_yaml::Value::Number(n) => u16::try_from(n.as_u64().unwrap()).unwrap(),
                v => u16::from_str_radix(v.as_str().unwrap().trim_start_matches("0x"), 16).unwrap(),
            };
            let cases = limits["cases"]
                .as_sequence()
                .unwrap()
                .iter()
                .map(|c| {
                    let codes = c["when"]
                        .as_sequence()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_u64().unwrap() as u16)
                        .collect();
                    let raw = |k: &str| (c[k].as_f64().unwrap() * per_unit).round() as i64;
                    (codes, raw("min"), raw("max"))
                })
                .collect();
            out.push(Ranged {
                name: r["param"].as_str().unwrap().to_owned(),
                address,
                per_unit,
                cases,
            });
        }
    }
    assert_eq!(out.len(), 2, "the fixture's two ranged registers");
    out
}

/// What happens to the selector's reads.
#[derive(Debug, Clone, Copy)]
enum Fault {
    None,
    /// The drive executes the read; its reply never arrives (the read times out).
    LoseReply,
    /// The drive answers the read with exception 04h.
    Exception,
    /// Another master sets the selector to this code right after the first read of it.
    ChangeAfterRead(u16),
}

#[derive(Debug, Default)]
struct Log {
    /// (address, raw word, selector code at that moment) of every register written.
    writes: Vec<(u16, u16, u16)>,
}

struct Drive {
    slave: SimulatedSlave,
    fault: Fault,
    selector_reads: u32,
    log: Log,
}

/// Serves Modbus TCP on loopback: every request goes to the simulated slave, faults applied
/// to reads covering the selector.
fn serve(drive: Arc<Mutex<Drive>>) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(stream) = stream else { continue };
            connection(stream, &drive);
        }
    });
    addr
}

fn connection(mut stream: TcpStream, drive: &Arc<Mutex<Drive>>) {
    let _ = stream.set_read_timeout(Some(Duration::from_secs(5)));
    loop {
        let mut head = [0u8; 7];
        if stream.read_exact(&mut head).is_err() {
            return;
        }
        let len = usize::from(u16::from_be_bytes([head[4], head[5]]));
        if !(1..=253).contains(&len) {
            return;
        }
        let mut frame = head.to_vec();
        frame.resize(7 + len - 1, 0);
        if stream.read_exact(&mut frame[7..]).is_err() {
            return;
        }
        let pdu = &frame[7..];
        let word = |i: usize| u16::from_be_bytes([pdu[i], pdu[i + 1]]);
        let mut d = drive.lock().unwrap();
        let reads_selector = matches!(pdu[0], 0x03 | 0x04)
            && pdu.len() >= 5
            && (word(1)..word(1).saturating_add(word(3))).contains(&SELECTOR);
        if reads_selector {
            d.selector_reads += 1;
            match d.fault {
                Fault::LoseReply => continue,
                Fault::Exception => {
                    let mut reply = head.to_vec();
                    reply[4..6].copy_from_slice(&3u16.to_be_bytes());
                    reply.extend([pdu[0] | 0x80, 0x04]);
                    let _ = stream.write_all(&reply);
                    continue;
                }
                Fault::None | Fault::ChangeAfterRead(_) => {}
            }
        }
        match pdu[0] {
            0x06 if pdu.len() >= 5 => {
                let code = d.slave.holding(SELECTOR);
                d.log.writes.push((word(1), word(3), code));
            }
            0x10 if pdu.len() >= 6 => {
                let code = d.slave.holding(SELECTOR);
                for k in 0..usize::from(word(3)) {
                    if 6 + 2 * k + 1 < pdu.len() {
                        let a = word(1) + k as u16;
                        d.log.writes.push((a, word(6 + 2 * k), code));
                    }
                }
            }
            _ => {}
        }
        let mut out = [0u8; 300];
        let n = d.slave.respond_tcp(&frame, &mut out);
        if let (true, Fault::ChangeAfterRead(code)) = (reads_selector, d.fault)
            && d.selector_reads == 1
        {
            d.slave.set_holding(SELECTOR, code);
        }
        drop(d);
        if let Some(n) = n
            && stream.write_all(&out[..n]).is_err()
        {
            return;
        }
    }
}

fn write(
    drive: &Map,
    profile: &'static Profile,
    addr: &str,
    assignment: &str,
) -> Result<ExitCode, String> {
    let maps = repo().join(format!("tests/fixtures/{ID}"));
    let argv = [
        "drivemap",
        "write",
        "--drive",
        ID,
        "--maps",
        maps.to_str().unwrap(),
        "--tcp",
        addr,
        "--timeout",
        "150ms",
        "--retries",
        "0",
        assignment,
    ];
    drivemap_cli::write_in_process(&argv, drive, profile)
}

fn fault() -> impl Strategy<Value = Fault> {
    prop_oneof![
        3 => Just(Fault::None),
        1 => Just(Fault::LoseReply),
        1 => Just(Fault::Exception),
        2 => prop::sample::select(vec![0u16, 1, 20, 7]).prop_map(Fault::ChangeAfterRead),
    ]
}

#[test]
fn nothing_outside_the_selected_range_reaches_the_wire() {
    let drive = drivemap_map::Loader::new()
        .load(&repo().join(format!("tests/fixtures/{ID}/{ID}.yaml")))
        .unwrap_or_else(|d| panic!("{d}"));
    let profile = drivemap_live::leak_profile(&drive);
    let registers = ranged();
    let state = Arc::new(Mutex::new(Drive {
        slave: SimulatedSlave::new(1, profile),
        fault: Fault::None,
        selector_reads: 0,
        log: Log::default(),
    }));
    let addr = serve(Arc::clone(&state));
    let mut runner = TestRunner::new(Config {
        cases: 96,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (
        prop::sample::select(vec![0u16, 1, 20, 7]),
        0..registers.len(),
        // Raw words around both cases' ranges, and a few beyond the word's.
        -200i64..70_000,
        fault(),
    );
    let arrived_clean = std::cell::Cell::new(0u32);
    runner
        .run(&strategy, |(mode, which, raw, fault)| {
            let r = &registers[which];
            {
                let mut d = state.lock().unwrap();
                d.slave.set_holding(SELECTOR, mode);
                d.slave.set_holding(r.address, 0);
                d.fault = fault;
                d.selector_reads = 0;
                d.log = Log::default();
            }
            let value = raw as f64 / r.per_unit;
            let result = write(&drive, profile, &addr, &format!("{}={value}", r.name));
            let d = state.lock().unwrap();
            // Every word that reached the register is inside the range of the case the
            // selector showed when it arrived.
            for &(a, word, code) in &d.log.writes {
                prop_assert_eq!(a, r.address, "only the register named is written");
                let Some((min, max)) = r.range(code) else {
                    prop_assert!(false, "{} written while P1300 = {code}, which selects no range: {word}", r.name);
                    unreachable!();
                };
                prop_assert!(
                    (min..=max).contains(&i64::from(word)),
                    "{} = {word} reached the wire under P1300 = {code} (range {min} ..= {max}); fault {fault:?}, asked {value}",
                    r.name
                );
            }
            // Liveness: with no fault, a value the selected case allows arrives, once.
            if let (Fault::None, Some((min, max))) = (fault, r.range(mode))
                && (min..=max).contains(&raw)
            {
                prop_assert_eq!(
                    d.log.writes.clone(),
                    vec![(r.address, raw as u16, mode)],
                    "{}={} under P1300 = {} must arrive once: {:?}",
                    r.name, value, mode, result
                );
                arrived_clean.set(arrived_clean.get() + 1);
            }
            // A fault on the selector's read sends nothing.
            if matches!(fault, Fault::LoseReply | Fault::Exception) {
                prop_assert!(d.log.writes.is_empty(), "{fault:?}: {:?}", d.log.writes);
                prop_assert!(result.is_err() || result == Ok(ExitCode::FAILURE), "{result:?}");
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        arrived_clean.get() > 0,
        "no clean case wrote: the test would not notice refusing everything"
    );
}

/// The refusals name the selector, its code (with its meaning) and the range in force, and a
/// selector changed between the read and the write is named with both codes.
#[test]
fn refusals_name_the_selector_its_code_and_the_range() {
    let drive = drivemap_map::Loader::new()
        .load(&repo().join(format!("tests/fixtures/{ID}/{ID}.yaml")))
        .unwrap_or_else(|d| panic!("{d}"));
    let profile = drivemap_live::leak_profile(&drive);
    let state = Arc::new(Mutex::new(Drive {
        slave: SimulatedSlave::new(1, profile),
        fault: Fault::None,
        selector_reads: 0,
        log: Log::default(),
    }));
    let addr = serve(Arc::clone(&state));
    state.lock().unwrap().slave.set_holding(SELECTOR, 20);
    let err = write(&drive, profile, &addr, "P0640=200").unwrap_err();
    assert!(
        err.contains("200 % is out of range 10 ..= 150 %")
            && err.contains("P1300 = 20 (Sensorless vector control) selects this range"),
        "{err}"
    );
    // The same value under V/f control is written.
    state.lock().unwrap().slave.set_holding(SELECTOR, 0);
    assert_eq!(
        write(&drive, profile, &addr, "P0640=200"),
        Ok(ExitCode::SUCCESS)
    );
    {
        let mut d = state.lock().unwrap();
        d.fault = Fault::ChangeAfterRead(20);
        d.selector_reads = 0;
    }
    let err = write(&drive, profile, &addr, "P0640=120").unwrap_err();
    assert!(
        err.contains("P1300") && err.contains("changed from 0: V/f control with linear characteristic to 20: Sensorless vector control"),
        "{err}"
    );
    {
        let mut d = state.lock().unwrap();
        d.fault = Fault::LoseReply;
        d.slave.set_holding(SELECTOR, 0);
    }
    let err = write(&drive, profile, &addr, "P0640=120").unwrap_err();
    assert!(
        err.contains("0100h") && err.contains("nothing written"),
        "names the selector's read that went unanswered: {err}"
    );
    state.lock().unwrap().fault = Fault::Exception;
    let err = write(&drive, profile, &addr, "P0640=120").unwrap_err();
    assert!(
        err.contains("P1300") && err.contains("nothing written"),
        "names the selector not known: {err}"
    );
    assert!(
        state.lock().unwrap().log.writes.iter().all(|w| w.1 == 2000),
        "only the one good write arrived"
    );
}
