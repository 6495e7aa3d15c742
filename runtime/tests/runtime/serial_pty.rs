//! The serial transport on a real pseudo-terminal pair made by `socat`: the client opens one
//! end with `SerialTransport`, a simulated drive serves the other end, also through
//! `SerialTransport`. Needs `socat` (Debian package `socat`); without it the test fails.
#![cfg(all(unix, feature = "serial"))]

use crate::common;

use std::io::Write;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::error::Error;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::serial::{Parity, SerialOptions, SerialTransport};
use drivemap_sim::SimulatedSlave;

use common::V7;

use drivemap_test_support::pty_pair;
use pty_pair::PtyPair;

fn options(path: &str) -> SerialOptions {
    SerialOptions::new(path, 19_200)
        .parity(Parity::Even)
        .with_profile(&V7)
}

/// Serves a simulated V7 at slave 1 on `path` for `for_how_long`.
fn serve(path: String, for_how_long: Duration) -> thread::JoinHandle<SimulatedSlave> {
    let mut link = SerialTransport::open(options(&path)).expect("opening the drive's end");
    thread::spawn(move || {
        let mut slave = SimulatedSlave::new(1, &V7);
        slave.set_holding(0x0020, 0x0005);
        slave.set_holding(0x0023, 6000);
        slave
            .serve(&mut link, Instant::now() + for_how_long)
            .expect("serving");
        slave
    })
}

#[test]
fn client_talks_to_a_drive_over_a_pseudo_terminal_pair() {
    let pty = PtyPair::new();
    let drive = serve(pty.paths[1].clone(), Duration::from_secs(3));
    let link = SerialTransport::open(options(&pty.paths[0])).expect("opening the client's end");
    assert!(link.inter_char_timeout().is_some());
    let mut client = Client::with_options(
        link,
        &V7,
        ClientOptions {
            timeout: Duration::from_millis(500),
            retries: 0,
            ..ClientOptions::default()
        },
    );

    let mut r = [0u16; 4];
    client.read_holding(1, 0x0020, &mut r).unwrap();
    assert_eq!(r, [0x0005, 0, 0, 6000]);
    client.write_registers(1, 0x0001, &[1, 600]).unwrap();
    client.write_register(1, 0x0002, 3575).unwrap();
    client.loop_back(1, 0xA537).unwrap();
    // Broadcast: sent, no reply awaited; the drive executes it.
    client.write_register(0, 0x0001, 0).unwrap();
    // A slave that is not on the line: timeout naming the request.
    let e = client.read_holding(2, 0x0020, &mut [0; 1]).unwrap_err();
    assert!(matches!(e, Error::Timeout { .. }), "{e}");
    assert_eq!(
        e.to_string(),
        "no reply from slave 2 to 03h read of 0020h x1 within 500 ms; the next request to slave 2 waits until the line has been silent for 500 ms, so that a late reply is not taken for its answer"
    );
    let mut r = [0u16; 2];
    client.read_holding(1, 0x0001, &mut r).unwrap();
    assert_eq!(r, [0, 3575]);

    let slave = drive.join().unwrap();
    assert_eq!(slave.holding(0x0002), 3575);
    assert_eq!(slave.holding(0x0001), 0, "broadcast executed");
}

#[test]
fn stale_bytes_on_the_line_are_flushed_before_the_request() {
    let pty = PtyPair::new();
    // Bytes the drive's side sends before anyone asks: the tail of an old reply and noise. They
    // sit in the client's input buffer when it sends its request.
    let mut raw = serialport::new(&pty.paths[1], 19_200)
        .timeout(Duration::from_millis(100))
        .open()
        .expect("opening the drive's end");
    let link = SerialTransport::open(options(&pty.paths[0])).expect("opening the client's end");
    // A complete, valid reply to a read of 1 register with value 1234h: if it were not flushed
    // it would be taken as the answer.
    raw.write_all(&[0x01, 0x03, 0x02, 0x12, 0x34, 0xB5, 0x33, 0xFF, 0x00])
        .unwrap();
    raw.flush().unwrap();
    drop(raw);
    thread::sleep(Duration::from_millis(50));
    let drive = serve(pty.paths[1].clone(), Duration::from_secs(2));
    let mut client = Client::with_options(
        link,
        &V7,
        ClientOptions {
            timeout: Duration::from_millis(500),
            retries: 0,
            ..ClientOptions::default()
        },
    );
    let mut r = [0u16; 1];
    client.read_holding(1, 0x0023, &mut r).unwrap();
    assert_eq!(r, [6000]);
    drive.join().unwrap();
}

/// Modbus ASCII on the pseudo-terminal pair at 7 data bits, even parity (Delta's factory
/// setting): the client's `SerialTransport` with `SerialOptions::ascii(7)`, the drive serving
/// through the same, the same requests as over RTU.
#[test]
fn client_talks_ascii_at_seven_data_bits_over_a_pseudo_terminal_pair() {
    use drivemap_runtime::core::profile::TransportKind;
    let ascii = |path: &str| options(path).ascii(7).expect("7 data bits");
    let pty = PtyPair::new();
    let mut drive_end = SerialTransport::open(ascii(&pty.paths[1])).expect("the drive's end");
    assert_eq!(drive_end.kind(), TransportKind::Ascii);
    let drive = thread::spawn(move || {
        let mut slave = SimulatedSlave::new(1, &V7);
        slave.set_holding(0x0020, 0x0005);
        slave.set_holding(0x0023, 6000);
        slave
            .serve(&mut drive_end, Instant::now() + Duration::from_secs(3))
            .expect("serving");
        slave
    });
    let link = SerialTransport::open(ascii(&pty.paths[0])).expect("the client's end");
    assert_eq!(link.kind(), TransportKind::Ascii);
    assert_eq!(link.options().serial_config().data_bits, 7);
    // A reply ends at its CR LF, not at a silence.
    assert!(link.inter_char_timeout().is_none());
    let mut client = Client::with_options(
        link,
        &V7,
        ClientOptions {
            timeout: Duration::from_millis(500),
            retries: 0,
            ..ClientOptions::default()
        },
    );
    let mut r = [0u16; 4];
    client.read_holding(1, 0x0020, &mut r).unwrap();
    assert_eq!(r, [0x0005, 0, 0, 6000]);
    client.write_registers(1, 0x0001, &[1, 600]).unwrap();
    client.write_register(1, 0x0002, 3575).unwrap();
    client.loop_back(1, 0xA537).unwrap();
    client.write_register(0, 0x0001, 0).unwrap();
    let e = client.read_holding(2, 0x0020, &mut [0; 1]).unwrap_err();
    assert!(matches!(e, Error::Timeout { .. }), "{e}");
    let mut r = [0u16; 2];
    client.read_holding(1, 0x0001, &mut r).unwrap();
    assert_eq!(r, [0, 3575]);
    let slave = drive.join().unwrap();
    assert_eq!(slave.holding(0x0002), 3575);
    assert_eq!(slave.holding(0x0001), 0, "broadcast executed");
}
