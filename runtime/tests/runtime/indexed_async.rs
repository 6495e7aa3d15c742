//! The async client's indexed access (`AsyncClient::read_entry`/`write_entry`, the same code as
//! the blocking client's, `drivemap_runtime::indexed`): the index is written before each access,
//! the value read with the index in one request, a lost reply to the index write never mixes
//! two entries, and the gate refuses before anything is sent. (Feature `tokio`.)
#![cfg(feature = "tokio")]

use crate::common;

use std::time::Duration;

use drivemap_runtime::async_client::{AsyncClient, BlockingTransport};
use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::core::indexed::{Entry, EntryRef, Indexed};
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::{Access, Table};
use drivemap_runtime::core::rule::WriteRule;
use drivemap_runtime::core::scale::{Decimal, RawRange};
use drivemap_runtime::error::Error;
use drivemap_sim::SimulatedSlave;
use drivemap_sim::{Fault, FaultyLink};

static WRITES: [WriteRule; 2] = [
    WriteRule::rw("parameter_index", 0x0040, 1, 40),
    WriteRule::rw("parameter_value", 0x0041, 0, 65535),
];

static PROFILE: Profile = Profile {
    writes: &WRITES,
    ..common::V7
};

const fn entry(id: &'static str, index: u16, min: i64, max: i64, access: Access) -> Entry {
    let mut rule = WriteRule::rw(id, 0x0041, min, max);
    rule.access = access;
    Entry {
        id,
        name: id,
        index,
        unit: "s",
        signed: false,
        scale: Decimal::new(1, 1),
        range: RawRange::new(min, max),
        access,
        rule,
        source: "test",
    }
}

static PAIR: Indexed = Indexed {
    register: "parameter_value",
    value_address: 0x0041,
    table: Table::Holding,
    index_register: "parameter_index",
    index_address: 0x0040,
    index_readable: true,
    index_range: RawRange::new(1, 40),
    entries: &[
        entry("acceleration_time", 1, 1, 6000, Access::ReadWrite),
        entry("deceleration_time", 2, 1, 6000, Access::ReadWrite),
    ],
    unknown: None,
    source: "test",
};

fn at(i: usize) -> EntryRef {
    EntryRef {
        pair: &PAIR,
        entry: &PAIR.entries[i],
    }
}

#[test]
fn the_async_client_reads_and_writes_entries_in_one_call() {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        for kind in [TransportKind::Rtu, TransportKind::Tcp] {
            let slave = SimulatedSlave::new(1, &PROFILE).with_indexed(std::slice::from_ref(&PAIR));
            let link = BlockingTransport::new(FaultyLink::new(kind, slave));
            let options = ClientOptions {
                timeout: Duration::from_millis(30),
                retries: 0,
                ..ClientOptions::default()
            };
            let mut c = AsyncClient::with_options(link, &PROFILE, options);
            c.write_entry(1, at(0), 5.0).await.unwrap();
            c.write_entry(1, at(1), 7.0).await.unwrap();
            assert_eq!(c.read_entry(1, at(0)).await.unwrap(), 5.0);
            // The reply to the index write (2) is lost: an error, and the next read of the
            // other entry writes its index again.
            c.transport().with(|l| l.inject(Fault::Drop));
            assert!(c.read_entry(1, at(1)).await.is_err());
            assert_eq!(c.read_entry(1, at(0)).await.unwrap(), 5.0, "{kind:?}");
            assert_eq!(c.read_entry(1, at(1)).await.unwrap(), 7.0, "{kind:?}");
            // The read of index and value is one 03h request of 0040h..0041h.
            let sent = c.transport().with(|l| l.sent.last().unwrap().clone());
            let pdu = if kind == TransportKind::Tcp {
                &sent[7..]
            } else {
                &sent[1..]
            };
            assert_eq!(&pdu[..5], &[0x03, 0x00, 0x40, 0x00, 0x02]);
            // Outside the entry's range: refused before anything is sent.
            let before = c.transport().with(|l| l.requests);
            let e = c.write_entry(1, at(0), 600.1).await.unwrap_err();
            assert!(matches!(e, Error::Value(_)), "{e}");
            let e = c.read_indexed(1, &PAIR, 41).await.unwrap_err();
            assert!(e.is_refusal(), "{e}");
            assert_eq!(c.transport().with(|l| l.requests), before);
        }
    });
}
