//! Reading many registers in few requests.
//!
//! Registers are sorted by table and address and read in runs of consecutive addresses, at most
//! the drive's `max_read` per request. A run may step over addresses nobody asked for only when
//! each of them is a readable register of the map (so the drive is known to answer for it);
//! otherwise a hole starts a new request.

use std::collections::BTreeSet;

use drivemap_codegen::model::ModbusTable;

/// One read request of the plan.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Batch {
    /// Holding (03h) or input (04h) registers.
    pub table: ModbusTable,
    /// First communication address.
    pub address: u16,
    /// Registers read.
    pub count: u16,
    /// For each wanted register served by this request: its index in the wanted list and its
    /// offset in the reply.
    pub members: Vec<(usize, u16)>,
}

fn table_key(t: ModbusTable) -> u8 {
    match t {
        ModbusTable::Holding => 0,
        ModbusTable::Input => 1,
    }
}

/// Plans the reads of `wanted` (table, address) pairs. `fillers` are the addresses that may be
/// read although nobody asked for them.
pub fn plan(
    wanted: &[(ModbusTable, u16)],
    max_read: u16,
    fillers: &BTreeSet<(u8, u16)>,
) -> Vec<Batch> {
    let max_read = max_read.max(1);
    let mut order: Vec<usize> = (0..wanted.len()).collect();
    order.sort_by_key(|&i| (table_key(wanted[i].0), wanted[i].1));
    let mut out: Vec<Batch> = Vec::new();
    for i in order {
        let (table, address) = wanted[i];
        if let Some(b) = out.last_mut() {
            if b.table == table {
                let end = u32::from(b.address) + u32::from(b.count) - 1;
                let a = u32::from(address);
                if a <= end {
                    b.members.push((i, (a - u32::from(b.address)) as u16));
                    continue;
                }
                let span = a - u32::from(b.address) + 1;
                let bridgeable =
                    ((end + 1)..a).all(|h| fillers.contains(&(table_key(table), h as u16)));
                if span <= u32::from(max_read) && bridgeable {
                    b.count = span as u16;
                    b.members.push((i, (a - u32::from(b.address)) as u16));
                    continue;
                }
            }
        }
        out.push(Batch {
            table,
            address,
            count: 1,
            members: vec![(i, 0)],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const H: ModbusTable = ModbusTable::Holding;
    const I: ModbusTable = ModbusTable::Input;

    #[test]
    fn consecutive_registers_share_a_request_up_to_max_read() {
        let wanted: Vec<(ModbusTable, u16)> = (0x20..0x30).rev().map(|a| (H, a)).collect();
        let plan = plan(&wanted, 16, &BTreeSet::new());
        assert_eq!(plan.len(), 1);
        assert_eq!((plan[0].address, plan[0].count), (0x20, 16));
        // wanted[0] is 0x2F: offset 15.
        assert!(plan[0].members.contains(&(0, 15)));

        let split = super::plan(&wanted, 8, &BTreeSet::new());
        assert_eq!(
            split
                .iter()
                .map(|b| (b.address, b.count))
                .collect::<Vec<_>>(),
            vec![(0x20, 8), (0x28, 8)]
        );
    }

    #[test]
    fn holes_are_bridged_only_over_known_registers() {
        let wanted = [(H, 0x10), (H, 0x12), (H, 0x20)];
        let none = plan(&wanted, 16, &BTreeSet::new());
        assert_eq!(none.len(), 3);
        let fillers: BTreeSet<(u8, u16)> = [(0, 0x11)].into_iter().collect();
        let bridged = plan(&wanted, 16, &fillers);
        assert_eq!(bridged.len(), 2);
        assert_eq!((bridged[0].address, bridged[0].count), (0x10, 3));
        assert_eq!(bridged[0].members, vec![(0, 0), (1, 2)]);
    }

    #[test]
    fn tables_and_duplicates() {
        let wanted = [(H, 5), (I, 5), (H, 5), (I, 6)];
        let p = plan(&wanted, 16, &BTreeSet::new());
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].table, H);
        assert_eq!(p[0].members, vec![(0, 0), (2, 0)]);
        assert_eq!(p[1].table, I);
        assert_eq!(p[1].count, 2);
    }

    #[test]
    fn the_top_of_the_address_space_does_not_overflow() {
        let wanted = [(H, 0xFFFE), (H, 0xFFFF)];
        let p = plan(&wanted, 0, &BTreeSet::new());
        assert_eq!(p.len(), 2, "max_read 0 is treated as 1");
        let p = plan(&wanted, 125, &BTreeSet::new());
        assert_eq!((p[0].address, p[0].count), (0xFFFE, 2));
    }
}
