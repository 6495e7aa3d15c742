//! The example program `examples/read_by_name.rs` reads registers by name from a simulated
//! drive through the library's `Session`, the scale selector first.

use drivemap_test_support::paths;

use std::path::PathBuf;

use drivemap_live::session::UnknownNames;
use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};

#[path = "../../examples/read_by_name.rs"]
#[allow(dead_code)] // the example's `main` is the program's; the test calls `read_by_name`
mod example;

fn v7_map() -> PathBuf {
    paths::shipped_map("yaskawa-v7")
}

/// A simulated V7 on loopback Modbus TCP with n018 = 1 (times in 0.01 s) and n019 = 12.34 s.
fn serve_v7() -> TcpServer {
    let drive = drivemap_map::Loader::new().load(&v7_map()).unwrap();
    let mut sim = Simulator::new(drive, SimOptions::new()).unwrap();
    sim.set("n018", 1.0).unwrap();
    sim.set("n019", 12.34).unwrap();
    let shared = drivemap_sim::server::shared(sim);
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

/// A session over a draft map (`draft:`, not reviewed) reads, and refuses every write unsent
/// unless opened with `DraftWrites::Allowed`: the link's transport stops the write request,
/// whichever client call made it.
#[test]
fn a_session_over_a_draft_writes_only_when_allowed() {
    use drivemap_live::LiveSettings;
    use drivemap_live::draft::DraftWrites;
    use drivemap_live::link::Link;
    use drivemap_live::session::Session;
    let dir = std::env::temp_dir().join(format!("drivemap-live-draft-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(v7_map()).unwrap();
    let marked = text.replacen("schema: 2\n", "schema: 2\ndraft: {by: a test}\n", 1);
    assert_ne!(marked, text, "the V7 map states its schema");
    let path = dir.join("yaskawa-v7.yaml");
    std::fs::write(&path, marked).unwrap();
    let drive = drivemap_map::Loader::new().load(&path).unwrap();
    assert!(drive.draft().is_some());
    let sim = Simulator::new(drive.clone(), SimOptions::new()).unwrap();
    let server = TcpServer::spawn(
        drivemap_sim::server::shared(sim),
        "127.0.0.1:0",
        TcpFraming::ModbusTcp,
        None,
    )
    .unwrap();
    let link = Link::tcp(server.local_addr().to_string());
    let r = drivemap_live::lookup::find(&drive, "n019").unwrap();
    let profile = drivemap_live::leak_profile(&drive);
    let mut session = Session::open(&drive, &link, LiveSettings::default()).unwrap();
    let at = session.address(r).unwrap();
    let before = session.read_raw(r).unwrap();
    let refused = session.client.write_registers(1, at, &[777]).unwrap_err();
    assert!(
        refused.to_string().contains("yaskawa-v7 is a draft map"),
        "{refused}"
    );
    assert_eq!(session.read_raw(r).unwrap(), before, "nothing was written");
    let mut allowed = Session::open_as(
        &drive,
        profile,
        &link,
        LiveSettings::default(),
        DraftWrites::Allowed,
    )
    .unwrap();
    allowed.client.write_registers(1, at, &[777]).unwrap();
    assert_eq!(allowed.read_raw(r).unwrap(), 777);
    let _ = std::fs::remove_dir_all(&dir);
}
