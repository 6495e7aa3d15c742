//! `drivemap read`, `write` and `poll` name coils and discrete inputs (`tests/fixtures/
//! tindra-tc4` served by its simulator over Modbus TCP): by id, parameter number or Modicon
//! reference (`00001` a coil, `10001` a discrete input), shown as `1 (on)` / `0 (off)`, written as
//! `on`/`off`, `1`/`0` with 05h; an address two tables share is named by neither; a discrete input
//! is never written.

use drivemap_test_support::paths;

use std::path::PathBuf;

use drivemap_sim::{
    SimOptions, Simulator, server::SharedSim, server::TcpFraming, server::TcpServer,
};

use crate::common;

struct Coils {
    server: TcpServer,
    sim: SharedSim,
    dir: PathBuf,
}

impl Coils {
    fn start() -> Coils {
        let dir = paths::fixture("tindra-tc4");
        let map = drivemap_map::Loader::new()
            .load(&dir.join("tindra-tc4.yaml"))
            .unwrap();
        let sim = drivemap_sim::server::shared(
            Simulator::new(
                map,
                SimOptions::new()
                    .network_source(drivemap_runtime::core::profile::TransportKind::Tcp),
            )
            .unwrap(),
        );
        let server =
            TcpServer::spawn(sim.clone(), "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
        Coils { server, sim, dir }
    }

    fn run(&self, command: &str, args: &[&str]) -> (i32, String, String) {
        let addr = self.server.local_addr().to_string();
        let mut all = vec![command, "--drive", "tindra-tc4", "--tcp", &addr];
        all.extend_from_slice(&["--timeout", "2s"]);
        all.extend_from_slice(args);
        common::drivemap_fixture(&self.dir, &all)
    }

    fn raw(&self, id: &str) -> u32 {
        drivemap_sim::server::lock(&self.sim).raw(id).unwrap()
    }
}

#[test]
fn read_write_and_poll_name_coils_and_discrete_inputs() {
    let d = Coils::start();
    let (code, out, err) = d.run("write", &["multi_speed_1=on", "JG=1"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("multi_speed_1 (CF1) = 1 (on)"), "{out}");
    assert_eq!((d.raw("multi_speed_1"), d.raw("jogging")), (1, 1));
    let (code, out, err) = d.run("write", &["CF1=off"]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(d.raw("multi_speed_1"), 0);
    // By id, parameter number and Modicon reference: 00008 is coil 0008h (JG), 10003 discrete
    // input 0003h (IRDY).
    let (code, out, err) = d.run("read", &["jogging", "CF1", "00008", "10003"]);
    assert_eq!(code, 0, "{out}{err}");
    let line = |id: &str| {
        out.lines()
            .filter(|l| l.starts_with(id))
            .collect::<Vec<_>>()
    };
    assert_eq!(line("jogging").len(), 2, "{out}");
    assert!(
        line("jogging").iter().all(|l| l.contains("1 (on)")),
        "{out}"
    );
    assert!(line("multi_speed_1")[0].contains("0 (off)"), "{out}");
    assert!(line("inverter_ready")[0].contains("1 (on)"), "{out}");
    // JSON: the value 1 or 0, the text as the table shows it.
    let (code, out, err) = d.run("read", &["inverter_ready", "--format", "json"]);
    assert_eq!(code, 0, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v[0]["value"], 1.0);
    assert_eq!(v[0]["text"], "1 (on)");
    assert_eq!(v[0]["pdu_address"], 2);
    // 0003h is coil EXT and discrete input IRDY: the address alone names neither.
    let (code, _, err) = d.run("read", &["0003h"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("coil external_trip (00003), discrete input inverter_ready (10003)"),
        "{err}"
    );
    // A value that is no state, and a discrete input: refused, nothing written.
    let (code, _, err) = d.run("write", &["jogging=2"]);
    assert_ne!(code, 0);
    assert!(err.contains("write on or off (1 or 0)"), "{err}");
    let (code, _, err) = d.run("write", &["inverter_ready=0"]);
    assert_ne!(code, 0);
    assert!(err.contains("read-only"), "{err}");
    assert_eq!(d.raw("jogging"), 1);
    // poll: the coils and inputs with a register, each table in requests of its own.
    let (code, out, err) = d.run(
        "poll",
        &["--count", "1", "operation_status", "inverter_ready", "d001"],
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("inverter_ready (IRDY)") && out.contains("0.00 Hz"),
        "{out}"
    );
}
