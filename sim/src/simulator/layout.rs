//! Where each register lies on a link: the address layout per transport, as the plan places it.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
use drivemap_runtime::core::width::Width;

use super::Simulator;

/// Hashes a communication address by one multiplication (Fibonacci hashing), so that the
/// request path's lookups cost a few nanoseconds instead of SipHash's tens. The keys are the
/// map's addresses; a peer only chooses which key to look up, so hash flooding does not apply.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct AddressHasher(u64);

impl Hasher for AddressHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u16(&mut self, n: u16) {
        // The multiplication spreads the address into the high bits, which the table's
        // control bytes use.
        self.0 = u64::from(n).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// What lies at one communication address: the register's index, which of its words (1 for
/// the second word of a 32-bit pair), and what a read needs, copied here so that serving a word
/// touches this entry and the register's raw value only.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Slot {
    pub(super) index: usize,
    pub(super) word: u16,
    pub(super) readable: bool,
    pub(super) width: Width,
}

impl Slot {
    /// The word the slot's register holds here: its word, a pair's half, or a string's
    /// characters (`texts`, by register).
    pub(super) fn word(&self, raw: &[u32], texts: &[Vec<u16>]) -> u16 {
        let w = usize::from(self.word);
        match self.width {
            Width::Text(_) => texts
                .get(self.index)
                .and_then(|t| t.get(w))
                .copied()
                .unwrap_or(0),
            width => width.split(raw[self.index]).get(w).copied().unwrap_or(0),
        }
    }
}

/// Communication address → what lies there.
pub(super) type AddressMap = HashMap<u16, Slot, BuildHasherDefault<AddressHasher>>;

#[derive(Debug, Clone, Default)]
pub(super) struct Layout {
    pub(super) holding: AddressMap,
    pub(super) input: AddressMap,
    pub(super) coil: AddressMap,
    pub(super) discrete_input: AddressMap,
    pub(super) broadcast: AddressMap,
}

impl Layout {
    /// The addresses of `table` (the broadcast-only registers are apart).
    pub(super) fn of(&self, table: Table) -> &AddressMap {
        match table {
            Table::Holding => &self.holding,
            Table::Input => &self.input,
            Table::Coil => &self.coil,
            Table::DiscreteInput => &self.discrete_input,
        }
    }
}

impl Simulator {
    /// The communication address of a register on a transport, as laid out at power-on (address
    /// alternatives resolved by the drive's own settings), if the register exists there.
    pub fn address_of(&self, name: &str, kind: TransportKind) -> Option<u16> {
        let i = self.index_of(name).ok()?;
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        [
            &layout.holding,
            &layout.input,
            &layout.coil,
            &layout.discrete_input,
            &layout.broadcast,
        ]
        .iter()
        .find_map(|m| {
            m.iter()
                .find(|(_, s)| s.index == i && s.word == 0)
                .map(|(a, _)| *a)
        })
    }

    /// Where each register lies on this link, as the plan places it: registers that do not exist
    /// on the transport are left out, and a register that moves (by setting, variant or
    /// transport) is at the address `RegisterPlan::address_for` gives, the same one the clients
    /// and the generated code use.
    pub(super) fn layout(&self, tcp: bool) -> Layout {
        let settings = self.settings();
        let view = settings.view(&self.map);
        let here = if tcp {
            TransportKind::Tcp
        } else {
            TransportKind::Rtu
        };
        let mut layout = Layout::default();
        for (i, r) in self.map.registers().enumerate() {
            let plan = r.plan();
            if !plan.transports.contains(here) {
                continue;
            }
            let address = plan.address_for(&view, here);
            let space = if r.broadcast_only() {
                &mut layout.broadcast
            } else {
                match plan.info.table {
                    Table::Holding => &mut layout.holding,
                    Table::Input => &mut layout.input,
                    Table::Coil => &mut layout.coil,
                    Table::DiscreteInput => &mut layout.discrete_input,
                }
            };
            for word in 0..plan.info.width.count() {
                space.entry(address.wrapping_add(word)).or_insert(Slot {
                    index: i,
                    word,
                    readable: r.readable(),
                    width: plan.info.width,
                });
            }
        }
        layout
    }

    pub(super) fn in_gap(&self, address: u16) -> bool {
        self.map
            .gaps()
            .iter()
            .filter_map(|g| g.addresses)
            .any(|[lo, hi]| (lo..=hi).contains(&address))
    }

    pub(super) fn communication_address(&self, kind: TransportKind, pdu: u32) -> Result<u16, u8> {
        u16::try_from(pdu)
            .ok()
            .and_then(|p| self.profile.address_offsets.communication_address(p, kind))
            .ok_or(self.plan.illegal_address)
    }
}
