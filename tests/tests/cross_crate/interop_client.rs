//! Our client against a slave nobody on this project wrote: a pymodbus server
//! (tests/interop/pymodbus_server.py) over Modbus TCP and over Modbus RTU on a socat
//! pseudo-terminal pair. Reads of both tables, single and multiple writes, loop-back, the
//! server's exceptions (02h, 03h), and a timeout: a register the server answers only after 1.5 s,
//! whose late reply the client must then discard. A missing peer fails the test with the install
//! step (tests/interop/install.sh).

use crate::interop_support;

use std::process::Command;
use std::time::Duration;

use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::error::Error;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::serial::{SerialOptions, SerialTransport};
use drivemap_runtime::transport::tcp::TcpTransport;
use drivemap_runtime::{client::Client, client::ClientOptions};
use interop_support::{PtyPair, free_port, python, script, start_ready};

fn client<T: Transport>(link: T) -> Client<T> {
    Client::with_options(
        link,
        &Profile::GENERIC,
        ClientOptions {
            timeout: Duration::from_millis(500),
            retries: 0,
            ..ClientOptions::default()
        },
    )
}

fn exception_code(e: &Error) -> u8 {
    e.exception()
        .unwrap_or_else(|| panic!("expected an exception, got: {e}"))
        .code
}

/// The same conversation on any link.
fn converse<T: Transport>(c: &mut Client<T>, link: &str) {
    let mut w = [0u16; 4];
    c.read_holding(1, 0, &mut w).unwrap();
    assert_eq!(w, [1000, 1001, 1002, 1003], "{link}: 03h");
    let mut w = [0u16; 3];
    c.read_input(1, 7, &mut w).unwrap();
    assert_eq!(w, [2007, 2008, 2009], "{link}: 04h");
    c.write_register(1, 10, 4242).unwrap();
    c.write_registers(1, 20, &[1, 2, 3]).unwrap();
    let mut w = [0u16; 1];
    c.read_holding(1, 10, &mut w).unwrap();
    assert_eq!(w, [4242], "{link}: 06h written");
    let mut w = [0u16; 4];
    c.read_holding(1, 19, &mut w).unwrap();
    assert_eq!(w, [1019, 1, 2, 3], "{link}: 10h written");
    c.loop_back(1, 0xA537).unwrap();
    // Exceptions: past the holding block (02h), past the input block (02h), a value the
    // server's action refuses (03h) - and the register keeps its value.
    let e = c.read_holding(1, 99, &mut [0; 2]).unwrap_err();
    assert_eq!(exception_code(&e), 0x02, "{link}: {e}");
    let e = c.read_input(1, 10, &mut [0; 1]).unwrap_err();
    assert_eq!(exception_code(&e), 0x02, "{link}: {e}");
    let e = c.write_register(1, 10, 60000).unwrap_err();
    assert_eq!(exception_code(&e), 0x03, "{link}: {e}");
    assert!(e.to_string().contains("exception 03h"), "{e}");
    let e = c.write_registers(1, 98, &[1, 2, 3]).unwrap_err();
    assert_eq!(exception_code(&e), 0x02, "{link}: {e}");
    let mut w = [0u16; 1];
    c.read_holding(1, 10, &mut w).unwrap();
    assert_eq!(w, [4242], "{link}: refused writes change nothing");
    // A reply later than the timeout: the client gives up and says what it waited for.
    let e = c.read_holding(1, 50, &mut [0; 1]).unwrap_err();
    assert!(matches!(e, Error::Timeout { .. }), "{link}: {e}");
    // RTU frames carry no transaction id: the client also says that the next request to the
    // slave waits for a silent line (Modbus TCP matches replies by transaction id instead).
    let expected = if link == "RTU" {
        "no reply from slave 1 to 03h read of 0032h x1 within 500 ms; the next request to \
         slave 1 waits until the line has been silent for 500 ms, so that a late reply is not \
         taken for its answer"
    } else {
        "no reply from slave 1 to 03h read of 0032h x1 within 500 ms"
    };
    assert_eq!(e.to_string(), expected, "{link}");
    // The late reply arrives meanwhile; the next transaction must not take it for its own.
    std::thread::sleep(Duration::from_millis(1500));
    // And the conversation goes on.
    let mut w = [0u16; 1];
    c.read_holding(1, 49, &mut w).unwrap();
    assert_eq!(w, [1049], "{link}: after the timeout");
}

#[test]
fn our_client_against_a_pymodbus_server_over_modbus_tcp() {
    let py = python(&["pymodbus"]);
    let port = free_port();
    let mut cmd = Command::new(py);
    cmd.arg(script("pymodbus_server.py"))
        .args(["--tcp", &port.to_string()]);
    let _server = start_ready(cmd);
    let link = TcpTransport::connect(("127.0.0.1", port), Duration::from_secs(5))
        .expect("connecting to the pymodbus server");
    converse(&mut client(link), "Modbus TCP");
}

#[test]
fn our_client_against_a_pymodbus_server_over_rtu_on_a_pty_pair() {
    let py = python(&["pymodbus", "serial"]);
    let pty = PtyPair::new();
    let mut cmd = Command::new(py);
    cmd.arg(script("pymodbus_server.py"))
        .args(["--serial", &pty.paths[0], "--baud", "19200"]);
    let _server = start_ready(cmd);
    let link = SerialTransport::open(SerialOptions::new(pty.paths[1].as_str(), 19_200))
        .expect("opening the client's end");
    converse(&mut client(link), "RTU");
}
