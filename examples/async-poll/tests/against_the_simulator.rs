//! The example against a simulated V7 served over Modbus TCP on loopback.

use drivemap_test_support::paths;

use std::process::Command;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_sim::server::{TcpFraming, TcpServer};
use drivemap_sim::{SimOptions, Simulator};

/// The example writes the reference, runs, polls and stops: the simulated drive holds the
/// reference it was given and its run command is off again, and the example printed each poll.
#[test]
fn polls_the_drive_and_writes_the_reference() {
    let path = paths::shipped_map("yaskawa-v7");
    let v7 = drivemap_map::Loader::new()
        .load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let sim = Simulator::new(v7, SimOptions::new().network_source(TransportKind::Tcp)).unwrap();
    let sim = drivemap_sim::server::shared(sim);
    let server = TcpServer::spawn(sim.clone(), "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
    let addr = server.local_addr().to_string();
    let out = Command::new(env!("CARGO_BIN_EXE_async-poll"))
        .args([addr.as_str(), "1", "42.5", "3"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 4, "{stdout}");
    for (i, line) in lines[..3].iter().enumerate() {
        assert!(
            line.starts_with(&format!("poll {}: output ", i + 1)) && line.contains(" Hz, status "),
            "{line}"
        );
    }
    assert_eq!(lines[3], "stopped; reference 42.5 Hz");
    let state = drivemap_sim::server::lock(&sim)
        .state()
        .expect("a drive model");
    assert_eq!(state.reference_hz, 42.5);
    assert!(!state.run_command, "the example stopped the drive");
    server.stop();
}

/// A peer that is not there: the example fails with the link's error, not a panic.
#[test]
fn an_unreachable_drive_is_a_clear_error() {
    // A port just bound and released: nothing listens there.
    let addr = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .to_string();
    let out = Command::new(env!("CARGO_BIN_EXE_async-poll"))
        .arg(&addr)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("refused"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
