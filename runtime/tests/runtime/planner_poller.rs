//! The poller against a simulated drive: planned requests, values per register, splitting of
//! merged requests the drive refuses, and what it remembers for later cycles.

use std::io;
use std::time::Instant;

use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::{Profile, TransportKind};
use drivemap_runtime::core::register::{Access, Readable, Register, RegisterInfo, Table};
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::planner::{Learned, PlanError, PolledError, Poller, Read, wanted};
use drivemap_runtime::transport::Transport;
use drivemap_sim::SimulatedSlave;

/// A link to a simulated drive that answers each request as it is sent.
struct Link {
    drive: SimulatedSlave,
    reply: Vec<u8>,
    requests: Vec<(u8, u16, u16)>,
}

impl Transport for Link {
    fn kind(&self) -> TransportKind {
        TransportKind::Rtu
    }
    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.requests.push((
            frame[1],
            u16::from_be_bytes([frame[2], frame[3]]),
            u16::from_be_bytes([frame[4], frame[5]]),
        ));
        let mut out = [0u8; 256];
        let n = self.drive.respond_rtu(frame, &mut out).unwrap_or(0);
        self.reply = out[..n].to_vec();
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], _: Instant) -> io::Result<usize> {
        let n = self.reply.len().min(buf.len());
        buf[..n].copy_from_slice(&self.reply[..n]);
        self.reply.drain(..n);
        Ok(n)
    }
}

static PROFILE: Profile = Profile {
    drive_id: "test-drive",
    max_read: 8,
    ..Profile::GENERIC
};

const fn info(address: u16, access: Access, table: Table) -> RegisterInfo {
    RegisterInfo {
        id: "r",
        param: None,
        name: "r",
        address,
        access,
        table,
        width: drivemap_runtime::core::width::Width::Word,
        broadcast_only: false,
        source: "",
    }
}

/// Holding 0020h-002Fh readable except 0028h (write-only); 0030h broadcast-only; input
/// 0100h-0103h readable.
static REGISTERS: &[RegisterInfo] = &[
    info(0x20, Access::Read, Table::Holding),
    info(0x21, Access::Read, Table::Holding),
    info(0x22, Access::Read, Table::Holding),
    info(0x23, Access::Read, Table::Holding),
    info(0x24, Access::Read, Table::Holding),
    info(0x25, Access::Read, Table::Holding),
    info(0x26, Access::ReadWrite, Table::Holding),
    info(0x27, Access::Read, Table::Holding),
    info(0x28, Access::Write, Table::Holding),
    info(0x29, Access::Read, Table::Holding),
    RegisterInfo {
        broadcast_only: true,
        ..info(0x30, Access::ReadWrite, Table::Holding)
    },
    info(0x100, Access::Read, Table::Input),
    info(0x101, Access::Read, Table::Input),
    info(0x102, Access::Read, Table::Input),
    info(0x103, Access::Read, Table::Input),
];

fn client() -> Client<Link> {
    let mut drive = SimulatedSlave::new(1, &PROFILE);
    for a in 0x20..=0x30 {
        drive.set_holding(a, 1000 + a);
    }
    for a in 0x100..=0x103 {
        drive.set_input(a, 2000 + a);
    }
    Client::new(
        Link {
            drive,
            reply: Vec::new(),
            requests: Vec::new(),
        },
        &PROFILE,
    )
}

fn holding(addresses: &[u16]) -> Vec<(Table, u16)> {
    addresses.iter().map(|&a| (Table::Holding, a)).collect()
}

fn plan(p: &Poller) -> Vec<(Table, Read)> {
    p.plan().collect()
}

fn read(address: u16, quantity: u16) -> Read {
    Read { address, quantity }
}

#[test]
fn one_planned_request_serves_every_wanted_register() {
    let mut wanted = holding(&[0x24, 0x20, 0x22, 0x20]);
    wanted.push((Table::Input, 0x103));
    wanted.push((Table::Input, 0x100));
    let mut poller = Poller::new(&PROFILE, REGISTERS, wanted).unwrap();
    assert_eq!(
        plan(&poller),
        vec![
            (Table::Holding, read(0x20, 5)),
            (Table::Input, read(0x100, 4))
        ]
    );
    assert!(poller.value(0).is_none(), "nothing before the first poll");
    let mut c = client();
    let stats = poller.poll(&mut c, 1);
    assert_eq!(stats.requests, 2);
    assert_eq!(stats.splits, 0);
    assert_eq!(stats.bus_ns, poller.plan_ns());
    let values: Vec<u16> = (0..6)
        .map(|i| *poller.value(i).unwrap().as_ref().unwrap())
        .collect();
    assert_eq!(values, vec![1036, 1032, 1034, 1032, 2259, 2256]);
    assert_eq!(
        c.transport().requests,
        vec![(0x03, 0x20, 5), (0x04, 0x100, 4)]
    );
    assert!(poller.learned().is_empty());
}

#[test]
fn write_only_and_broadcast_registers_are_neither_wanted_nor_bridged() {
    for address in [0x28, 0x30, 0x2A, 0x1F] {
        assert_eq!(
            Poller::new(&PROFILE, REGISTERS, holding(&[address])).unwrap_err(),
            PlanError::NotReadable {
                table: Table::Holding,
                address
            }
        );
    }
    // 0027h and 0029h: 0028h is write-only, so two requests.
    let poller = Poller::new(&PROFILE, REGISTERS, holding(&[0x27, 0x29])).unwrap();
    assert_eq!(
        plan(&poller),
        vec![
            (Table::Holding, read(0x27, 1)),
            (Table::Holding, read(0x29, 1))
        ]
    );
}

#[test]
fn a_refused_bridge_is_split_and_not_bridged_again() {
    let mut poller = Poller::new(&PROFILE, REGISTERS, holding(&[0x20, 0x22, 0x24])).unwrap();
    assert_eq!(plan(&poller), vec![(Table::Holding, read(0x20, 5))]);
    let mut c = client();
    // The map says 0021h is readable, the drive says otherwise.
    c.transport().drive.fail_at(0x21, 0x02);
    let stats = poller.poll(&mut c, 1);
    assert_eq!((stats.requests, stats.splits), (4, 1));
    for (i, a) in [0x20u16, 0x22, 0x24].into_iter().enumerate() {
        assert_eq!(poller.value(i).unwrap().unwrap(), 1000 + a);
    }
    assert_eq!(
        poller.learned(),
        &[
            (Table::Holding, 0x21, Learned::NotBridged),
            (Table::Holding, 0x23, Learned::NotBridged)
        ]
    );
    // Next cycle: three requests, no exception.
    c.transport().requests.clear();
    let stats = poller.poll(&mut c, 1);
    assert_eq!((stats.requests, stats.splits), (3, 0));
    assert_eq!(
        c.transport().requests,
        vec![(0x03, 0x20, 1), (0x03, 0x22, 1), (0x03, 0x24, 1)]
    );
    // Forgetting restores the merged plan.
    poller.forget();
    assert!(poller.learned().is_empty());
    assert_eq!(plan(&poller), vec![(Table::Holding, read(0x20, 5))]);
}

#[test]
fn a_wanted_register_refused_alone_is_found_by_halving_and_then_read_alone() {
    let mut poller = Poller::new(&PROFILE, REGISTERS, holding(&[0x20, 0x21, 0x22, 0x23])).unwrap();
    let mut c = client();
    c.transport().drive.fail_at(0x22, 0x21);
    let stats = poller.poll(&mut c, 1);
    // 0020h x4 refused; halves 0020h x2 (fine) and 0022h x2 (refused); 0022h x1 refused,
    // 0023h x1 fine.
    assert_eq!(
        c.transport().requests,
        vec![
            (0x03, 0x20, 4),
            (0x03, 0x20, 2),
            (0x03, 0x22, 2),
            (0x03, 0x22, 1),
            (0x03, 0x23, 1)
        ]
    );
    assert_eq!((stats.requests, stats.splits), (5, 2));
    assert_eq!(poller.value(0).unwrap().unwrap(), 0x20 + 1000);
    assert_eq!(poller.value(1).unwrap().unwrap(), 0x21 + 1000);
    let e = poller.value(2).unwrap().unwrap_err();
    assert_eq!(e.exception().map(|x| x.code), Some(0x21));
    assert_eq!(poller.value(3).unwrap().unwrap(), 0x23 + 1000);
    assert_eq!(
        poller.learned(),
        &[(Table::Holding, 0x22, Learned::Refused)]
    );
    // From now on 0022h is read alone and never bridged; its error is still reported.
    c.transport().requests.clear();
    let stats = poller.poll(&mut c, 1);
    assert_eq!(
        c.transport().requests,
        vec![(0x03, 0x20, 2), (0x03, 0x22, 1), (0x03, 0x23, 1)]
    );
    assert_eq!((stats.requests, stats.splits), (3, 0));
    assert!(poller.value(2).unwrap().is_err());
    assert_eq!(poller.value(3).unwrap().unwrap(), 0x23 + 1000);
}

#[test]
fn other_errors_are_reported_for_every_member_without_splitting() {
    let mut poller = Poller::new(&PROFILE, REGISTERS, holding(&[0x20, 0x22])).unwrap();
    let mut c = client();
    c.transport().drive.fail_at(0x21, 0x04);
    let stats = poller.poll(&mut c, 1);
    assert_eq!((stats.requests, stats.splits), (1, 0));
    for i in 0..2 {
        let e = poller.value(i).unwrap().unwrap_err();
        assert_eq!(e.exception().map(|x| x.code), Some(0x04));
    }
    assert!(poller.learned().is_empty());
    assert_eq!(plan(&poller), vec![(Table::Holding, read(0x20, 3))]);
}

struct OutputFrequency;

impl Register for OutputFrequency {
    type Value = f64;
    type Settings = ();
    const ID: &'static str = "output_frequency";
    const PARAM: Option<&'static str> = None;
    const NAME: &'static str = "Output frequency";
    const ADDRESS: u16 = 0x23;
    const TABLE: Table = Table::Holding;
    const SOURCE: &'static str = "";
    fn decode(raw: u32, _: &()) -> Result<f64, ValueError> {
        Ok(f64::from(raw) / 100.0)
    }
}

impl Readable for OutputFrequency {}

#[test]
fn typed_values_of_generated_registers() {
    let mut poller = Poller::new(
        &PROFILE,
        REGISTERS,
        [wanted::<OutputFrequency>(), (Table::Holding, 0x20)],
    )
    .unwrap();
    assert!(poller.register::<OutputFrequency>(&()).is_none());
    let mut c = client();
    poller.poll(&mut c, 1);
    assert_eq!(
        poller.register::<OutputFrequency>(&()).unwrap().unwrap(),
        10.35
    );
    c.transport().drive.fail_at(0x23, 0x02);
    poller.poll(&mut c, 1);
    match poller.register::<OutputFrequency>(&()).unwrap() {
        Err(PolledError::Read(e)) => assert_eq!(e.exception().map(|x| x.code), Some(0x02)),
        other => panic!("expected the read error, got {other:?}"),
    }
    assert_eq!(poller.get(Table::Holding, 0x20).unwrap().unwrap(), 1032);
}

/// The V7's timing as its map states it (24 bits + n156 default 10 ms before a reply, 24 bits +
/// 10 ms after it), with a generous max_read.
static V7_LIKE: Profile = Profile {
    drive_id: "yaskawa-v7",
    max_read: 125,
    timing: drivemap_runtime::core::profile::Timing {
        response_delay_bits: Some(24),
        response_delay_param: Some("n156"),
        response_delay_param_default_us: Some(10_000),
        request_gap_bits: Some(24),
        request_gap_us: Some(10_000),
        ..drivemap_runtime::core::profile::Timing::MODBUS
    },
    ..Profile::GENERIC
};

static RUN: &[RegisterInfo] = &{
    let mut all = [info(0, Access::Read, Table::Holding); 64];
    let mut i = 0;
    while i < 64 {
        all[i].address = i as u16;
        i += 1;
    }
    all
};

#[test]
fn the_model_decides_whether_a_hole_is_bridged() {
    // 0000h and 001Ah: bridging 25 registers costs 50 characters. At 9600 8N1 (1.04 ms a
    // character) that is 52 ms, more than a second request (15 bytes, 24 bits + 10 ms before
    // and after the reply: 40.6 ms). At 19 200 baud it is 26 ms against 30.3 ms.
    let wanted = holding(&[0x00, 0x1A]);
    let at_9600 = Poller::new(&V7_LIKE, RUN, wanted.clone()).unwrap();
    assert_eq!(
        plan(&at_9600),
        vec![
            (Table::Holding, read(0x00, 1)),
            (Table::Holding, read(0x1A, 1))
        ]
    );
    let model = BusModel::new(&V7_LIKE, SerialConfig::new(19_200));
    let at_19200 = Poller::new(&V7_LIKE, RUN, wanted.clone())
        .unwrap()
        .with_model(model);
    assert_eq!(plan(&at_19200), vec![(Table::Holding, read(0x00, 27))]);
    // A longer n156 makes each request dearer: bridged at 9600 baud too.
    let slow_drive = BusModel::new(&V7_LIKE, SerialConfig::new(9600))
        .with_delay_param(std::time::Duration::from_millis(65));
    let bridged = Poller::new(&V7_LIKE, RUN, wanted)
        .unwrap()
        .with_model(slow_drive);
    assert_eq!(plan(&bridged), vec![(Table::Holding, read(0x00, 27))]);
}

/// 0040h a word, 0041h-0042h a 32-bit pair (high word first), 0043h a word, 0044h-0045h a pair
/// (low word first).
static PAIRS: &[RegisterInfo] = &[
    info(0x40, Access::Read, Table::Holding),
    RegisterInfo {
        width: drivemap_runtime::core::width::Width::Pair(
            drivemap_runtime::core::width::WordOrder::HighFirst,
        ),
        ..info(0x41, Access::Read, Table::Holding)
    },
    info(0x43, Access::Read, Table::Holding),
    RegisterInfo {
        width: drivemap_runtime::core::width::Width::Pair(
            drivemap_runtime::core::width::WordOrder::LowFirst,
        ),
        ..info(0x44, Access::Read, Table::Holding)
    },
];

fn pair_client(profile: &'static Profile) -> Client<Link> {
    let mut drive = SimulatedSlave::new(1, profile);
    for a in 0x40..=0x45 {
        drive.set_holding(a, 0x100 + a);
    }
    Client::new(
        Link {
            drive,
            reply: Vec::new(),
            requests: Vec::new(),
        },
        profile,
    )
}

/// Whether any request sent reads one word of the pair at `first` without the other.
fn split_a_pair(requests: &[(u8, u16, u16)], first: u16) -> bool {
    requests.iter().any(|&(_, a, q)| {
        let last = a + q - 1;
        (a..=last).contains(&first) != (a..=last).contains(&(first + 1))
    })
}

#[test]
fn a_pair_is_never_split_by_the_plan_and_reads_as_one_value() {
    static TWO: Profile = Profile {
        drive_id: "test-drive",
        max_read: 2,
        ..Profile::GENERIC
    };
    // With two registers per request, 0040h-0041h + 0042h-0043h would be as cheap as any plan,
    // but it cuts the pair: the plan reads the pair in a request of its own.
    let mut p = Poller::new(&TWO, PAIRS, holding(&[0x40, 0x41, 0x43, 0x44])).unwrap();
    let reads: Vec<Read> = plan(&p).into_iter().map(|(_, r)| r).collect();
    assert_eq!(
        reads,
        [
            Read {
                address: 0x40,
                quantity: 1
            },
            Read {
                address: 0x41,
                quantity: 2
            },
            Read {
                address: 0x43,
                quantity: 1
            },
            Read {
                address: 0x44,
                quantity: 2
            },
        ]
    );
    let mut c = pair_client(&TWO);
    p.poll(&mut c, 1);
    let high_first = drivemap_runtime::core::width::Width::Pair(
        drivemap_runtime::core::width::WordOrder::HighFirst,
    );
    let low_first = drivemap_runtime::core::width::Width::Pair(
        drivemap_runtime::core::width::WordOrder::LowFirst,
    );
    assert_eq!(p.raw(1, high_first).unwrap().unwrap(), 0x0141_0142);
    assert_eq!(p.raw(3, low_first).unwrap().unwrap(), 0x0145_0144);
    assert!(!split_a_pair(&c.transport().requests, 0x41));
    assert!(!split_a_pair(&c.transport().requests, 0x44));

    // A drive that reads one register per request cannot give a pair whole.
    static ONE: Profile = Profile {
        drive_id: "test-drive",
        max_read: 1,
        ..Profile::GENERIC
    };
    assert_eq!(
        Poller::new(&ONE, PAIRS, holding(&[0x41])).unwrap_err(),
        PlanError::SplitPair {
            table: Table::Holding,
            address: 0x41
        }
    );
}

#[test]
fn splitting_a_refused_request_keeps_pairs_whole() {
    let mut c = pair_client(&PROFILE);
    // 0043h refuses: the merged request 0040h-0045h is split, without cutting either pair.
    c.transport().drive.fail_at(0x43, 0x02);
    let mut p = Poller::new(&PROFILE, PAIRS, holding(&[0x40, 0x41, 0x43, 0x44])).unwrap();
    assert_eq!(plan(&p).len(), 1, "one merged request");
    p.poll(&mut c, 1);
    let requests = &c.transport().requests;
    assert!(requests.len() > 1, "{requests:?}");
    assert!(!split_a_pair(requests, 0x41), "{requests:?}");
    assert!(!split_a_pair(requests, 0x44), "{requests:?}");
    let high_first = drivemap_runtime::core::width::Width::Pair(
        drivemap_runtime::core::width::WordOrder::HighFirst,
    );
    assert_eq!(p.raw(1, high_first).unwrap().unwrap(), 0x0141_0142);
    assert!(p.value(2).unwrap().is_err(), "0043h got its own error");
    // Next cycle: 0043h is read alone, the pairs still whole.
    c.transport().requests.clear();
    p.poll(&mut c, 1);
    assert!(!split_a_pair(&c.transport().requests, 0x41));
    assert!(!split_a_pair(&c.transport().requests, 0x44));
}

/// 0040h a word, 0041h.. a string of `n` registers, then words up to 004Fh.
fn string_infos(n: u8) -> Vec<RegisterInfo> {
    let mut out = vec![
        info(0x40, Access::Read, Table::Holding),
        RegisterInfo {
            width: drivemap_runtime::core::width::Width::Text(n),
            ..info(0x41, Access::Read, Table::Holding)
        },
    ];
    out.extend((0x41 + u16::from(n)..=0x4F).map(|a| info(a, Access::Read, Table::Holding)));
    out
}

/// Whether a request reads some registers of the string at `first` (`n` of them) but not all.
fn cuts(requests: &[(u8, u16, u16)], first: u16, n: u16) -> bool {
    requests.iter().any(|&(_, a, q)| {
        let covered = (first..first + n)
            .filter(|x| (a..a + q).contains(x))
            .count();
        covered != 0 && covered != usize::from(n)
    })
}

fn string_client(profile: &'static Profile) -> Client<Link> {
    let mut drive = SimulatedSlave::new(1, profile);
    for a in 0x40..=0x4F {
        drive.set_holding(a, 0x4100 + a);
    }
    Client::new(
        Link {
            drive,
            reply: Vec::new(),
            requests: Vec::new(),
        },
        profile,
    )
}

#[test]
fn a_string_is_read_whole_even_when_a_merged_request_is_refused() {
    let infos = string_infos(6);
    let mut c = string_client(&PROFILE);
    // 0047h refuses: the merged request 0040h-0047h is split, without cutting the string.
    c.transport().drive.fail_at(0x47, 0x02);
    let mut p = Poller::new(&PROFILE, &infos, holding(&[0x40, 0x41, 0x47])).unwrap();
    assert_eq!(plan(&p), vec![(Table::Holding, read(0x40, 8))]);
    p.poll(&mut c, 1);
    assert!(
        !cuts(&c.transport().requests, 0x41, 6),
        "{:?}",
        c.transport().requests
    );
    let mut words = [0u16; 6];
    assert!(p.words(1, &mut words).unwrap().is_ok());
    assert_eq!(words, [0x4141, 0x4142, 0x4143, 0x4144, 0x4145, 0x4146]);
    let text = drivemap_runtime::core::text::Text::<12>::decode(
        &words,
        drivemap_runtime::core::text::ByteOrder::HighFirst,
    );
    assert_eq!(text.as_str(), Some("AAABACADAEAF"));
    assert!(p.get(Table::Holding, 0x47).unwrap().is_err());
}

proptest::proptest! {
    /// Whatever the drive's `max_read` and the string's length, the plan reads the string in one
    /// request of all its registers (or refuses to plan when it cannot), and every word of it
    /// arrives as the drive holds it.
    #[test]
    fn a_string_is_never_cut_by_the_plan(
        max_read in 1u16..=12,
        n in 1u8..=10,
        others in proptest::collection::vec(0x40u16..=0x4F, 0..6),
    ) {
        let profile: &'static Profile = Box::leak(Box::new(Profile {
            drive_id: "test-drive",
            max_read,
            ..Profile::GENERIC
        }));
        let infos = string_infos(n);
        let last = 0x41 + u16::from(n) - 1;
        let mut wanted = vec![0x41];
        wanted.extend(others.into_iter().filter(|a| *a == 0x40 || *a > last));
        match Poller::new(profile, &infos, holding(&wanted)) {
            Err(e) => proptest::prop_assert!(u16::from(n) > max_read, "{e:?}"),
            Ok(mut p) => {
                proptest::prop_assert!(u16::from(n) <= max_read);
                let mut c = string_client(profile);
                p.poll(&mut c, 1);
                let requests = c.transport().requests.clone();
                proptest::prop_assert!(!cuts(&requests, 0x41, u16::from(n)), "{requests:?}");
                let mut words = vec![0u16; usize::from(n)];
                proptest::prop_assert!(p.words(0, &mut words).unwrap().is_ok());
                let held: Vec<u16> = (0x41..=last).map(|a| 0x4100 + a).collect();
                proptest::prop_assert_eq!(words, held);
            }
        }
    }
}
