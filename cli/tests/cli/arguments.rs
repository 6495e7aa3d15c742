//! Hostile command lines and closed pipes: every number and duration option is range-checked
//! by clap (exit 2 with a message, no panic, no endless loop), and a command whose output pipe
//! closes ends quietly with status 141, as `cat` would.

use crate::common;

use std::io::Read;
use std::process::Stdio;
use std::time::Duration;

use common::{command, repo, run_bounded};

/// `drivemap ARGS` in the workspace root: exit code and stderr; a hang fails the test.
fn drivemap(args: &[&str]) -> (i32, String) {
    let (code, _, err, _) = run_bounded(
        command().args(args).current_dir(repo()),
        Duration::from_secs(30),
    );
    (code, err)
}

#[test]
fn out_of_range_numbers_and_durations_are_refused_by_the_parser() {
    let read = ["read", "--drive", "ptlk-tds-v8", "--tcp", "127.0.0.1:9"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["demo", "--step", "1e300"], "outside 0.01..=5"),
        (vec!["demo", "--step", "nan"], "outside 0.01..=5"),
        (vec!["demo", "--time-scale", "1e-300"], "outside 0.1..=1000"),
        (vec!["demo", "--time-scale", "1e308"], "outside 0.1..=1000"),
        (vec!["demo", "--frequency", "inf"], "outside 0..=1000"),
        (vec!["demo", "--ramp=-1"], "outside 0..=6000"),
        (
            vec![
                "simulate",
                "--drive",
                "ptlk-tds-v8",
                "--tcp",
                "5020",
                "--time-scale",
                "0",
            ],
            "outside 0.1..=1000",
        ),
        (
            [&read[..], &["--timeout", "99999999999999999999s", "Bn-01"]].concat(),
            "longer than the 1 hour",
        ),
        (
            [&read[..], &["--request-gap", "1e300s", "Bn-01"]].concat(),
            "is not a unit of time",
        ),
        (
            vec![
                "poll",
                "--drive",
                "ptlk-tds-v8",
                "--tcp",
                "127.0.0.1:9",
                "--interval",
                "90min",
            ],
            "longer than the 1 hour",
        ),
        // A zero timeout gives up before any reply can arrive; a zero idle timeout closes
        // every connection at once: both are refused, not accepted and useless.
        (
            [&read[..], &["--timeout", "0s", "Bn-01"]].concat(),
            "`0s` is zero",
        ),
        (
            vec!["scan", "--tcp", "127.0.0.1:9", "--timeout", "0ms"],
            "`0ms` is zero",
        ),
        (
            vec![
                "simulate",
                "--drive",
                "ptlk-tds-v8",
                "--tcp",
                "5020",
                "--idle-timeout",
                "0s",
            ],
            "`0s` is zero",
        ),
        (
            vec![
                "simulate",
                "--drive",
                "ptlk-tds-v8",
                "--tcp",
                "5020",
                "--frame-timeout",
                "0",
            ],
            "`0` is zero",
        ),
    ];
    for (args, message) in cases {
        let (code, stderr) = drivemap(&args);
        assert_eq!(code, 2, "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

#[test]
fn a_closed_output_pipe_ends_quietly() {
    for args in [
        &["export", "--drive", "automationdirect-acn"][..],
        &["doc", "--drive", "automationdirect-acn"],
        &["check"],
    ] {
        let mut child = command()
            .args(args)
            .current_dir(repo())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Close the reading end before the command has loaded its map and printed anything.
        drop(child.stdout.take());
        let mut stderr = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut stderr)
            .unwrap();
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(141), "{args:?}: {stderr}");
        // The map's own warnings (ACN's slave range beyond 247) may come first; nothing else.
        let noise: Vec<&str> = stderr
            .lines()
            .filter(|l| !l.contains(": warning: "))
            .collect();
        assert!(noise.is_empty(), "{args:?}: {stderr}");
    }
}

/// The ACN's map lists the formats CM.04 selects (8N1, 8N2, 8E1, 8O1): a link or a simulated
/// port set to another (8E2) is refused with the map's list before the port is opened, and a
/// listed one gets as far as opening it.
#[test]
fn a_serial_format_the_map_does_not_list_is_refused() {
    let refused = "automationdirect-acn's serial line offers only the formats its map lists (CM.04: 0 = 8N1, 1 = 8N2, 2 = 8E1, 3 = 8O1); 8E2 is not one of them (`004_c5cbf92472673495.txt:262`)";
    let line = [
        "--serial",
        "/dev/null",
        "--parity",
        "even",
        "--stop-bits",
        "2",
    ];
    let read = [
        &["read", "--drive", "automationdirect-acn"][..],
        &line,
        &["CM.04"],
    ]
    .concat();
    let (code, err) = drivemap(&read);
    assert_ne!(code, 0, "{err}");
    assert!(err.contains(refused), "{err}");
    let simulate = [&["simulate", "--drive", "automationdirect-acn"][..], &line].concat();
    let (code, err) = drivemap(&simulate);
    assert_ne!(code, 0, "{err}");
    assert!(err.contains(refused), "{err}");
    // 8E1 (even parity takes its only stop bits, 1) and 8N2 are listed: the port is opened
    // (and /dev/null is no serial port).
    for line in [
        &["--serial", "/dev/null", "--parity", "even"][..],
        &[
            "--serial",
            "/dev/null",
            "--parity",
            "none",
            "--stop-bits",
            "2",
        ],
    ] {
        let args = [
            &["read", "--drive", "automationdirect-acn"][..],
            line,
            &["CM.04"],
        ]
        .concat();
        let (code, err) = drivemap(&args);
        assert_ne!(code, 0, "{err}");
        assert!(!err.contains("offers only the formats"), "{err}");
        assert!(err.contains("cannot open serial port /dev/null"), "{err}");
    }
}

/// `--parity` is the vocabulary crate's `Parity` (one definition for map, link and profile),
/// parsed by `drivemap_live::link::ParityParser`: every command that takes it refuses another
/// word naming the three it accepts, and `--help` lists them.
#[test]
fn parity_is_refused_naming_the_three_accepted() {
    for command in [
        &[
            "read",
            "--drive",
            "automationdirect-acn",
            "--serial",
            "/dev/null",
        ][..],
        &[
            "simulate",
            "--drive",
            "automationdirect-acn",
            "--serial",
            "/dev/null",
        ],
        &["scan", "--serial", "/dev/null"],
        &[
            "bridge",
            "--drive",
            "automationdirect-acn",
            "--serial",
            "/dev/null",
        ],
    ] {
        let args = [command, &["--parity", "mark"]].concat();
        let (code, err) = drivemap(&args);
        assert_ne!(code, 0, "{args:?}: {err}");
        assert!(
            err.contains("invalid value 'mark' for '--parity")
                && err.contains("[possible values: none, even, odd]"),
            "{args:?}: {err}"
        );
    }
    let help = command()
        .args(["read", "--help"])
        .output()
        .expect("drivemap runs");
    let out = String::from_utf8_lossy(&help.stdout);
    assert!(help.status.success(), "{out}");
    for value in [
        "none: No parity bit",
        "even: Even parity",
        "odd:  Odd parity",
    ] {
        assert!(out.contains(value), "{value} missing from:\n{out}");
    }
}
