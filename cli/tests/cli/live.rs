//! `drivemap read`, `write` and `poll` end to end: the binary talks over loopback TCP (Modbus TCP
//! or RTU frames over TCP) to a `SimulatedSlave` of the runtime served in a thread of the test.
//! Addresses in the slave are PDU addresses, so the map's per-transport offsets are checked too.

use drivemap_test_support::paths;

use crate::common;
mod coils;
mod paramset;

use std::net::{TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use drivemap_sim::SimulatedSlave;

/// A simulated drive listening on loopback.
struct Drive {
    addr: String,
    flag: &'static str,
    slave: Arc<Mutex<SimulatedSlave>>,
}

impl Drive {
    fn start(id: &str, framing: Framing, setup: impl FnOnce(&mut SimulatedSlave)) -> Drive {
        let path = paths::maps().join(format!("{id}.yaml"));
        let map = drivemap_map::Loader::new()
            .load(&path)
            .expect("shipped map");
        let mut slave = SimulatedSlave::new(1, drivemap_live::leak_profile(&map));
        setup(&mut slave);
        Drive::serve(slave, framing)
    }

    /// Serves `slave` on loopback.
    fn serve(slave: SimulatedSlave, framing: Framing) -> Drive {
        let (addr, slave) = serve(slave, framing);
        Drive {
            addr,
            flag: framing.flag(),
            slave,
        }
    }

    /// Runs `drivemap <command> --drive <id> <link> <args...>`.
    fn run(&self, command: &str, id: &str, args: &[&str]) -> (i32, String, String) {
        let mut all = vec![command, "--drive", id, self.flag, &self.addr];
        all.extend_from_slice(&["--timeout", "2s"]);
        all.extend_from_slice(args);
        drivemap(&all)
    }

    fn requests(&self) -> u32 {
        self.slave.lock().unwrap().executed
    }

    fn holding(&self, pdu: u16) -> u16 {
        self.slave.lock().unwrap().holding(pdu)
    }

    fn writes(&self) -> Vec<(u16, u16)> {
        self.slave.lock().unwrap().writes.clone()
    }
}

/// The row of `register` in a read table, with runs of spaces collapsed.
fn row(out: &str, register: &str) -> String {
    let line = out
        .lines()
        .find(|l| l.starts_with(&format!("{register} ")))
        .unwrap_or_else(|| panic!("no row for {register} in:\n{out}"));
    line.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The TDS-V8 speaks RTU only: it is reached through a Modbus TCP gateway.
fn tds() -> Drive {
    Drive::start("ptlk-tds-v8", Framing::Gateway, |s| {
        s.set_holding(0x0301, 600); // Cn-02 max output frequency 60.0 Hz
        s.set_holding(0x0001, 24000); // frequency command: 80 % of Cn-02
        s.set_holding(0x0020, 0x0019); // running, ready, DRV mode
        s.set_holding(0x0024, 15000); // frequency command monitor: 50 %
        s.set_holding(0x0025, 30000); // output frequency: 100 %
        s.set_holding(0x0027, 123); // output current 12.3 A
        s.set_holding(0x0200, 100); // Bn-01 10.0 s
    })
}

#[test]
fn read_decodes_scaled_relative_and_bit_values_by_name_and_parameter() {
    let d = tds();
    let (code, out, err) = d.run(
        "read",
        "ptlk-tds-v8",
        &[
            "frequency_command",
            "Bn-01",
            "inverter_status",
            "output current",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out.lines()
            .next()
            .map(|l| l.split_whitespace().collect::<Vec<_>>()),
        Some(vec!["REGISTER", "ADDRESS", "VALUE", "RAW"])
    );
    assert_eq!(
        row(&out, "frequency_command"),
        "frequency_command 0001h 48.00 Hz 5DC0h"
    );
    assert_eq!(
        row(&out, "accel_time_1"),
        "accel_time_1 (Bn-01) 0200h 10.0 s 0064h"
    );
    assert_eq!(
        row(&out, "output_current"),
        "output_current 0027h 12.3 A 007Bh"
    );
    assert_eq!(
        row(&out, "inverter_status"),
        "inverter_status 0020h 0019h [running, ready, drv_mode] 0019h"
    );
    // Every field of a bit register is listed by name under its row.
    assert!(
        out.contains("running = 1   [bit 0: 0: STOP; 1: RUNNING]"),
        "{out}"
    );
    assert!(
        out.contains("zero_speed = 0   [bit 1: 1: Zero Speed]"),
        "{out}"
    );
    assert!(
        out.contains("setting_error = 0   [bits 12–15: Parameter setting error code]"),
        "{out}"
    );
}

#[test]
fn reads_are_planned_into_few_requests_and_dependencies_read_once() {
    let d = tds();
    let (code, out, err) = d.run(
        "read",
        "ptlk-tds-v8",
        &[
            "frequency_command_monitor",
            "output_frequency",
            "output_current",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_command_monitor"),
        "frequency_command_monitor 0024h 30.00 Hz 3A98h"
    );
    assert_eq!(
        row(&out, "output_frequency"),
        "output_frequency 0025h 60.00 Hz 7530h"
    );
    // Cn-02 once, then 0024h..0027h in one request (0026h is a readable register between).
    assert_eq!(d.requests(), 2);
}

#[test]
fn poll_reads_the_monitor_group_in_one_request_per_cycle() {
    let d = tds();
    let (code, out, err) = d.run(
        "poll",
        "ptlk-tds-v8",
        &["--interval", "50ms", "--count", "3"],
    );
    assert_eq!(code, 0, "{err}");
    for n in 1..=3 {
        assert!(out.contains(&format!("— poll {n} at ")), "{out}");
    }
    assert_eq!(out.matches("output_frequency ").count(), 3, "{out}");
    assert!(out.contains("every 50 ms"), "{out}");
    // 16 monitor registers 0020h..002Fh, max_read 16: one request a cycle, after Cn-02.
    assert_eq!(d.requests(), 1 + 3);
    let last = out.rsplit("— poll 3").next().unwrap();
    assert_eq!(
        row(last, "output_frequency"),
        "output_frequency 0025h 60.00 Hz 7530h"
    );
}

#[test]
fn write_converts_engineering_units_enumerations_and_bits() {
    let d = tds();
    let (code, out, err) = d.run(
        "write",
        "ptlk-tds-v8",
        &[
            "frequency_command=30",
            "Bn-01=12.5 s",
            "operation_command=run,reverse",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.holding(0x0001), 15000);
    assert_eq!(d.holding(0x0200), 125);
    assert_eq!(d.holding(0x0000), 0x0003);
    assert!(
        out.contains("wrote frequency_command = 30.00 Hz (3A98h) at 0001h"),
        "{out}"
    );
    assert!(
        out.contains("wrote accel_time_1 (Bn-01) = 12.5 s (007Dh) at 0200h"),
        "{out}"
    );
    assert!(
        out.contains("wrote operation_command = 0003h [run, reverse] (0003h) at 0000h"),
        "{out}"
    );
}

#[test]
fn out_of_range_is_refused_before_connecting_and_prints_the_range() {
    let d = tds();
    let (code, out, err) = d.run("write", "ptlk-tds-v8", &["Bn-01=7000"]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(
        err.contains("accel_time_1: 7000 s is out of range 0 ..= 6000 s"),
        "{err}"
    );
    assert_eq!(d.requests(), 0);
    assert!(d.writes().is_empty());
}

#[test]
fn variant_selects_the_range() {
    let d = tds();
    // Cn-01 input voltage: 150..255 V on the 220 V class, 300..510 V on the 440 V class.
    let (code, _, err) = d.run("write", "ptlk-tds-v8", &["Cn-01=400"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("input_voltage: 400 V is out of range 150 ..= 255 V"),
        "{err}"
    );
    let (code, out, err) = d.run(
        "write",
        "ptlk-tds-v8",
        &["--variant", "voltage_class=v440", "Cn-01=400"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("(0FA0h) at 0300h"), "{out}");
    assert_eq!(d.holding(0x0300), 4000);
    let (code, _, err) = d.run(
        "write",
        "ptlk-tds-v8",
        &["--variant", "voltage_class=v380", "Cn-01=400"],
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("voltage_class has options v220, v440"),
        "{err}"
    );
}

#[test]
fn unknown_names_suggest_the_nearest_and_read_only_registers_are_not_written() {
    let d = tds();
    let (code, _, err) = d.run("read", "ptlk-tds-v8", &["accel_tme_1", "Bn-99"]);
    assert_eq!(code, 2);
    assert!(
        err.contains(
            "ptlk-tds-v8 has no register `accel_tme_1`; did you mean accel_time_1 (Bn-01)"
        ),
        "{err}"
    );
    assert!(err.contains("ptlk-tds-v8 has no register `Bn-99`"), "{err}");
    let (code, _, err) = d.run("write", "ptlk-tds-v8", &["inverter_status=1"]);
    assert_eq!(code, 2);
    assert!(err.contains("inverter_status is read-only"), "{err}");
    let (code, _, err) = d.run("write", "ptlk-tds-v8", &["Sn-04=rs232"]);
    assert_eq!(code, 2);
    assert!(err.contains("is not a code of"), "{err}");
    assert_eq!(d.requests(), 0);
}

#[test]
fn a_timeout_says_what_was_sent_and_waited_for() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    // Accepts and never answers.
    thread::spawn(move || {
        let mut held: Vec<TcpStream> = Vec::new();
        for s in listener.incoming().flatten() {
            held.push(s);
        }
    });
    let (code, out, _) = drivemap(&[
        "read",
        "--drive",
        "ptlk-tds-v8",
        "--gateway",
        &addr,
        "--timeout",
        "200ms",
        "--retries",
        "0",
        "inverter_status",
    ]);
    assert_eq!(code, 1);
    assert!(
        out.contains("error: no reply from slave 1 to 03h read of 0020h x1 within 200 ms"),
        "{out}"
    );
}

#[test]
fn nothing_listening_is_a_connection_error() {
    let port = {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let (code, _, err) = drivemap(&[
        "read",
        "--drive",
        "ptlk-tds-v8",
        "--gateway",
        &format!("127.0.0.1:{port}"),
        "inverter_status",
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("cannot connect to Modbus TCP gateway 127.0.0.1:"),
        "{err}"
    );
}

#[test]
fn rtu_over_tcp_applies_the_maps_rtu_offset() {
    // ACN: PDU address = manual address - 1 on RTU (the manual's 1103h example sends 1102h).
    let d = Drive::start("automationdirect-acn", Framing::RtuOverTcp, |s| {
        s.set_holding(0x1102, 50)
    });
    let (code, out, err) = d.run("read", "automationdirect-acn", &["dr.03"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(row(&out, "acc_time"), "acc_time (dr.03) 1103h 5.0 s 0032h");
    let (code, _, err) = d.run("write", "automationdirect-acn", &["acc_time=7.5"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.writes(), vec![(0x1102, 75)]);
}

#[test]
fn a_selector_read_from_the_drive_picks_the_scale_unless_set() {
    // V7 n152 (0198h) selects the unit of the frequency reference (0002h, RTU only).
    let d = Drive::start("yaskawa-v7", Framing::RtuOverTcp, |s| {
        s.set_holding(0x0198, 1);
        s.set_holding(0x0002, 3575);
    });
    let (code, out, err) = d.run("read", "yaskawa-v7", &["frequency_reference"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_reference"),
        "frequency_reference 0002h 35.75 Hz 0DF7h"
    );
    assert_eq!(d.requests(), 2, "n152, then the register");
    // A --set the drive contradicts is refused (issue 37): read as n152 = 0 the word would say
    // 357.5 Hz.
    let (code, _, err) = d.run(
        "read",
        "yaskawa-v7",
        &["--set", "n152=0", "frequency_reference"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("`--set n152=0`: the drive holds"), "{err}");
    assert_eq!(
        d.requests(),
        3,
        "n152 read to check the --set, nothing else"
    );
    let (code, out, err) = d.run(
        "read",
        "yaskawa-v7",
        &["--set", "n152=1", "frequency_reference"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_reference"),
        "frequency_reference 0002h 35.75 Hz 0DF7h"
    );
    assert_eq!(d.requests(), 5, "n152 checked, then the register");
    // Over Modbus TCP the register does not exist: nothing is sent.
    let (code, out, err) = drivemap(&[
        "read",
        "--drive",
        "yaskawa-v7",
        "--tcp",
        &d.addr,
        "frequency_reference",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        out.contains("error: frequency_reference exists only on RTU"),
        "{out}"
    );
    assert_eq!(d.requests(), 5);
}

#[test]
fn an_external_reference_is_given_with_set() {
    // J7: n69 = 2 scales the frequency reference relative to the maximum output frequency,
    // which no register holds.
    let d = Drive::start("yaskawa-j7", Framing::RtuOverTcp, |s| {
        s.set_holding(0x0198, 2);
        s.set_holding(0x0002, 15000);
    });
    let (code, out, err) = d.run("read", "yaskawa-j7", &["frequency_reference"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        out.contains("give it with --set max_output_frequency=<value>"),
        "{out}"
    );
    let (code, out, err) = d.run(
        "read",
        "yaskawa-j7",
        &["--set", "max_output_frequency=60", "frequency_reference"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_reference"),
        "frequency_reference 0002h 30.00 Hz 3A98h"
    );
    // The J7 has no 06h: a single write goes out as 10h.
    let (code, _, err) = d.run(
        "write",
        "yaskawa-j7",
        &["--set", "max_output_frequency=60", "frequency_reference=45"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.holding(0x0002), 22500);
    let (code, _, err) = d.run(
        "read",
        "yaskawa-j7",
        &["--set", "rated_power=3", "frequency_reference"],
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("(external quantities and what conversions depend on: max_output_frequency"),
        "{err}"
    );
    // `--external`, the simulator's older name, is the same option.
    let (code, out, err) = d.run(
        "read",
        "yaskawa-j7",
        &[
            "--external",
            "max_output_frequency=60",
            "frequency_reference",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_reference"),
        "frequency_reference 0002h 45.00 Hz 57E4h"
    );
}

/// `--set NAME=VALUE` is the drive's value of a register or external quantity everywhere: the
/// simulator starts with it, and read takes it as known. One command line's `--set`s serve both.
#[test]
fn set_means_the_drives_value_for_simulate_and_read() {
    let sets = [
        "--set",
        "max_output_frequency=60",
        "--set",
        "n69=2",
        "--set",
        "frequency_reference=30",
    ];
    let sim = Sim::start(&[&["--drive", "yaskawa-j7", "--rtu-tcp", "0"][..], &sets[..]].concat());
    let read = |extra: &[&str]| {
        let mut args = vec![
            "read",
            "--drive",
            "yaskawa-j7",
            "--rtu-tcp",
            sim.addr.as_str(),
        ];
        args.extend_from_slice(extra);
        drivemap(&args)
    };
    // The simulator started with n69 = 2 and 30 Hz of 60 Hz (15000); read, told the same
    // external quantity, converts it back; n69 given is not read (and agrees).
    let (code, out, err) = read(&[&sets[..], &["frequency_reference"]].concat());
    let (code_n69, out_n69, _) = read(&[
        "--set",
        "max_output_frequency=60",
        "n69",
        "frequency_reference",
    ]);
    drop(sim);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_reference"),
        "frequency_reference 0002h 30.00 Hz 3A98h"
    );
    assert_eq!(code_n69, 0);
    assert_eq!(
        row(&out_n69, "modbus_frequency_reference_unit_selection"),
        "modbus_frequency_reference_unit_selection (n69) 0198h 2: 30,000 = n011 0002h"
    );
    // A register no conversion depends on is accepted as the drive's value, but must be one.
    let (code, _, err) = drivemap(&[
        "read",
        "--drive",
        "yaskawa-j7",
        "--rtu-tcp",
        "127.0.0.1:9",
        "--set",
        "n69=x",
        "n69",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("`--set n69=x`"), "{err}");
}

#[test]
fn persist_runs_the_maps_save_command() {
    let d = tds();
    let (code, out, err) = d.run(
        "write",
        "ptlk-tds-v8",
        &["Bn-01=20", "--persist", "save_parameters"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("ran command save_parameters"), "{out}");
    assert_eq!(d.writes(), vec![(0x0200, 200), (0x0500, 0)]);
    let (code, _, err) = d.run("write", "ptlk-tds-v8", &["Bn-01=20", "--persist", "enter"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("ptlk-tds-v8 has no command `enter`; commands: save_parameters"),
        "{err}"
    );
}

#[test]
fn broadcast_writes_go_to_slave_0_without_reply() {
    let d = tds();
    // Slave 0 answers nothing, so Cn-02 cannot be read: it is given.
    let (code, out, err) = d.run(
        "write",
        "ptlk-tds-v8",
        &["--slave", "0", "--set", "Cn-02=60", "frequency_command=30"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("wrote frequency_command = 30.00 Hz (3A98h) at 0001h"),
        "{out}"
    );
    // Nothing answers a broadcast, so the command may end before the slave's thread has
    // taken the frame: wait for it a little.
    let until = Instant::now() + Duration::from_secs(2);
    while d.writes().is_empty() && Instant::now() < until {
        thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(d.writes(), vec![(0x0001, 15000)]);
    // The drive refuses other registers in a broadcast; the write gate says so before
    // connecting.
    let (code, _, err) = d.run("write", "ptlk-tds-v8", &["--slave", "0", "Bn-01=20"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("ptlk-tds-v8 does not accept accel_time_1 in a broadcast")
            && err.contains("nothing written"),
        "{err}"
    );
    assert_eq!(d.writes().len(), 1);
}

use drivemap_test_support::pty_pair;
use pty_pair::PtyPair;

use common::{Framing, Sim, drivemap, repo, serve};

#[test]
fn serial_line_through_a_pseudo_terminal_pair() {
    use drivemap_runtime::transport::serial::{Parity, SerialOptions, SerialTransport};
    let pty = PtyPair::new();
    let map = drivemap_map::Loader::new()
        .load(&repo().join("maps/yaskawa-v7.yaml"))
        .unwrap();
    let profile = drivemap_live::leak_profile(&map);
    let mut link = SerialTransport::open(
        SerialOptions::new(pty.paths[1].as_str(), 19_200)
            .parity(Parity::Even)
            .with_profile(profile),
    )
    .expect("opening the drive's end");
    let drive = thread::spawn(move || {
        let mut slave = SimulatedSlave::new(1, profile);
        slave.set_holding(0x0198, 1);
        slave.set_holding(0x0002, 3575);
        slave.set_holding(0x010B, 600); // n011 = 60.0 Hz bounds the reference
        slave
            .serve(&mut link, Instant::now() + Duration::from_secs(4))
            .expect("serving");
        slave
    });
    let serial = [
        "--serial",
        pty.paths[0].as_str(),
        "--baud",
        "19200",
        "--parity",
        "even",
    ];
    let mut args = vec!["read", "--drive", "yaskawa-v7"];
    args.extend_from_slice(&serial);
    args.push("frequency_reference");
    let (code, out, err) = drivemap(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        row(&out, "frequency_reference"),
        "frequency_reference 0002h 35.75 Hz 0DF7h"
    );
    let mut args = vec!["write", "--drive", "yaskawa-v7"];
    args.extend_from_slice(&serial);
    args.push("frequency_reference=40");
    let (code, out, err) = drivemap(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("wrote frequency_reference = 40.00 Hz (0FA0h) at 0002h"),
        "{out}"
    );
    // The write gate on a serial line: the TCP option card's register and an ordinary
    // register sent as a broadcast are refused; nothing else reaches the drive.
    for refused in [
        &["tcp_digital_input_command=terminal_s1"][..],
        &["--slave", "0", "digital_input_command=run_command"][..],
    ] {
        let mut args = vec!["write", "--drive", "yaskawa-v7"];
        args.extend_from_slice(&serial);
        args.extend_from_slice(refused);
        let (code, _, err) = drivemap(&args);
        assert_eq!(code, 2, "{refused:?}: {err}");
        assert!(err.contains("nothing written"), "{err}");
    }
    let slave = drive.join().unwrap();
    assert_eq!(slave.holding(0x0002), 4000);
    assert_eq!(
        slave.writes,
        vec![(0x0002, 4000)],
        "only the legal write arrived"
    );
}

#[test]
fn a_refused_bridge_is_split_and_not_bridged_again() {
    let d = tds();
    // 0026h answers 02h: reading 0024h..0027h in one request fails.
    d.slave.lock().unwrap().fail_at(0x0026, 0x02);
    let (code, out, err) = d.run(
        "poll",
        "ptlk-tds-v8",
        &[
            "frequency_command_monitor",
            "output_current",
            "--interval",
            "10ms",
            "--count",
            "2",
        ],
    );
    assert_eq!(code, 0, "{err}");
    for cycle in out.split("— poll ").skip(1) {
        assert_eq!(
            row(cycle, "frequency_command_monitor"),
            "frequency_command_monitor 0024h 30.00 Hz 3A98h"
        );
        assert_eq!(
            row(cycle, "output_current"),
            "output_current 0027h 12.3 A 007Bh"
        );
    }
    // Cn-02; cycle 1: 0024h..0027h refused, then 0024h and 0027h; cycle 2: 0024h and 0027h.
    assert_eq!(d.requests(), 1 + 3 + 2);
}

#[test]
fn poll_by_default_reads_the_monitors_this_link_has() {
    // The V7's Modbus TCP option card registers (2000h..) exist only on TCP.
    let d = Drive::start("yaskawa-v7", Framing::RtuOverTcp, |_| {});
    let (code, out, err) = d.run("poll", "yaskawa-v7", &["--count", "1"]);
    assert_eq!(code, 0, "{err}\n{out}");
    assert!(out.contains("output_current "), "{out}");
    assert!(!out.contains("tcp_status_word"), "{out}");
    assert!(!out.contains("error: "), "{out}");
}

/// Naming some fields of a bit-field register changes those fields only: the others keep the
/// value read from the drive (V7 0001h, Table 4.1, `000_032dced3a1e91a75.txt:853-867`) — in a
/// command register, as the drive trait composes it: the run bit only while the status shows
/// the drive running, the fault reset only when named (issue 37).
#[test]
fn writing_one_field_keeps_the_others() {
    let d = Drive::start("yaskawa-v7", Framing::RtuOverTcp, |s| {
        s.set_holding(0x0001, 0x0003); // running in reverse
        s.set_holding(0x0020, 0x0003); // status: during run, reverse
    });
    let (code, out, err) = d.run(
        "write",
        "yaskawa-v7",
        &["digital_input_command=fault_reset"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.holding(0x0001), 0x000B, "{out}");
    let (code, _, err) = d.run(
        "write",
        "yaskawa-v7",
        &["digital_input_command=reverse=off,fault_reset=0"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        d.holding(0x0001),
        0x0001,
        "run kept, reverse and reset cleared"
    );
    // A number is the whole word.
    let (code, _, err) = d.run("write", "yaskawa-v7", &["digital_input_command=0x0000"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        d.writes(),
        vec![(0x0001, 0x000B), (0x0001, 0x0001), (0x0001, 0x0000)]
    );
    // A one-bit field by on/off, in any case.
    let (code, _, err) = d.run(
        "write",
        "yaskawa-v7",
        &["digital_input_command=run_command=On"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.holding(0x0001), 0x0001);
    // Stopped (the status shows no run): a word read back with run and reverse set goes out
    // without the run; the reset only because it is named.
    d.slave.lock().unwrap().set_holding(0x0020, 0x0000);
    d.slave.lock().unwrap().set_holding(0x0001, 0x0003);
    let (code, _, err) = d.run(
        "write",
        "yaskawa-v7",
        &["digital_input_command=fault_reset"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        d.holding(0x0001),
        0x000A,
        "reverse kept, run released, reset set"
    );
}

/// The fixture drive of another vendor (`tests/fixtures/acme-vf1`, its own fictional manual):
/// 32-bit values in two registers in both word orders and decimals chosen by a field of another
/// register, read and written at slave 254 through the tool.
#[test]
fn pairs_and_field_selected_decimals_of_another_vendor_at_slave_254() {
    let fixture = paths::fixture("acme-vf1");
    let map = drivemap_map::Loader::new()
        .load(&fixture.join("acme-vf1.yaml"))
        .expect("fixture map");
    let mut slave = SimulatedSlave::new(254, drivemap_live::leak_profile(&map));
    slave.set_holding(0x2200, 0x0001); // energy counter 0001E240h = 123456: 12345.6 kWh
    slave.set_holding(0x2201, 0xE240);
    slave.set_holding(0x2202, 0x0002); // running hours 00020000h = 131072 h, beyond a word
    slave.set_holding(0x2203, 0x0000);
    slave.set_holding(0x2206, 0xCFC7); // motor speed, low word first: FFFFCFC7h = -12345
    slave.set_holding(0x2207, 0xFFFF);
    slave.set_holding(0x2300, 0x0200); // current decimals: 2 (bits 8-15)
    slave.set_holding(0x2301, 1234);
    slave.reads = Some(Vec::new());
    let d = Drive::serve(slave, Framing::Tcp);
    let link = [
        "--tcp",
        d.addr.as_str(),
        "--slave",
        "254",
        "--timeout",
        "2s",
    ];
    let run = |command: &str, args: &[&str]| {
        let mut all = vec![command, "--drive", "acme-vf1"];
        all.extend_from_slice(&link);
        all.extend_from_slice(args);
        common::run(common::command().args(&all).arg("--maps").arg(&fixture))
    };
    let (code, out, err) = run(
        "read",
        &[
            "energy_counter",
            "running_hours",
            "motor_speed",
            "motor_current",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        row(&out, "energy_counter").contains("12345.6 kWh 0001E240h"),
        "{out}"
    );
    assert!(row(&out, "running_hours").contains("131072 h"), "{out}");
    assert!(
        row(&out, "motor_speed").contains("-1234.5 rpm FFFFCFC7h"),
        "{out}"
    );
    assert!(row(&out, "motor_current").contains("12.34 A"), "{out}");
    let reads: Vec<(u16, u16)> = d.slave.lock().unwrap().reads.clone().unwrap();
    for (address, quantity) in &reads {
        for first in [0x2200u16, 0x2202, 0x2206] {
            let covers = |a: u16| (*address..address + quantity).contains(&a);
            assert_eq!(
                covers(first),
                covers(first + 1),
                "a pair split by {reads:?}"
            );
        }
    }

    // A signed pair written whole, high word first, in one 10h request.
    let (code, out, err) = run("write", &["position_setpoint=-123456"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("FFFE1DC0h"), "{out}");
    assert_eq!(d.holding(0x2204), 0xFFFE);
    assert_eq!(d.holding(0x2205), 0x1DC0);
    // Out of the 32-bit range the manual prints: refused, nothing sent.
    let before = d.requests();
    let (code, _, err) = run("write", &["position_setpoint=1000001"]);
    assert_ne!(code, 0);
    assert!(err.contains("out of range -1000000 ..= 1000000"), "{err}");
    assert_eq!(d.requests(), before);
}

/// ACN 0h03E8 (Lock parameter mode): `write` takes a number, the password, and writes the
/// map's intermediate 0 first, since the drive executes only a changed value ("244 > 0 > 244",
/// `004_c5cbf92472673495.txt:1113`-`:1115`); `read` shows what a read means (0 Unlock, 1 Lock),
/// not the number written.
#[test]
fn a_password_is_written_after_the_intermediate_and_read_as_the_lock_state() {
    let d = Drive::start("automationdirect-acn", Framing::Tcp, |s| {
        s.set_holding(0x03E8, 1); // locked (TCP: PDU address = communication address)
    });
    let (code, out, err) = d.run(
        "write",
        "automationdirect-acn",
        &["lock_parameter_mode=244"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.writes(), vec![(0x03E8, 0), (0x03E8, 244)]);
    assert!(
        out.contains("wrote lock_parameter_mode = 244 (00F4h) at 03E8h after 0 (0000h)"),
        "{out}"
    );
    // The same password again is executed again: 0 then 244 once more.
    let (code, _, err) = d.run(
        "write",
        "automationdirect-acn",
        &["lock_parameter_mode=244"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.writes().len(), 4);
    // Writing the intermediate itself is one write.
    let (code, _, err) = d.run("write", "automationdirect-acn", &["lock_parameter_mode=0"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(d.writes()[4..], [(0x03E8, 0)]);
    // A read gives the read meaning of the word the drive holds.
    d.slave.lock().unwrap().set_holding(0x03E8, 1);
    let (code, out, err) = d.run("read", "automationdirect-acn", &["lock_parameter_mode"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        row(&out, "lock_parameter_mode").contains("1: Lock"),
        "{out}"
    );
    // A password is a number: the read meaning is not a write value.
    let (code, _, err) = d.run(
        "write",
        "automationdirect-acn",
        &["lock_parameter_mode=lock"],
    );
    assert_ne!(code, 0);
    assert!(err.contains("is not a number"), "{err}");
}

/// `probe` checks a word read from a register with `read_values` against the read codes (0
/// Unlock, 1 Lock), not against what a write would encode.
#[test]
fn probe_checks_a_read_meaning_against_its_read_codes() {
    let d = Drive::start("automationdirect-acn", Framing::Tcp, |s| {
        s.set_holding(0x03E7, 1); // hide parameter mode: Lock
        s.set_holding(0x03E8, 244); // lock parameter mode: not a read code
    });
    let (code, out, err) = d.run("probe", "automationdirect-acn", &["--format", "json"]);
    assert!(code == 0 || code == 1, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).expect("JSON report");
    let found = |id: &str| {
        report["disagreements"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["register"] == id)
            .cloned()
    };
    assert_eq!(found("hide_parameter_mode"), None, "1 is Lock");
    let lock = found("lock_parameter_mode").expect("244 is no read code");
    assert_eq!(lock["kind"], "unlisted_code");
    assert!(
        lock["detail"]
            .as_str()
            .unwrap()
            .contains("read_values do not list (listed: 0, 1)"),
        "{lock}"
    );
}
