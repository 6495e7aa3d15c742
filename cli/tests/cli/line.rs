//! A line of drives (issue 25, item 8): `drivemap simulate --drive ID@SLAVE ...` serves several
//! simulated drives on one link, each at its address, and `drivemap scan` finds every one and
//! names its map. Through the binary.

use crate::common;

use common::{Sim, drivemap};

/// `(slave, best map)` per slave found, from scan's JSON report.
fn found(json: &str) -> Vec<(u64, String)> {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    v["found"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["slave"].as_u64().unwrap(),
                f["maps"][0]["drive"].as_str().unwrap().to_owned(),
            )
        })
        .collect()
}

/// Two drives of two vendors on one RTU-over-TCP link and behind a simulated gateway: scan
/// finds both, at their addresses, and names each one's map; the empty address 3 is not found.
#[test]
fn scan_finds_both_drives_of_a_simulated_line() {
    for link in ["--rtu-tcp", "--gateway"] {
        let sim = Sim::start(&[
            "--drive",
            "yaskawa-v7@1",
            "--drive",
            "ptlk-tds-v8@2",
            link,
            "0",
        ]);
        assert!(
            sim.first.contains("yaskawa-v7 at slave 1")
                && sim.first.contains("ptlk-tds-v8 at slave 2"),
            "{}",
            sim.first
        );
        let (code, out, err) = drivemap(&[
            "scan",
            link,
            &sim.addr,
            "--slaves",
            "1-3",
            "--drive",
            "yaskawa-v7",
            "--drive",
            "ptlk-tds-v8",
            "--drive",
            "yaskawa-gpd515",
            "--format",
            "json",
        ]);
        assert_eq!(code, 0, "{link}: {err}");
        assert_eq!(
            found(&out),
            [(1, "yaskawa-v7".to_owned()), (2, "ptlk-tds-v8".to_owned())],
            "{link}: {out}"
        );
    }
}

/// The same line on a serial port (a socat pseudo-terminal pair): `simulate --serial` serves
/// both drives on the one port, `scan --serial` finds both.
#[test]
fn scan_finds_both_drives_on_a_simulated_serial_line() {
    let pty = drivemap_test_support::pty_pair::PtyPair::new();
    let sim = Sim::start_any(&[
        "--drive",
        "yaskawa-v7@2",
        "--drive",
        "ptlk-tds-v8@7",
        "--serial",
        &pty.paths[1],
        "--baud",
        "9600",
        "--parity",
        "even",
    ]);
    assert!(
        sim.first.contains("9600 baud, parity even"),
        "{}",
        sim.first
    );
    let (code, out, err) = drivemap(&[
        "scan",
        "--serial",
        &pty.paths[0],
        "--baud",
        "9600",
        "--parity",
        "even",
        "--slaves",
        "1-8",
        "--drive",
        "yaskawa-v7",
        "--drive",
        "ptlk-tds-v8",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        found(&out),
        [(2, "yaskawa-v7".to_owned()), (7, "ptlk-tds-v8".to_owned())],
        "{out}"
    );
}

/// Reads reach the drive at their address: the `--set` prefixed with a slave address sets that
/// drive only.
#[test]
fn each_drive_of_a_line_keeps_its_own_values() {
    let sim = Sim::start(&[
        "--drive",
        "yaskawa-v7@5",
        "--drive",
        "yaskawa-v7@6",
        "--set",
        "6:n011=50",
        "--rtu-tcp",
        "0",
    ]);
    let read = |slave: &str| {
        let (code, out, err) = drivemap(&[
            "read",
            "--drive",
            "yaskawa-v7",
            "--rtu-tcp",
            &sim.addr,
            "--slave",
            slave,
            "n011",
            "--format",
            "json",
        ]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        v[0]["value"].as_f64().unwrap()
    };
    assert_eq!(read("5"), 60.0);
    assert_eq!(read("6"), 50.0);
}

#[test]
fn a_line_refuses_ambiguous_addresses_clearly() {
    let cases: [(&[&str], &str); 4] = [
        (
            &["--drive", "yaskawa-v7@1", "--drive", "ptlk-tds-v8@1"],
            "slave address 1 is taken on this line by yaskawa-v7; cannot add ptlk-tds-v8 there",
        ),
        (
            &["--drive", "yaskawa-v7@1", "--drive", "ptlk-tds-v8"],
            "--drive `ptlk-tds-v8`: on a line of several drives give each its slave address (`ptlk-tds-v8@1`)",
        ),
        (
            &[
                "--drive",
                "yaskawa-v7@1",
                "--drive",
                "ptlk-tds-v8@2",
                "--slave",
                "3",
            ],
            "--slave is for a single drive",
        ),
        (
            &["--drive", "yaskawa-v7@x"],
            "--drive `yaskawa-v7@x`: give ID@SLAVE with a slave address 1-255",
        ),
    ];
    for (args, want) in cases {
        let mut all = vec!["simulate"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--rtu-tcp", "0"]);
        let (code, _, err) = drivemap(&all);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    // A serial line's character format must be one every drive on it offers: the ACN lists
    // 8N1, 8N2, 8E1 and 8O1 (CM.04), so 8E2 is refused, naming it, before the port is opened.
    let (code, _, err) = drivemap(&[
        "simulate",
        "--drive",
        "yaskawa-v7@1",
        "--drive",
        "automationdirect-acn@2",
        "--serial",
        "/nonexistent/tty",
        "--parity",
        "even",
        "--stop-bits",
        "2",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("automationdirect-acn's serial line offers only the formats its map lists"),
        "{err}"
    );
}
