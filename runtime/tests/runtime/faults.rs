//! Fault injection: every fault gives the expected error, and the very next transaction on the
//! same client is correct.

use crate::common;

use std::thread;
use std::time::Duration;

use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::error::Error;
use drivemap_runtime::pdu::FrameError;
use drivemap_runtime::reply::Discard;
use drivemap_sim::SimulatedSlave;
use drivemap_sim::{Fault, FaultyLink};

use common::{V7, strict};

const KINDS: [TransportKind; 5] = [
    TransportKind::Rtu,
    TransportKind::RtuOverTcp,
    TransportKind::Tcp,
    TransportKind::Ascii,
    TransportKind::AsciiOverTcp,
];

/// The links without a transaction id: RTU and ASCII, on a line or over TCP.
const SERIAL_FRAMED: [TransportKind; 4] = [
    TransportKind::Rtu,
    TransportKind::RtuOverTcp,
    TransportKind::Ascii,
    TransportKind::AsciiOverTcp,
];

fn client(kind: TransportKind, options: ClientOptions) -> Client<FaultyLink> {
    let mut slave = SimulatedSlave::new(1, &V7);
    slave.set_holding(0x20, 0x1234);
    slave.set_holding(0x21, 0x5678);
    Client::with_options(FaultyLink::new(kind, slave), &V7, options)
}

/// A correct transaction right after a fault: reads 0021h, which only the drive's current answer
/// holds (a stale reply to a read of 0020h would give 1234h).
fn assert_recovers(c: &mut Client<FaultyLink>) {
    let mut r = [0u16; 1];
    c.read_holding(1, 0x21, &mut r)
        .expect("transaction after the fault");
    assert_eq!(r, [0x5678]);
    let mut r = [0u16; 2];
    c.read_holding(1, 0x20, &mut r)
        .expect("second transaction after the fault");
    assert_eq!(r, [0x1234, 0x5678]);
}

fn timeout_of(e: Error) -> Option<Discard> {
    match e {
        Error::Timeout { discarded, .. } => discarded.first,
        other => panic!("expected a timeout, got {other}"),
    }
}

fn read_0020(c: &mut Client<FaultyLink>) -> Result<u16, Error> {
    let mut r = [0u16; 1];
    c.read_holding(1, 0x20, &mut r).map(|_| r[0])
}

#[test]
fn dropped_reply_times_out_naming_the_request() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::Drop);
        let e = read_0020(&mut c).unwrap_err();
        let settle = if kind.is_serial_framed() {
            "; the next request to slave 1 waits until the line has been silent for 100 ms, so that a late reply is not taken for its answer"
        } else {
            ""
        };
        assert_eq!(
            e.to_string(),
            format!("no reply from slave 1 to 03h read of 0020h x1 within 100 ms{settle}"),
            "{kind:?}"
        );
        assert_eq!(timeout_of(e), None);
        assert_recovers(&mut c);
    }
}

#[test]
fn dropped_reply_is_recovered_by_a_retry() {
    for kind in KINDS {
        let mut c = client(
            kind,
            ClientOptions {
                retries: 1,
                ..strict()
            },
        );
        c.transport().inject(Fault::Drop);
        assert_eq!(read_0020(&mut c).unwrap(), 0x1234);
        assert_eq!(c.transport().requests, 2, "{kind:?}");
        assert_recovers(&mut c);
    }
}

#[test]
fn truncated_reply_times_out_with_the_incomplete_frame_reported() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::Truncate { keep: 4 });
        let e = read_0020(&mut c).unwrap_err();
        assert!(
            e.to_string().contains("incomplete frame of 4 byte(s)"),
            "{e}"
        );
        assert_eq!(timeout_of(e), Some(Discard::Gap { bytes: 4 }), "{kind:?}");
        assert_recovers(&mut c);
    }
}

#[test]
fn corrupt_crc_is_rejected() {
    for kind in [TransportKind::Rtu, TransportKind::RtuOverTcp] {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::CorruptCrc);
        let e = read_0020(&mut c).unwrap_err();
        assert!(e.to_string().contains("CRC"), "{e}");
        assert!(matches!(
            timeout_of(e),
            Some(Discard::Frame(FrameError::Crc { .. }))
                | Some(Discard::Frame(FrameError::UnknownFunction(_)))
        ));
        assert_recovers(&mut c);
    }
}

#[test]
fn corrupt_lrc_is_rejected() {
    for kind in [TransportKind::Ascii, TransportKind::AsciiOverTcp] {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::CorruptCrc);
        let e = read_0020(&mut c).unwrap_err();
        assert!(e.to_string().contains("LRC"), "{e}");
        assert!(
            matches!(
                timeout_of(e),
                Some(Discard::Ascii(
                    drivemap_runtime::ascii::AsciiError::Lrc { .. }
                ))
            ),
            "{kind:?}"
        );
        assert_recovers(&mut c);
    }
}

#[test]
fn reply_after_the_timeout_is_a_timeout_and_is_not_taken_later() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport()
            .inject(Fault::Delay(Duration::from_millis(250)));
        let e = read_0020(&mut c).unwrap_err();
        assert!(matches!(e, Error::Timeout { .. }), "{e}");
        // The late reply arrives while the link is idle; it is flushed before the next request.
        thread::sleep(Duration::from_millis(200));
        assert_recovers(&mut c);
    }
}

#[test]
fn duplicate_reply_is_not_taken_for_the_next_answer() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::Duplicate);
        assert_eq!(read_0020(&mut c).unwrap(), 0x1234);
        assert_recovers(&mut c);
    }
}

#[test]
fn reply_from_another_slave_is_discarded() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::WrongSlave(2));
        let e = read_0020(&mut c).unwrap_err();
        let expected = if kind == TransportKind::Tcp {
            FrameError::Unit {
                expected: 1,
                got: 2,
            }
        } else {
            FrameError::Slave {
                expected: 1,
                got: 2,
            }
        };
        assert!(e.to_string().contains("discarded 1 frame(s)"), "{e}");
        assert_eq!(timeout_of(e), Some(Discard::Frame(expected)), "{kind:?}");
        assert_recovers(&mut c);
    }
}

#[test]
fn late_reply_to_the_previous_request_is_discarded() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::LateReply);
        assert!(matches!(read_0020(&mut c), Err(Error::Timeout { .. })));
        // The reply to that read (1234h) now arrives after the next request was sent, ahead of
        // the real answer. Modbus TCP tells it apart by transaction id; RTU by the echo checks
        // (here the byte count: 2 registers asked, 1 in the late reply).
        let mut r = [0u16; 2];
        c.read_holding(1, 0x21, &mut r).unwrap();
        assert_eq!(r, [0x5678, 0], "{kind:?}");
        assert_recovers(&mut c);
    }
}

#[test]
fn late_reply_is_discarded_by_transaction_id_even_for_an_identical_request() {
    let mut c = client(TransportKind::Tcp, strict());
    c.transport().inject(Fault::LateReply);
    assert!(read_0020(&mut c).is_err());
    c.transport().slave.set_holding(0x20, 0x4321);
    assert_eq!(read_0020(&mut c).unwrap(), 0x4321);
    c.transport().slave.set_holding(0x20, 0x1234);
    assert_recovers(&mut c);
}

#[test]
fn late_write_echo_is_not_taken_for_another_write() {
    for kind in SERIAL_FRAMED {
        let mut c = client(kind, strict());
        c.transport().inject(Fault::LateReply);
        assert!(matches!(
            c.write_register(1, 0x0001, 1),
            Err(Error::Timeout { .. })
        ));
        c.write_register(1, 0x0002, 600).unwrap();
        assert_eq!(c.transport().slave.holding(0x0002), 600);
        assert_recovers(&mut c);
    }
}

#[test]
fn garbage_before_the_reply_is_skipped() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport()
            .inject(Fault::Noise(vec![0xFF, 0x01, 0x03, 0xFA, 0x00, 0x13]));
        assert_eq!(read_0020(&mut c).unwrap(), 0x1234, "{kind:?}");
        assert_recovers(&mut c);
    }
}

#[test]
fn exception_keeps_the_drive_code_and_names_it_from_the_profile() {
    for kind in KINDS {
        let mut c = client(kind, strict());
        c.transport().slave.fail_at(0x0101, 0x21);
        let e = c.write_register(1, 0x0101, 9999).unwrap_err();
        let ex = *e.exception().expect("an exception");
        assert_eq!(
            (ex.function, ex.code, ex.name),
            (0x06, 0x21, "Data Limits Exceeded")
        );
        assert!(ex.from_profile);
        assert_eq!(
            e.to_string(),
            "slave 1 answered 06h write of 0101h = 270Fh with exception 21h (Data Limits Exceeded: The write command message data is out range for the requested register)"
        );
        // Exceptions are answers: not retried.
        assert_eq!(c.transport().requests, 1);
        assert_recovers(&mut c);
    }
}

#[test]
fn frame_broken_off_by_an_inter_character_gap_is_discarded() {
    for kind in [TransportKind::Rtu, TransportKind::RtuOverTcp] {
        let mut c = client(kind, strict());
        c.transport().inter_char_timeout = Some(Duration::from_millis(15));
        c.transport().inject(Fault::Gap {
            keep: 4,
            pause: Duration::from_millis(50),
        });
        // The 4 bytes before the pause are thrown away when the gap exceeds 15 ms; the rest of
        // that frame is then garbage, and the repeated reply is the answer. Without the
        // inter-character timeout, the two halves would have been joined.
        assert_eq!(read_0020(&mut c).unwrap(), 0x1234);
        assert_eq!(
            c.discarded().first,
            Some(Discard::Gap { bytes: 4 }),
            "{kind:?}"
        );
        assert!(c.discarded().bytes >= 4 + 3);
        assert_recovers(&mut c);

        // The same stall within the allowed gap is one frame.
        c.transport().inject(Fault::Gap {
            keep: 4,
            pause: Duration::from_millis(3),
        });
        c.transport().inter_char_timeout = Some(Duration::from_millis(40));
        assert_eq!(read_0020(&mut c).unwrap(), 0x1234);
        assert!(c.discarded().is_empty(), "{:?}", c.discarded());
    }
}

/// A peer that sends ASCII characters without end: a frame that never ends is dropped at the
/// largest frame's length (the assembler holds no more), a flood past the client's bound ends
/// the call with an overrun, and in both cases the next transaction is correct.
#[test]
fn endless_ascii_characters_are_bounded() {
    use drivemap_runtime::ascii;
    for kind in [TransportKind::Ascii, TransportKind::AsciiOverTcp] {
        // A ':' and then more hex digits than a frame holds, before the reply: thrown away,
        // the reply found.
        let mut c = client(kind, strict());
        let mut noise = vec![b':'];
        noise.extend(std::iter::repeat_n(b'0', 3 * ascii::MAX_FRAME));
        c.transport().inject(Fault::Noise(noise));
        assert_eq!(read_0020(&mut c).unwrap(), 0x1234, "{kind:?}");
        assert!(
            c.discarded().bytes as usize > 3 * ascii::MAX_FRAME,
            "{kind:?}"
        );
        assert_recovers(&mut c);
        // A flood past the bound: an overrun, not a wait without end.
        let mut c = client(kind, strict());
        c.transport().inject(Fault::Noise(vec![
            b'7';
            2 * drivemap_runtime::client::MAX_UNANSWERED_BYTES
        ]));
        let e = read_0020(&mut c).unwrap_err();
        assert!(matches!(e, Error::Overrun { .. }), "{kind:?}: {e}");
        assert_recovers(&mut c);
    }
}
