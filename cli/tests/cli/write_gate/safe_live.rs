//! Issue 37: from a draft to a live drive, safely. Nothing a user did not check decides what
//! goes on the wire: a draft map is not written through without `--draft`, a `--set` value
//! outside its range or disagreeing with a drive that gives it is not used, a write of one
//! field of a command register carries no run or reset bit the call did not ask for, and a
//! setting others depend on is not changed under a running drive without `--while-running`.
//!
//! Property tests (proptest) over every map of `maps/` (the directory is read, no list) and the
//! drafts `drivemap import` makes of the import fixtures' manuals, through the CLI's own write
//! command in-process (and, for drafts, a `drivemap_live::session::Session`'s client) against a simulated
//! drive that records every write; and the
//! reproductions of the report through the binary, each asserting what reached the drive.

use drivemap_test_support::paths;

use drivemap_map::{Map, RegisterRef};
use std::collections::BTreeSet;

use drivemap_live::LiveSettings;
use drivemap_runtime::core::roles::FieldRole;
use drivemap_runtime::core::roles::{Role, RoleKind, Target as Place};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, TestRunner};

use super::*;
use crate::common::{Framing, Scratch, serve};

/// `drivemap write` in-process against the maps of `maps`, slave 1, `extra` before the
/// assignment.
fn write_in(
    maps: &Path,
    drive: &Map,
    profile: &'static Profile,
    wire: &Wire,
    extra: &[&str],
    assignment: &str,
) -> Result<ExitCode, String> {
    let mut argv = vec![
        "drivemap",
        "write",
        "--drive",
        &drive.id(),
        "--maps",
        maps.to_str().unwrap(),
        wire.flag(),
        &wire.addr,
        // The simulated drive answers as slave 1 whatever the map's factory address (GPD 515:
        // 31), so that every map's case reaches a drive that answers.
        "--slave",
        "1",
        "--timeout",
        "500ms",
        "--retries",
        "0",
    ];
    argv.extend_from_slice(extra);
    argv.push(assignment);
    let result = drivemap_cli::write_in_process(&argv, drive, profile);
    if let Err(e) = &result {
        // A command line clap refuses is the test's mistake, not a refusal of the write.
        assert!(
            !e.starts_with("error: "),
            "the test's own arguments parse: {e}"
        );
    }
    result
}

/// Every map of `maps/` copied into `dir` with a `draft:` mark, and the drafts `drivemap import`
/// writes of the import fixtures' manuals (`tests/fixtures/import/manuals/*.txt`).
fn drafts(dir: &Path) -> Vec<PathBuf> {
    for path in maps_in(&paths::maps()) {
        let text = std::fs::read_to_string(&path).unwrap();
        let mut out = String::new();
        let mut marked = false;
        for line in text.lines() {
            out.push_str(line);
            out.push('\n');
            if !marked && line.starts_with("schema:") {
                out.push_str("draft: {by: issue 37 test}\n");
                marked = true;
            }
        }
        assert!(marked, "{}: no schema line to mark after", path.display());
        std::fs::write(dir.join(path.file_name().unwrap()), out).unwrap();
    }
    let manuals = paths::fixture("import/manuals");
    let mut n = 0;
    for entry in std::fs::read_dir(&manuals).unwrap() {
        let manual = entry.unwrap().path();
        if manual.extension().is_none_or(|e| e != "txt") {
            continue;
        }
        let id = manual.file_stem().unwrap().to_str().unwrap().to_owned();
        let out = dir.join(format!("{id}.yaml"));
        let (code, _, err) = common::run(common::command().args([
            "import",
            "--manual",
            manual.to_str().unwrap(),
            "--id",
            &id,
            "-o",
            out.to_str().unwrap(),
        ]));
        assert_eq!(code, 0, "drivemap import {}: {err}", manual.display());
        n += 1;
    }
    assert!(n >= 2, "the import fixtures' manuals");
    maps_in(dir)
}

/// The RTU-framed link every map has (`--rtu-tcp`): a draft of an import fixture lists `rtu`.
const KIND: TransportKind = TransportKind::RtuOverTcp;

/// No write reaches the wire through a draft without `--draft`: every draft (each shipped map
/// marked, each import fixture's draft), a register and a value form drawn at random, legal or
/// not. On the old code every legal write arrived.
#[test]
fn no_write_reaches_the_wire_through_a_draft_without_draft() {
    let scratch = Scratch::new("issue37-drafts");
    let paths = drafts(&scratch.0);
    let mut loaded = Vec::new();
    for p in &paths {
        let drive = drivemap_map::Loader::new()
            .load(p)
            .unwrap_or_else(|e| panic!("{}: {e:?}", p.display()));
        assert!(drive.draft().is_some(), "{} is a draft", p.display());
        let profile = drivemap_live::leak_profile(&drive);
        let wire = Wire::start(profile, KIND);
        loaded.push((drive, profile, wire));
    }
    let mut runner = TestRunner::new(Config {
        cases: 96,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (any::<Index>(), any::<Index>(), any::<Index>());
    let sessions = std::cell::Cell::new(0usize);
    runner
        .run(&strategy, |(m, ri, vi)| {
            let (drive, profile, wire) = &loaded[m.index(loaded.len())];
            let r = drive
                .register_at(ri.index(drive.registers().len()))
                .unwrap();
            let values = values(r);
            let (value, _) = &values[vi.index(values.len())];
            let assignment = format!("{}={value}", r.id());
            let before = wire.writes();
            let result = write_in(&scratch.0, drive, profile, wire, &[], &assignment);
            wire.settle();
            let arrived = wire.writes_since(before);
            prop_assert!(
                arrived.is_empty(),
                "{} {assignment}: {arrived:?} reached the wire through a draft",
                drive.id()
            );
            prop_assert!(result.is_err(), "{} {assignment}: {result:?}", drive.id());
            // The library's path: a session over the draft, a write request made through its
            // client directly, is refused at the link.
            // (The simulated drive is locked while it serves a connection: counted before.)
            let before = wire.writes();
            let link = drivemap_live::link::Link::rtu_over_tcp(wire.addr.clone());
            let mut session =
                drivemap_live::session::Session::open(drive, &link, LiveSettings::default())
                    .expect("the simulated drive is there");
            if let Ok(at) = session.address(r) {
                sessions.set(sessions.get() + 1);
                let result = session.client.write_registers(1, at, &[1]);
                drop(session);
                wire.settle();
                let arrived = wire.writes_since(before);
                prop_assert!(
                    arrived.is_empty(),
                    "{} {}: the session's write {arrived:?} reached the wire",
                    drive.id(),
                    r.id()
                );
                prop_assert!(result.is_err());
            }
            Ok(())
        })
        .unwrap();
    assert!(sessions.get() > 0, "the session's path was tried");
    // With --draft a register whose access nobody wrote (neither the row nor its group) is
    // read-only: refused, nothing sent. The import fixtures' drafts have such rows.
    let mut checked = 0;
    for (drive, profile, wire) in &loaded {
        for r in drive.registers() {
            if r.plan().info.access != drivemap_runtime::core::register::Access::Read
                || !on_transport(r, KIND)
            {
                continue;
            }
            let Some((value, _)) = values(r).into_iter().next() else {
                continue;
            };
            let before = wire.writes();
            let result = write_in(
                &scratch.0,
                drive,
                profile,
                wire,
                &["--draft"],
                &format!("{}={value}", r.id()),
            );
            wire.settle();
            assert_eq!(
                wire.writes(),
                before,
                "{} {}: read-only",
                drive.id(),
                r.id()
            );
            assert!(result.is_err(), "{} {}", drive.id(), r.id());
            if r.access_written().is_none() {
                checked += 1;
            }
        }
    }
    assert!(checked > 0, "a draft register without access was tried");
}

/// The command fields of plan row `row`, with their roles.
fn command_fields(drive: &Map, row: u16) -> Vec<(Role, FieldRole)> {
    drive
        .plan()
        .roles
        .places
        .iter()
        .filter_map(|p| match (p.role.kind(), p.target) {
            (RoleKind::Command, Place::Field(f)) if f.row == row => Some((p.role, f)),
            _ => None,
        })
        .collect()
}

/// The PDU address of plan row `row` on `KIND` (an RTU link: the map's RTU address offset
/// applies) at the drive's default settings.
fn pdu(drive: &Map, row: u16) -> Option<u16> {
    let settings = LiveSettings::default();
    let at = drive.plan().registers[usize::from(row)]
        .locate(&settings.view(drive), KIND)
        .ok()?;
    u16::try_from(i32::from(at) + drive.address_offsets().0).ok()
}

fn runs(role: Role) -> bool {
    matches!(role, Role::Run | Role::RunForward | Role::RunReverse)
}

/// One field of a command register written, on every map of `maps/` that has command roles:
/// whatever the drive's word holds (run and reset bits set by someone), the word sent carries
/// the fault reset (and every edge command) released, and a run bit only where the status
/// role shows the drive running and the word had it. On the old code the word read back went
/// out with its run and reset bits.
#[test]
fn a_field_write_carries_no_run_or_reset_bit_it_did_not_ask_for() {
    let maps = paths::maps();
    // (drive, profile, wire, command register, field ids writable that are no run or reset)
    let mut cases = Vec::new();
    for path in maps_in(&maps) {
        let drive = drivemap_map::Loader::new().load(&path).unwrap();
        let profile = drivemap_live::leak_profile(&drive);
        let rows: BTreeSet<u16> = drive
            .plan()
            .roles
            .places
            .iter()
            .filter_map(|p| match (p.role.kind(), p.target) {
                (RoleKind::Command, Place::Field(f)) => Some(f.row),
                _ => None,
            })
            .collect();
        let mut regs = Vec::new();
        for row in rows {
            let Some(r) = drive.register_of_row(usize::from(row)) else {
                continue;
            };
            if !allowed_on_link(&drive, r, KIND, 1) || !r.readable() || pdu(&drive, row).is_none() {
                continue;
            }
            let guarded: u16 = command_fields(&drive, row)
                .iter()
                .filter(|(role, f)| {
                    runs(*role) || *role == Role::FaultReset || f.edge.needs_release_first()
                })
                .fold(0, |m, (_, f)| m | f.mask());
            let ValueKind::Bits(fields) = value_kind(r) else {
                continue;
            };
            let free: Vec<(String, u16)> = fields
                .iter()
                .filter_map(|f| {
                    let (lsb, width) = field_span(f)?;
                    let mask = ((((1u32 << width) - 1) << lsb) & 0xFFFF) as u16;
                    (mask & guarded == 0 && width == 1).then(|| (f.id.clone(), mask))
                })
                .collect();
            if !free.is_empty() && guarded != 0 {
                regs.push((row, free));
            }
        }
        if !regs.is_empty() {
            let wire = Wire::start(profile, KIND);
            cases.push((drive, profile, wire, regs));
        }
    }
    assert!(cases.len() >= 2, "maps with command registers");
    let mut runner = TestRunner::new(Config {
        cases: 128,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (
        any::<Index>(),
        any::<Index>(),
        any::<Index>(),
        any::<u16>(),
        any::<bool>(),
        any::<bool>(),
    );
    runner
        .run(&strategy, |(m, ri, fi, preset, running, on)| {
            let (drive, profile, wire, regs) = &cases[m.index(cases.len())];
            let (row, free) = &regs[ri.index(regs.len())];
            let (field, field_mask) = &free[fi.index(free.len())];
            let r = drive.register_of_row(usize::from(*row)).unwrap();
            let at = pdu(drive, *row).unwrap();
            let mask = field_mask_of(r);
            let preset = preset & mask;
            // The status the drive shows: the running role where the link has it.
            let status = drive
                .plan()
                .roles
                .places
                .iter()
                .find_map(|p| match p.target {
                    Place::Field(f)
                        if p.role == Role::Running
                            && drive.plan().registers[usize::from(f.row)]
                                .transports
                                .contains(KIND) =>
                    {
                        Some(f)
                    }
                    _ => None,
                });
            {
                let mut s = wire.slave.lock().unwrap();
                s.set_holding(at, preset);
                if let Some(f) = status
                    && f.row != *row
                    && let Some(st) = pdu(drive, f.row)
                {
                    let word = s.holding(st);
                    let code = if running { f.on[0] } else { f.off.unwrap_or(0) };
                    s.set_holding(st, f.put(word, code));
                }
            }
            let shows_running = running && status.is_some_and(|f| f.row != *row);
            let before = wire.writes();
            let assignment = format!("{}={field}={}", r.id(), u8::from(on));
            let result = write_in(&paths::maps(), drive, profile, wire, &[], &assignment);
            wire.settle();
            let arrived = wire.writes_since(before);
            let words: Vec<u16> = arrived
                .iter()
                .filter(|(a, _)| *a == at)
                .map(|(_, w)| *w)
                .collect();
            prop_assert!(
                words.len() == 1,
                "{} {assignment}: {result:?}, arrived {arrived:?}",
                drive.id()
            );
            let word = words[0];
            prop_assert_eq!(word & field_mask, if on { *field_mask } else { 0 });
            for (role, f) in command_fields(drive, *row) {
                let sent = f.get(word);
                if role == Role::FaultReset || f.edge.needs_release_first() {
                    prop_assert_eq!(
                        sent,
                        f.code(false),
                        "{} {}: {:?} sent set in {:04X}h (drive held {:04X}h)",
                        drive.id(),
                        assignment,
                        role,
                        word,
                        preset
                    );
                } else if runs(role) && !shows_running {
                    prop_assert_eq!(
                        sent,
                        f.code(false),
                        "{} {}: {:?} sent to a stopped drive in {:04X}h (it held {:04X}h)",
                        drive.id(),
                        assignment,
                        role,
                        word,
                        preset
                    );
                } else if runs(role) {
                    prop_assert_eq!(sent, f.get(preset), "a running drive keeps its run");
                }
            }
            Ok(())
        })
        .unwrap();
}

fn field_mask_of(r: RegisterRef<'_>) -> u16 {
    field_mask(r).unwrap_or(0xFFFF)
}

/// A `--set` value of a register the drive gives is checked against it: on every map of
/// `maps/`, for every selector or reference register readable on the link and every register
/// whose conversion or limit uses it, a given value outside the register's range or other than
/// the drive's sends nothing. On the old code the given value was used as it was.
#[test]
fn no_set_value_outside_its_range_or_against_the_drive_is_used() {
    let maps = paths::maps();
    let mut cases = Vec::new();
    for path in maps_in(&maps) {
        let drive = drivemap_map::Loader::new().load(&path).unwrap();
        let profile = drivemap_live::leak_profile(&drive);
        let mut pairs = Vec::new();
        let settings = LiveSettings::default();
        let mut sources: Vec<RegisterRef<'_>> = drive.references();
        sources.extend(drive.selectors());
        for s in sources {
            if !s.readable() || !on_transport(s, KIND) || s.broadcast_only() {
                continue;
            }
            let users: Vec<String> = drive
                .registers()
                .filter(|&x| {
                    x.id() != s.id()
                        && allowed_on_link(&drive, x, KIND, 1)
                        && drivemap_live::session::settings_used(&drive, x, &settings)
                            .iter()
                            .any(|u| u == s.id())
                })
                .map(|x| x.id().to_owned())
                .collect();
            if !users.is_empty() {
                pairs.push((s.id().to_owned(), users));
            }
        }
        if !pairs.is_empty() {
            let wire = Wire::start(profile, KIND);
            cases.push((drive, profile, wire, pairs));
        }
    }
    assert!(!cases.is_empty(), "maps whose conversions read a setting");
    let mut runner = TestRunner::new(Config {
        cases: 96,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (
        any::<Index>(),
        any::<Index>(),
        any::<Index>(),
        any::<Index>(),
        -1.0f64..2.0,
        any::<bool>(),
    );
    runner
        .run(&strategy, |(m, si, ui, hi, given, same)| {
            let (drive, profile, wire, pairs) = &cases[m.index(cases.len())];
            let (sid, users) = &pairs[si.index(pairs.len())];
            let s = drive.register(sid).unwrap();
            let u = drive.register(&users[ui.index(users.len())]).unwrap();
            let settings = LiveSettings::default();
            let plan = s.plan();
            let at = u16::try_from(
                i32::from(plan.locate(&settings.view(drive), KIND).unwrap())
                    + drive.address_offsets().0,
            )
            .unwrap();
            // What the drive holds: a value of the register (its range, or its codes).
            let (min, max) = s.limits();
            let (lo, hi_v) = (min.unwrap_or(0.0), max.unwrap_or(100.0));
            let held_text = match value_kind(s) {
                ValueKind::Enum(list) => list[hi.index(list.len())].value.to_string(),
                _ => number(min.unwrap_or(0.0).max(lo)),
            };
            let held = drivemap_live::codec::parse_value(drive, s, &held_text, &settings)
                .expect("a value of the setting") as u16;
            wire.slave.lock().unwrap().set_holding(at, held);
            // What is given: the drive's value, or anything from below the range to above it.
            let given_text = if same {
                held_text.clone()
            } else {
                number(((lo + given * (hi_v - lo)) * 10.0).round() / 10.0)
            };
            let value = values(u)
                .into_iter()
                .next()
                .map(|(v, _)| v)
                .unwrap_or_else(|| "0".into());
            let before = wire.writes();
            let set = format!("{}={given_text}", s.id());
            let result = write_in(
                &paths::maps(),
                drive,
                profile,
                wire,
                &["--set", &set],
                &format!("{}={value}", u.id()),
            );
            wire.settle();
            let arrived = wire.writes_since(before);
            let agrees = drivemap_live::codec::parse_value_with(
                drive,
                s,
                &given_text,
                &settings,
                drivemap_runtime::core::scale::Rounding::Nearest,
            )
            .is_ok_and(|raw| raw == u32::from(held));
            if !agrees {
                prop_assert!(
                    arrived.is_empty(),
                    "{}: --set {set} (the drive holds {held_text}) {}={value}: {arrived:?} arrived ({result:?})",
                    drive.id(),
                    u.id()
                );
            }
            Ok(())
        })
        .unwrap();
}

/// The report's draft write, through the binary: an import draft is refused without
/// `--draft` (nothing reaches the drive), written with it (and said so), and read with a
/// note; a register whose access the draft does not give is read-only even with `--draft`.
#[test]
fn repro_a_draft_map_is_not_written_without_draft() {
    let scratch = Scratch::new("issue37-repro-draft");
    let paths = drafts(&scratch.0);
    let k20 = paths
        .iter()
        .find(|p| p.ends_with("kestrel-k20.yaml"))
        .expect("the kestrel draft");
    let drive = drivemap_map::Loader::new().load(k20).unwrap();
    let profile = drivemap_live::leak_profile(&drive);
    let (addr, slave) = serve(
        drivemap_sim::SimulatedSlave::new(1, profile),
        Framing::RtuOverTcp,
    );
    let maps = scratch.0.to_str().unwrap();
    let r = drive
        .register("frequency_reference")
        .expect("the draft's reference");
    let writable = r.writable();
    let base = [
        "write",
        "--drive",
        "kestrel-k20",
        "--maps",
        maps,
        "--rtu-tcp",
        &addr,
        "frequency_reference=50",
    ];
    let (code, _, err) = common::run(common::command().args(base));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("kestrel-k20 is a draft map"), "{err}");
    assert!(
        err.contains("--draft") && err.contains("nothing written"),
        "{err}"
    );
    assert!(slave.lock().unwrap().writes.is_empty());
    let (code, out, err) = common::run(common::command().args(base).arg("--draft"));
    let writes = slave.lock().unwrap().writes.clone();
    // The manual's row prints `rw`, and the draft says so.
    assert!(writable, "the draft's frequency_reference is read-write");
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("through draft map kestrel-k20 (--draft)"),
        "{out}"
    );
    assert_eq!(writes, vec![(0x2001, 5000)]);
    let (_, _, err) = common::run(common::command().args([
        "read",
        "--drive",
        "kestrel-k20",
        "--maps",
        maps,
        "--rtu-tcp",
        &addr,
        "frequency_reference",
    ]));
    assert!(err.contains("kestrel-k20 is a draft map"), "{err}");
}

/// A shipped map's profile, for a simulated drive of it.
fn shipped(id: &str) -> &'static Profile {
    let drive = drivemap_map::Loader::new()
        .load(&repo().join(format!("maps/{id}.yaml")))
        .unwrap();
    drivemap_live::leak_profile(&drive)
}

/// `drivemap write --drive <id> <flag> <addr> <args>` with the shipped maps.
fn write_bin(id: &str, framing: Framing, addr: &str, args: &[&str]) -> (i32, String, String) {
    let mut all = vec![
        "write",
        "--drive",
        id,
        framing.flag(),
        addr,
        "--timeout",
        "2s",
    ];
    all.extend_from_slice(args);
    common::drivemap(&all)
}

/// The report's `--set` cases on the V7 over Modbus TCP (n011 bounds and, with n152 = 2 or 3,
/// scales the TCP card's frequency reference): a value outside n011's range and one other than
/// the drive's are refused naming both, nothing sent; the drive's own value is used. An
/// external quantity (the TDS-V8's inverter rated current) cannot be read: each write converted
/// with it says it was assumed.
#[test]
fn repro_set_values_are_checked_and_disclosed() {
    let mut slave = drivemap_sim::SimulatedSlave::new(1, shipped("yaskawa-v7"));
    slave.set_holding(0x010B, 600); // n011 = 60.0 Hz
    let (addr, slave) = serve(slave, Framing::Tcp);
    let (code, _, err) = write_bin(
        "yaskawa-v7",
        Framing::Tcp,
        &addr,
        &["--set", "n011=500", "tcp_frequency_reference=400"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("`--set n011=500`") && err.contains("out of range"),
        "{err}"
    );
    let (code, _, err) = write_bin(
        "yaskawa-v7",
        Framing::Tcp,
        &addr,
        &["--set", "n011=400", "tcp_frequency_reference=400"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("the drive holds max_output_frequency (n011) = 60.0 Hz, not 400"),
        "{err}"
    );
    assert!(err.contains("nothing written"), "{err}");
    assert!(
        slave.lock().unwrap().writes.is_empty(),
        "nothing reached the drive"
    );
    let (code, out, err) = write_bin(
        "yaskawa-v7",
        Framing::Tcp,
        &addr,
        &["--set", "n011=60", "tcp_frequency_reference=40"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("assuming"), "read, so not assumed: {out}");
    assert_eq!(slave.lock().unwrap().writes, vec![(0x0002, 400)]);

    let (addr, slave) = serve(
        drivemap_sim::SimulatedSlave::new(1, shipped("ptlk-tds-v8")),
        Framing::RtuOverTcp,
    );
    let (code, out, err) = write_bin(
        "ptlk-tds-v8",
        Framing::RtuOverTcp,
        &addr,
        &[
            "--set",
            "inverter_rated_current=10",
            "motor_rated_current=15",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("; assuming inverter_rated_current = 10, given, not read"),
        "{out}"
    );
    let writes = slave.lock().unwrap().writes.clone();
    assert_eq!(writes.len(), 1, "{writes:?}");
    assert_eq!(writes[0].1, 150);
    // Above 200 % of the rated current given: refused, nothing more sent.
    let (code, _, err) = write_bin(
        "ptlk-tds-v8",
        Framing::RtuOverTcp,
        &addr,
        &[
            "--set",
            "inverter_rated_current=10",
            "motor_rated_current=25",
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert_eq!(slave.lock().unwrap().writes.len(), 1);
}

/// The report's field write, on the ACN (0382h: run bit 0, forward bit 1, trip initialization
/// bit 2 on its 0 -> 1 edge): the drive's word holds run, forward and the reset; writing the
/// direction alone sends neither the reset nor, to a stopped drive, the run; to a running
/// drive (0305h shows operating forward) the run is kept, the reset still released.
#[test]
fn repro_a_field_write_does_not_resend_run_or_reset() {
    let mut slave = drivemap_sim::SimulatedSlave::new(1, shipped("automationdirect-acn"));
    slave.set_holding(0x0381, 0x0007); // PDU = 0382h - 1 on RTU
    slave.set_holding(0x0304, 0x0000); // stopped
    let (addr, slave) = serve(slave, Framing::RtuOverTcp);
    let (code, _, err) = write_bin(
        "automationdirect-acn",
        Framing::RtuOverTcp,
        &addr,
        &["operation_command=forward=0"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().writes, vec![(0x0381, 0x0000)]);
    {
        let mut s = slave.lock().unwrap();
        s.set_holding(0x0381, 0x0007);
        s.set_holding(0x0304, 0x0001); // operating forward
    }
    let (code, _, err) = write_bin(
        "automationdirect-acn",
        Framing::RtuOverTcp,
        &addr,
        &["operation_command=forward=0"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        slave.lock().unwrap().writes,
        vec![(0x0381, 0x0000), (0x0381, 0x0001)]
    );
    // A field list naming nothing is refused, never taken as "write back what was read".
    let (code, _, err) = write_bin(
        "automationdirect-acn",
        Framing::RtuOverTcp,
        &addr,
        &["operation_command=,"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("names no field of operation_command"), "{err}");
    assert_eq!(slave.lock().unwrap().writes.len(), 2);
}

/// The report's running reference change, on the V7 (n011 bounds every frequency reference
/// and scales the monitors): while the status shows the drive running, a write of n011 is
/// refused naming what depends on it, nothing sent; `--while-running` sends it; stopped, it
/// is sent with a note naming the dependants.
#[test]
fn repro_a_setting_others_depend_on_is_not_changed_under_a_running_drive() {
    let mut slave = drivemap_sim::SimulatedSlave::new(1, shipped("yaskawa-v7"));
    slave.set_holding(0x010B, 600);
    slave.set_holding(0x0020, 0x0001); // status signal 1: during run
    let (addr, slave) = serve(slave, Framing::RtuOverTcp);
    let (code, _, err) = write_bin("yaskawa-v7", Framing::RtuOverTcp, &addr, &["n011=50"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the drive is running"), "{err}");
    assert!(err.contains("bounds frequency_reference"), "{err}");
    assert!(
        err.contains("--while-running") && err.contains("nothing written"),
        "{err}"
    );
    assert!(slave.lock().unwrap().writes.is_empty());
    let (code, _, err) = write_bin(
        "yaskawa-v7",
        Framing::RtuOverTcp,
        &addr,
        &["n011=50", "--while-running"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().writes, vec![(0x010B, 500)]);
    slave.lock().unwrap().set_holding(0x0020, 0x0000);
    let (code, _, err) = write_bin("yaskawa-v7", Framing::RtuOverTcp, &addr, &["n011=55"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("note: max_output_frequency bounds frequency_reference"),
        "{err}"
    );
    assert_eq!(
        slave.lock().unwrap().writes,
        vec![(0x010B, 500), (0x010B, 550)]
    );
}

/// `simulate --tcp` refuses a map whose transports lack Modbus TCP, as `read --tcp` does.
#[test]
fn simulate_refuses_a_link_the_map_lacks_as_read_does() {
    let (code, _, err, _) = common::drivemap_bounded(
        &[
            "simulate",
            "--drive",
            "yaskawa-gpd515",
            "--tcp",
            "127.0.0.1:0",
            "--quiet",
        ],
        Duration::from_secs(20),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("yaskawa-gpd515 has no Modbus TCP interface"),
        "{err}"
    );
    assert!(err.contains("--gateway 127.0.0.1:0"), "{err}");
    let (code, _, err) = common::drivemap(&[
        "read",
        "--drive",
        "yaskawa-gpd515",
        "--tcp",
        "127.0.0.1:9",
        "output_frequency",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("yaskawa-gpd515 has no Modbus TCP interface"),
        "{err}"
    );
}

/// `demo` drives its simulated drive through the map: a draft is refused without `--draft`
/// and said with it; `--set` gives the simulated drive a setting (the TDS-V8's Cn-02, the
/// maximum frequency its reference is taken against), which the client reads from it.
#[test]
fn demo_refuses_a_draft_and_takes_set() {
    let scratch = Scratch::new("issue37-demo");
    drafts(&scratch.0);
    let maps = scratch.0.to_str().unwrap();
    let base = [
        "demo",
        "--drive",
        "ptlk-tds-v8",
        "--maps",
        maps,
        "--time-scale",
        "100",
        "--frequency",
        "30",
    ];
    let (code, out, err, _) =
        common::run_bounded(common::command().args(base), Duration::from_secs(60));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("ptlk-tds-v8 is a draft map"), "{err}");
    assert!(!out.contains("written:"), "{out}");
    let mut with = base.to_vec();
    with.extend_from_slice(&["--draft", "--set", "Cn-02=50"]);
    let (code, out, err, _) =
        common::run_bounded(common::command().args(&with), Duration::from_secs(120));
    assert_eq!(code, 0, "{err}\n{out}");
    assert!(
        out.contains("note: writes go through draft map ptlk-tds-v8 (--draft)"),
        "{out}"
    );
    assert!(
        out.contains("written: frequency reference 30.00 Hz"),
        "{out}"
    );
}

/// Values as typed: a quantity is a decimal number in its unit (`0032h` is refused, not taken
/// as 50 Hz), a code is a whole number (`-1` is no code, not code 0), a huge number is quoted
/// short, an address in a gap of the map is said to be one; every refusal says nothing was
/// written, and nothing was. A `read --set` the drive contradicts is refused too.
#[test]
fn values_are_taken_as_typed() {
    let mut slave = drivemap_sim::SimulatedSlave::new(1, shipped("yaskawa-v7"));
    slave.set_holding(0x010B, 600);
    let (addr, slave) = serve(slave, Framing::RtuOverTcp);
    let cases: [(&str, &str); 5] = [
        (
            "frequency_reference=0032h",
            "`0032h` is hexadecimal, but frequency_reference takes a decimal number of Hz",
        ),
        ("n019=10h", "accel_time_1 takes a decimal number of s"),
        (
            "n003=-1",
            "`-1` is not a code of run_stop_source_selection: the codes the manual lists are 0 (keypad)",
        ),
        (
            "n019=1e308",
            "accel_time_1: 1e308 s is out of range 0 ..= 6000 s",
        ),
        (
            "digital_input_command=,",
            "names no field of digital_input_command",
        ),
    ];
    for (assignment, expected) in cases {
        let (code, _, err) = write_bin("yaskawa-v7", Framing::RtuOverTcp, &addr, &[assignment]);
        assert_eq!(code, 2, "{assignment}: {err}");
        assert!(err.contains(expected), "{assignment}: {err}");
        assert!(
            err.trim_end().ends_with("nothing written"),
            "{assignment}: {err}"
        );
    }
    assert!(slave.lock().unwrap().writes.is_empty());
    // A raw word may still be written in hex where the register is a word (bit fields).
    let (code, _, err) = write_bin(
        "yaskawa-v7",
        Framing::RtuOverTcp,
        &addr,
        &["digital_input_command=0x0002"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().writes, vec![(0x0001, 0x0002)]);
    let (code, _, err) = common::drivemap(&[
        "read",
        "--drive",
        "yaskawa-v7",
        "--rtu-tcp",
        &addr,
        "--set",
        "n011=50",
        "frequency_reference",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("the drive holds max_output_frequency (n011) = 60.0 Hz, not 50"),
        "{err}"
    );
    // The ACN's 0108h-010Fh is a gap of its map.
    let (code, _, err) = common::drivemap(&[
        "write",
        "--drive",
        "automationdirect-acn",
        "--rtu-tcp",
        "127.0.0.1:9",
        "0x0109=1",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("has no register at `0x0109`: it is in a gap of the map"),
        "{err}"
    );
    assert!(!err.contains("did you mean"), "{err}");
}

/// `check --strict` on a draft names the reviewer's fix (remove `draft:` after the review),
/// not `drivemap migrate`, which has nothing to do with it.
#[test]
fn check_strict_on_a_draft_says_to_review_it() {
    let scratch = Scratch::new("issue37-check");
    let paths = drafts(&scratch.0);
    let k20 = paths
        .iter()
        .find(|p| p.ends_with("kestrel-k20.yaml"))
        .expect("the kestrel draft");
    let (code, _, err) = common::run(
        common::command()
            .args(["check", "--strict", k20.to_str().unwrap()])
            .env("DRIVEMAP_MANUALS", paths::fixture("import/manuals")),
    );
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("a draft (made by drivemap import)"), "{err}");
    assert!(
        err.contains(
            "(--strict: review every row against the manual, confirm the items listed, then remove `draft:`)"
        ),
        "{err}"
    );
    // The import writes the current schema: nothing here is for migrate.
    assert!(!err.contains("drivemap migrate"), "{err}");
}
