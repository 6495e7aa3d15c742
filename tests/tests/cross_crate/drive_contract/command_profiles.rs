//! Drives run through a control-word state machine (`profile:` of a map: CiA 402, PROFIdrive,
//! the ABB Drives profile, the Danfoss FC profile): the drive trait walks the machine, the simulated drive follows it,
//! the generated module carries it as data. The fault-injection property test
//! (`the_contract_holds_under_faults`) plays every fixture of [`FIXTURES`] too.

use drivemap_test_support::paths;

use drivemap_map::Map;
use drivemap_runtime::core::command_profile::{CommandProfile, PathKind};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::roles::Role;
use drivemap_runtime::error::Error;
use drivemap_runtime::vfd::{VariableFrequencyDrive, Vfd};

use drivemap_runtime::client::Client;
use drivemap_runtime::pdu::Request;
use drivemap_sim::framing::{self, Decoded};
use drivemap_test_support::sim_link::SimLink;

use super::{connect, map, run_command, wire};

// The generated module of the CiA 402 fixture (`build.rs`), compiled with this runtime.
#[allow(dead_code)]
mod kestrel_kd4 {
    include!(concat!(env!("OUT_DIR"), "/kestrel_kd4.rs"));
}

/// The fixtures with a command profile.
pub(super) const FIXTURES: &[&str] = &[
    "tests/fixtures/kestrel-kd4/kestrel-kd4.yaml",
    "tests/fixtures/norrland-nv20/norrland-nv20.yaml",
    "tests/fixtures/oskar-ax3/oskar-ax3.yaml",
    "tests/fixtures/solvik-sf7/solvik-sf7.yaml",
];

/// The words written (06h / 10h, the first word) since the log was last cleared, on either
/// framing.
fn written<S: drivemap_runtime::core::plan::SettingsView>(
    d: &mut Vfd<S, &mut Client<SimLink>>,
) -> Vec<u16> {
    let kind = drivemap_runtime::transport::Transport::kind(d.client().transport());
    let w: Vec<u16> = d
        .client()
        .transport()
        .log
        .iter()
        .filter_map(|s| match framing::decode(kind, &s.frame) {
            Decoded::Request {
                request: Request::WriteSingle { value, .. },
                ..
            } => Some(value),
            Decoded::Request {
                request: Request::WriteMultiple { values, .. },
                ..
            } => values.get(0),
            _ => None,
        })
        .collect();
    d.client().transport().log.clear();
    w
}

fn kestrel() -> Map {
    map(FIXTURES[0])
}

/// The CiA 402 fixture run from power-on: 0006h, 0007h, 000Fh, each verified in the
/// statusword; stop is shutdown (0006h), coast disable voltage (0000h), quick stop 0002h; over
/// RTU framing and Modbus TCP.
#[test]
fn run_and_stops_walk_the_machine_from_power_on() {
    let drive = kestrel();
    let p = drive.plan();
    for kind in [TransportKind::RtuOverTcp, TransportKind::Tcp] {
        let (mut c, settings, slave) = connect(&drive, kind, 0);
        let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
        assert!(d.supports(Role::Run) && d.supports(Role::FaultReset));
        assert_eq!(d.profile_state().unwrap(), Some("switch_on_disabled"));
        d.set_reference(30.0).unwrap();
        written(&mut d);
        d.run()
            .unwrap_or_else(|e| panic!("{e}: {}", wire(d.client())));
        assert_eq!(written(&mut d), [0x0006, 0x0007, 0x000F], "{kind:?}");
        assert!(run_command(d.client()));
        assert_eq!(d.profile_state().unwrap(), Some("operation_enabled"));
        // Running already: nothing to write.
        d.run().unwrap();
        assert_eq!(written(&mut d), [] as [u16; 0]);
        d.stop().unwrap();
        assert_eq!(written(&mut d), [0x0006]);
        assert!(!run_command(d.client()));
        assert_eq!(d.profile_state().unwrap(), Some("ready_to_switch_on"));
        // From ready to switch on the run path goes on from there.
        d.run().unwrap();
        assert_eq!(written(&mut d), [0x0007, 0x000F]);
        d.coast().unwrap();
        assert_eq!(written(&mut d), [0x0000]);
        assert_eq!(d.profile_state().unwrap(), Some("switch_on_disabled"));
        d.run().unwrap();
        written(&mut d);
        d.quick_stop().unwrap();
        assert_eq!(written(&mut d), [0x0002]);
        assert_eq!(d.profile_state().unwrap(), Some("quick_stop_active"));
        assert!(!run_command(d.client()));
        // A stop that finds the drive stopped writes the stop word once all the same.
        d.coast().unwrap();
        d.stop().unwrap();
        assert_eq!(written(&mut d), [0x0000, 0x0006]);
    }
}

/// The final word written directly (skipping shutdown and switch on) moves nothing: the
/// simulated drive stays in switch on disabled and does not run; so does 000Fh from ready to
/// switch on (switched on is skipped).
#[test]
fn a_word_that_skips_a_state_leaves_the_drive_where_it_is() {
    let drive = kestrel();
    for kind in [TransportKind::RtuOverTcp, TransportKind::Tcp] {
        let (mut c, _, slave) = connect(&drive, kind, 0);
        c.write_register(slave, 0x6040, 0x000F).unwrap();
        let sim = &mut c.transport().sim;
        assert_eq!(sim.profile_state(), Some("switch_on_disabled"));
        assert!(!sim.state().unwrap().run_command);
        c.write_register(slave, 0x6040, 0x0006).unwrap();
        assert_eq!(
            c.transport().sim.profile_state(),
            Some("ready_to_switch_on")
        );
        c.write_register(slave, 0x6040, 0x000F).unwrap();
        let sim = &mut c.transport().sim;
        assert_eq!(sim.profile_state(), Some("ready_to_switch_on"));
        assert!(!sim.state().unwrap().run_command);
        // In order, it runs.
        c.write_register(slave, 0x6040, 0x0007).unwrap();
        c.write_register(slave, 0x6040, 0x000F).unwrap();
        let sim = &mut c.transport().sim;
        assert_eq!(sim.profile_state(), Some("operation_enabled"));
        assert!(sim.state().unwrap().run_command);
        // The statusword shows the state as the guide prints it: x01x 0111.
        assert_eq!(sim.raw("statusword").unwrap() & 0x6F, 0x27);
    }
}

/// A trip: the drive shows fault and stops; run() is refused by the machine, naming the
/// state; the fault reset acts on the edge only (0080h held does not acknowledge twice) and
/// only in the fault state (elsewhere reset_fault() writes nothing); then the drive runs again.
#[test]
fn a_trip_needs_the_acknowledge_edge_in_the_fault_state() {
    let drive = kestrel();
    let p = drive.plan();
    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    d.reset_fault().unwrap();
    assert_eq!(written(&mut d), [] as [u16; 0], "no fault: nothing written");
    d.run().unwrap();
    d.client().transport().sim.trip(0x2310);
    assert_eq!(d.profile_state().unwrap(), Some("fault"));
    assert!(d.status().unwrap().fault == Some(true));
    assert_eq!(d.fault_code().unwrap().name, Some("Overcurrent"));
    written(&mut d);
    match d.run() {
        Err(Error::StateMachine { state, path, .. }) => {
            assert_eq!((state.as_str(), path), ("fault", "run"));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(written(&mut d), [] as [u16; 0]);
    // The edge acknowledges (0080h after 000Fh); the level alone does not: tripped again with
    // 0080h held, 0080h written again leaves the fault.
    d.client().write_register(slave, 0x6040, 0x0080).unwrap();
    assert_eq!(d.profile_state().unwrap(), Some("switch_on_disabled"));
    d.client().transport().sim.trip(0x2310);
    d.client().write_register(slave, 0x6040, 0x0080).unwrap();
    assert_eq!(d.profile_state().unwrap(), Some("fault"));
    d.client().transport().log.clear();
    // The drive object does not know what the word holds now: the edge is cleared first,
    // then set, the state awaited, then cleared.
    d.forget_commands();
    d.reset_fault().unwrap();
    assert_eq!(written(&mut d), [0x0000, 0x0080, 0x0000]);
    assert_eq!(d.profile_state().unwrap(), Some("switch_on_disabled"));
    assert_eq!(d.fault_code().unwrap().code, 0);
    d.run().unwrap();
    assert!(run_command(d.client()));
}

/// A transition the drive does not take: the trait waits the transition's time limit (100 ms,
/// as the guide prints) and reports the state the drive is in. Here the plan's enable
/// operation word is changed (000Bh: quick stop bit clear), which the simulated drive takes
/// for no command.
#[test]
fn a_refused_transition_times_out_naming_the_state() {
    let drive = kestrel();
    let p = drive.plan();
    let real = p.roles.profile.unwrap();
    let transitions: Vec<_> = real
        .transitions
        .iter()
        .map(|t| {
            let mut t = *t;
            if t.id == "enable_operation" {
                t.word = 0x000B;
            }
            t
        })
        .collect();
    let changed: &'static CommandProfile = Box::leak(Box::new(CommandProfile {
        transitions: Box::leak(transitions.into_boxed_slice()),
        ..*real
    }));
    let roles = drivemap_runtime::core::roles::Roles {
        profile: Some(changed),
        ..p.roles
    };
    let (mut c, settings, slave) = connect(&drive, TransportKind::Tcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, roles);
    let started = std::time::Instant::now();
    let e = d.run().unwrap_err();
    let waited = started.elapsed();
    match &e {
        Error::StateMachine { state, why, .. } => {
            assert_eq!(state, "switched_on");
            assert!(why.contains("within 100 ms of `enable_operation`"), "{why}");
        }
        other => panic!("{other:?}"),
    }
    assert!(
        waited >= std::time::Duration::from_millis(100)
            && waited < std::time::Duration::from_secs(5),
        "{waited:?}"
    );
    assert!(
        e.to_string().contains("the drive is in state switched_on"),
        "{e}"
    );
    assert!(!run_command(d.client()));
    // stop() still stops: shutdown from switched on.
    written(&mut d);
    d.stop().unwrap();
    assert_eq!(written(&mut d), [0x0006]);
}

/// A stop never takes a run transition: a hand-built plan whose stop path goes through enable
/// operation (validation refuses such a map) is refused before anything is sent.
#[test]
fn a_stop_path_through_a_run_transition_is_refused() {
    let drive = kestrel();
    let p = drive.plan();
    let real = p.roles.profile.unwrap();
    let enable = real
        .transitions
        .iter()
        .position(|t| t.id == "enable_operation")
        .unwrap() as u8;
    let paths: Vec<_> = real
        .paths
        .iter()
        .map(|path| {
            let mut path = *path;
            if path.kind == PathKind::Stop {
                path.via = Box::leak(vec![enable].into_boxed_slice());
            }
            path
        })
        .collect();
    let changed: &'static CommandProfile = Box::leak(Box::new(CommandProfile {
        paths: Box::leak(paths.into_boxed_slice()),
        ..*real
    }));
    let roles = drivemap_runtime::core::roles::Roles {
        profile: Some(changed),
        ..p.roles
    };
    let (mut c, settings, slave) = connect(&drive, TransportKind::Tcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, roles);
    d.client().write_register(slave, 0x6040, 0x0006).unwrap();
    d.client().write_register(slave, 0x6040, 0x0007).unwrap();
    written(&mut d);
    assert!(d.stop().is_err());
    assert!(!written(&mut d).contains(&0x000F));
    assert!(!run_command(d.client()));
    // And the map that says so is refused with where.
    let text = std::fs::read_to_string(paths::workspace().join(FIXTURES[0]))
    .unwrap()
    .replace(
        "  transitions:\n",
        "  paths:\n    stop: {via: [enable_operation], to: [ready_to_switch_on]}\n  transitions:\n",
    );
    let e = drivemap_map::Loader::new()
        .load_str("kestrel-kd4.yaml", &text)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("path `stop` takes `enable_operation`, a run transition"),
        "{e}"
    );
}

/// The generated module carries the profile the map lowers to, as const data.
#[test]
fn the_generated_module_carries_the_profile() {
    let drive = kestrel();
    let lowered = drive.plan().roles.profile.expect("a profile");
    let generated = kestrel_kd4::plan::ROLES.profile.expect("a profile");
    assert_eq!(generated, lowered);
    assert_eq!(generated.name, "cia402");
    let run = generated.path(PathKind::Run).unwrap();
    let words: Vec<u16> = run
        .via
        .iter()
        .map(|&t| generated.transitions[usize::from(t)].word)
        .collect();
    assert_eq!(words, [0x0006, 0x0007, 0x000F]);
}

/// Every profile fixture (CiA 402, PROFIdrive, ABB Drives, FC), from its own data: the simulated
/// drive powers on in the state its manual names; the run path's last word written directly
/// does not run it (where the path has more than one transition); run() reaches the run path's
/// end and stop() the stop path's; a trip stops it and run() is refused until reset_fault();
/// over every link the map lists.
#[test]
fn every_profile_fixture_follows_its_machine() {
    for file in FIXTURES {
        let drive = map(file);
        let p = drive.plan();
        let profile = p.roles.profile.expect("a profile");
        let run = profile.path(PathKind::Run).unwrap();
        let last = profile.transitions[usize::from(*run.via.last().unwrap())];
        let control = p.registers[usize::from(profile.control)].info.address;
        for kind in super::links(&drive) {
            let (mut c, settings, slave) = connect(&drive, kind, 0);
            let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
            let id = &drive.id();
            let power_on = profile.state_id(profile.power_on);
            assert_eq!(d.profile_state().unwrap(), Some(power_on), "{id}");
            // A run path of one transition (the FC profile's start) skips nothing.
            if run.via.len() > 1 {
                d.client()
                    .write_register(slave, control, last.word)
                    .unwrap();
                assert_eq!(
                    d.profile_state().unwrap(),
                    Some(power_on),
                    "{id}: {:#06X}",
                    last.word
                );
                assert!(!run_command(d.client()), "{id}: ran on a skipped state");
            }
            d.set_reference(20.0).unwrap();
            d.run().unwrap_or_else(|e| panic!("{id} {kind:?}: {e}"));
            assert!(run_command(d.client()), "{id}");
            let state = d.profile_state().unwrap().unwrap();
            assert!(
                run.to.iter().any(|&s| profile.state_id(s) == state),
                "{id}: {state}"
            );
            d.stop().unwrap();
            assert!(!run_command(d.client()), "{id}");
            let stop = profile.path(PathKind::Stop).unwrap();
            let state = d.profile_state().unwrap().unwrap();
            assert!(
                stop.to.iter().any(|&s| profile.state_id(s) == state),
                "{id}: {state}"
            );
            d.run().unwrap();
            d.client().transport().sim.trip(7);
            assert!(!run_command(d.client()), "{id}");
            assert!(matches!(d.run(), Err(Error::StateMachine { .. })), "{id}");
            assert_eq!(d.status().unwrap().fault, Some(true), "{id}");
            d.reset_fault().unwrap();
            assert_eq!(d.status().unwrap().fault, Some(false), "{id}");
            d.run().unwrap();
            assert!(run_command(d.client()), "{id}");
            d.coast().unwrap();
            assert!(!run_command(d.client()), "{id}");
        }
    }
}

/// PROFIdrive keeps STW1 bit 11 (reversing, the map's `reverse` role) through every
/// transition: 047Eh then 047Fh forward, 0C7Fh once reversed, 0C7Eh to stop in reverse.
#[test]
fn profidrive_keeps_the_direction_bit_through_the_machine() {
    let drive = map(FIXTURES[1]);
    let p = drive.plan();
    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    d.set_reference(25.0).unwrap();
    written(&mut d);
    d.run().unwrap();
    assert_eq!(written(&mut d), [0x047E, 0x047F]);
    d.set_direction(drivemap_runtime::vfd::Direction::Reverse)
        .unwrap();
    assert_eq!(written(&mut d), [0x0C7F]);
    assert!(d.client().transport().sim.state().unwrap().reverse_command);
    d.stop().unwrap();
    assert_eq!(written(&mut d), [0x0C7E]);
    assert_eq!(d.profile_state().unwrap(), Some("ready_for_switching_on"));
    d.client().transport().sim.trip(3);
    d.reset_fault().unwrap();
    // The acknowledge edge (bit 7) with the direction kept, then released.
    assert_eq!(written(&mut d), [0x0CFE, 0x0C7E]);
}

/// The active fault and the last fault are two roles: after a trip both show the code; after
/// the reset the active one is 0 again and the last one keeps it (PROFIdrive r0947 / r0948,
/// ABB FLT / LASTFLT).
#[test]
fn active_fault_and_last_fault_are_two_roles() {
    for file in &FIXTURES[1..] {
        let drive = map(file);
        let p = drive.plan();
        let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
        let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
        let id = &drive.id();
        assert!(d.supports(Role::LastFault), "{id}");
        assert_eq!(d.last_fault().unwrap().code, 0, "{id}");
        d.run().unwrap();
        d.client().transport().sim.trip(42);
        assert_eq!(d.fault_code().unwrap().code, 42, "{id}");
        assert_eq!(d.last_fault().unwrap().code, 42, "{id}");
        d.reset_fault().unwrap();
        assert_eq!(d.fault_code().unwrap().code, 0, "{id}");
        assert_eq!(
            d.last_fault().unwrap().code,
            42,
            "{id}: the history keeps the trip"
        );
    }
    // A map without the role refuses it before sending.
    let drive = kestrel();
    let p = drive.plan();
    let (mut c, settings, slave) = connect(&drive, TransportKind::Tcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    assert!(matches!(
        d.last_fault(),
        Err(Error::Refused(
            drivemap_runtime::error::Refusal::NoRole { .. }
        ))
    ));
}

/// Status roles on codes of a whole register (an inverter status register: 0 initial,
/// 2 stop, 3 run, 5 trip): the drive trait reads them, the simulated drive shows the code
/// that agrees with every role (3 while running, not "stopped" at 30 Hz).
#[test]
fn status_roles_read_codes_of_a_whole_register() {
    let text = r#"
drive:
  id: codes-as-states
  vendor: Example
  models: [MD-1]
  manuals:
    - {file: manual.txt, title: Example manual}
protocol:
  transports: [rtu]
  function_codes: [0x03, 0x06, 0x10]
  max_read: 8
  max_write: 8
  slave_address: {min: 1, max: 31}
groups:
  - id: main
    name: Main registers
    access: rw
    registers:
      - id: command
        name: Operation command
        address: 0x0001
        fields:
          - {id: run, name: Run, bit: 0, source: "manual.txt:10"}
          - {id: reset, name: Trip reset, bit: 1, source: "manual.txt:11"}
        source: "manual.txt:9"
      - {id: reference, name: Frequency reference, address: 0x0002, unit: Hz, scale: 0.01, min: 0.0, max: 400.0, source: "manual.txt:12"}
      - {id: output, name: Output frequency, address: 0x0003, access: r, unit: Hz, scale: 0.01, source: "manual.txt:13"}
      - id: status_a
        name: Inverter status A
        address: 0x0004
        access: r
        values:
          - {value: 0, id: initial, name: Initial status, source: "manual.txt:14"}
          - {value: 2, id: stop, name: Stop, source: "manual.txt:14"}
          - {value: 3, id: run, name: Run, source: "manual.txt:14"}
          - {value: 5, id: trip, name: Trip, source: "manual.txt:14"}
        source: "manual.txt:14"
roles:
  run: [{register: command, field: run, source: "manual.txt:10"}]
  fault_reset: [{register: command, field: reset, edge: true, source: "manual.txt:11"}]
  frequency_reference: [{register: reference, source: "manual.txt:12"}]
  output_frequency: [{register: output, source: "manual.txt:13"}]
  running: [{register: status_a, on: run, source: "manual.txt:14"}]
  fault: [{register: status_a, on: trip, source: "manual.txt:14"}]
"#;
    let drive = drivemap_map::Loader::new()
        .load_str("codes-as-states.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"));
    let p = drive.plan();
    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    assert_eq!(d.status().unwrap().running, Some(false));
    d.set_reference(30.0).unwrap();
    d.run().unwrap();
    let s = d.status().unwrap();
    assert_eq!((s.running, s.fault), (Some(true), Some(false)));
    assert_eq!(d.client().transport().sim.raw("status_a").unwrap(), 3);
    d.client().transport().sim.trip(1);
    let s = d.status().unwrap();
    assert_eq!((s.running, s.fault), (Some(false), Some(true)));
    assert_eq!(d.client().transport().sim.raw("status_a").unwrap(), 5);
    // With `off: stop` on both, the two cannot hold together: refused with why.
    let both = text
        .replace("on: run, source", "on: run, off: stop, source")
        .replace("on: trip, source", "on: trip, off: stop, source");
    let e = drivemap_map::Loader::new()
        .load_str("codes-as-states.yaml", &both)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot hold together"), "{e}");
}

/// The profile in the other outputs of a map: the Markdown reference (`drivemap doc`) prints
/// the machine with its citations, `export` carries `profile:` as written, `diff` reports a
/// changed time limit as breaking and a changed citation as documentation; the shipped maps'
/// reference and export have no such section.
#[test]
fn doc_export_and_diff_cover_the_profile() {
    use drivemap_review::diff::{ChangeKind, Severity, compare};
    let drive = kestrel();
    let doc = drivemap_review::reference::render(&drive, "kestrel-kd4.yaml");
    assert!(doc.contains("## Command profile"), "{doc}");
    assert!(
        doc.contains("| `enable_operation` | 000Fh | FF70h | 0000h | `switched_on` | `operation_enabled` | 100 ms | `kestrel-kd4.txt:40` |"),
        "{doc}"
    );
    assert!(
        doc.contains("| `operation_enabled` | 006Fh | 0027h | `kestrel-kd4.txt:64` |"),
        "{doc}"
    );
    assert!(doc.contains("At power-on: `switch_on_disabled`"), "{doc}");
    let export = drive.export();
    assert_eq!(export["profile"]["standard"], "cia402");
    assert_eq!(
        export["profile"]["transitions"]["shutdown"]["source"],
        "kestrel-kd4.txt:38"
    );
    let shipped = map("maps/yaskawa-v7.yaml");
    assert!(
        !drivemap_review::reference::render(&shipped, "yaskawa-v7.yaml")
            .contains("Command profile")
    );
    assert!(shipped.export().get("profile").is_none());

    let text = std::fs::read_to_string(paths::workspace().join(FIXTURES[0])).unwrap();
    let changed = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        drivemap_map::Loader::new()
            .load_str("kestrel-kd4.yaml", &text.replace(from, to))
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let slower = changed(
        r#"enable_operation: {limit_ms: 100, source: "kestrel-kd4.txt:40"}"#,
        r#"enable_operation: {limit_ms: 250, source: "kestrel-kd4.txt:40"}"#,
    );
    let d = compare(&drive, &slower);
    let c: Vec<_> = d
        .changes
        .iter()
        .filter(|c| c.subject == "profile")
        .collect();
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!(c[0].what, "transition enable_operation");
    assert_eq!(c[0].kind, ChangeKind::RoleCodesChanged);
    assert_eq!(c[0].severity(), Severity::Breaking);
    let recited = changed(
        r#"quick_stop_active: {source: "kestrel-kd4.txt:65"}"#,
        r#"quick_stop_active: {source: "kestrel-kd4.txt:54"}"#,
    );
    let d = compare(&drive, &recited);
    let c: Vec<_> = d
        .changes
        .iter()
        .filter(|c| c.subject == "profile")
        .collect();
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!(c[0].severity(), Severity::Compatible, "{c:?}");
    let none = compare(&shipped, &drive);
    assert!(
        none.changes
            .iter()
            .any(|c| c.subject == "profile" && c.kind == ChangeKind::RoleAdded)
    );
}

/// The Danfoss FC profile definition (`standard: danfoss_fc`) on a small map of its own: 047Ch
/// starts, 043Ch ramps to a stop, 0474h coasts; the reverse bit (15) is kept; a trip is reset by
/// 04BCh's rising bit 7.
#[test]
fn the_danfoss_fc_profile_runs_and_stops_a_drive() {
    let text = r#"
drive:
  id: fc-example
  vendor: Example
  models: [FC-1]
  manuals:
    - {file: fc.txt, title: Example FC manual}
protocol:
  transports: [rtu, tcp]
  function_codes: [0x03, 0x06, 0x10]
  max_read: 8
  max_write: 8
  slave_address: {min: 1, max: 247}
groups:
  - id: main
    name: Process data
    access: rw
    registers:
      - id: ctw
        name: Control word
        address: 0x07D0
        fields:
          - {id: dc_brake, name: DC brake, bit: 2, source: "fc.txt:3"}
          - {id: coasting, name: Coasting, bit: 3, source: "fc.txt:4"}
          - {id: quick_stop, name: Quick stop, bit: 4, source: "fc.txt:5"}
          - {id: hold, name: Hold output frequency, bit: 5, source: "fc.txt:6"}
          - {id: ramp_start, name: Ramp stop/start, bit: 6, source: "fc.txt:7"}
          - {id: reset, name: Reset, bit: 7, source: "fc.txt:8"}
          - {id: data_valid, name: Data valid, bit: 10, source: "fc.txt:9"}
          - {id: reversing, name: Reversing, bit: 15, source: "fc.txt:10"}
        source: "fc.txt:2"
      - {id: reference, name: Reference, address: 0x07D1, unit: Hz, scale: 0.01, min: 0.0, max: 400.0, source: "fc.txt:11"}
      - id: stw
        name: Status word
        address: 0x07D2
        access: r
        fields:
          - {id: trip, name: Trip, bit: 3, source: "fc.txt:13"}
          - {id: running, name: Running, bit: 11, source: "fc.txt:14"}
        source: "fc.txt:12"
roles:
  reverse: [{register: ctw, field: reversing, source: "fc.txt:10"}]
  frequency_reference: [{register: reference, source: "fc.txt:11"}]
  fault: [{register: stw, field: trip, source: "fc.txt:13"}]
profile:
  standard: danfoss_fc
  control: ctw
  status: stw
  source: "fc.txt:1"
  power_on: {state: stopped, source: "fc.txt:15"}
  states:
    stopped: {source: "fc.txt:14"}
    running: {source: "fc.txt:14"}
    fault: {source: "fc.txt:13"}
  transitions:
    start: {source: "fc.txt:16"}
    ramp_stop: {source: "fc.txt:17"}
    coast: {source: "fc.txt:18"}
    quick_stop: {source: "fc.txt:19"}
    reset: {source: "fc.txt:20"}
"#;
    let drive = drivemap_map::Loader::new()
        .load_str("fc-example.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"));
    let p = drive.plan();
    for kind in [TransportKind::RtuOverTcp, TransportKind::Tcp] {
        let (mut c, settings, slave) = connect(&drive, kind, 0);
        let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
        assert_eq!(d.profile_state().unwrap(), Some("stopped"));
        d.set_reference(10.0).unwrap();
        d.set_direction(drivemap_runtime::vfd::Direction::Reverse)
            .unwrap();
        written(&mut d);
        d.run().unwrap();
        assert_eq!(written(&mut d), [0x847C]);
        assert!(run_command(d.client()));
        d.stop().unwrap();
        assert_eq!(written(&mut d), [0x843C]);
        assert!(!run_command(d.client()));
        d.run().unwrap();
        d.coast().unwrap();
        written(&mut d);
        assert!(!run_command(d.client()));
        d.run().unwrap();
        d.client().transport().sim.trip(9);
        written(&mut d);
        d.reset_fault().unwrap();
        assert_eq!(written(&mut d), [0x84BC, 0x843C]);
        assert_eq!(d.profile_state().unwrap(), Some("stopped"));
    }
}

/// A field write of a profile's control word (`Vfd::command_fields_word`, what `drivemap write`
/// and the bridge use for a command register) that would ask for a run transition is refused
/// unless this drive object's last run() succeeded; the direction bit alone is composed with the
/// stop word.
#[test]
fn a_field_write_never_asks_the_machine_to_run() {
    let drive = map(FIXTURES[1]);
    let p = drive.plan();
    let stw1 = p.roles.profile.unwrap().control;
    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    d.client().write_register(slave, 0x0063, 0x047E).unwrap();
    match d.command_fields_word(stw1, 0x000F, 0x000F) {
        Err(Error::Refused(drivemap_runtime::error::Refusal::FieldNotWritable {
            role, ..
        })) => {
            assert_eq!(role, "run")
        }
        other => panic!("{other:?}"),
    }
    // The direction alone: the word read back (047Eh) with bit 11, no run.
    assert_eq!(d.command_fields_word(stw1, 0x0800, 0x0800).unwrap(), 0x0C7E);
    d.run().unwrap();
    assert_eq!(d.command_fields_word(stw1, 0x0800, 0x0800).unwrap(), 0x0C7F);
}

/// A map's own profile, no standard named: a drive that runs only with RUN ENABLE (bit 1) and
/// START (bit 0) both set, enabled first (as the V20's Modbus table prints them as two
/// commands). The trait writes 0002h then 0003h; 0003h alone from power-on (the skipped enable)
/// leaves the simulated drive stopped.
#[test]
fn a_profile_of_the_maps_own_runs_through_its_two_bits() {
    let text = r#"
drive:
  id: two-bits
  vendor: Example
  models: [TB-1]
  manuals:
    - {file: tb.txt, title: Example manual}
protocol:
  transports: [rtu]
  function_codes: [0x03, 0x06, 0x10]
  max_read: 8
  max_write: 8
  slave_address: {min: 1, max: 247}
groups:
  - id: main
    name: Registers
    access: rw
    registers:
      - id: command
        name: Command
        address: 0x0010
        fields:
          - {id: start, name: START, bit: 0, source: "tb.txt:2"}
          - {id: run_enable, name: RUN ENABLE, bit: 1, source: "tb.txt:3"}
          - {id: fault_ack, name: Fault acknowledge, bit: 7, source: "tb.txt:4"}
        source: "tb.txt:1"
      - id: status
        name: Status
        address: 0x0011
        access: r
        fields:
          - {id: enabled, name: Enabled, bit: 0, source: "tb.txt:6"}
          - {id: running, name: Running, bit: 1, source: "tb.txt:7"}
          - {id: fault, name: Fault, bit: 2, source: "tb.txt:8"}
        source: "tb.txt:5"
profile:
  control: command
  status: status
  source: "tb.txt:9"
  power_on: {state: disabled, source: "tb.txt:10"}
  states:
    disabled: {mask: 0x0007, value: 0x0000, source: "tb.txt:11"}
    enabled: {mask: 0x0007, value: 0x0001, source: "tb.txt:12"}
    running: {mask: 0x0007, value: 0x0003, source: "tb.txt:13"}
    fault: {mask: 0x0004, value: 0x0004, source: "tb.txt:14"}
  transitions:
    enable: {word: 0x0002, from: [disabled, running], to: enabled, limit_ms: 200, source: "tb.txt:15"}
    start: {word: 0x0003, from: [enabled], to: running, limit_ms: 200, source: "tb.txt:16"}
    disable: {word: 0x0000, from: [enabled, running], to: disabled, limit_ms: 200, source: "tb.txt:17"}
    acknowledge: {word: 0x0080, edge: 0x0080, from: [fault], to: disabled, limit_ms: 200, source: "tb.txt:18"}
  paths:
    run: {via: [enable, start], to: [running]}
    stop: {via: [enable], to: [enabled, disabled, fault]}
    coast: {via: [disable], to: [disabled, fault]}
    reset_fault: {via: [acknowledge], to: [disabled]}
"#;
    let drive = drivemap_map::Loader::new()
        .load_str("two-bits.yaml", text)
        .unwrap_or_else(|e| panic!("{e}"));
    let p = drive.plan();
    assert_eq!(p.roles.profile.unwrap().name, "own");
    let (mut c, settings, slave) = connect(&drive, TransportKind::RtuOverTcp, 0);
    c.write_register(slave, 0x0010, 0x0003).unwrap();
    assert_eq!(c.transport().sim.profile_state(), Some("disabled"));
    assert!(!c.transport().sim.state().unwrap().run_command);
    c.write_register(slave, 0x0010, 0x0000).unwrap();
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    written(&mut d);
    d.run().unwrap();
    assert_eq!(written(&mut d), [0x0002, 0x0003]);
    assert!(run_command(d.client()));
    d.stop().unwrap();
    assert_eq!(written(&mut d), [0x0002]);
    assert!(!run_command(d.client()));
    assert!(matches!(
        d.quick_stop(),
        Err(Error::Refused(
            drivemap_runtime::error::Refusal::NoRole { .. }
        ))
    ));
}

/// An interlock at the drive (safe torque off open): the simulated drive refuses the
/// transitions towards running; run() waits out switch on's 100 ms and names the state the drive
/// stayed in (shutdown, a stop's transition too, was taken); stop still acts; once the interlock
/// closes, run() completes.
#[test]
fn an_interlock_refuses_the_way_to_running_and_run_says_where_it_stopped() {
    let drive = kestrel();
    let p = drive.plan();
    let (mut c, settings, slave) = connect(&drive, TransportKind::Tcp, 0);
    let mut d = Vfd::from_plan(&mut c, slave, settings.view(&drive), p.registers, p.roles);
    d.client().transport().sim.set_interlock(true);
    match d.run() {
        Err(Error::StateMachine { state, why, .. }) => {
            assert_eq!(state, "ready_to_switch_on");
            assert!(
                why.contains("`switched_on` within 100 ms of `switch_on`"),
                "{why}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(!run_command(d.client()));
    d.stop().unwrap();
    assert_eq!(d.profile_state().unwrap(), Some("ready_to_switch_on"));
    d.client().transport().sim.set_interlock(false);
    d.run().unwrap();
    assert!(run_command(d.client()));
}
