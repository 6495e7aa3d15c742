//! What `drivemap write` sends is the value given, within every limit the manual states, at an
//! address it knows, or nothing: through the binary, against a simulated drive.
//!
//! - a value above a limit through another parameter (V7 n011) is refused, after reading it;
//! - a register whose address moves with a setting that cannot be read (GPD 515 o2-09) is
//!   refused, never written to its printed address;
//! - an empty value is refused;
//! - a register whose range the manual does not print gets a warning naming that.

use crate::common;

use std::sync::{Arc, Mutex};

use drivemap_sim::SimulatedSlave;
use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};

use common::{Framing, drivemap, repo, serve};

/// The drive simulator of a shipped map, with its drive model, on loopback Modbus TCP.
fn simulator(id: &str) -> (Arc<Mutex<Simulator>>, TcpServer, String) {
    let path = repo().join(format!("maps/{id}.yaml"));
    let drive = drivemap_map::Loader::new().load(&path).unwrap();
    let sim = drivemap_sim::server::shared(Simulator::new(drive, SimOptions::new()).unwrap());
    let server =
        TcpServer::spawn(Arc::clone(&sim), "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
    let addr = server.local_addr().to_string();
    (sim, server, addr)
}

/// A bare simulated slave of `id`'s profile on loopback Modbus TCP that executes every write
/// it receives and answers the faults set with `fail_at`.
fn bare_slave(
    id: &str,
    setup: impl FnOnce(&mut SimulatedSlave),
) -> (Arc<Mutex<SimulatedSlave>>, String) {
    let path = repo().join(format!("maps/{id}.yaml"));
    let drive = drivemap_map::Loader::new().load(&path).unwrap();
    let profile = drivemap_live::leak_profile(&drive);
    let mut slave = SimulatedSlave::new(1, profile);
    setup(&mut slave);
    let (addr, slave) = serve(slave, Framing::Tcp);
    (slave, addr)
}

/// The repro: 500 Hz to a V7 whose maximum output frequency n011 is 60 Hz. The map
/// prints no range for the register, but n011 bounds it ("30000 = Max. output frequency"):
/// refused after reading n011, and the simulated drive keeps its reference.
#[test]
fn a_reference_above_n011_is_refused() {
    let (sim, server, addr) = simulator("yaskawa-v7");
    assert_eq!(
        sim.lock()
            .unwrap()
            .value("max_output_frequency")
            .unwrap()
            .as_f64(),
        Some(60.0)
    );
    let (code, _, err) = drivemap(&[
        "write",
        "--drive",
        "yaskawa-v7",
        "--tcp",
        &addr,
        "tcp_frequency_reference=500",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("tcp_frequency_reference: 500 Hz is above 60 Hz, 100 % of n011")
            && err.contains("nothing written"),
        "{err}"
    );
    assert_eq!(
        sim.lock().unwrap().raw("tcp_frequency_reference").unwrap(),
        0
    );
    // 60 Hz is the maximum itself: written, as given.
    let (code, stdout, err) = drivemap(&[
        "write",
        "--drive",
        "yaskawa-v7",
        "--tcp",
        &addr,
        "tcp_frequency_reference=60",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains("wrote tcp_frequency_reference = 60.0 Hz (0258h)"),
        "{stdout}"
    );
    assert_eq!(
        sim.lock().unwrap().raw("tcp_frequency_reference").unwrap(),
        600
    );
    // n011 lowered on the drive: the limit follows it, read afresh.
    sim.lock()
        .unwrap()
        .set("max_output_frequency", 50.0)
        .unwrap();
    let (code, _, err) = drivemap(&[
        "write",
        "--drive",
        "yaskawa-v7",
        "--tcp",
        &addr,
        "tcp_frequency_reference=55",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("above 50 Hz"), "{err}");
    assert_eq!(
        sim.lock().unwrap().raw("tcp_frequency_reference").unwrap(),
        600
    );
    server.stop();
}

/// GPD 515 (RTU only, reached through a Modbus TCP gateway): the frequency reference is at
/// 0002h with o2-09 = 1, where 0001h is the operation command. When o2-09 (50Dh) cannot be read, nothing is written anywhere; given with `--set`,
/// the write goes to the address it selects.
#[test]
fn an_address_chosen_by_an_unreadable_setting_is_refused() {
    let (slave, addr) = bare_slave("yaskawa-gpd515", |s| {
        s.fail_at(0x050D, 0x02);
        s.set_holding(0x0303, 600); // E1-04 = 60.0 Hz
    });
    let (code, _, err) = drivemap(&[
        "write",
        "--drive",
        "yaskawa-gpd515",
        "--gateway",
        &addr,
        "--slave",
        "1",
        "frequency_reference=60",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("its address depends on o2-09, which could not be read")
            && err.contains("--set o2-09=<value>")
            && err.contains("nothing written"),
        "{err}"
    );
    assert!(
        slave.lock().unwrap().writes.is_empty(),
        "a write reached the drive"
    );
    // o2-09 given: written where o2-09 = 1 puts it.
    let (code, stdout, err) = drivemap(&[
        "write",
        "--drive",
        "yaskawa-gpd515",
        "--gateway",
        &addr,
        "--slave",
        "1",
        "--set",
        "o2-09=1",
        "frequency_reference=60",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("at 0002h"), "{stdout}");
    assert_eq!(slave.lock().unwrap().writes, vec![(0x0002, 0x1770)]);
}

/// `name=` is refused, never taken as "write back what the drive holds".
#[test]
fn an_empty_value_is_refused() {
    let (slave, addr) = bare_slave("yaskawa-v7", |_| {});
    let (code, _, err) = drivemap(&[
        "write",
        "--drive",
        "yaskawa-v7",
        "--tcp",
        &addr,
        "tcp_digital_input_command=",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("`tcp_digital_input_command=`: no value given"),
        "{err}"
    );
    assert!(slave.lock().unwrap().writes.is_empty());
}

/// The ACN's frequency command prints no range and no limit through another parameter: the
/// write says so (and writes, since the word bounds it); a register with a printed range does
/// not warn.
#[test]
fn a_register_without_a_printed_range_is_named() {
    let (slave, addr) = bare_slave("automationdirect-acn", |_| {});
    let (code, _, err) = drivemap(&[
        "write",
        "--drive",
        "automationdirect-acn",
        "--tcp",
        &addr,
        "frequency_command=10",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: the manual prints no range for frequency_command")
            && err.contains("only its 16-bit word bounds the value sent"),
        "{err}"
    );
    assert_eq!(slave.lock().unwrap().writes.len(), 1);
    let (_, addr) = bare_slave("yaskawa-v7", |_| {});
    let (code, _, err) = drivemap(&["write", "--drive", "yaskawa-v7", "--tcp", &addr, "n011=60"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("prints no range"), "{err}");
}

/// Sent as given or refused (issue 23, item 4), through the binary against the V7 simulator:
/// `n019=0.04` and 35.75 Hz are refused with the two nearest values, `--round` sends the
/// nearest and says so, and the range applies to the value given (-0.04 s is refused with
/// `--round` too).
#[test]
fn a_value_between_steps_is_refused_unless_rounded() {
    let (sim, server, addr) = simulator("yaskawa-v7");
    let write = |args: &[&str]| {
        let mut all = vec!["write", "--drive", "yaskawa-v7", "--tcp", addr.as_str()];
        all.extend_from_slice(args);
        drivemap(&all)
    };
    let before = sim.lock().unwrap().raw("accel_time_1").unwrap();
    let (code, _, err) = write(&["n019=0.04"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("accel_time_1: 0.04 s is between 0 and 0.1 s; the register counts 0.1 s")
            && err.contains("--round sends the nearest")
            && err.contains("nothing written"),
        "{err}"
    );
    for args in [&["n019=-0.04"][..], &["--round", "n019=-0.04"]] {
        let (code, _, err) = write(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("-0.04 s is out of range 0 ..= 6000 s"),
            "{err}"
        );
    }
    assert_eq!(sim.lock().unwrap().raw("accel_time_1").unwrap(), before);
    let (code, _, err) = write(&["tcp_frequency_reference=35.75"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("35.75 Hz is between 35.7 and 35.8 Hz; the register counts 0.1 Hz"),
        "{err}"
    );
    assert_eq!(
        sim.lock().unwrap().raw("tcp_frequency_reference").unwrap(),
        0
    );
    let (code, stdout, err) = write(&["--round", "tcp_frequency_reference=35.75"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains(
            "wrote tcp_frequency_reference = 35.8 Hz, rounded from 35.75 (--round) (0166h)"
        ),
        "{stdout}"
    );
    assert_eq!(
        sim.lock().unwrap().raw("tcp_frequency_reference").unwrap(),
        358
    );
    // A value on a step needs no rounding and says none.
    let (code, stdout, err) = write(&["--round", "n019=12.5"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains("= 12.5 s (007Dh)") && !stdout.contains("rounded"),
        "{stdout}"
    );
    server.stop();
}

/// The interpreted codec (what the CLI, the simulator and tools use): the same refusal and the
/// same explicit rounding as the typed API.
#[test]
fn the_interpreted_codec_refuses_between_steps() {
    use drivemap_live::LiveSettings;
    use drivemap_live::codec;
    use drivemap_runtime::core::scale::{Rounding, ValueError};
    let path = repo().join("maps/yaskawa-v7.yaml");
    let drive = drivemap_map::Loader::new().load(&path).unwrap();
    let r = drivemap_live::lookup::find(&drive, "tcp_frequency_reference").unwrap();
    let mut settings = LiveSettings::default();
    settings
        .selectors
        .insert("modbus_frequency_reference_unit_selection".into(), 0);
    settings
        .references
        .insert("max_output_frequency".into(), 60.0);
    assert!(matches!(
        codec::encode(&drive, r, 35.75, &settings),
        Err(ValueError::NotAStep { below, above, .. }) if below == 35.7 && above == 35.8
    ));
    assert_eq!(
        codec::encode_with(&drive, r, 35.75, &settings, Rounding::Nearest),
        Ok(358)
    );
    assert!(matches!(
        codec::encode_with(&drive, r, 60.04, &settings, Rounding::Nearest),
        Err(ValueError::AboveLimit { .. })
    ));
    assert!(matches!(
        codec::parse_value(&drive, r, " ", &settings),
        Err(codec::InputError::Parse(m)) if m.contains("no value given")
    ));
}

/// The J7's maximum output frequency n09 has no register number in its manual: the map makes it
/// an external quantity, so a reference is written only with `--set max_output_frequency`, and
/// is refused above it.
#[test]
fn a_limit_through_an_external_quantity_needs_it_given() {
    let (slave, addr) = bare_slave("yaskawa-j7", |_| {});
    let write = |args: &[&str]| {
        let mut all = vec![
            "write",
            "--drive",
            "yaskawa-j7",
            "--gateway",
            addr.as_str(),
            "--slave",
            "1",
        ];
        all.extend_from_slice(args);
        drivemap(&all)
    };
    let (code, _, err) = write(&["frequency_reference=30"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("its limit is a percentage of max_output_frequency")
            && err.contains("--set max_output_frequency=<value>"),
        "{err}"
    );
    let (code, _, err) = write(&["--set", "max_output_frequency=60", "frequency_reference=70"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("70 Hz is above 60 Hz"), "{err}");
    assert!(slave.lock().unwrap().writes.is_empty());
    let (code, _, err) = write(&["--set", "max_output_frequency=60", "frequency_reference=30"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().writes, vec![(0x0002, 300)]);
}
