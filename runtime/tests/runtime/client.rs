//! The client against a simulated drive: typed access through hand-written register types (as
//! the generator will emit them), refusals before sending, broadcast, and EEPROM writes.

use crate::common;

use std::time::{Duration, Instant};

use drivemap_runtime::client::{Client, ClientOptions};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::{
    BitRegister, Bits, Code, Readable, Register, Table, Writable,
};
use drivemap_runtime::core::rule::WriteRule;
use drivemap_runtime::core::scale::{self, Decimal, RawRange, ValueError};
use drivemap_runtime::error::{Error, Refusal};
use drivemap_sim::SimulatedSlave;
use drivemap_sim::{Fault, FaultyLink};

use common::{ACN, J7, V7, strict};

// --- Register types, written by hand the way the generator emits them (V7, Tables 4.1/4.3). ---

/// V7 settings: n152 selects the frequency unit (`003_8bcf5d50afb8e230.txt:102`).
#[derive(Default)]
struct Settings {
    n152: Option<u16>,
}

fn frequency_scale(register: &'static str, s: &Settings) -> Result<Decimal, ValueError> {
    match s.n152 {
        None => Err(ValueError::MissingSetting {
            register,
            setting: "n152",
        }),
        Some(0) => Ok(Decimal::new(1, 1)),
        Some(1) => Ok(Decimal::new(1, 2)),
        Some(code) => Err(ValueError::UnsupportedSetting {
            register,
            setting: "n152",
            code,
        }),
    }
}

macro_rules! register {
    ($ty:ident, $id:literal, $addr:literal, $value:ty, $decode:expr) => {
        struct $ty;
        impl Register for $ty {
            type Value = $value;
            type Settings = Settings;
            const ID: &'static str = $id;
            const PARAM: Option<&'static str> = None;
            const NAME: &'static str = $id;
            const ADDRESS: u16 = $addr;
            const TABLE: Table = Table::Holding;
            const SOURCE: &'static str = "000_032dced3a1e91a75.txt:853";
            fn decode(raw: u32, settings: &Settings) -> Result<$value, ValueError> {
                let f: fn(u16, &Settings) -> Result<$value, ValueError> = $decode;
                f(raw as u16, settings)
            }
        }
        impl Readable for $ty {}
    };
}

/// Operation command bits 0-A (`000_032dced3a1e91a75.txt:855-867`); B-F reserved.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Command(u16);
impl Code for Command {
    fn code(&self) -> u16 {
        self.0
    }
    fn from_code(raw: u16) -> Self {
        Command(raw & 0x07FF)
    }
    fn is_known(&self) -> bool {
        true
    }
}
impl Bits for Command {
    const MASK: u16 = 0x07FF;
}

register!(
    OperationCommand,
    "operation_command",
    0x0001,
    Command,
    |raw, _| Ok(Command::from_bits(raw))
);
impl Writable for OperationCommand {
    type Input = Command;
    const RULE: WriteRule = WriteRule::rw("operation_command", 0x0001, 0, 65535).reserved(0xF800);
    fn encode(value: &Command, _: &Settings) -> Result<u32, ValueError> {
        Ok(u32::from(value.bits() & 0x07FF))
    }
}
impl BitRegister for OperationCommand {
    const FIELD_MASK: u16 = 0x07FF;
}

register!(
    FrequencyReference,
    "frequency_reference",
    0x0002,
    f64,
    |raw, s| {
        Ok(scale::decode_decimal(
            raw,
            false,
            frequency_scale("frequency_reference", s)?,
        ))
    }
);
impl Writable for FrequencyReference {
    type Input = f64;
    const RULE: WriteRule = WriteRule::rw("frequency_reference", 0x0002, 0, 40000);
    fn encode(value: &f64, s: &Settings) -> Result<u32, ValueError> {
        let scale = frequency_scale(Self::ID, s)?;
        // 0-400 Hz in either unit.
        let max = scale.encode(400.0).unwrap_or(0);
        scale::encode_decimal(Self::ID, "Hz", *value, scale, RawRange { min: 0, max })
            .map(|raw| raw as u32)
    }
}

register!(
    FrequencyMonitor,
    "frequency_monitor",
    0x0023,
    f64,
    |raw, s| {
        Ok(scale::decode_decimal(
            raw,
            false,
            frequency_scale("frequency_monitor", s)?,
        ))
    }
);
register!(
    OutputFrequency,
    "output_frequency",
    0x0024,
    f64,
    |raw, s| {
        Ok(scale::decode_decimal(
            raw,
            false,
            frequency_scale("output_frequency", s)?,
        ))
    }
);
register!(OutputCurrent, "output_current", 0x0027, f64, |raw, _| {
    Ok(scale::decode_decimal(raw, false, Decimal::new(1, 1)))
});

const HZ_001: Settings = Settings { n152: Some(1) };

fn v7(options: ClientOptions) -> Client<FaultyLink> {
    v7_on(TransportKind::Rtu, options)
}

fn v7_on(kind: TransportKind, options: ClientOptions) -> Client<FaultyLink> {
    let mut slave = SimulatedSlave::new(1, &V7);
    slave.set_holding(0x0023, 6000);
    slave.set_holding(0x0024, 5950);
    slave.set_holding(0x0027, 123);
    Client::with_options(FaultyLink::new(kind, slave), &V7, options)
}

fn sent(c: &mut Client<FaultyLink>) -> Vec<Vec<u8>> {
    c.transport().sent.clone()
}

#[test]
fn typed_read_converts_with_the_settings() {
    let mut c = v7(strict());
    assert_eq!(c.read::<FrequencyMonitor>(1, &HZ_001).unwrap(), 60.0);
    assert_eq!(c.read::<OutputCurrent>(1, &HZ_001).unwrap(), 12.3);
    let e = c
        .read::<FrequencyMonitor>(1, &Settings::default())
        .unwrap_err();
    assert!(matches!(
        e,
        Error::Value(ValueError::MissingSetting {
            setting: "n152",
            ..
        })
    ));
}

#[test]
fn typed_write_checks_the_range_before_anything_is_sent() {
    let mut c = v7(strict());
    c.write::<FrequencyReference>(1, &35.75, &HZ_001).unwrap();
    assert_eq!(c.transport().slave.holding(0x0002), 3575);
    for bad in [400.01, -1.0, f64::NAN] {
        let e = c.write::<FrequencyReference>(1, &bad, &HZ_001).unwrap_err();
        assert!(matches!(e, Error::Value(_)), "{e}");
        assert!(e.is_refusal());
    }
    assert_eq!(
        c.transport().requests,
        1,
        "nothing out of range reached the wire"
    );
}

#[test]
fn bit_fields_are_read_modified_and_written_keeping_the_other_fields() {
    let mut c = v7(strict());
    // Forward/reverse (bit 1) and S7 (bit A) set, plus a reserved bit the drive reports.
    c.transport().slave.set_holding(0x0001, 0x8402);
    let v = c
        .modify_bits::<OperationCommand>(1, &HZ_001, 0x0001, 0x0002)
        .unwrap();
    assert_eq!(v, Command(0x0401));
    assert_eq!(
        c.transport().slave.holding(0x0001),
        0x0401,
        "reserved bit written as 0"
    );
    let v = c
        .update::<OperationCommand>(1, &HZ_001, |v| v.0 |= 0x0008)
        .unwrap();
    assert_eq!(v, Command(0x0409));
    let before = c.transport().requests;
    let e = c
        .modify_bits::<OperationCommand>(1, &HZ_001, 0x8000, 0)
        .unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::ReservedBits { bits: 0x8000, .. })
    ));
    assert_eq!(c.transport().requests, before);
}

#[test]
fn consecutive_registers_in_one_request() {
    let mut c = v7(strict());
    let (reference, output) = c
        .read_many::<(FrequencyMonitor, OutputFrequency)>(1, &HZ_001)
        .unwrap();
    assert_eq!((reference, output), (60.0, 59.5));
    assert_eq!(
        sent(&mut c),
        vec![vec![0x01, 0x03, 0x00, 0x23, 0x00, 0x02, 0x35, 0xC1]]
    );
    c.write_many::<(OperationCommand, FrequencyReference)>(1, &(Command(1), 60.0), &HZ_001)
        .unwrap();
    assert_eq!(c.transport().slave.holding(0x0001), 1);
    assert_eq!(c.transport().slave.holding(0x0002), 6000);
    assert_eq!(sent(&mut c)[1][1], 0x10, "one 10h request");
    let e = c
        .read_many::<(FrequencyMonitor, OutputCurrent)>(1, &HZ_001)
        .unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::NotContiguous {
            expected: 0x0024,
            got: 0x0027,
            ..
        })
    ));
    assert_eq!(c.transport().requests, 2);
}

#[test]
fn broadcast_returns_without_waiting_and_is_refused_where_the_manual_forbids_it() {
    let mut c = v7(ClientOptions {
        timeout: Duration::from_secs(5),
        ..strict()
    });
    let t = Instant::now();
    c.write_register(0, 0x0002, 0x1000).unwrap();
    c.write_registers(0, 0x0001, &[1, 0x1000]).unwrap();
    assert!(t.elapsed() < Duration::from_secs(1), "waited for a reply");
    assert_eq!(
        c.transport().slave.holding(0x0001),
        1,
        "the drive executed the broadcast"
    );
    assert_eq!(sent(&mut c)[0][0], 0, "sent to slave 0");

    let mut r = [0u16; 1];
    let refused = [
        c.read_holding(0, 0x0020, &mut r).unwrap_err(),
        c.loop_back(0, 0x1234).unwrap_err(),
        c.write_register(0, 0x0101, 5).unwrap_err(),
    ];
    assert!(matches!(
        refused[0],
        Error::Refused(Refusal::BroadcastRead { function: 3 })
    ));
    assert!(matches!(
        refused[1],
        Error::Refused(Refusal::BroadcastLoopBack)
    ));
    assert!(matches!(
        refused[2],
        Error::Refused(Refusal::BroadcastAddress {
            address: 0x0101,
            ..
        })
    ));
    assert_eq!(c.transport().requests, 2, "nothing refused was sent");

    let mut acn = Client::with_options(
        FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &ACN)),
        &ACN,
        strict(),
    );
    let e = acn.write_register(0, 0x0382, 1).unwrap_err();
    assert!(
        matches!(e, Error::Refused(Refusal::BroadcastFunction { .. })),
        "{e}"
    );
}

#[test]
fn requests_the_drive_cannot_serve_are_refused_before_sending() {
    let mut c = v7(strict());
    let mut nine = [0u16; 9];
    let e = c.read_holding(1, 0x0020, &mut nine).unwrap_err();
    assert_eq!(
        e.to_string(),
        "refused before sending: yaskawa-v7 accepts at most 8 registers per 03h request; 9 asked"
    );
    let e = c.write_registers(1, 0x0001, &[0; 17]).unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::TooManyRegisters { max: 16, .. })
    ));
    let e = c.read_input(1, 0x0020, &mut [0; 1]).unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::UnsupportedFunction { function: 4, .. })
    ));
    let e = c.read_holding(33, 0x0020, &mut [0; 1]).unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::Slave { slave: 33, .. })
    ));
    let e = c.read_holding(1, 0x0020, &mut []).unwrap_err();
    assert!(matches!(e, Error::Refused(Refusal::NoRegisters { .. })));
    let e = c.read_holding(1, 0xFFFF, &mut [0; 2]).unwrap_err();
    assert!(matches!(e, Error::Refused(Refusal::AddressOverflow { .. })));
    assert_eq!(c.transport().requests, 0);
}

#[test]
fn a_drive_without_06h_is_written_with_10h() {
    let mut slave = SimulatedSlave::new(1, &J7);
    slave.set_holding(0x0002, 0);
    let mut c = Client::with_options(FaultyLink::new(TransportKind::Rtu, slave), &J7, strict());
    c.write::<FrequencyReference>(1, &60.0, &Settings { n152: Some(0) })
        .unwrap();
    assert_eq!(c.transport().slave.holding(0x0002), 600);
    assert_eq!(sent(&mut c)[0][1], 0x10);
}

#[test]
fn loop_back_checks_the_echo() {
    let mut c = v7(strict());
    c.loop_back(1, 0xA537).unwrap();
    assert_eq!(
        sent(&mut c),
        vec![vec![0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D]]
    );
}

#[test]
fn retries_are_bounded_and_reported() {
    let mut c = v7(ClientOptions {
        retries: 2,
        ..strict()
    });
    for _ in 0..3 {
        c.transport().inject(Fault::Drop);
    }
    let e = c.read_holding(1, 0x0020, &mut [0; 1]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no reply from slave 1 to 03h read of 0020h x1 within 100 ms (3 attempts); the next request to slave 1 waits until the line has been silent for 100 ms, so that a late reply is not taken for its answer"
    );
    assert_eq!(c.transport().requests, 3);
    assert_eq!(c.read::<FrequencyMonitor>(1, &HZ_001).unwrap(), 60.0);
}

#[test]
fn persisting_goes_through_the_budget() {
    let mut c = v7(ClientOptions {
        eeprom_writes_per_hour: 2,
        ..strict()
    });
    c.persist(1, "enter").unwrap();
    c.persist(1, "enter").unwrap();
    let e = c.persist(1, "enter").unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::EepromBudget {
            used: 2,
            budget: 2,
            ..
        })
    ));
    assert!(
        e.to_string().contains("EEPROM write budget spent: 2 of 2"),
        "{e}"
    );
    // ACCEPT does not write EEPROM: not counted.
    for _ in 0..5 {
        c.persist(1, "accept").unwrap();
    }
    assert_eq!(c.eeprom().total(), 2);
    assert_eq!(
        c.transport()
            .slave
            .writes
            .iter()
            .filter(|w| w.0 == 0x0900)
            .count(),
        2
    );
    // The command registers cannot be written around the budget.
    let e = c.write_register(1, 0x0900, 0).unwrap_err();
    assert!(matches!(
        e,
        Error::Refused(Refusal::CommandRegister {
            address: 0x0900,
            command: "enter",
            ..
        })
    ));
    let e = c.write_registers(1, 0x08FF, &[0, 0]).unwrap_err();
    assert!(matches!(e, Error::Refused(Refusal::CommandRegister { .. })));
    let e = c.persist(1, "save").unwrap_err();
    assert!(matches!(e, Error::Refused(Refusal::UnknownCommand { .. })));
}

#[test]
fn an_eeprom_write_is_never_retried() {
    let mut c = v7(ClientOptions {
        retries: 3,
        ..strict()
    });
    c.transport().inject(Fault::Drop);
    let e = c.persist(1, "enter").unwrap_err();
    assert!(matches!(e, Error::Timeout { attempts: 1, .. }), "{e}");
    assert_eq!(c.transport().requests, 1);
    assert_eq!(
        c.eeprom().total(),
        1,
        "the write that may have happened is counted"
    );
}

#[test]
fn acn_save_writes_zero_then_one_at_the_mapped_address() {
    let mut c = Client::with_options(
        FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &ACN)),
        &ACN,
        strict(),
    );
    c.persist(1, "save_parameters").unwrap();
    assert_eq!(c.transport().slave.writes, vec![(0x03DF, 0), (0x03DF, 1)]);
    assert_eq!(c.eeprom().total(), 1);
    // Over Modbus TCP the ACN's offset is 0.
    let mut c = Client::with_options(
        FaultyLink::new(TransportKind::Tcp, SimulatedSlave::new(1, &ACN)),
        &ACN,
        strict(),
    );
    c.persist(1, "save_parameters").unwrap();
    assert_eq!(c.transport().slave.writes, vec![(0x03E0, 0), (0x03E0, 1)]);
}

#[test]
fn busy_exception_from_the_profile() {
    let mut slave = SimulatedSlave::new(1, &ACN);
    slave.fail_at(0x02FF, 0x06);
    let mut c = Client::with_options(FaultyLink::new(TransportKind::Tcp, slave), &ACN, strict());
    let e = c.read_input(1, 0x02FF, &mut [0; 1]).unwrap_err();
    let ex = e.exception().unwrap();
    assert_eq!((ex.code, ex.name), (0x06, "SLAVE DEVICE BUSY"));
    assert!(ex.is_busy());
    let _ = v7_on(TransportKind::Tcp, strict());
}

/// A drive whose manual asks the master for 24 bit times + 10 ms after each reply (as the
/// V7/J7's, `003_8bcf5d50afb8e230.txt:284`) and answers within 24 bits + 10 ms.
static TIMED: drivemap_runtime::core::profile::Profile = drivemap_runtime::core::profile::Profile {
    timing: drivemap_runtime::core::profile::Timing {
        request_gap_bits: Some(24),
        request_gap_us: Some(10_000),
        response_delay_bits: Some(24),
        response_delay_us: Some(10_000),
        ..drivemap_runtime::core::profile::Timing::MODBUS
    },
    ..drivemap_runtime::core::profile::Profile::GENERIC
};

/// `Client::new(link, &PROFILE)`, the README's first example, keeps the drive's timing (issue
/// 23, item 8): on a link to the drive's serial side the manual's request gap between a reply
/// and the next request and its response time in the timeout; on the drive's own Modbus TCP
/// interface the timeout but no request gap. A client that ignores the timing is the explicit
/// `ClientOptions::generic()`.
#[test]
fn client_new_applies_the_profile_timing() {
    let gap = Duration::from_micros(12_500); // 24 bits at 9600 baud + 10 ms
    for kind in [
        TransportKind::Rtu,
        TransportKind::RtuOverTcp,
        TransportKind::TcpGateway,
    ] {
        let link = FaultyLink::new(kind, SimulatedSlave::new(1, &TIMED));
        let mut c = Client::new(link, &TIMED);
        assert_eq!(*c.options(), ClientOptions::for_profile(&TIMED), "{kind:?}");
        assert_eq!(c.options().request_gap, gap, "{kind:?}");
        assert_eq!(
            c.options().timeout,
            Duration::from_secs(1) + gap,
            "{kind:?}"
        );
        // On the wire: five reads keep four gaps between them.
        let started = Instant::now();
        for _ in 0..5 {
            c.read_holding(1, 0x0020, &mut [0; 1]).unwrap();
        }
        assert!(
            started.elapsed() >= gap * 4,
            "{kind:?}: {:?}",
            started.elapsed()
        );
        // The async client's constructor takes the same options.
        assert_eq!(
            ClientOptions::for_link(&TIMED, kind),
            ClientOptions::for_profile(&TIMED)
        );
    }
    let tcp = Client::new(
        FaultyLink::new(TransportKind::Tcp, SimulatedSlave::new(1, &TIMED)),
        &TIMED,
    );
    assert_eq!(tcp.options().request_gap, Duration::ZERO);
    assert_eq!(tcp.options().timeout, Duration::from_secs(1) + gap);
    // The generic client is a choice made in writing.
    let generic = Client::with_options(
        FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &TIMED)),
        &TIMED,
        ClientOptions::generic(),
    );
    assert_eq!(generic.options().request_gap, Duration::ZERO);
    assert_eq!(generic.options().timeout, Duration::from_secs(1));
}

/// After an unanswered request on RTU framing, the next request to the same slave and any
/// broadcast wait until the line has been silent for the timeout, counted from the end of the
/// unanswered attempt; a request to another slave does not (its reply names it, so a late reply
/// of the first is discarded by the slave check), nor does one after a pause that long.
#[test]
fn after_a_timeout_the_same_slave_and_broadcasts_wait_for_silence() {
    let quiet = strict().timeout;
    let mut c = v7(strict());
    let mut w = [0u16; 1];
    c.transport().inject(Fault::Drop);
    let e = c.read_holding(1, 0x0023, &mut w).unwrap_err();
    assert!(
        matches!(e, Error::Timeout { settle: Some(q), .. } if q == quiet),
        "{e}"
    );
    // A broadcast waits: no reply would show it was lost in a collision.
    c.write_register(0, 0x0001, 0).unwrap();
    let s = c.settled().expect("the broadcast waited for silence");
    assert!(s.waited >= quiet - Duration::from_millis(5), "{s}");
    assert_eq!(s.quiet, quiet);

    // The same slave after a pause as long as the timeout: no further wait.
    c.transport().inject(Fault::Drop);
    c.read_holding(1, 0x0023, &mut w).unwrap_err();
    std::thread::sleep(quiet + Duration::from_millis(20));
    c.read_holding(1, 0x0023, &mut w).unwrap();
    assert_eq!(w, [6000]);
    assert!(
        c.settled()
            .is_none_or(|s| s.waited < Duration::from_millis(20)),
        "{:?}",
        c.settled()
    );

    // Another slave at once: no wait.
    c.transport().inject(Fault::Drop);
    c.read_holding(1, 0x0023, &mut w).unwrap_err();
    let e = c.read_holding(2, 0x0023, &mut w).unwrap_err();
    assert!(matches!(e, Error::Timeout { .. }), "{e}");
    assert_eq!(c.settled(), None);
    // Modbus TCP never waits: the transaction id tells replies apart.
    let mut t = v7_on(TransportKind::Tcp, strict());
    t.transport().inject(Fault::Drop);
    let e = t.read_holding(1, 0x0023, &mut w).unwrap_err();
    assert!(matches!(e, Error::Timeout { settle: None, .. }), "{e}");
    t.read_holding(1, 0x0023, &mut w).unwrap();
    assert_eq!(t.settled(), None);
}
