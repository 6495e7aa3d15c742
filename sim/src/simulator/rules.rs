//! The manual's rules on reads and writes: readable and writable registers, reserved addresses
//! and gaps, values the generated `encode` would refuse, broadcast addresses, and the persist
//! commands a sequence of writes completes.

use drivemap_live::LiveSettings;
use drivemap_live::codec::{self, Value};
use drivemap_map::RegisterRef;
use drivemap_runtime::core::profile::{CommandKind, TransportKind};
use drivemap_runtime::core::register::Table;
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::pdu;

use super::Simulator;

#[derive(Debug, Clone)]
pub(super) struct CommandTrack {
    pub(super) id: &'static str,
    pub(super) kind: CommandKind,
    pub(super) writes: &'static [(u16, u16)],
    pub(super) progress: usize,
    pub(super) count: u32,
}

impl Simulator {
    /// Persist commands (`protocol.commands` of kind persist: ENTER, save) executed.
    pub fn persist_count(&self) -> u32 {
        self.commands
            .iter()
            .filter(|c| c.kind == CommandKind::Persist)
            .map(|c| c.count)
            .sum()
    }

    /// How often the command with this map id was executed, if the map has it.
    pub fn command_count(&self, id: &str) -> Option<u32> {
        self.commands.iter().find(|c| c.id == id).map(|c| c.count)
    }

    /// Whether the generated `encode` of this register would produce `raw`: decode it, encode
    /// the value back. Conversions that need a setting the drive cannot supply are accepted.
    pub(super) fn accepts(&self, r: RegisterRef<'_>, raw: u32, settings: &LiveSettings) -> bool {
        let value = match codec::decode_written(&self.map, r, raw, settings) {
            Ok(Value::Bits { .. }) => f64::from(raw),
            Ok(v) => match v.as_f64() {
                Some(v) => v,
                None => return true,
            },
            Err(_) => return true,
        };
        match codec::encode(&self.map, r, value, settings) {
            Ok(_) => true,
            Err(
                ValueError::OutOfRange { .. }
                | ValueError::WordOverflow { .. }
                | ValueError::UnknownCode { .. }
                | ValueError::NotFinite { .. }
                // Above a limit through another parameter (V7 reference above n011): the drive
                // answers a data setting error ("a simple upper/lower limit error occurred
                // with control data", 003_8bcf5d50afb8e230.txt:739).
                | ValueError::AboveLimit { .. },
            ) => false,
            Err(_) => true,
        }
    }

    /// One word of a read. The first address must hold a readable register (or lie in a gap the
    /// map records); further addresses without a register are reserved and read 0 ("Reserved
    /// registers and data are meaningless", `000_032dced3a1e91a75.txt:908`). A write-only
    /// register answers 02h wherever it is.
    pub(super) fn read_one(
        &self,
        kind: TransportKind,
        table: Table,
        pdu: u32,
        first: bool,
    ) -> Result<u16, u8> {
        let address = self.communication_address(kind, pdu)?;
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        let map = layout.of(table);
        let word = |a: u16| {
            layout
                .holding
                .get(&a)
                .map_or(0, |s| s.word(&self.raw, &self.texts))
        };
        match map.get(&address) {
            Some(_) if table == Table::Holding && self.indexed.shown(address, word).is_some() => {
                Ok(self.indexed.shown(address, word).unwrap_or(0))
            }
            Some(s) if s.readable => Ok(s.word(&self.raw, &self.texts)),
            Some(_) => Err(self.plan.illegal_address),
            None if !first || (table == Table::Holding && self.in_gap(address)) => Ok(0),
            None => Err(self.plan.illegal_address),
        }
    }

    /// Checks every register of a write, then writes them all; a refused register writes none.
    pub(super) fn write(
        &mut self,
        kind: TransportKind,
        address: u16,
        values: &[u16],
        broadcast: bool,
    ) -> Result<(), u8> {
        self.write_in(kind, Table::Holding, address, values, broadcast)
    }

    /// [`Simulator::write`] into `table`: holding registers (06h, 10h) or coils (05h, 0Fh, the
    /// values 1 on and 0 off).
    pub(super) fn write_in(
        &mut self,
        kind: TransportKind,
        table: Table,
        address: u16,
        values: &[u16],
        broadcast: bool,
    ) -> Result<(), u8> {
        // The checked writes go to a buffer kept from write to write: no allocation per request.
        let mut targets = std::mem::take(&mut self.write_targets);
        let result = self.write_checked(kind, table, address, values, broadcast, &mut targets);
        self.write_targets = targets;
        result
    }

    fn write_checked(
        &mut self,
        kind: TransportKind,
        table: Table,
        address: u16,
        values: &[u16],
        broadcast: bool,
        targets: &mut Vec<(u16, Option<usize>, u32)>,
    ) -> Result<(), u8> {
        self.refresh_settings();
        let settings = &self.cache.settings;
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        let broadcast_space = broadcast && table == Table::Holding && !layout.broadcast.is_empty();
        let allowed = self
            .profile
            .broadcast
            .map(|b| b.addresses)
            .unwrap_or_default();
        if values.len() > usize::from(pdu::MAX_WRITE_BITS) {
            return Err(self.plan.illegal_quantity);
        }
        targets.clear();
        targets.resize(values.len(), (0, None, 0));
        let mut pair_second = false;
        for (k, &word) in values.iter().enumerate() {
            if std::mem::take(&mut pair_second) {
                continue; // taken with the pair's first word
            }
            let comm = self.communication_address(kind, u32::from(address) + k as u32)?;
            let found = if broadcast_space {
                layout.broadcast.get(&comm)
            } else {
                layout.of(table).get(&comm)
            };
            match found {
                Some(&super::layout::Slot {
                    index: i,
                    word: half,
                    width,
                    ..
                }) => {
                    // A 32-bit pair is written whole: both words, in one request.
                    let v = match (width.count(), half, values.get(k + 1)) {
                        (1, _, _) => u32::from(word),
                        (_, 0, Some(&second)) => {
                            pair_second = true;
                            width.join(&[word, second])
                        }
                        _ => return Err(self.plan.illegal_address),
                    };
                    let r = self.reg(i);
                    // The listed addresses are of registers and coils alike: a coil's own
                    // broadcast use decides where a coil and a register share one.
                    if broadcast
                        && !broadcast_space
                        && !allowed.is_empty()
                        && (!allowed.contains(&comm)
                            || (table == Table::Coil
                                && r.plan().broadcast
                                    == drivemap_runtime::core::rule::Broadcast::No))
                    {
                        return Err(self.plan.illegal_address);
                    }
                    if !r.writable() {
                        return Err(self.plan.read_only);
                    }
                    if !self.may_write_now(r) {
                        return Err(self.plan.refused_now);
                    }
                    let (raw, texts) = (&self.raw, &self.texts);
                    let word = |a: u16| layout.holding.get(&a).map_or(0, |s| s.word(raw, texts));
                    // Index/value pairs are holding registers.
                    if table == Table::Holding {
                        match self.indexed.check(comm, v as u16, word) {
                            crate::indexed::WriteCheck::ReadOnly => {
                                return Err(self.plan.read_only);
                            }
                            crate::indexed::WriteCheck::OutOfRange => {
                                return Err(self.plan.out_of_range);
                            }
                            _ => {}
                        }
                    }
                    if !self.accepts(r, v, settings) {
                        return Err(self.plan.out_of_range);
                    }
                    targets[k] = (comm, Some(i), v);
                }
                None if !broadcast && word == 0 && table == Table::Holding && self.in_gap(comm) => {
                    targets[k] = (comm, None, 0)
                }
                None => return Err(self.plan.illegal_address),
            }
        }
        for (k, &(comm, i, v)) in targets[..values.len()].iter().enumerate() {
            if let Some(i) = i {
                let plan = self.reg(i).plan();
                // "When the same parameter value is entered continuously, the parameter is
                // executed just once" (`004_c5cbf92472673495.txt:1111`).
                let executes =
                    plan.repeat_needs_change.is_none() || self.last_written[i] != Some(v);
                self.last_written[i] = Some(v);
                // A register read with other meanings keeps its read word: what a password
                // write does to the lock state depends on a password the simulator lacks.
                let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
                let (raw, texts) = (&self.raw, &self.texts);
                if table == Table::Holding {
                    self.indexed.store(comm, v as u16, |a| {
                        layout.holding.get(&a).map_or(0, |s| s.word(raw, texts))
                    });
                }
                // A register whose reads mean something else (`read_values`) or return another
                // parameter than the one written (`read_param`, BICO) keeps its read state: the
                // write is recorded (`last_written`), what reads give is set by hand.
                if plan.read_values.is_empty() && plan.read_param.is_none() {
                    let before = self.raw[i];
                    self.raw[i] = v;
                    if executes {
                        self.after_write(i, before, Some(kind));
                    }
                }
                if executes {
                    self.executed[i] += 1;
                }
            }
            if table == Table::Holding {
                self.track_commands(comm, values[k]);
            }
        }
        self.tick();
        Ok(())
    }

    pub(super) fn track_commands(&mut self, address: u16, value: u16) {
        let mut stored = false;
        for c in &mut self.commands {
            if !c.writes.iter().any(|&(a, _)| a == address) {
                continue;
            }
            if c.writes.get(c.progress) == Some(&(address, value)) {
                c.progress += 1;
            } else if c.writes.first() == Some(&(address, value)) {
                c.progress = 1;
            } else {
                c.progress = 0;
            }
            if c.progress == c.writes.len() {
                c.count += 1;
                c.progress = 0;
                stored |= c.kind == CommandKind::Persist;
            }
        }
        if stored {
            // What is in force now survives a power cycle.
            self.stored = self.raw.clone();
        }
    }
}
