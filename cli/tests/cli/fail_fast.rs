//! A silent peer (accepts the connection, never answers) fails a whole command within one
//! timeout and its retries, not one per read: `read output_frequency` of the V7 depends on two
//! settings (n152 selects the unit, n011 is the full scale), which were each retried before
//! the register itself (3 × 2 attempts × 1 s ≥ 6 s here, 9 s over RTU framing; 9.3 s in
//! issue 27). Now the first
//! request that goes unanswered through every attempt stops the command, and the messages say
//! which request was tried and which were then not sent. Wall time measured on the binary.

use crate::common;

use std::net::{TcpListener, TcpStream};
use std::thread;
use std::time::Duration;

use common::drivemap_bounded;

/// A TCP peer that accepts and never sends a byte.
fn silent_peer() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    thread::spawn(move || {
        let mut held: Vec<TcpStream> = Vec::new();
        for s in listener.incoming().flatten() {
            held.push(s);
        }
    });
    addr
}

const TIMEOUT: Duration = Duration::from_secs(1);
/// `--retries 1`: two attempts.
const ATTEMPTS: u32 = 2;

/// One request's attempts, plus 1.5 s to start and load the map. On RTU framing the client
/// waits for the line to be silent for a timeout before each retry (a late reply must not be
/// taken for the next answer): one more timeout per retry there.
fn bound(link: &str) -> Duration {
    let retries_wait = if link == "--rtu-tcp" { ATTEMPTS - 1 } else { 0 };
    TIMEOUT * (ATTEMPTS + retries_wait) + Duration::from_millis(1500)
}

#[test]
fn a_read_with_two_settings_to_read_first_fails_within_one_timeout_and_its_retries() {
    for link in ["--rtu-tcp", "--gateway"] {
        let addr = silent_peer();
        let (code, out, err, took) = drivemap_bounded(
            &[
                "read",
                "--drive",
                "yaskawa-v7",
                link,
                &addr,
                "--timeout",
                "1s",
                "--retries",
                "1",
                "output_frequency",
            ],
            Duration::from_secs(20),
        );
        assert_eq!(code, 1, "{link}: {out}{err}");
        assert!(
            took <= bound(link),
            "{link}: took {took:?}, more than {:?}\n{err}",
            bound(link)
        );
        // The first setting's read went unanswered through both attempts, said with its name.
        assert!(
            err.contains(
                "reading modbus_frequency_reference_unit_selection (n152), which conversions depend on: no reply from slave 1 to 03h read of 0198h x1 within 1000 ms (2 attempts)"
            ),
            "{link}: {err}"
        );
        // Then once for the command: what was tried and what was not sent after it.
        assert!(
            err.contains(
                "did not answer: no reply to 03h read of 0198h x1 (2 attempt(s) each); 2 later request(s) not sent"
            ),
            "{link}: {err}"
        );
        // The later requests were not sent, each saying so with what it was.
        assert!(
            err.contains("reading max_output_frequency (n011), which conversions depend on: 03h read of 010Bh x1 to slave 1: not sent"),
            "{link}: {err}"
        );
        // The register's own row says why it has no value.
        let row = out
            .lines()
            .find(|l| l.starts_with("output_frequency"))
            .unwrap_or_else(|| panic!("{link}: no row in {out}"));
        assert!(
            row.contains("not sent: the peer gave no reply to 03h read of 0198h x1"),
            "{link}: {row}"
        );
    }
}

#[test]
fn a_write_to_a_silent_peer_stops_after_its_first_unanswered_request() {
    let addr = silent_peer();
    let (code, out, err, took) = drivemap_bounded(
        &[
            "write",
            "--drive",
            "yaskawa-v7",
            "--gateway",
            &addr,
            "--timeout",
            "1s",
            "--retries",
            "1",
            "frequency_reference=30",
        ],
        Duration::from_secs(30),
    );
    assert_eq!(code, 2, "{out}{err}");
    assert!(took <= bound("--gateway"), "took {took:?}\n{err}");
    assert!(
        err.contains("did not answer: no reply to 03h read of"),
        "{err}"
    );
    assert!(err.ends_with("; nothing written\n"), "{err}");
    assert!(!out.contains("wrote"), "{out}");
}

#[test]
fn each_poll_cycle_tries_again_and_ends_within_one_timeout_and_its_retries() {
    let addr = silent_peer();
    // Settings first (one unanswered request), then two cycles of one unanswered request each.
    let (code, out, err, took) = drivemap_bounded(
        &[
            "poll",
            "--drive",
            "yaskawa-v7",
            "--gateway",
            &addr,
            "--timeout",
            "1s",
            "--retries",
            "1",
            "--count",
            "2",
            "--interval",
            "10ms",
            "--format",
            "json",
            "output_frequency",
            "output_current",
        ],
        Duration::from_secs(40),
    );
    assert_eq!(code, 1, "{out}{err}");
    let limit = TIMEOUT * ATTEMPTS * 3 + Duration::from_millis(1500);
    assert!(took <= limit, "took {took:?}, more than {limit:?}\n{err}");
    // Both cycles printed a record per register, each an error.
    let records: Vec<&str> = out.lines().collect();
    assert_eq!(records.len(), 4, "{out}");
    assert!(
        records.iter().all(|r| r.contains("\"status\":\"error\"")),
        "{out}"
    );
}
