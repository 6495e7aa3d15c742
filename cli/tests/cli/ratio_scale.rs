//! A ratio scale through the tool (the fictional Borealis BF6 of `tests/fixtures/borealis-bf6/`,
//! "60.0 Hz = 3600"): `read` shows the exact value (a decimal where it is one, else the fraction
//! and six decimals), `write` sends a value that is a whole number of counts as that count and
//! refuses any other, naming the two nearest legal values, before anything reaches the wire.

use drivemap_test_support::paths;

use crate::common;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use drivemap_sim::SimulatedSlave;

use common::{Framing, drivemap_fixture, serve};

fn fixture() -> PathBuf {
    paths::fixture("borealis-bf6")
}

/// A simulated BF6 register file on loopback (RTU over TCP); its address and the shared slave.
fn serve_bf6() -> (String, Arc<Mutex<SimulatedSlave>>) {
    let map = drivemap_map::Loader::new()
        .load(&fixture().join("borealis-bf6.yaml"))
        .expect("fixture map");
    serve(
        SimulatedSlave::new(1, drivemap_live::leak_profile(&map)),
        Framing::RtuOverTcp,
    )
}

fn live(command: &str, addr: &str, rest: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        command,
        "--maps",
        ".",
        "--drive",
        "borealis-bf6",
        "--rtu-tcp",
        addr,
        "--timeout",
        "2s",
    ];
    args.extend_from_slice(rest);
    drivemap_fixture(&fixture(), &args)
}

fn row<'a>(out: &'a str, id: &str) -> &'a str {
    out.lines()
        .find(|l| l.starts_with(&format!("{id} ")))
        .unwrap_or_else(|| panic!("no row {id} in {out}"))
}

#[test]
fn read_shows_the_exact_value_of_a_ratio() {
    let (addr, slave) = serve_bf6();
    {
        let mut s = slave.lock().unwrap();
        s.set_holding(0x0011, 3599); // output frequency 3599/60 Hz
        s.set_holding(0x0002, 3594); // frequency reference 59.9 Hz
        s.set_holding(0x0013, 0xF800); // torque monitor -2048 counts = -50 %
    }
    let (code, out, err) = live(
        "read",
        &addr,
        &["output_frequency", "frequency_reference", "torque_monitor"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        row(&out, "output_frequency").contains("3599/60 (≈59.983333) Hz"),
        "{out}"
    );
    assert!(
        row(&out, "frequency_reference").contains("59.9 Hz"),
        "{out}"
    );
    assert!(row(&out, "torque_monitor").contains("-50 %"), "{out}");
}

#[test]
fn write_sends_whole_counts_and_refuses_values_between_them() {
    let (addr, slave) = serve_bf6();
    let (code, _, err) = live("write", &addr, &["frequency_reference=59.9"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().holding(0x0002), 3594);
    // A count that is no decimal, typed as its fraction.
    let (code, _, err) = live("write", &addr, &["frequency_reference=3599/60 Hz"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().holding(0x0002), 3599);
    // Between two counts: refused, nothing written, both neighbours named exactly.
    let (code, _, err) = live("write", &addr, &["frequency_reference=59.99"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("59.99 Hz is not a whole number of counts")
            && err.contains("the nearest legal values are 3599/60 (≈59.983333) and 60 Hz"),
        "{err}"
    );
    // The float nearest 3599/60, typed out, is not that count either: the text is compared.
    let (code, _, err) = live("write", &addr, &["frequency_reference=59.983333"]);
    assert_ne!(code, 0);
    assert!(err.contains("not a whole number of counts"), "{err}");
    assert_eq!(slave.lock().unwrap().holding(0x0002), 3599);
    // The range is checked on counts too.
    let (code, _, err) = live("write", &addr, &["frequency_reference=400.5"]);
    assert_ne!(code, 0);
    assert!(err.contains("out of range"), "{err}");
    let (code, _, err) = live("write", &addr, &["frequency_reference=400"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(slave.lock().unwrap().holding(0x0002), 24000);
}
