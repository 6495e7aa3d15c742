//! The string fixture (`tests/fixtures/lumen-lx2`) through its generated module: a string
//! register is `Reg<Drive, Text<N>, ReadOnly, _>`, read with one request of all its registers
//! (03h holding, 04h input) and decoded in its byte order, padding dropped, against the
//! simulated drive serving the manual's examples; alone or in a set with other registers.

use std::time::Duration;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Register;
use drivemap_runtime::core::text::Text;
use drivemap_runtime::core::width::Width;
use drivemap_runtime::pdu::Request;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{client::Client, client::ClientOptions};
use drivemap_sim::framing::{self, Decoded};
use drivemap_sim::{SimOptions, Simulator};
use drivemap_test_support::sim_link::SimLink;

// The generated module of the string fixture (`build.rs`), compiled with this runtime.
#[allow(dead_code)]
mod lumen_lx2 {
    include!(concat!(env!("OUT_DIR"), "/lumen_lx2.rs"));
}

use lumen_lx2::{FrequencyCommand, ModelName, SerialNumber, Settings, SoftwareVersion};

fn client() -> Client<SimLink> {
    let path = format!(
        "{}/fixtures/lumen-lx2/lumen-lx2.yaml",
        env!("CARGO_MANIFEST_DIR")
    );
    let map = drivemap_map::Loader::new()
        .load(path.as_ref())
        .unwrap_or_else(|e| panic!("{path}: {e}"));
    let sim = Simulator::new(map, SimOptions::new()).unwrap();
    let options = ClientOptions {
        timeout: Duration::from_millis(50),
        retries: 0,
        ..ClientOptions::default()
    };
    Client::with_options(
        SimLink::new(TransportKind::Tcp, sim),
        &lumen_lx2::PROFILE,
        options,
    )
}

/// The reads the client sent: (function, PDU address, quantity).
fn reads(c: &mut Client<SimLink>) -> Vec<(u8, u16, u16)> {
    let kind = c.transport().kind();
    c.transport()
        .log
        .iter()
        .filter_map(|s| match framing::decode(kind, &s.frame) {
            Decoded::Request { request, .. } => match request {
                Request::ReadHolding { address, quantity } => Some((0x03, address, quantity)),
                Request::ReadInput { address, quantity } => Some((0x04, address, quantity)),
                _ => None,
            },
            _ => None,
        })
        .collect()
}

#[test]
fn a_generated_string_register_reads_its_text_in_one_request() {
    assert_eq!(ModelName::WIDTH, Width::Text(8));
    assert_eq!(SerialNumber::WIDTH, Width::Text(6));
    let mut c = client();
    let s = Settings::default();
    let model: Text<16> = c.read::<ModelName>(1, &s).unwrap();
    assert_eq!(model.as_str(), Some("LX2-0750-E"));
    assert_eq!(model.to_string(), "LX2-0750-E");
    let version: Text<8> = c.read::<SoftwareVersion>(1, &s).unwrap();
    assert_eq!(version.as_str(), Some("V1.04"));
    // Input registers, low byte first.
    let serial: Text<12> = c.read::<SerialNumber>(1, &s).unwrap();
    assert_eq!(serial.as_str(), Some("SN2407A113"));
    assert_eq!(
        reads(&mut c),
        [(0x03, 0x2100, 8), (0x03, 0x2108, 4), (0x04, 0x3000, 6)]
    );
}

#[test]
fn a_set_reads_a_string_beside_other_registers_in_one_request() {
    let mut c = client();
    let (model, version) = c
        .read_many::<(ModelName, SoftwareVersion)>(1, &Settings::default())
        .unwrap();
    assert_eq!(
        (model.as_str(), version.as_str()),
        (Some("LX2-0750-E"), Some("V1.04"))
    );
    assert_eq!(reads(&mut c), [(0x03, 0x2100, 12)]);
    let f: f64 = c.read::<FrequencyCommand>(1, &Settings::default()).unwrap();
    assert_eq!(f, 0.0);
}

#[test]
fn a_write_into_a_string_is_refused_before_the_wire() {
    let mut c = client();
    for address in [0x2100, 0x2103, 0x2107] {
        assert!(
            c.write_register(1, address, 0x4141).is_err(),
            "{address:04X}h"
        );
        assert!(
            c.write_registers(1, address, &[0x4141]).is_err(),
            "{address:04X}h"
        );
    }
    let rule = lumen_lx2::REGISTERS
        .iter()
        .find(|r| r.info.id == "model_name")
        .unwrap()
        .write_rule();
    assert!(c.write_rule(1, &rule, 0x2103, 0x4141).is_err());
    assert!(
        c.transport().log.is_empty(),
        "nothing was sent: {:?}",
        c.transport().log.len()
    );
    let model: Text<16> = c.read::<ModelName>(1, &Settings::default()).unwrap();
    assert_eq!(model.as_str(), Some("LX2-0750-E"));
}
