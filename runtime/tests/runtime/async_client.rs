//! The async client (feature `tokio`): same behaviour as the blocking one, over a tokio duplex
//! pipe, a loopback TCP socket, and the fault-injection link on the blocking pool.
#![cfg(feature = "tokio")]

use crate::common;

use std::time::{Duration, Instant};

use drivemap_runtime::async_client::{AsyncClient, AsyncStreamTransport, BlockingTransport};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::error::{Error, Refusal};
use drivemap_runtime::pdu::FrameError;
use drivemap_runtime::reply::Discard;
use drivemap_runtime::{ascii, rtu, tcp};
use drivemap_sim::SimulatedSlave;
use drivemap_sim::{Fault, FaultyLink};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

use common::{V7, strict};

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

fn drive() -> SimulatedSlave {
    let mut slave = SimulatedSlave::new(1, &V7);
    slave.set_holding(0x0020, 0x1234);
    slave.set_holding(0x0021, 0x5678);
    slave
}

/// Serves `slave` on an async stream until the peer closes it.
async fn serve(
    mut stream: impl AsyncRead + AsyncWrite + Unpin,
    kind: TransportKind,
    mut slave: SimulatedSlave,
) -> SimulatedSlave {
    let mut buf = Vec::new();
    let mut chunk = [0u8; 300];
    let mut out = [0u8; tcp::MAX_FRAME];
    loop {
        if kind.is_ascii() {
            // Modbus ASCII: a frame runs to its LF; the drive answers the RTU frame it stands
            // for, and its reply goes back as ASCII.
            if let Some(lf) = buf.iter().position(|&c| c == b'\n') {
                let frame: Vec<u8> = buf.drain(..=lf).collect();
                let mut request = [0u8; rtu::MAX_FRAME];
                if let Ok(n) = ascii::to_rtu(&frame, &mut request)
                    && let Some(m) = slave.respond(kind, &request[..n], &mut out)
                {
                    let mut reply = [0u8; ascii::MAX_FRAME];
                    let k = ascii::from_rtu(&out[..m], &mut reply).unwrap();
                    stream.write_all(&reply[..k]).await.unwrap();
                }
                continue;
            }
            match stream.read(&mut chunk).await {
                Ok(0) | Err(_) => return slave,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            }
            continue;
        }
        let total = if kind.is_rtu_framed() {
            rtu::request_frame_len(&buf).ok().flatten()
        } else {
            tcp::Header::parse(&buf)
                .ok()
                .flatten()
                .map(|h| h.frame_len())
        };
        match total {
            Some(total) if total <= buf.len() => {
                let frame: Vec<u8> = buf.drain(..total).collect();
                if let Some(n) = slave.respond(kind, &frame, &mut out) {
                    stream.write_all(&out[..n]).await.unwrap();
                }
            }
            _ => match stream.read(&mut chunk).await {
                Ok(0) | Err(_) => return slave,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            },
        }
    }
}

#[test]
fn async_client_over_a_duplex_pipe() {
    runtime().block_on(async {
        for kind in [
            TransportKind::Rtu,
            TransportKind::Tcp,
            TransportKind::Ascii,
            TransportKind::AsciiOverTcp,
        ] {
            let (a, b) = tokio::io::duplex(1024);
            let server = tokio::spawn(serve(b, kind, drive()));
            let mut c =
                AsyncClient::with_options(AsyncStreamTransport::new(a, kind), &V7, strict());
            let mut r = [0u16; 2];
            c.read_holding(1, 0x0020, &mut r).await.unwrap();
            assert_eq!(r, [0x1234, 0x5678]);
            c.write_registers(1, 0x0001, &[1, 600]).await.unwrap();
            c.loop_back(1, 0xA537).await.unwrap();
            let t = Instant::now();
            c.write_register(0, 0x0002, 0x1000).await.unwrap();
            assert!(t.elapsed() < Duration::from_millis(50), "broadcast waited");
            let e = c.read_holding(0, 0x0020, &mut r).await.unwrap_err();
            assert!(matches!(e, Error::Refused(Refusal::BroadcastRead { .. })));
            let e = c.read_holding(1, 0x0020, &mut [0; 9]).await.unwrap_err();
            assert!(matches!(
                e,
                Error::Refused(Refusal::TooManyRegisters { .. })
            ));
            let e = c.write_register(1, 0x0900, 0).await.unwrap_err();
            assert!(matches!(e, Error::Refused(Refusal::CommandRegister { .. })));
            c.persist(1, "enter").await.unwrap();
            assert_eq!(c.eeprom().total(), 1);
            // A slave that is not there: timeout naming the request.
            // On RTU framing (no transaction id) it says that the next request waits for
            // silence first, so that a late reply is not taken for its answer.
            let e = c.read_holding(2, 0x0020, &mut [0; 1]).await.unwrap_err();
            let settle = if kind.is_serial_framed() {
                "; the next request to slave 2 waits until the line has been silent for 100 ms, so that a late reply is not taken for its answer"
            } else {
                ""
            };
            assert_eq!(
                e.to_string(),
                format!("no reply from slave 2 to 03h read of 0020h x1 within 100 ms{settle}")
            );
            drop(c);
            let slave = server.await.unwrap();
            assert_eq!(
                slave.holding(0x0002),
                0x1000,
                "{kind:?}: broadcast executed"
            );
            assert_eq!(slave.holding(0x0900), 0);
        }
    });
}

#[test]
fn async_client_over_loopback_tcp() {
    runtime().block_on(async {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let server = tokio::spawn(async move {
            let (stream, _) = listener.accept().await.unwrap();
            serve(stream, TransportKind::Tcp, drive()).await
        });
        let link = AsyncStreamTransport::connect(addr, TransportKind::Tcp)
            .await
            .unwrap();
        let mut c = AsyncClient::with_options(link, &V7, strict());
        let mut r = [0u16; 1];
        c.read_holding(1, 0x0021, &mut r).await.unwrap();
        assert_eq!(r, [0x5678]);
        drop(c);
        server.await.unwrap();
    });
}

#[test]
fn async_client_faults_and_recovery() {
    runtime().block_on(async {
        for kind in [TransportKind::Rtu, TransportKind::Tcp] {
            let link = BlockingTransport::new(FaultyLink::new(kind, drive()));
            let mut c = AsyncClient::with_options(link, &V7, strict());
            for (fault, check) in [
                (Fault::Drop, None),
                (
                    Fault::WrongSlave(2),
                    Some(if kind == TransportKind::Tcp {
                        FrameError::Unit {
                            expected: 1,
                            got: 2,
                        }
                    } else {
                        FrameError::Slave {
                            expected: 1,
                            got: 2,
                        }
                    }),
                ),
            ] {
                inject_into(&mut c, fault);
                let e = c.read_holding(1, 0x0020, &mut [0; 1]).await.unwrap_err();
                match e {
                    Error::Timeout { discarded, .. } => {
                        assert_eq!(discarded.first, check.map(Discard::Frame), "{kind:?}")
                    }
                    other => panic!("{other}"),
                }
                let mut r = [0u16; 1];
                c.read_holding(1, 0x0021, &mut r).await.unwrap();
                assert_eq!(r, [0x5678]);
            }
            inject_into(&mut c, Fault::LateReply);
            assert!(c.read_holding(1, 0x0020, &mut [0; 1]).await.is_err());
            let mut r = [0u16; 2];
            c.read_holding(1, 0x0020, &mut r).await.unwrap();
            assert_eq!(r, [0x1234, 0x5678]);
        }
    });
}

fn inject_into(c: &mut AsyncClient<BlockingTransport<FaultyLink>>, fault: Fault) {
    c.transport().with(|link| link.inject(fault));
}

/// `AsyncClient::new` keeps the drive's timing as `Client::new` does (issue 23, item 8): the
/// manual's request gap and response time on a link to the serial side, no request gap on the
/// drive's own Modbus TCP interface; `ClientOptions::generic()` is the explicit opt-out.
#[test]
fn async_client_new_applies_the_profile_timing() {
    use drivemap_runtime::client::ClientOptions;
    use drivemap_runtime::core::profile::Timing;
    static TIMED: drivemap_runtime::core::profile::Profile =
        drivemap_runtime::core::profile::Profile {
            timing: Timing {
                request_gap_bits: Some(24),
                request_gap_us: Some(10_000),
                ..Timing::MODBUS
            },
            ..drivemap_runtime::core::profile::Profile::GENERIC
        };
    let gap = Duration::from_micros(12_500); // 24 bits at 9600 baud + 10 ms
    for kind in [
        TransportKind::Rtu,
        TransportKind::RtuOverTcp,
        TransportKind::TcpGateway,
        TransportKind::Tcp,
    ] {
        let (a, _b) = tokio::io::duplex(64);
        let c = AsyncClient::new(AsyncStreamTransport::new(a, kind), &TIMED);
        let want = if kind == TransportKind::Tcp {
            Duration::ZERO
        } else {
            gap
        };
        assert_eq!(c.options().request_gap, want, "{kind:?}");
        assert_eq!(
            c.options().timeout,
            ClientOptions::for_profile(&TIMED).timeout
        );
    }
    let (a, _b) = tokio::io::duplex(64);
    let generic = AsyncClient::with_options(
        AsyncStreamTransport::new(a, TransportKind::Rtu),
        &TIMED,
        ClientOptions::generic(),
    );
    assert_eq!(generic.options().request_gap, Duration::ZERO);
}

/// Coils and discrete inputs through the async client: the one implementation the blocking
/// client has (reads split at `max_read_bits`, 05h/0Fh through the gate in the coils' space),
/// over RTU and Modbus TCP framing.
#[test]
fn async_client_reads_and_writes_coils() {
    use drivemap_runtime::core::profile::Profile;
    use drivemap_runtime::core::register::Table;
    use drivemap_runtime::core::rule::WriteRule;
    static WRITES: [WriteRule; 2] = [
        WriteRule::rw("run", 0x0010, 0, 1).in_table(Table::Coil),
        WriteRule::rw("jog", 0x0011, 0, 1).in_table(Table::Coil),
    ];
    static COILS: Profile = Profile {
        function_codes: &[0x01, 0x02, 0x05, 0x0F],
        max_read_bits: 16,
        writes: &WRITES,
        ..Profile::GENERIC
    };
    runtime().block_on(async {
        for kind in [TransportKind::Rtu, TransportKind::Tcp] {
            let mut slave = SimulatedSlave::new(1, &COILS);
            slave.set_discrete_input(0x0021, true);
            slave.reads = Some(Vec::new());
            let (a, b) = tokio::io::duplex(1024);
            let server = tokio::spawn(serve(b, kind, slave));
            let mut c =
                AsyncClient::with_options(AsyncStreamTransport::new(a, kind), &COILS, strict());
            c.write_coil(1, 0x0010, true).await.unwrap();
            c.write_coils(1, 0x0010, &[true, true]).await.unwrap();
            let mut coils = [false; 20];
            c.read_coils(1, 0x0000, &mut coils).await.unwrap();
            let on: Vec<usize> = (0..20).filter(|&i| coils[i]).collect();
            assert_eq!(on, [16, 17], "{kind:?}");
            let mut inputs = [false; 2];
            c.read_discrete_inputs(1, 0x0020, &mut inputs)
                .await
                .unwrap();
            assert_eq!(inputs, [false, true], "{kind:?}");
            // No coil of the map at 0012h: refused before anything is sent.
            let e = c.write_coil(1, 0x0012, true).await.unwrap_err();
            assert!(
                matches!(e, Error::Refused(Refusal::NoWritableCoil { .. })),
                "{kind:?}: {e}"
            );
            drop(c);
            let slave = server.await.unwrap();
            // 20 coils at 16 per request: two reads, then the inputs.
            assert_eq!(
                slave.reads.as_deref(),
                Some(&[(0x0000, 16), (0x0010, 4), (0x0020, 2)][..]),
                "{kind:?}"
            );
            assert_eq!(slave.writes, [(0x0010, 1), (0x0010, 1), (0x0011, 1)]);
        }
    });
}
