//! The clients against a hostile peer on loopback (`support/hostile_peer.rs`): a server that
//! floods, trickles one byte per 100 ms, never ends a frame, resets mid-frame, announces an
//! MBAP length of 65535, or answers another transaction or unit. Every call must return within
//! timeout × attempts + 2 s with an error that says what happened, over Modbus TCP and RTU over
//! TCP, blocking and async. And a server that restarts is reconnected to.
//!
//! Each call runs in a thread of its own and the test fails, rather than hangs, when the call
//! is still running past the bound.

use drivemap_test_support::hostile_peer;

use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::client::{Client, ClientOptions, Reconnect};
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::error::Error;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::transport::tcp::TcpTransport;

use hostile_peer::{HostilePeer, Script};

static PROFILE: Profile = Profile {
    max_read: 16,
    ..Profile::GENERIC
};

const TIMEOUT: Duration = Duration::from_millis(500);
const RETRIES: u8 = 1;

/// timeout × attempts + 2 s.
fn bound() -> Duration {
    TIMEOUT * (u32::from(RETRIES) + 1) + Duration::from_secs(2)
}

fn options() -> ClientOptions {
    ClientOptions {
        timeout: TIMEOUT,
        retries: RETRIES,
        ..ClientOptions::default()
    }
}

/// Runs `f` in a thread; fails the test if it has not returned within the bound.
fn bounded<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    let started = Instant::now();
    thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(bound() + Duration::from_secs(1)) {
        Ok(v) => {
            let took = started.elapsed();
            assert!(
                took <= bound(),
                "{what}: took {took:?}, more than the bound {:?}",
                bound()
            );
            v
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: the call panicked"),
        Err(mpsc::RecvTimeoutError::Timeout) => panic!(
            "{what}: still running after {:?} (bound {:?})",
            started.elapsed(),
            bound()
        ),
    }
}

/// What the error of each script must say.
fn expect(script: Script, kind: TransportKind, e: &Error) {
    let text = e.to_string();
    let timeout = format!(
        "within {} ms ({} attempts)",
        TIMEOUT.as_millis(),
        RETRIES + 1
    );
    match script {
        Script::Flood => assert!(
            matches!(e, Error::Overrun { .. }) && text.contains("floods the link"),
            "{script:?}: {text}"
        ),
        // On RTU framing the retry first waits for the line to fall silent (a late reply
        // could be on its way), which a peer that keeps sending never lets happen.
        Script::Trickle | Script::LyingLength if kind.is_rtu_framed() => assert!(
            matches!(e, Error::Unsettled { .. })
                && text.contains("the line never fell silent")
                && text.contains(&format!("silent for {} ms", TIMEOUT.as_millis())),
            "{script:?}: {text}"
        ),
        Script::Trickle | Script::LyingLength => assert!(
            matches!(e, Error::Timeout { .. })
                && text.contains(&timeout)
                && text.contains("byte(s)"),
            "{script:?}: {text}"
        ),
        Script::Unfinished => assert!(
            matches!(e, Error::Timeout { .. })
                && text.contains(&timeout)
                && text.contains("an incomplete frame"),
            "{script:?}: {text}"
        ),
        Script::ResetMidFrame => assert!(
            matches!(e, Error::Io { .. })
                && (text.contains("reset") || text.contains("closed the connection")),
            "{script:?}: {text}"
        ),
        Script::OtherTransaction => {
            let why = if kind.is_rtu_framed() {
                "reply from slave 2, expected slave 1"
            } else {
                "transaction"
            };
            assert!(
                matches!(e, Error::Timeout { .. }) && text.contains(&timeout) && text.contains(why),
                "{script:?}: {text}"
            )
        }
        Script::OtherUnit => {
            let why = if kind.is_rtu_framed() {
                "reply from slave 2, expected slave 1"
            } else {
                "unit 2 in reply, expected unit 1"
            };
            assert!(
                matches!(e, Error::Timeout { .. }) && text.contains(&timeout) && text.contains(why),
                "{script:?}: {text}"
            )
        }
        Script::Answer | Script::Late { .. } => panic!("no error expected"),
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

fn blocking_link(kind: TransportKind, peer: &HostilePeer) -> Box<dyn Transport + Send> {
    match kind {
        TransportKind::Tcp => Box::new(TcpTransport::connect(peer.addr, TIMEOUT).unwrap()),
        _ => Box::new(RtuOverTcpTransport::connect(peer.addr, TIMEOUT).unwrap()),
    }
}

fn blocking_against(kind: TransportKind, script: Script) {
    let peer = HostilePeer::start(kind, &PROFILE, script);
    let link = blocking_link(kind, &peer);
    let what = format!("blocking client, {kind:?}, {script:?}");
    let e = bounded(&what, move || {
        let mut c = Client::with_options(link, &PROFILE, options());
        let mut words = [0u16; 16];
        c.read_holding(1, 0, &mut words).unwrap_err()
    });
    expect(script, kind, &e);
}

#[test]
fn blocking_modbus_tcp_against_each_hostile_script() {
    for script in SCRIPTS {
        blocking_against(TransportKind::Tcp, script);
    }
}

#[test]
fn blocking_rtu_over_tcp_against_each_hostile_script() {
    for script in SCRIPTS {
        blocking_against(TransportKind::RtuOverTcp, script);
    }
}

/// A flood that is on before the request: the flush of stale input must stop too.
#[test]
fn blocking_flush_of_a_flooding_peer_is_bounded() {
    for kind in [TransportKind::Tcp, TransportKind::RtuOverTcp] {
        let peer = HostilePeer::start(kind, &PROFILE, Script::Flood);
        let link = blocking_link(kind, &peer);
        let e = bounded(
            &format!("{kind:?}: flood before the second request"),
            move || {
                let mut c = Client::with_options(link, &PROFILE, options());
                let mut words = [0u16; 16];
                let _ = c.read_holding(1, 0, &mut words);
                // The peer is still flooding: this request's flush meets it first.
                c.read_holding(1, 0, &mut words).unwrap_err()
            },
        );
        expect(Script::Flood, kind, &e);
    }
}

/// The server restarts on the same port between two requests: the next request goes out on a
/// new connection and succeeds, unnoticed by the caller.
#[test]
fn blocking_client_reconnects_after_the_server_restarts() {
    for kind in [TransportKind::Tcp, TransportKind::RtuOverTcp] {
        let peer = HostilePeer::start(kind, &PROFILE, Script::Answer);
        let link = blocking_link(kind, &peer);
        let mut c = Client::with_options(link, &PROFILE, options());
        let mut words = [0u16; 4];
        c.read_holding(1, 3, &mut words).unwrap();
        assert_eq!(words, [3, 4, 5, 6]);
        let addr = peer.shut_down();
        let _restarted = HostilePeer::start_at(addr, kind, &PROFILE, Script::Answer);
        let started = Instant::now();
        c.read_holding(1, 7, &mut words)
            .unwrap_or_else(|e| panic!("{kind:?}: after the restart: {e}"));
        assert_eq!(words, [7, 8, 9, 10]);
        assert!(started.elapsed() < bound());
        assert_eq!(c.reconnects(), 1, "{kind:?}");
    }
}

/// While the server is down each request fails at once with what happened, reconnect attempts
/// back off, and the client comes back when the server does.
#[test]
fn blocking_client_backs_off_while_the_server_is_down() {
    let kind = TransportKind::Tcp;
    let peer = HostilePeer::start(kind, &PROFILE, Script::Answer);
    let link = blocking_link(kind, &peer);
    let mut c = Client::with_options(
        link,
        &PROFILE,
        ClientOptions {
            reconnect: Reconnect::Backoff {
                first: Duration::from_millis(300),
                max: Duration::from_secs(1),
            },
            ..options()
        },
    );
    let mut words = [0u16; 1];
    c.read_holding(1, 1, &mut words).unwrap();
    let addr = peer.shut_down();
    // Down: the reconnect is refused.
    let e = c.read_holding(1, 1, &mut words).unwrap_err().to_string();
    assert!(e.contains("reconnecting failed"), "{e}");
    assert!(e.contains("next attempt in 300 ms"), "{e}");
    // Within the back-off: no attempt, an immediate error saying when.
    let t = Instant::now();
    let e = c.read_holding(1, 1, &mut words).unwrap_err().to_string();
    assert!(
        t.elapsed() < Duration::from_millis(50),
        "waited in back-off"
    );
    assert!(e.contains("next reconnect attempt in"), "{e}");
    let _restarted = HostilePeer::start_at(addr, kind, &PROFILE, Script::Answer);
    thread::sleep(Duration::from_millis(350));
    c.read_holding(1, 1, &mut words).unwrap();
    assert_eq!(words, [1]);
    assert_eq!(c.reconnects(), 1);
}

/// `Reconnect::Never`: the connection stays lost, as before reconnecting existed.
#[test]
fn reconnect_never_keeps_the_connection_lost() {
    let kind = TransportKind::Tcp;
    let peer = HostilePeer::start(kind, &PROFILE, Script::Answer);
    let link = blocking_link(kind, &peer);
    let mut c = Client::with_options(
        link,
        &PROFILE,
        ClientOptions {
            reconnect: Reconnect::Never,
            ..options()
        },
    );
    let mut words = [0u16; 1];
    c.read_holding(1, 1, &mut words).unwrap();
    let addr = peer.shut_down();
    let _restarted = HostilePeer::start_at(addr, kind, &PROFILE, Script::Answer);
    let e = c.read_holding(1, 1, &mut words).unwrap_err().to_string();
    assert!(e.contains("closed the connection"), "{e}");
    assert_eq!(c.reconnects(), 0);
}

/// A connection reset after the request went out fails that attempt; the retry reconnects.
#[test]
fn a_reset_mid_reply_is_retried_on_a_new_connection() {
    let kind = TransportKind::Tcp;
    let peer = HostilePeer::start(kind, &PROFILE, Script::ResetMidFrame);
    let link = blocking_link(kind, &peer);
    let mut c = Client::with_options(link, &PROFILE, options());
    let mut words = [0u16; 2];
    // First request: reset, then the retry meets another reset.
    assert!(matches!(
        c.read_holding(1, 2, &mut words),
        Err(Error::Io { .. })
    ));
    peer.set_script(Script::Answer);
    c.read_holding(1, 2, &mut words).unwrap();
    assert_eq!(words, [2, 3]);
    assert!(c.reconnects() >= 2, "{}", c.reconnects());
}

/// The receive timeout is set only when it changes: after many quick requests, a timeout
/// still waits the whole time, neither less nor much more.
#[test]
fn blocking_timeout_after_quick_requests_is_neither_early_nor_late() {
    let kind = TransportKind::Tcp;
    let peer = HostilePeer::start(kind, &PROFILE, Script::Answer);
    let mut c = Client::with_options(blocking_link(kind, &peer), &PROFILE, options());
    let mut words = [0u16; 2];
    for _ in 0..50 {
        c.read_holding(1, 2, &mut words).unwrap();
    }
    thread::sleep(Duration::from_millis(200));
    for _ in 0..5 {
        c.read_holding(1, 2, &mut words).unwrap();
    }
    peer.set_script(Script::Unfinished);
    let t = Instant::now();
    let e = c.read_holding(1, 2, &mut words).unwrap_err();
    let took = t.elapsed();
    assert!(took >= TIMEOUT * 2, "returned early: {took:?}");
    assert!(took <= bound(), "{took:?}");
    expect(Script::Unfinished, kind, &e);
}

#[cfg(feature = "tokio")]
mod async_client {
    use super::*;
    use drivemap_runtime::async_client::{AsyncClient, AsyncStreamTransport, AsyncTcpTransport};

    fn runtime() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap()
    }

    fn against(kind: TransportKind, script: Script, reconnecting: bool) {
        let peer = HostilePeer::start(kind, &PROFILE, script);
        let addr = peer.addr;
        let what = format!("async client, {kind:?}, {script:?}");
        let e = bounded(&what, move || {
            runtime().block_on(async move {
                let mut words = [0u16; 16];
                if reconnecting {
                    let link = AsyncTcpTransport::connect(addr, kind, TIMEOUT)
                        .await
                        .unwrap();
                    let mut c = AsyncClient::with_options(link, &PROFILE, options());
                    c.read_holding(1, 0, &mut words).await.unwrap_err()
                } else {
                    let link = AsyncStreamTransport::connect(addr, kind).await.unwrap();
                    let mut c = AsyncClient::with_options(link, &PROFILE, options());
                    c.read_holding(1, 0, &mut words).await.unwrap_err()
                }
            })
        });
        expect(script, kind, &e);
        drop(peer);
    }

    #[test]
    fn async_modbus_tcp_against_each_hostile_script() {
        for script in SCRIPTS {
            against(TransportKind::Tcp, script, true);
            against(TransportKind::Tcp, script, false);
        }
    }

    #[test]
    fn async_rtu_over_tcp_against_each_hostile_script() {
        for script in SCRIPTS {
            against(TransportKind::RtuOverTcp, script, true);
        }
    }

    #[test]
    fn async_flush_of_a_flooding_peer_is_bounded() {
        let peer = HostilePeer::start(TransportKind::Tcp, &PROFILE, Script::Flood);
        let addr = peer.addr;
        let e = bounded("async: flood before the second request", move || {
            runtime().block_on(async move {
                let link = AsyncStreamTransport::connect(addr, TransportKind::Tcp)
                    .await
                    .unwrap();
                let mut c = AsyncClient::with_options(link, &PROFILE, options());
                let mut words = [0u16; 16];
                let _ = c.read_holding(1, 0, &mut words).await;
                c.read_holding(1, 0, &mut words).await.unwrap_err()
            })
        });
        expect(Script::Flood, TransportKind::Tcp, &e);
    }

    /// `AsyncTcpTransport` keeps one timer armed across requests: after many quick requests,
    /// a timeout still waits the whole time, neither less nor much more.
    #[test]
    fn async_timeout_after_quick_requests_is_neither_early_nor_late() {
        let kind = TransportKind::Tcp;
        let peer = HostilePeer::start(kind, &PROFILE, Script::Answer);
        runtime().block_on(async {
            let link = AsyncTcpTransport::connect(peer.addr, kind, TIMEOUT)
                .await
                .unwrap();
            let mut c = AsyncClient::with_options(link, &PROFILE, options());
            let mut words = [0u16; 2];
            for _ in 0..50 {
                c.read_holding(1, 2, &mut words).await.unwrap();
            }
            tokio::time::sleep(Duration::from_millis(200)).await;
            for _ in 0..5 {
                c.read_holding(1, 2, &mut words).await.unwrap();
            }
            peer.set_script(Script::Unfinished);
            let t = Instant::now();
            let e = c.read_holding(1, 2, &mut words).await.unwrap_err();
            let took = t.elapsed();
            assert!(took >= TIMEOUT * 2, "returned early: {took:?}");
            assert!(took <= bound(), "{took:?}");
            expect(Script::Unfinished, kind, &e);
        });
    }

    #[test]
    fn async_client_reconnects_after_the_server_restarts() {
        for kind in [TransportKind::Tcp, TransportKind::RtuOverTcp] {
            let peer = HostilePeer::start(kind, &PROFILE, Script::Answer);
            let rt = runtime();
            let mut c = rt.block_on(async {
                let link = AsyncTcpTransport::connect(peer.addr, kind, TIMEOUT)
                    .await
                    .unwrap();
                AsyncClient::with_options(link, &PROFILE, options())
            });
            let mut words = [0u16; 4];
            rt.block_on(c.read_holding(1, 3, &mut words)).unwrap();
            assert_eq!(words, [3, 4, 5, 6]);
            let addr = peer.shut_down();
            let _restarted = HostilePeer::start_at(addr, kind, &PROFILE, Script::Answer);
            rt.block_on(c.read_holding(1, 7, &mut words))
                .unwrap_or_else(|e| panic!("{kind:?}: after the restart: {e}"));
            assert_eq!(words, [7, 8, 9, 10]);
            assert_eq!(c.reconnects(), 1);
        }
    }
}
