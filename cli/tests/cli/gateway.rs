//! The link's topology (issue 23, item 6): a serial drive behind a Modbus TCP to RTU gateway is
//! a link of its own. `drivemap read --gateway` sends Modbus TCP frames with the map's RTU
//! addressing, RTU registers and RTU timing; `--tcp` on a map whose transports lack `tcp` is
//! refused, naming `--gateway`. Through the binary, against `drivemap simulate --gateway`. An
//! ASCII-only drive (`tests/fixtures/quill-q2`) reached over ASCII frames, RTU refused to it.

use drivemap_test_support::paths;

use crate::common;

use std::net::TcpListener;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::thread;
use std::time::Duration;

use common::{Sim, drivemap};

/// The row of `register` in a read table, with runs of spaces collapsed.
fn row(out: &str, register: &str) -> String {
    let line = out
        .lines()
        .find(|l| l.starts_with(&format!("{register} ")))
        .unwrap_or_else(|| panic!("no row for {register} in:\n{out}"));
    line.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A listener that counts the connections it accepts.
fn counting_listener() -> (String, Arc<AtomicU32>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let count = Arc::new(AtomicU32::new(0));
    let seen = Arc::clone(&count);
    thread::spawn(move || {
        for s in listener.incoming().flatten() {
            seen.fetch_add(1, Ordering::Relaxed);
            drop(s);
        }
    });
    (addr, count)
}

/// The J7 speaks RTU only (`protocol.transports: [rtu]`): `--tcp` is refused before connecting,
/// with a message that names `--gateway`, for every live command.
#[test]
fn tcp_to_a_drive_without_modbus_tcp_is_refused_naming_the_gateway_option() {
    let (addr, connections) = counting_listener();
    for command in [
        vec!["read", "status_signal_1"],
        vec!["write", "digital_input_command=0"],
        vec!["poll", "--count", "1"],
        vec!["probe"],
    ] {
        let mut args = vec![command[0], "--drive", "yaskawa-j7", "--tcp", addr.as_str()];
        args.extend_from_slice(&command[1..]);
        let (code, out, err) = drivemap(&args);
        assert_eq!(code, 2, "{command:?}: {out}{err}");
        assert!(
            err.contains("yaskawa-j7 has no Modbus TCP interface")
                && err.contains(&format!("--gateway {addr}"))
                && err.contains("protocol.transports is [rtu]"),
            "{command:?}: {err}"
        );
    }
    thread::sleep(Duration::from_millis(50));
    assert_eq!(connections.load(Ordering::Relaxed), 0, "nothing connected");
}

/// `--gateway` reaches the J7 behind a simulated Modbus TCP to RTU gateway and reads its
/// registers where the map puts them on RTU.
#[test]
fn gateway_reads_a_serial_only_drive() {
    let sim = Sim::start(&["--drive", "yaskawa-j7", "--gateway", "0", "--set", "n69=2"]);
    assert!(
        sim.first
            .contains("on Modbus TCP gateway to RTU 127.0.0.1:"),
        "{}",
        sim.first
    );
    let (code, out, err) = drivemap(&[
        "read",
        "--drive",
        "yaskawa-j7",
        "--gateway",
        &sim.addr,
        "n69",
        "status_signal_1",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "modbus_frequency_reference_unit_selection"),
        "modbus_frequency_reference_unit_selection (n69) 0198h 2: 30,000 = n011 0002h"
    );
    assert!(row(&out, "status_signal_1").starts_with("status_signal_1 0020h"));
}

/// A drive with an RTU address offset (the ACN: PDU address = communication address - 1 on
/// RTU, 0 on its own Modbus TCP interface) behind a gateway: `--gateway` addresses it with the
/// RTU offset and reads acc_time (dr.03, 1103h) as set; Modbus TCP addressing through the same
/// gateway lands one register off (dec_time's word): the reason the link must be named.
#[test]
fn gateway_applies_the_maps_rtu_address_offset() {
    let sim = Sim::start(&[
        "--drive",
        "automationdirect-acn",
        "--gateway",
        "0",
        "--set",
        "acc_time=5",
        "--set",
        "dec_time=7",
    ]);
    let read = |flag: &str| {
        drivemap(&[
            "read",
            "--drive",
            "automationdirect-acn",
            flag,
            &sim.addr,
            "acc_time",
            "dec_time",
        ])
    };
    let (code, out, err) = read("--gateway");
    assert_eq!(code, 0, "{err}");
    assert_eq!(row(&out, "acc_time"), "acc_time (dr.03) 1103h 5.0 s 0032h");
    assert_eq!(row(&out, "dec_time"), "dec_time (dr.04) 1104h 7.0 s 0046h");
    // The same gateway addressed as the drive's own Modbus TCP interface: one off.
    let (code, out, err) = read("--tcp");
    assert_eq!(code, 0, "{err}");
    assert_eq!(row(&out, "acc_time"), "acc_time (dr.03) 1103h 7.0 s 0046h");
}

/// The V7 has both: through a gateway its RTU-only command register is reachable and its
/// Modbus TCP option card's registers are not.
#[test]
fn gateway_has_the_rtu_registers_of_a_drive_with_both_transports() {
    let sim = Sim::start(&["--drive", "yaskawa-v7", "--gateway", "0"]);
    let (code, out, err) = drivemap(&[
        "read",
        "--drive",
        "yaskawa-v7",
        "--gateway",
        &sim.addr,
        "digital_input_command",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(row(&out, "digital_input_command").starts_with("digital_input_command 0001h"));
    let (code, out, _) = drivemap(&[
        "read",
        "--drive",
        "yaskawa-v7",
        "--gateway",
        &sim.addr,
        "tcp_digital_input_command",
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("error: tcp_digital_input_command exists only on TCP, not on this link (Modbus TCP gateway to RTU)"),
        "{out}"
    );
}

/// The fictional Quill Q2 (`tests/fixtures/quill-q2`) speaks Modbus ASCII only, 7E1.
fn quill() -> std::path::PathBuf {
    paths::fixture("quill-q2")
}

/// `drivemap simulate` of the Quill Q2 with `args`, its maps from the fixture.
fn quill_sim(args: &[&str]) -> Sim {
    let mut cmd = common::command();
    cmd.arg("simulate")
        .args(["--drive", "quill-q2", "--quiet"])
        .args(args)
        .env("DRIVEMAP_MAPS", quill());
    Sim::listening(&mut cmd)
}

/// An ASCII-only drive through the binary: `check --strict` accepts its map (its manual's
/// ASCII frames verified by their LRC), `simulate --rtu-tcp --ascii` serves it as ASCII frames
/// over TCP, and `read`/`probe`/`scan --ascii` reach it there; RTU framing to it is refused before
/// anything is sent, and so is `--ascii` to a map that does not list ASCII.
#[test]
fn an_ascii_drive_is_checked_simulated_read_and_probed_over_ascii() {
    let (code, out, err) = common::drivemap_fixture(
        &quill(),
        &["check", "--strict", "--require-manuals", "quill-q2.yaml"],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("example frames: 2 of 2 verified"), "{out}");

    let sim = quill_sim(&[
        "--rtu-tcp",
        "0",
        "--ascii",
        "--set",
        "frequency_command=42.5",
    ]);
    assert!(
        sim.first.contains("on ASCII over TCP 127.0.0.1:"),
        "{}",
        sim.first
    );
    let maps = quill();
    let maps = maps.to_str().unwrap();
    let (code, out, err) = common::run(common::command().args([
        "read",
        "--maps",
        maps,
        "--drive",
        "quill-q2",
        "--rtu-tcp",
        sim.addr.as_str(),
        "--ascii",
        "frequency_command",
        "status",
    ]));
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(
        row(&out, "frequency_command"),
        "frequency_command 0101h 42.50 Hz 109Ah"
    );
    let (code, out, err) = common::run(common::command().args([
        "probe",
        "--maps",
        maps,
        "--drive",
        "quill-q2",
        "--rtu-tcp",
        sim.addr.as_str(),
        "--ascii",
    ]));
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("over ASCII over TCP") && out.contains("6 agree, 0 disagree"),
        "{out}"
    );
    // scan --ascii finds it at slave 1 and names its map.
    let (code, out, err) = common::run(common::command().args([
        "scan",
        "--maps",
        maps,
        "--rtu-tcp",
        sim.addr.as_str(),
        "--ascii",
        "--slaves",
        "1-2",
    ]));
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("scan of ASCII over TCP"), "{out}");
    let row = out
        .lines()
        .find(|l| l.starts_with("1 "))
        .unwrap_or_else(|| panic!("no slave 1 in {out}"));
    assert!(row.contains("quill-q2 4/4"), "{out}");

    // RTU frames to it: refused before connecting, naming --ascii.
    let (addr, connections) = counting_listener();
    let (code, out, err) = common::run(common::command().args([
        "read",
        "--maps",
        maps,
        "--drive",
        "quill-q2",
        "--rtu-tcp",
        addr.as_str(),
        "frequency_command",
    ]));
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("quill-q2 speaks Modbus ASCII, not RTU") && err.contains("add --ascii"),
        "{err}"
    );
    // ASCII to a drive whose map lists RTU only.
    let (code, out, err) = drivemap(&[
        "read",
        "--drive",
        "yaskawa-j7",
        "--rtu-tcp",
        addr.as_str(),
        "--ascii",
        "status_signal_1",
    ]);
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("yaskawa-j7's map does not list Modbus ASCII"),
        "{err}"
    );
    thread::sleep(Duration::from_millis(50));
    assert_eq!(connections.load(Ordering::Relaxed), 0, "nothing connected");
}

/// `drivemap demo` of the ASCII-only drive runs and stops it through the drive trait over
/// Modbus ASCII frames.
#[test]
fn an_ascii_drive_is_demoed_over_ascii() {
    let maps = quill();
    let (code, out, err) = common::run(common::command().args([
        "demo",
        "--maps",
        maps.to_str().unwrap(),
        "--drive",
        "quill-q2",
        "--frequency",
        "30",
        "--time-scale",
        "50",
    ]));
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("Modbus ASCII frames over TCP"), "{out}");
    assert!(out.contains("30.00"), "{out}");
    assert!(out.contains("0 exceptions"), "{out}");
}
