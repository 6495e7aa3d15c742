//! A planned poll cycle allocates nothing once its buffers exist: counted with a global
//! allocator that counts the allocations of the current thread.

use drivemap_test_support::alloc_count::{self, Counting};
use drivemap_test_support::instant_link::InstantLink;

use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::register::{Access, RegisterInfo, Table};
use drivemap_runtime::planner::Poller;
use drivemap_sim::SimulatedSlave;

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    alloc_count::this_thread()
}

static PROFILE: Profile = Profile {
    max_read: 8,
    ..Profile::GENERIC
};

static REGISTERS: &[RegisterInfo] = &{
    let mut all = [RegisterInfo {
        id: "r",
        param: None,
        name: "r",
        address: 0,
        access: Access::Read,
        table: Table::Holding,
        width: drivemap_runtime::core::width::Width::Word,
        broadcast_only: false,
        source: "",
    }; 40];
    let mut i = 0;
    while i < 40 {
        all[i].address = 0x20 + i as u16;
        i += 1;
    }
    all
};

#[test]
fn a_planned_poll_cycle_allocates_nothing() {
    let wanted: Vec<(Table, u16)> = (0x20..0x48)
        .filter(|a| a % 3 != 0)
        .map(|a| (Table::Holding, a))
        .collect();
    let mut poller = Poller::new(&PROFILE, REGISTERS, wanted).unwrap();
    let mut drive = SimulatedSlave::new(1, &PROFILE);
    for a in 0x20..0x48 {
        drive.set_holding(a, a * 10);
    }
    let mut client = Client::new(InstantLink::new(drive), &PROFILE);
    poller.poll(&mut client, 1);
    let before = allocations();
    let mut requests = 0;
    for _ in 0..100 {
        requests += poller.poll(&mut client, 1).requests;
    }
    let during = allocations() - before;
    assert_eq!(requests, 100 * poller.plan().count() as u32);
    assert!(requests > 100);
    assert_eq!(during, 0, "{during} allocations in 100 poll cycles");
    assert_eq!(
        poller.get(Table::Holding, 0x47).unwrap().unwrap(),
        0x47 * 10
    );
    // The counter does count: planning allocates.
    let before = allocations();
    let again = Poller::new(&PROFILE, REGISTERS, [(Table::Holding, 0x21)]).unwrap();
    assert!(allocations() > before);
    drop(again);
}
