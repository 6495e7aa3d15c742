//! Several drives of one line polled in one cycle (issue 25, item 8): two drives of two
//! vendors on one RTU-over-TCP link (a simulated line, `drivemap_sim::Line`), each with its
//! own planned poller, polled by `planner::poll_line` through one client that switches to
//! each drive's profile and timing in turn. Every wanted word comes back equal to its drive's.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use drivemap_drives::{ptlk_tds_v8 as tds, yaskawa_v7 as v7};
use drivemap_runtime::client::Client;
use drivemap_runtime::core::plan::RegisterPlan;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::core::width::Width;
use drivemap_runtime::planner::{Poller, poll_line};
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_sim::server::lock;
use drivemap_sim::{
    Line, SimOptions, Simulator, clock::ManualClock, server::TcpFraming, server::TcpServer,
};

fn sim(id: &str, slave: u8, clock: &ManualClock) -> Simulator {
    let path = paths::shipped_map(id);
    let drive = drivemap_map::Loader::new().load(path.as_ref()).unwrap();
    Simulator::new(
        drive,
        SimOptions::new()
            .slave(slave)
            .clock(Arc::new(clock.clone())),
    )
    .unwrap()
}

/// Every one-word holding register readable over RTU at a fixed address: the wanted set.
fn wanted(registers: &[RegisterPlan]) -> Vec<&RegisterPlan> {
    registers
        .iter()
        .filter(|r| {
            r.info.access.readable()
                && r.info.table == Table::Holding
                && r.info.width == Width::Word
                && !r.info.broadcast_only
                && r.moves.is_empty()
                && r.transports.contains(TransportKind::Rtu)
        })
        .collect()
}

#[test]
fn one_cycle_polls_two_drives_of_one_line_each_with_its_own_map() {
    let clock = ManualClock::new();
    let mut line = Line::new();
    let a = line.add(sim("yaskawa-v7", 1, &clock)).unwrap();
    let b = line.add(sim("ptlk-tds-v8", 2, &clock)).unwrap();
    // Distinct values where both drives have a reference at nearby addresses.
    lock(&a).set_raw("frequency_reference", 123).unwrap();
    lock(&b).set_raw("frequency_command", 4567).unwrap();
    let server = TcpServer::spawn(line, "127.0.0.1:0", TcpFraming::RtuOverTcp, None).unwrap();

    let v7_wanted = wanted(v7::REGISTERS);
    let tds_wanted = wanted(tds::REGISTERS);
    assert!(v7_wanted.len() > 50 && tds_wanted.len() > 50);
    let poller = |profile, registers, list: &[&RegisterPlan]| {
        Poller::new(
            profile,
            registers,
            list.iter().map(|r| (r.info.table, r.info.address)),
        )
        .unwrap()
    };
    let mut drives = [
        (1, poller(&v7::PROFILE, v7::REGISTERS, &v7_wanted)),
        (2, poller(&tds::PROFILE, tds::REGISTERS, &tds_wanted)),
    ];
    let planned: u32 = drives.iter().map(|(_, p)| p.plan().count() as u32).sum();

    let link = RtuOverTcpTransport::connect(server.local_addr(), Duration::from_secs(1)).unwrap();
    // The client starts as the V7's; poll_line switches it to the TDS-V8's for slave 2 (whose
    // requests of up to 16 registers the V7's profile, at most 8, would refuse).
    assert!(
        drives[1]
            .1
            .plan()
            .any(|(_, r)| r.quantity > v7::PROFILE.max_read)
    );
    let mut client = Client::new(link, &v7::PROFILE);
    for _ in 0..2 {
        let stats = poll_line(&mut client, &mut drives);
        assert_eq!(
            stats.requests, planned,
            "one request per planned read, no split"
        );
        assert_eq!(stats.splits, 0);
    }
    for ((_, poller), (sim, list)) in drives.iter().zip([(&a, &v7_wanted), (&b, &tds_wanted)]) {
        let sim = lock(sim);
        for r in list {
            let got = poller
                .get(r.info.table, r.info.address)
                .unwrap()
                .unwrap_or_else(|e| panic!("{}: {e}", r.info.id));
            assert_eq!(
                u32::from(got),
                sim.raw(r.info.id).unwrap(),
                "{} {} at {:04X}h",
                sim.drive().id(),
                r.info.id,
                r.info.address
            );
        }
    }
    assert_eq!(
        drives[0].1.get(Table::Holding, 0x0002).unwrap().unwrap(),
        123
    );
    assert_eq!(
        drives[1].1.get(Table::Holding, 0x0001).unwrap().unwrap(),
        4567
    );
    // The client is left speaking to the last drive polled.
    assert_eq!(client.profile().drive_id, "ptlk-tds-v8");
}

/// One client per link, not per drive: switched to another drive of the line it takes that
/// drive's limits (a 16-register read the V7's profile refuses before sending is sent to the
/// TDS-V8), blocking and async alike.
#[test]
fn a_client_switched_to_another_drive_takes_its_profile() {
    use drivemap_runtime::async_client::{AsyncClient, AsyncTcpTransport};
    use drivemap_runtime::{client::ClientOptions, error::Refusal};
    let clock = ManualClock::new();
    let mut line = Line::new();
    line.add(sim("yaskawa-v7", 1, &clock)).unwrap();
    let tds_sim = line.add(sim("ptlk-tds-v8", 2, &clock)).unwrap();
    let want: Vec<u16> = (0..16)
        .map(|i| {
            let s = lock(&tds_sim);
            let r = tds::REGISTERS.iter().find(|r| r.info.address == 0x0300 + i);
            r.map_or(0, |r| s.raw(r.info.id).unwrap() as u16)
        })
        .collect();
    let server = TcpServer::spawn(line, "127.0.0.1:0", TcpFraming::RtuOverTcp, None).unwrap();
    let refused = |e: drivemap_runtime::error::Error| {
        matches!(
            e,
            drivemap_runtime::error::Error::Refused(Refusal::TooManyRegisters { .. })
        )
    };
    let tds_options = ClientOptions::for_link(&tds::PROFILE, TransportKind::RtuOverTcp);

    let link = RtuOverTcpTransport::connect(server.local_addr(), Duration::from_secs(1)).unwrap();
    let mut client = Client::new(link, &v7::PROFILE);
    let mut words = [0u16; 16];
    let e = client.read_holding(2, 0x0300, &mut words).unwrap_err();
    assert!(refused(e));
    client.switch_drive(&tds::PROFILE, tds_options);
    client.read_holding(2, 0x0300, &mut words).unwrap();
    assert_eq!(words.to_vec(), want);

    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let link = AsyncTcpTransport::connect(
            server.local_addr(),
            TransportKind::RtuOverTcp,
            Duration::from_secs(1),
        )
        .await
        .unwrap();
        let mut client = AsyncClient::new(link, &v7::PROFILE);
        let mut words = [0u16; 16];
        let e = client
            .read_holding(2, 0x0300, &mut words)
            .await
            .unwrap_err();
        assert!(refused(e));
        client.switch_drive(&tds::PROFILE, tds_options);
        client.read_holding(2, 0x0300, &mut words).await.unwrap();
        assert_eq!(words.to_vec(), want);
    });
}
