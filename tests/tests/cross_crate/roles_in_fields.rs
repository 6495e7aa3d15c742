//! Number roles on a field of a register, and a reset whose edge or level the manual does not
//! print, through the drive trait against a drive simulated from its map:
//!
//! - the acme-vf1 fixture's fault code is its status word's high byte (`acme-vf1.txt:58`):
//!   `fault_code()` returns that byte and its name, the rest of the word keeps the status bits;
//! - the brenner-fx4 fixture's fault code is a signed byte: `fault_code()` gives its value
//!   sign-extended;
//! - the brenner-fx4 reset says `edge: {unknown: ..}`: the simulated drive acts on the edge (the
//!   stricter reading), and under lost, late and refused replies and reconnects every
//!   `reset_fault()` that succeeds has cleared the trip and left the reset bit released.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_live::LiveSettings;
use drivemap_live::View;
use drivemap_map::Map;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::roles::{Edge, Role, Roles, Target};
use drivemap_runtime::vfd::{VariableFrequencyDrive, Vfd};
use drivemap_runtime::{client::Client, client::ClientOptions, error::Error, error::Refusal};
use drivemap_sim::{SimOptions, Simulator, clock::ManualClock};
use drivemap_test_support::sim_link::{LinkFault, SimLink};

fn map(path: &str) -> Map {
    let path = paths::workspace().join(path);
    drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn acme() -> Map {
    map("tests/fixtures/acme-vf1/acme-vf1.yaml")
}

fn brenner() -> Map {
    map("tests/fixtures/brenner-fx4/brenner-fx4.yaml")
}

/// A simulator of `drive` installed for network control on `kind`.
fn simulator(drive: &Map, kind: TransportKind) -> Simulator {
    Simulator::new(
        drive.clone(),
        SimOptions::new()
            .clock(Arc::new(ManualClock::new()))
            .network_source(kind),
    )
    .unwrap()
}

/// Options that make a lost reply cheap: the link answers at once or never.
fn options(retries: u8) -> ClientOptions {
    ClientOptions {
        timeout: Duration::from_micros(20),
        retries,
        request_gap: Duration::ZERO,
        ..ClientOptions::default()
    }
}

/// A client on a simulated drive over `kind` (`retries` after a lost reply), with the
/// simulator's slave and settings: what the drive trait is made of.
struct Rig {
    client: Client<SimLink>,
    slave: u8,
    settings: LiveSettings,
}

impl Rig {
    fn new(drive: &Map, sim: Simulator, kind: TransportKind, retries: u8) -> Rig {
        let (settings, slave) = (sim.settings(), sim.slave());
        let client = Client::with_options(
            SimLink::new(kind, sim),
            drive.plan().profile,
            options(retries),
        );
        Rig {
            client,
            slave,
            settings,
        }
    }

    /// The drive trait on it, `drive`'s plan rows with `roles` (the plan's, or changed).
    fn vfd<'a>(
        &'a mut self,
        drive: &'a Map,
        roles: Roles,
    ) -> Vfd<View<'a>, &'a mut Client<SimLink>> {
        Vfd::from_plan(
            &mut self.client,
            self.slave,
            self.settings.view(drive),
            drive.plan().registers,
            roles,
        )
    }
}

#[test]
fn acme_reports_its_fault_code_from_the_status_words_high_byte() {
    let drive = acme();
    let plan = drive.plan();
    assert!(
        matches!(
            plan.roles.of(Role::FaultCode).next().map(|p| p.target),
            Some(Target::NumberField(f)) if f.lsb == 8 && f.width == 8 && !f.signed
        ),
        "acme-vf1's fault code is the status word's high byte"
    );
    let kind = TransportKind::Rtu;
    let mut rig = Rig::new(&drive, simulator(&drive, kind), kind, 0);
    let mut d = rig.vfd(&drive, plan.roles);
    let none = d.fault_code().unwrap();
    assert_eq!((none.code, none.value, none.name), (0, 0, Some("No fault")));
    d.client().transport().sim.trip(3);
    let status = d.status().unwrap();
    assert_eq!(status.fault, Some(true), "{status}");
    let code = d.fault_code().unwrap();
    assert_eq!(
        (code.code, code.value, code.name),
        (3, 3, Some("Undervoltage"))
    );
    // The code is in bits 8-15; the fault status bit (5) is in the same word, kept.
    let word = d.client().transport().sim.raw("status_word").unwrap();
    assert_eq!(word >> 8, 3, "status word {word:04X}h");
    assert_ne!(word & (1 << 5), 0, "status word {word:04X}h: fault bit");
    d.reset_fault().unwrap();
    assert_eq!(d.status().unwrap().fault, Some(false));
    assert_eq!(d.fault_code().unwrap().code, 0);
    assert_eq!(
        d.client().transport().sim.raw("status_word").unwrap() >> 8,
        0
    );
}

#[test]
fn a_signed_fault_byte_reads_as_a_negative_value() {
    let drive = brenner();
    let plan = drive.plan();
    let kind = TransportKind::Rtu;
    let mut rig = Rig::new(&drive, simulator(&drive, kind), kind, 0);
    let mut d = rig.vfd(&drive, plan.roles);
    // Code 255 is -1, "Low DC bus" (brenner-fx4.txt:17).
    d.client().transport().sim.trip(0xFF);
    let code = d.fault_code().unwrap();
    assert_eq!(
        (code.code, code.value, code.name),
        (255, -1, Some("Low DC bus (-1)"))
    );
    d.client().transport().sim.trip(2);
    let code = d.fault_code().unwrap();
    assert_eq!((code.code, code.value), (2, 2));
}

/// A setpoint on a field is read, changed in place and written back only where that is safe:
/// on acme-vf1 with its frequency reference moved into the status word's high byte, which is
/// read-only, and then into the control word, which holds command fields, the write is refused
/// before anything is sent.
#[test]
fn a_setpoint_on_a_field_is_refused_where_read_modify_write_is_not_safe() {
    let text = std::fs::read_to_string(paths::fixture("acme-vf1/acme-vf1.yaml")).unwrap();
    let moved = text.replace(
        r#"    - {register: speed_reference, source: "acme-vf1.txt:19"}"#,
        r#"    - {register: status_word, field: active_fault, scale: 1, source: "acme-vf1.txt:19"}"#,
    );
    assert_ne!(moved, text);
    // The status word is read-only: validation refuses a setpoint there.
    let e = drivemap_map::Loader::new()
        .load_str("acme-vf1.yaml", &moved)
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("role `frequency_reference` is written, but `status_word` is not writable"),
        "{e}"
    );
    // A plan built by hand may still put it on a word with command fields: the trait refuses.
    let drive = acme();
    let plan = drive.plan();
    let control = plan
        .registers
        .iter()
        .position(|r| r.info.id == "control_word")
        .unwrap() as u16;
    let mut places: Vec<_> = plan.roles.places.to_vec();
    for p in &mut places {
        if p.role == Role::FrequencyReference {
            p.target = Target::NumberField(drivemap_runtime::core::roles::NumberField {
                row: control,
                lsb: 8,
                width: 8,
                signed: false,
                scale: drivemap_runtime::core::scale::Decimal::ONE,
            });
        }
    }
    let roles = Roles {
        places: Box::leak(places.into_boxed_slice()),
        profile: None,
    };
    let kind = TransportKind::Rtu;
    let mut rig = Rig::new(&drive, simulator(&drive, kind), kind, 0);
    let mut d = rig.vfd(&drive, roles);
    let sent = d.client().transport().log.len();
    match d.set_reference(10.0) {
        Err(Error::Refused(Refusal::FieldNotWritable { role, why, .. })) => {
            assert_eq!(role, "frequency_reference");
            assert!(why.contains("command fields"), "{why}");
        }
        other => panic!("a reference in the control word: {other:?}"),
    }
    // The source check reads (the command source parameter); nothing is written.
    assert!(
        d.client().transport().log[sent..]
            .iter()
            .all(|s| s.frame[1] == 0x03),
        "only reads on the wire"
    );
}

/// One step of a reset sequence.
#[derive(Debug, Clone, Copy)]
enum Step {
    /// The simulated drive trips with this code.
    Trip(u16),
    ResetFault,
    Run,
    Stop,
    FaultCode,
}

fn step() -> impl proptest::strategy::Strategy<Value = Step> {
    use proptest::prelude::*;
    prop_oneof![
        2 => (1u16..256).prop_map(Step::Trip),
        4 => Just(Step::ResetFault),
        1 => Just(Step::Run),
        1 => Just(Step::Stop),
        1 => Just(Step::FaultCode),
    ]
}

fn fault() -> impl proptest::strategy::Strategy<Value = Option<LinkFault>> {
    use proptest::prelude::*;
    prop_oneof![
        8 => Just(None),
        3 => Just(Some(LinkFault::LoseReply)),
        1 => Just(Some(LinkFault::LoseRequest)),
        3 => Just(Some(LinkFault::LateReply)),
        1 => Just(Some(LinkFault::Exception(6))),
        1 => any::<bool>().prop_map(|executed| Some(LinkFault::Disconnect { executed })),
    ]
}

/// Plays `steps` on brenner-fx4 over RTU framing (over TCP: it reconnects) with `faults` on the
/// link; returns a violation of the reset contract, if any.
fn play(
    drive: &Map,
    roles: drivemap_runtime::core::roles::Roles,
    template: &Simulator,
    steps: &[Step],
    faults: &[Option<LinkFault>],
    retries: u8,
) -> Result<(), String> {
    let kind = TransportKind::RtuOverTcp;
    let mut rig = Rig::new(drive, template.clone(), kind, retries);
    rig.client.transport().script(faults.iter().copied());
    let mut d = rig.vfd(drive, roles);
    let tripped = |sim: &Simulator| sim.raw("state_word").unwrap() & 0b10 != 0;
    for (i, &s) in steps.iter().enumerate() {
        match s {
            Step::Trip(code) => d.client().transport().sim.trip(code),
            Step::ResetFault => {
                let before = d.client().transport().log.len();
                let result = d.reset_fault();
                if result.is_ok() {
                    if tripped(&d.client().transport().sim) {
                        return Err(format!(
                            "step {i}: reset_fault() succeeded but the drive is still tripped"
                        ));
                    }
                    // The last word the drive executed for this call has the reset released.
                    let log = &d.client().transport().log[before..];
                    let last = log
                        .iter()
                        .rev()
                        .find(|s| s.executed && s.frame[1] == 0x06)
                        .map(|s| u16::from_be_bytes([s.frame[4], s.frame[5]]));
                    if last.is_none_or(|w| w & 0b1000 != 0) {
                        return Err(format!(
                            "step {i}: reset_fault() succeeded, last command word executed {last:04X?}: the reset is not released"
                        ));
                    }
                }
            }
            Step::Run => {
                let _ = d.run();
            }
            Step::Stop => {
                let _ = d.stop();
            }
            Step::FaultCode => {
                if let Ok(code) = d.fault_code() {
                    // Read through the link (a late reply may be an earlier read's): the
                    // value is the byte's, sign-extended.
                    if code.value != i32::from(code.code as u8 as i8) {
                        return Err(format!(
                            "step {i}: fault code {} read as {}",
                            code.code, code.value
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// The reset path of a drive whose manual does not print edge or level, under injected
/// faults. Were `edge: {unknown}` taken as level, a reset whose set was executed but whose reply
/// was lost would leave the bit set at the drive, and the next `reset_fault()` would write set
/// (no transition: the drive does not act) then release, and report success with the drive
/// still tripped; the first case below is that sequence.
#[test]
fn a_reset_of_unknown_edge_acts_under_faults() {
    use proptest::test_runner::{Config, TestCaseError, TestRunner};
    let drive = brenner();
    let [Target::Field(reset)] = drive
        .plan()
        .roles
        .of(Role::FaultReset)
        .map(|p| p.target)
        .collect::<Vec<_>>()[..]
    else {
        panic!("brenner-fx4 has one reset field");
    };
    assert!(
        matches!(reset.edge, Edge::NotPrinted(_)),
        "{:?}",
        reset.edge
    );
    let template = simulator(&drive, TransportKind::RtuOverTcp);
    // Trip; the reset's set executes and its reply is lost (no retries: the call fails); trip
    // again; reset.
    let sequence = [
        Step::Trip(1),
        Step::ResetFault,
        Step::Trip(2),
        Step::ResetFault,
    ];
    let lost = [Some(LinkFault::LoseReply)];
    let roles = drive.plan().roles;
    play(&drive, roles, &template, &sequence, &lost, 0).unwrap();
    // The same plan with the reset taken as level (what a trait that read "not printed" as
    // level would do): the check catches it.
    let level: Vec<_> = roles
        .places
        .iter()
        .map(|p| match p.target {
            Target::Field(f) if p.role == Role::FaultReset => {
                drivemap_runtime::core::roles::Place {
                    target: Target::Field(drivemap_runtime::core::roles::FieldRole {
                        edge: Edge::Level,
                        ..f
                    }),
                    ..*p
                }
            }
            _ => *p,
        })
        .collect();
    let level = Roles {
        places: Box::leak(level.into_boxed_slice()),
        profile: None,
    };
    let caught = play(&drive, level, &template, &sequence, &lost, 0).unwrap_err();
    assert!(caught.contains("still tripped"), "{caught}");
    let mut runner = TestRunner::new(Config {
        cases: 800,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (
        proptest::collection::vec(step(), 1..16),
        proptest::collection::vec(fault(), 0..30),
        0u8..3,
    );
    runner
        .run(&strategy, |(steps, faults, retries)| {
            play(&drive, roles, &template, &steps, &faults, retries).map_err(TestCaseError::fail)
        })
        .unwrap();
}

/// A field of a command register written through the library (`Vfd::write_command_fields`,
/// what `drivemap write reg=field=value` composes with): the fault reset never goes out unless
/// named, the run bit only while this master's last `run()` stands (or the status shows the
/// drive running); a register that holds no command is refused, nothing sent (issue 37).
#[test]
fn a_command_field_is_written_from_the_roles_not_from_a_read_back() {
    let drive = map("maps/yaskawa-v7.yaml");
    let kind = TransportKind::Rtu;
    let mut rig = Rig::new(&drive, simulator(&drive, kind), kind, 0);
    let command = drive.register("digital_input_command").unwrap();
    let row = u16::try_from(command.row()).unwrap();
    let bit = |id: &str| match &drive.plan().registers[usize::from(row)].conversion {
        drivemap_runtime::core::plan::Conversion::Bits { fields, .. } => {
            fields.iter().find(|f| f.id == id).unwrap().mask()
        }
        _ => unreachable!("a bit-field register"),
    };
    let (run, reset, s3) = (bit("run_command"), bit("fault_reset"), bit("terminal_s3"));
    let mut d = rig.vfd(&drive, drive.plan().roles);
    assert!(d.holds_command(row));
    // Stopped: S3 on, nothing else.
    assert_eq!(d.write_command_fields(row, s3, s3).unwrap(), s3);
    // Running by this master: the run is kept, the reset still not sent.
    d.run().unwrap();
    let word = d.write_command_fields(row, s3, 0).unwrap();
    assert_eq!(word & (run | reset | s3), run, "{word:04X}h");
    // A reset named is sent; the next write releases it.
    let word = d.write_command_fields(row, reset, reset).unwrap();
    assert_eq!(word & (run | reset), run | reset, "{word:04X}h");
    let word = d.write_command_fields(row, s3, s3).unwrap();
    assert_eq!(word & (run | reset | s3), run | s3, "{word:04X}h");
    // Stopped again: no run in any word a field write sends.
    d.stop().unwrap();
    let word = d.write_command_fields(row, s3, 0).unwrap();
    assert_eq!(word & (run | reset | s3), 0, "{word:04X}h");
    // A register without a command role is refused, not written.
    let other = drive.register("n019").unwrap();
    let other_row = u16::try_from(other.row()).unwrap();
    assert!(!d.holds_command(other_row));
    assert!(matches!(
        d.write_command_fields(other_row, 1, 1),
        Err(Error::Refused(Refusal::FieldNotWritable { .. }))
    ));
}
