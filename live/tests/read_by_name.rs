//! The example program `examples/read_by_name.rs` reads registers by name from a simulated
//! drive through the library's `Session`, the scale selector first.

use std::path::PathBuf;

use drivemap_live::session::UnknownNames;
use drivemap_sim::{SimOptions, Simulator, TcpFraming, TcpServer};

#[path = "../examples/read_by_name.rs"]
#[allow(dead_code)] // the example's `main` is the program's; the test calls `read_by_name`
mod example;

fn v7_map() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../maps/yaskawa-v7.yaml")
}

/// A simulated V7 on loopback Modbus TCP with n018 = 1 (times in 0.01 s) and n019 = 12.34 s.
fn serve_v7() -> TcpServer {
    let drive = drivemap_map::read_map(&v7_map(), &Default::default()).unwrap();
    let mut sim = Simulator::new(drive, SimOptions::new()).unwrap();
    sim.set("n018", 1.0).unwrap();
    sim.set("n019", 12.34).unwrap();
    let shared = drivemap_sim::shared(sim);
    TcpServer::spawn(shared, "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap()
}

#[test]
fn the_example_reads_a_register_by_name_decoded_with_its_selected_scale() {
    let server = serve_v7();
    let addr = server.local_addr().to_string();
    let names = ["n019".to_owned(), "Accel Time 1".to_owned()];
    let values = example::read_by_name(&v7_map(), &addr, &names).unwrap();
    assert_eq!(values.len(), 2);
    for (id, value) in &values {
        assert_eq!(id, "accel_time_1");
        // Decoded with 0.01 s per count: read with n018's default scale (0.1 s) the raw
        // word 1234 would say 123.4 s.
        assert_eq!(value.as_ref().unwrap(), "12.34 s");
    }
}

#[test]
fn an_unknown_name_is_a_typed_error_with_the_nearest_names() {
    let server = serve_v7();
    let addr = server.local_addr().to_string();
    let e = example::read_by_name(&v7_map(), &addr, &["n0199".to_owned()]).unwrap_err();
    let unknown = e
        .downcast_ref::<UnknownNames>()
        .expect("names not in the map are UnknownNames");
    assert_eq!(unknown.0[0].name, "n0199");
    assert!(
        unknown.0[0].suggestions.iter().any(|s| s.contains("n019")),
        "{e}"
    );
}
