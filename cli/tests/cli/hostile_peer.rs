//! `drivemap read` and `drivemap poll` as subprocesses against the runtime's hostile peer
//! (`drivemap_test_support::hostile_peer`): each must end within timeout × attempts + 2 s
//! (per request) with an error that says what happened; `poll` must come back after the server
//! restarts. A subprocess still running past its bound is killed and the test fails.

use drivemap_test_support::paths;

use crate::common;

use drivemap_test_support::hostile_peer;

use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::{Profile, TransportKind};

use hostile_peer::{HostilePeer, Script};

use common::{drivemap_bounded, repo};

/// RTU only: its Modbus TCP runs go through a Modbus TCP gateway (`--gateway`).
const DRIVE: &str = "ptlk-tds-v8";
/// 0027h, 0.1 A, no dependency: the peer holds 0027h = 39.
const REGISTER: &str = "output_current";

fn profile() -> &'static Profile {
    let map = drivemap_map::Loader::new()
        .load(&paths::maps().join(format!("{DRIVE}.yaml")))
        .expect("shipped map");
    drivemap_live::leak_profile(&map)
}

/// Runs `drivemap <args> --maps maps`, killing it after `bound`. Returns exit code, stdout,
/// stderr and the time it took.
fn drivemap(args: &[&str], bound: Duration) -> (i32, String, String, Duration) {
    drivemap_bounded(args, bound + Duration::from_secs(1))
}

fn flag(kind: TransportKind) -> &'static str {
    if kind.is_rtu_framed() {
        "--rtu-tcp"
    } else {
        "--gateway"
    }
}

/// What each script's error must say in the output of `read`.
fn expected(script: Script, kind: TransportKind) -> &'static str {
    match script {
        Script::Flood => "the peer floods the link",
        // On RTU framing the retry waits for the line to fall silent first (a late reply could
        // be on its way), which a peer that keeps sending never lets happen.
        Script::Trickle | Script::LyingLength if kind.is_rtu_framed() => {
            "held back because the line never fell silent"
        }
        Script::Trickle | Script::LyingLength => "within 500 ms (2 attempts); discarded",
        Script::Unfinished => "an incomplete frame",
        Script::ResetMidFrame => "reset",
        Script::OtherTransaction if !kind.is_rtu_framed() => "transaction",
        Script::OtherUnit if !kind.is_rtu_framed() => "unit 2 in reply, expected unit 1",
        _ => "reply from slave 2, expected slave 1",
    }
}

const SCRIPTS: [Script; 7] = [
    Script::Flood,
    Script::Trickle,
    Script::Unfinished,
    Script::ResetMidFrame,
    Script::LyingLength,
    Script::OtherTransaction,
    Script::OtherUnit,
];

fn read_against(kind: TransportKind) {
    let profile = profile();
    // timeout × attempts + 2 s.
    let bound = Duration::from_millis(500) * 2 + Duration::from_secs(2);
    for script in SCRIPTS {
        let peer = HostilePeer::start(kind, profile, script);
        let addr = peer.addr.to_string();
        let (code, out, err, took) = drivemap(
            &[
                "read",
                "--drive",
                DRIVE,
                flag(kind),
                &addr,
                "--timeout",
                "500ms",
                "--retries",
                "1",
                REGISTER,
            ],
            bound,
        );
        assert!(took <= bound, "{script:?}: took {took:?}");
        assert_eq!(code, 1, "{script:?}: {out}{err}");
        let want = expected(script, kind);
        assert!(
            out.contains("error: ") && out.contains(want),
            "{kind:?} {script:?}: wanted `{want}` in\n{out}{err}"
        );
    }
}

#[test]
fn read_over_a_modbus_tcp_gateway_against_each_hostile_script() {
    read_against(TransportKind::TcpGateway);
}

#[test]
fn read_over_rtu_over_tcp_against_each_hostile_script() {
    read_against(TransportKind::RtuOverTcp);
}

#[test]
fn poll_against_a_flooding_and_a_trickling_peer_is_bounded() {
    let profile = profile();
    for script in [Script::Flood, Script::Trickle] {
        let peer = HostilePeer::start(TransportKind::TcpGateway, profile, script);
        let addr = peer.addr.to_string();
        // Two cycles of one request each: 2 × (timeout × attempts) + 2 s.
        let bound = Duration::from_millis(500) * 2 * 2 + Duration::from_secs(2);
        let (code, out, err, took) = drivemap(
            &[
                "poll",
                "--drive",
                DRIVE,
                "--gateway",
                &addr,
                "--timeout",
                "500ms",
                "--retries",
                "1",
                "--interval",
                "100ms",
                "--count",
                "2",
                REGISTER,
            ],
            bound,
        );
        assert!(took <= bound, "{script:?}: took {took:?}");
        assert_eq!(code, 1, "{script:?}: {out}{err}");
        assert!(out.contains("— poll 2 at "), "{script:?}: {out}");
        assert!(
            out.contains(expected(script, TransportKind::TcpGateway)),
            "{script:?}: {out}"
        );
    }
}

/// The server goes away and comes back on the same port while `poll` runs: polling resumes on
/// a new connection (before, every later cycle failed with "the server closed the
/// connection").
#[test]
fn poll_reconnects_after_the_server_restarts() {
    let profile = profile();
    for kind in [TransportKind::TcpGateway, TransportKind::RtuOverTcp] {
        let peer = HostilePeer::start(kind, profile, Script::Answer);
        let addr = peer.addr;
        let restart = thread::spawn(move || {
            thread::sleep(Duration::from_millis(700));
            let addr = peer.shut_down();
            thread::sleep(Duration::from_millis(400));
            let again = HostilePeer::start_at(addr, kind, profile, Script::Answer);
            thread::sleep(Duration::from_secs(4));
            drop(again);
        });
        let (_, out, err, _) = drivemap(
            &[
                "poll",
                "--drive",
                DRIVE,
                flag(kind),
                &addr.to_string(),
                "--timeout",
                "300ms",
                "--retries",
                "1",
                "--interval",
                "200ms",
                "--count",
                "12",
                REGISTER,
            ],
            Duration::from_secs(15),
        );
        restart.join().unwrap();
        let cycles: Vec<&str> = out.split("— poll ").skip(1).collect();
        assert_eq!(cycles.len(), 12, "{out}{err}");
        assert!(cycles[0].contains("3.9 A"), "{kind:?}: first cycle:\n{out}");
        let last = cycles[11];
        assert!(
            last.contains("3.9 A") && last.contains("reconnected 1 time(s)"),
            "{kind:?}: after the restart:\n{out}{err}"
        );
    }
}

/// The report's reproduction (issue 23, item 2), scaled down: a V7 over RTU over TCP that
/// answers every request just after the timeout (250 ms for a 200 ms timeout, one retry),
/// `read max_output_frequency accel_time_1`. Before, the late answer to n011 (010Bh = 600) was
/// printed as accel_time_1 (0113h), "60.0 s", exit 1 only for the first register. Now no value
/// is printed for either, and each error says that the next request waits for silence.
#[test]
fn read_never_prints_a_late_reply_as_another_registers_value() {
    use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
    use drivemap_sim::SimulatedSlave;
    use drivemap_test_support::late_slave::serve_late;
    use std::net::TcpListener;

    let map = drivemap_map::Loader::new()
        .load(&repo().join("maps/yaskawa-v7.yaml"))
        .expect("shipped map");
    let profile = drivemap_live::leak_profile(&map);
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let mut slave = SimulatedSlave::new(1, profile);
            slave.set_holding(0x010B, 600); // n011 60.0 Hz
            slave.set_holding(0x0113, 100); // n019 10.0 s
            let mut link = RtuOverTcpTransport::from_stream(stream).unwrap();
            let until = Instant::now() + Duration::from_secs(20);
            serve_late(&mut link, &mut slave, 1, Duration::from_millis(250), until);
        }
    });
    let (code, out, err, _) = drivemap(
        &[
            "read",
            "--drive",
            "yaskawa-v7",
            "--rtu-tcp",
            &addr,
            "--timeout",
            "200ms",
            "--retries",
            "1",
            "--set",
            "n018=0",
            "max_output_frequency",
            "accel_time_1",
        ],
        Duration::from_secs(15),
    );
    assert_eq!(code, 1, "{out}{err}");
    for register in ["max_output_frequency", "accel_time_1"] {
        let row = out
            .lines()
            .find(|l| l.starts_with(register))
            .unwrap_or_else(|| panic!("no row for {register}:\n{out}"));
        assert!(
            row.contains("error: no reply from slave 1")
                && row.contains(
                    "the next request to slave 1 waits until the line has been silent for 200 ms"
                ),
            "{register}: {row}\n{out}"
        );
    }
    assert!(
        !out.contains("60.0 s"),
        "n011's word printed as accel_time_1:\n{out}"
    );
}

/// `scan` against a peer that floods the link says why its probes got no answer, by cause,
/// with the client's own words for the first one, instead of a bare "0 answered". A quiet
/// address (nothing listening on the line's other slaves) is told apart: no reply in time.
#[test]
fn scan_against_a_flooding_peer_says_why_nothing_answered() {
    for kind in [TransportKind::TcpGateway, TransportKind::RtuOverTcp] {
        let peer = HostilePeer::start(kind, profile(), Script::Flood);
        let addr = peer.addr.to_string();
        // Three probes of at most 300 ms each, and 2 s to start and print.
        let bound = Duration::from_millis(300) * 3 + Duration::from_secs(3);
        let (code, out, err, took) = drivemap(
            &[
                "scan",
                flag(kind),
                &addr,
                "--drive",
                DRIVE,
                "--slaves",
                "1-3",
                "--timeout",
                "300ms",
            ],
            bound,
        );
        assert!(took <= bound, "{kind:?}: took {took:?}");
        assert_eq!(code, 1, "{kind:?}: {out}{err}");
        assert!(out.contains(": 0 answered in "), "{kind:?}: {out}");
        assert!(
            out.contains("why no answer (3 probe(s)): "),
            "{kind:?}: {out}"
        );
        // The flood is named, with the client's words for it.
        assert!(
            out.contains("flooded: the peer sent more bytes than any answer, without the answer"),
            "{kind:?}: {out}"
        );
        assert!(
            out.contains("e.g. ") && out.contains("the peer floods the link"),
            "{kind:?}: {out}"
        );
    }
    // A peer that answers only for another unit: no reply in time, said so.
    let peer = HostilePeer::start(TransportKind::TcpGateway, profile(), Script::OtherUnit);
    let addr = peer.addr.to_string();
    let bound = Duration::from_millis(300) * 2 + Duration::from_secs(3);
    let (code, out, err, _) = drivemap(
        &[
            "scan",
            "--gateway",
            &addr,
            "--drive",
            DRIVE,
            "--slaves",
            "1-2",
            "--timeout",
            "300ms",
        ],
        bound,
    );
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        out.contains("why no answer (2 probe(s)): 2 no reply within the probe timeout"),
        "{out}"
    );
}
