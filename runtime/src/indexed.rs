//! Indexed access in one call: an entry of an index/value register pair
//! ([`drivemap_core::indexed`], the map's `indexed:`) read or written by writing its index to the
//! index register, then reading or writing the value register.
//!
//! What each call guarantees, on the blocking and the async client alike:
//! - **the pair is one call**: the client is borrowed mutably for the whole call, so no other
//!   request of this client goes out between the index write and the value access;
//! - **the index is written before every access**, never assumed from an earlier call: a lost
//!   reply to an index write, another master or the keypad may have selected another entry
//!   since, and a client that skips the write would attribute that entry's value to this one;
//! - **verified where the map allows**: when the index register is readable, the value is read
//!   together with the index (one 03h request of both words when they are consecutive, else the
//!   index read right after the value) and refused with [`Error::IndexChanged`] unless the drive
//!   still shows the index written; a write reads the index back before writing the value, and
//!   writes nothing when another entry is selected;
//! - **the gate checks both**: the index against the index register's rule (its range), the
//!   value against the entry's rule (its range, its access), before anything is sent.
//!
//! [`Error::IndexChanged`]: crate::error::Error::IndexChanged

use drivemap_core::indexed::{EntryRef, Indexed};

use crate::client::{Client, Session};
use crate::error::{Error, Refusal};
use crate::gate::WriteTarget;
use crate::transport::Transport;
use crate::wire::{Wire, block_on};
use drivemap_core::rule::WriteRule;

/// Indexed access, one implementation for the blocking and the async client.
impl<W: Wire> Session<'_, W> {
    /// [`Client::read_entry`].
    pub(crate) async fn read_entry(&mut self, slave: u8, entry: EntryRef) -> Result<f64, Error> {
        if !entry.entry.access.readable() {
            return Err(Refusal::WriteOnly {
                register: entry.entry.id,
            }
            .into());
        }
        let raw = self
            .read_indexed(slave, entry.pair, entry.entry.index)
            .await?;
        Ok(entry.entry.decode(raw))
    }

    /// [`Client::write_entry`].
    pub(crate) async fn write_entry(
        &mut self,
        slave: u8,
        entry: EntryRef,
        value: f64,
    ) -> Result<(), Error> {
        let raw = entry.entry.encode(value)?;
        self.write_indexed(slave, entry.pair, &entry.entry.rule, entry.entry.index, raw)
            .await
    }

    /// [`Client::read_indexed`].
    pub(crate) async fn read_indexed(
        &mut self,
        slave: u8,
        pair: &Indexed,
        index: u16,
    ) -> Result<u16, Error> {
        self.select_index(slave, pair, index).await?;
        let mut words = [0u16; 2];
        let both = self.core.profile.max_read >= 2;
        let (value, shown) = match (pair.index_readable, pair.index_below_value()) {
            (true, Some(true)) if both => {
                self.read_holding(slave, pair.index_address, &mut words)
                    .await?;
                (words[1], Some(words[0]))
            }
            (true, Some(false)) if both => {
                self.read_holding(slave, pair.value_address, &mut words)
                    .await?;
                (words[0], Some(words[1]))
            }
            (readable, _) => {
                self.read_holding(slave, pair.value_address, &mut words[..1])
                    .await?;
                if readable {
                    self.read_holding(slave, pair.index_address, &mut words[1..])
                        .await?;
                    (words[0], Some(words[1]))
                } else {
                    (words[0], None)
                }
            }
        };
        match shown {
            Some(shown) if shown != index => Err(Error::IndexChanged {
                register: pair.register,
                index_register: pair.index_register,
                selected: index,
                shown,
            }),
            _ => Ok(value),
        }
    }

    /// [`Client::write_indexed`].
    pub(crate) async fn write_indexed(
        &mut self,
        slave: u8,
        pair: &Indexed,
        rule: &WriteRule,
        index: u16,
        raw: u16,
    ) -> Result<(), Error> {
        if !rule.access.writable() {
            return Err(Refusal::ReadOnly {
                register: rule.register,
            }
            .into());
        }
        let target = WriteTarget::Rule(rule);
        crate::gate::check(
            self.core.profile,
            self.core.kind,
            slave,
            target,
            pair.value_address,
            [raw],
        )?;
        self.select_index(slave, pair, index).await?;
        if pair.index_readable {
            let mut shown = [0u16; 1];
            self.read_holding(slave, pair.index_address, &mut shown)
                .await?;
            if shown[0] != index {
                return Err(Error::IndexChanged {
                    register: pair.register,
                    index_register: pair.index_register,
                    selected: index,
                    shown: shown[0],
                });
            }
        }
        self.write_rule(slave, rule, pair.value_address, u32::from(raw))
            .await
    }

    /// Writes `index` to the index register of `pair` through the gate (the index register's
    /// write rule: its range).
    async fn select_index(&mut self, slave: u8, pair: &Indexed, index: u16) -> Result<(), Error> {
        if !pair.index_allowed(index) {
            return Err(Refusal::RawOutOfRange {
                register: pair.index_register,
                raw: i64::from(index),
                min: pair.index_range.min,
                max: pair.index_range.max,
            }
            .into());
        }
        let rule = crate::gate::rule(self.core.profile, pair.index_register)?;
        self.write_rule(slave, rule, pair.index_address, u32::from(index))
            .await
    }
}

/// Indexed access.
impl<T: Transport> Client<T> {
    /// Reads the entry `entry` of an indexed register (a handle from the generated code, or
    /// [`drivemap_core::indexed::find`]) as its engineering value: writes its index to the index
    /// register, then reads the value register (see [`crate::indexed`] for what is verified).
    pub fn read_entry(&mut self, slave: u8, entry: EntryRef) -> Result<f64, Error> {
        block_on(self.session().read_entry(slave, entry))
    }

    /// Writes the engineering value `value` to the entry `entry` of an indexed register: the
    /// value is encoded and checked against the entry's range and access first, the index is
    /// written, read back where the index register is readable, then the value is written.
    /// Nothing reaches the value register unless the index was written, and verified where it
    /// can be.
    pub fn write_entry(&mut self, slave: u8, entry: EntryRef, value: f64) -> Result<(), Error> {
        block_on(self.session().write_entry(slave, entry, value))
    }

    /// Reads the word the value register of `pair` shows for `index` (an entry the manual does
    /// not list, on a map whose `indexed:` says why): the index is checked against the index
    /// register's range and written, then the value read and, where the index register is
    /// readable, verified.
    pub fn read_indexed(&mut self, slave: u8, pair: &Indexed, index: u16) -> Result<u16, Error> {
        block_on(self.session().read_indexed(slave, pair, index))
    }

    /// Writes the word `raw` to the value register of `pair` for `index`, checked by the gate
    /// against `rule` (an entry's [`rule`](drivemap_core::indexed::Entry::rule)) before the
    /// index is written; see [`write_entry`](Self::write_entry).
    pub fn write_indexed(
        &mut self,
        slave: u8,
        pair: &Indexed,
        rule: &WriteRule,
        index: u16,
        raw: u16,
    ) -> Result<(), Error> {
        block_on(self.session().write_indexed(slave, pair, rule, index, raw))
    }
}

/// Indexed access.
#[cfg(feature = "tokio")]
impl<T: crate::async_client::AsyncTransport> crate::async_client::AsyncClient<T> {
    /// As [`Client::read_entry`](Client::read_entry).
    pub async fn read_entry(&mut self, slave: u8, entry: EntryRef) -> Result<f64, Error> {
        self.session().read_entry(slave, entry).await
    }

    /// As [`Client::write_entry`](Client::write_entry).
    pub async fn write_entry(
        &mut self,
        slave: u8,
        entry: EntryRef,
        value: f64,
    ) -> Result<(), Error> {
        self.session().write_entry(slave, entry, value).await
    }

    /// As [`Client::read_indexed`](Client::read_indexed).
    pub async fn read_indexed(
        &mut self,
        slave: u8,
        pair: &Indexed,
        index: u16,
    ) -> Result<u16, Error> {
        self.session().read_indexed(slave, pair, index).await
    }

    /// As [`Client::write_indexed`](Client::write_indexed).
    pub async fn write_indexed(
        &mut self,
        slave: u8,
        pair: &Indexed,
        rule: &WriteRule,
        index: u16,
        raw: u16,
    ) -> Result<(), Error> {
        self.session()
            .write_indexed(slave, pair, rule, index, raw)
            .await
    }
}
