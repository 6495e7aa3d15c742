//! A planned poll cycle allocates nothing once its buffers exist: counted with a global
//! allocator that counts the allocations of the current thread.

use drivemap_test_support::alloc_count::{self, Counting};
use std::io;
use std::time::Instant;

use drivemap_runtime::planner::Poller;
use drivemap_runtime::profile::{Profile, TransportKind};
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{Access, Client, RegisterInfo, Table};
use drivemap_sim::slave::SimulatedSlave;

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    alloc_count::this_thread()
}

/// Answers each request as it is sent, into a fixed buffer.
struct Link {
    drive: SimulatedSlave,
    reply: [u8; 256],
    len: usize,
}

impl Transport for Link {
    fn kind(&self) -> TransportKind {
        TransportKind::Rtu
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.len = self.drive.respond_rtu(frame, &mut self.reply).unwrap_or(0);
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], _: Instant) -> io::Result<usize> {
        let n = self.len.min(buf.len());
        buf[..n].copy_from_slice(&self.reply[..n]);
        self.reply.copy_within(n..self.len, 0);
        self.len -= n;
        Ok(n)
    }
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
        width: drivemap_runtime::Width::Word,
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
    let mut client = Client::new(
        Link {
            drive,
            reply: [0; 256],
            len: 0,
        },
        &PROFILE,
    );
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
