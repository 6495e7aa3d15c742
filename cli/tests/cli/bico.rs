//! A register read from one parameter and written to another (Siemens BICO; the fictional
//! `tests/fixtures/lindgren-lg7`: register 0200h reads r0055 bit 8 and writes P2200), issue 38
//! item 7: found by either number for its own direction and refused by the other naming the
//! right one, through the binary against the fixture's own simulator (which does not change
//! what a read gives when the register is written); `check`, `doc`, `export`, `diff` and
//! `probe` see both numbers; parameter sets leave it out, saying why, and a set that names it
//! is refused, naming why, before anything is written.

use drivemap_sim::{SimOptions, Simulator, server::TcpFraming, server::TcpServer};

use crate::common::{self, repo};

const ID: &str = "lindgren-lg7";

fn serve() -> (TcpServer, String) {
    let drive = drivemap_map::Loader::new()
        .load(&repo().join(format!("tests/fixtures/{ID}/{ID}.yaml")))
        .unwrap_or_else(|d| panic!("{d}"));
    let sim = Simulator::new(drive, SimOptions::new()).unwrap();
    assert_eq!(sim.warnings(), [] as [String; 0]);
    let server = TcpServer::spawn(sim, "127.0.0.1:0", TcpFraming::ModbusTcp, None).unwrap();
    let addr = server.local_addr().to_string();
    (server, addr)
}

fn run(addr: &str, args: &[&str]) -> (i32, String, String) {
    let dir = repo().join(format!("tests/fixtures/{ID}"));
    let mut all = args.to_vec();
    all.extend(["--drive", ID, "--tcp", addr]);
    common::drivemap_fixture(&dir, &all)
}

#[test]
fn read_by_the_read_number_write_by_the_write_number() {
    let (_server, addr) = serve();
    let (code, out, err) = run(&addr, &["read", "r0055.8"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("fixed_frequency_bit_0") && out.contains("0000h"),
        "{out}"
    );
    // Reading by the write-only number names the read number.
    let (code, out, err) = run(&addr, &["read", "P2200"]);
    assert_ne!(code, 0, "{out}");
    assert!(
        err.contains("P2200 is the parameter a write of fixed_frequency_bit_0 (0200H) sets")
            && err.contains("read `r0055.8`"),
        "{err}"
    );
    // Writing by the read-only number names the write number; nothing is written.
    let (code, out, err) = run(&addr, &["write", "r0055.8=1"]);
    assert_ne!(code, 0, "{out}");
    assert!(
        err.contains("a write there sets P2200") && err.contains("nothing written"),
        "{err}"
    );
    // Written by P2200 (and by id): the simulated drive takes the write, and what a read
    // returns (the status bit) does not follow it.
    let (code, out, err) = run(&addr, &["write", "P2200=1"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("wrote fixed_frequency_bit_0 (P2200) = 1 (0001h) at 0200h"),
        "{out}"
    );
    let (code, out, err) = run(
        &addr,
        &["read", "fixed_frequency_bit_0", "--format", "json"],
    );
    assert_eq!(code, 0, "{out}{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        json[0]["raw"], 0,
        "a write of P2200 is not read back as r0055.8: {out}"
    );
}

#[test]
fn parameter_sets_leave_it_out_saying_why() {
    let (_server, addr) = serve();
    let (code, set, err) = run(&addr, &["save"]);
    assert_eq!(code, 0, "{set}{err}");
    assert!(
        !set.contains("fixed_frequency_bit_0") && !set.contains("on_off1_command"),
        "{set}"
    );
    assert!(set.contains("control_mode"), "{set}");
    assert!(
        err.contains("fixed_frequency_bit_0 (P2200) is left out of parameter sets: a read returns r0055.8, a write sets P2200"),
        "{err}"
    );
    // A set that names it (written by hand) is refused before anything is written.
    let scratch = common::Scratch::new("bico-set");
    let file = scratch.0.join("set.yaml");
    let edited = set.replace(
        "unread:",
        "  - {id: \"fixed_frequency_bit_0\", param: \"P2200\", value: 1}\nunread:",
    );
    assert_ne!(edited, set);
    std::fs::write(&file, edited).unwrap();
    let (code, out, err) = run(&addr, &["restore", file.to_str().unwrap()]);
    assert_ne!(code, 0, "{out}");
    assert!(
        err.contains("fixed_frequency_bit_0 (P2200): not a setting a set restores (a read returns another parameter")
            && err.contains("nothing written"),
        "{err}"
    );
}

#[test]
fn check_doc_export_probe_and_diff_see_both_numbers() {
    let dir = repo().join(format!("tests/fixtures/{ID}"));
    assert_eq!(
        crate::probe_sim::every_map_agrees_with_its_simulator(&dir),
        [ID.to_owned()]
    );
    let file = format!("{ID}.yaml");
    let (code, out, err) = common::drivemap_fixture(&dir, &["check", "--strict", &file]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("0 unverified"), "{out}");
    let (code, out, err) = common::drivemap_fixture(&dir, &["doc", &file]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("| 0200h | r0055.8 (read) / P2200 (write) |"),
        "{out}"
    );
    let (code, out, err) = common::drivemap_fixture(&dir, &["export", &file]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    let reg = |id: &str| {
        json["registers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["id"] == id)
            .cloned()
            .unwrap()
    };
    assert_eq!(reg("fixed_frequency_bit_0")["param"], "P2200");
    assert_eq!(reg("fixed_frequency_bit_0")["read_param"], "r0055.8");
    assert!(
        reg("control_mode").get("read_param").is_none(),
        "only where given"
    );
    // The read parameter changed: a breaking change, both sides shown.
    let scratch = common::Scratch::new("bico-diff");
    let text = std::fs::read_to_string(dir.join(&file)).unwrap();
    let changed = scratch.0.join(&file);
    std::fs::write(
        &changed,
        text.replace("read_param: r0055.8", "read_param: r0055.9"),
    )
    .unwrap();
    let (code, out, err) = common::drivemap_fixture(
        &dir,
        &[
            "diff",
            dir.join(&file).to_str().unwrap(),
            changed.to_str().unwrap(),
        ],
    );
    assert_ne!(code, 0, "{out}{err}");
    assert!(
        out.contains("read parameter") && out.contains("r0055.8") && out.contains("r0055.9"),
        "{out}"
    );
}
