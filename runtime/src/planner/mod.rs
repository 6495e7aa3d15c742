//! Read planning: the requests that read a set of registers in the least bus time.
//!
//! An application wants some registers of a drive (communication addresses in one table). Each
//! read request costs its bus time ([`crate::bus_time::BusModel::read_ns`]): a large fixed part
//! (request, drive latency, turnaround) and a small part per register. Reading a few registers
//! nobody asked for is often cheaper than a second request, but only registers that may be read
//! can be bridged: the drive may answer 02h for a reserved or unmapped address, and reading a
//! write-only register is not allowed. [`plan_reads`] finds the cheapest set of requests under
//! those rules and the drive's `max_read`.
//!
//! ## The algorithm
//!
//! Sort and deduplicate the wanted addresses `w[0] < … < w[k-1]`. The readable addresses fall
//! into runs of consecutive addresses; a request may only lie inside one run. Any set of requests
//! that covers the wanted addresses can be reduced (dropping requests whose wanted addresses
//! others cover, which costs nothing) to requests ordered by start and by end, and then charged
//! to disjoint blocks `w[i..=j]` of consecutive wanted addresses, each request containing its
//! block. A request containing `w[i..=j]` has a length `L` with `w[j] - w[i] + 1 <= L <=
//! min(max_read, run length)`, and every such length fits inside the run. So, with
//! `eff(span, U) = min over L in span..=U of cost(L)`:
//!
//! ```text
//! best[0] = 0
//! best[j+1] = min over i <= j, w[i] in the run of w[j], span = w[j]-w[i]+1 <= U:
//!                 best[i] + eff(span, U)          U = min(max_read, length of the run of w[j])
//! ```
//!
//! `best[k]` is the optimum for any non-negative cost function (for the bus-time model, which
//! grows with the quantity, `eff(span, U) = cost(span)`). The inner loop stops after `max_read`
//! steps: O(k · max_read) time. `runtime/tests/runtime/planner_exhaustive.rs` compares it with an
//! exhaustive search over all sets of requests on tens of thousands of random cases.
//!
//! ## At run time
//!
//! [`Poller`] keeps a plan for a fixed set of wanted registers and executes it with a
//! [`Client`](crate::client::Client). When a request that bridges or merges several registers is answered with
//! exception 02h (invalid address) or 21h, it is split: the wanted registers are read without
//! bridging, halving on further exceptions, so each wanted register gets its own value or its own
//! error. The poller remembers what it learned (a wanted register that fails alone; the bridged
//! addresses of a request whose wanted registers all read fine on their own) and plans around it
//! from the next cycle on.

use crate::pdu;
use drivemap_core::functions::Functions;
use drivemap_core::plan::RegisterPlan;
use drivemap_core::register::{RegisterInfo, Table};

/// A register the planner plans reads over: where it is, and which functions it accepts.
/// Implemented by [`RegisterInfo`] (every function of the drive) and by [`RegisterPlan`] (its
/// map's `function_codes`): pass a drive's plans (a generated module's `REGISTERS`) for the
/// planner to respect them.
pub trait PlannedRegister: AsRef<RegisterInfo> {
    /// The functions the register accepts.
    fn functions(&self) -> Functions {
        Functions::ANY
    }
}

impl PlannedRegister for RegisterInfo {}

impl PlannedRegister for RegisterPlan {
    fn functions(&self) -> Functions {
        self.functions
    }
}

impl<T: PlannedRegister> PlannedRegister for &T {
    fn functions(&self) -> Functions {
        (**self).functions()
    }
}

/// One read request: `quantity` registers from `address`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Read {
    /// First communication address.
    pub address: u16,
    /// Registers read (at least 1).
    pub quantity: u16,
}

impl Read {
    /// The last address read.
    pub const fn last(&self) -> u16 {
        self.address.saturating_add(self.quantity.saturating_sub(1))
    }

    /// Whether the request reads `address`.
    pub const fn contains(&self, address: u16) -> bool {
        address >= self.address && address <= self.last() && self.quantity > 0
    }
}

/// The addresses of one table that may be read, with the runs of consecutive ones.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ReadableSet {
    /// Sorted, unique.
    addresses: Vec<u16>,
    /// For each address, the index of the first address of its run.
    run_start: Vec<u32>,
    /// For each address, the index of the last address of its run.
    run_end: Vec<u32>,
    /// Second addresses of 32-bit pairs, and every later address of a string (text in
    /// several registers), sorted: a request may not begin there while the word before is read
    /// too (see [`ReadableSet::pair_second`]).
    pair_seconds: Vec<u16>,
}

impl ReadableSet {
    /// The set of `addresses` (any order, duplicates allowed).
    pub fn new(addresses: impl IntoIterator<Item = u16>) -> ReadableSet {
        let mut addresses: Vec<u16> = addresses.into_iter().collect();
        addresses.sort_unstable();
        addresses.dedup();
        let mut set = ReadableSet {
            addresses,
            run_start: Vec::new(),
            run_end: Vec::new(),
            pair_seconds: Vec::new(),
        };
        set.index_runs();
        set
    }

    /// The addresses of `table` that a register of `registers` lets you read: readable and not
    /// broadcast-only, both words of a 32-bit pair. Reserved, unmapped and write-only addresses
    /// are left out. Pairs are kept whole by the plans made over the set.
    ///
    /// A register whose map restricts its functions (`function_codes`) to a list without the
    /// table's read function (03h holding, 04h input) is left out too: no read is planned over
    /// it, so the drive never sees a read function the register refuses. The tables are
    /// planned apart, so 03h and 04h registers (and 01h coils and 02h discrete inputs) are
    /// never read in one request.
    pub fn from_registers<R: PlannedRegister>(registers: &[R], table: Table) -> ReadableSet {
        let read = table.read_function();
        let readable = || {
            registers
                .iter()
                .filter(move |r| r.functions().allows(read))
                .map(AsRef::as_ref)
                .filter(|r| r.table == table && r.access.readable() && !r.broadcast_only)
        };
        let mut set = ReadableSet::new(
            readable().flat_map(|r| (0..r.width.count()).filter_map(|i| r.address.checked_add(i))),
        );
        set.pair_seconds = readable()
            .flat_map(|r| (1..r.width.count()).filter_map(|i| r.address.checked_add(i)))
            .collect();
        set.pair_seconds.sort_unstable();
        set.pair_seconds.dedup();
        set
    }

    /// [`ReadableSet::from_registers`] of every table, in the order of [`Table::ALL`]
    /// (holding, input, coil, discrete input): what a [`Poller`] plans over.
    pub fn tables<R: PlannedRegister>(registers: &[R]) -> [ReadableSet; 4] {
        Table::ALL.map(|t| ReadableSet::from_registers(registers, t))
    }

    /// Whether `address` is the second word of a 32-bit pair, or a later word of a string: a
    /// read of the word before must take it in the same request.
    pub fn pair_second(&self, address: u16) -> bool {
        self.pair_seconds.binary_search(&address).is_ok()
    }

    /// `wanted` with the second word of every wanted pair, and every later word of a wanted
    /// string, added (sorted, unique).
    pub fn whole_pairs(&self, wanted: &[u16]) -> Vec<u16> {
        let mut w = sorted_unique(wanted);
        let mut rest = Vec::new();
        for &a in &w {
            let mut next = a.checked_add(1);
            while let Some(n) = next.filter(|n| self.pair_second(*n)) {
                rest.push(n);
                next = n.checked_add(1);
            }
        }
        w.extend(rest);
        sorted_unique(&w)
    }

    fn index_runs(&mut self) {
        let n = self.addresses.len();
        self.run_start.clear();
        self.run_end.clear();
        self.run_start.resize(n, 0);
        self.run_end.resize(n, 0);
        let mut start = 0usize;
        for i in 0..n {
            if i > 0 && u32::from(self.addresses[i - 1]) + 1 != u32::from(self.addresses[i]) {
                start = i;
            }
            self.run_start[i] = start as u32;
        }
        let mut end = n.saturating_sub(1);
        for i in (0..n).rev() {
            if i + 1 < n && u32::from(self.addresses[i]) + 1 != u32::from(self.addresses[i + 1]) {
                end = i;
            }
            self.run_end[i] = end as u32;
        }
    }

    /// Whether `address` may be read.
    pub fn contains(&self, address: u16) -> bool {
        self.addresses.binary_search(&address).is_ok()
    }

    /// Puts `address` (back) into the set.
    pub fn insert(&mut self, address: u16) {
        if let Err(i) = self.addresses.binary_search(&address) {
            self.addresses.insert(i, address);
            self.index_runs();
        }
    }

    /// Takes `address` out of the set; returns whether it was in it.
    pub fn remove(&mut self, address: u16) -> bool {
        match self.addresses.binary_search(&address) {
            Ok(i) => {
                self.addresses.remove(i);
                self.index_runs();
                true
            }
            Err(_) => false,
        }
    }

    /// The addresses, ascending.
    pub fn addresses(&self) -> &[u16] {
        &self.addresses
    }

    /// Number of addresses.
    pub fn len(&self) -> usize {
        self.addresses.len()
    }

    /// Whether no address may be read.
    pub fn is_empty(&self) -> bool {
        self.addresses.is_empty()
    }

    /// The first and last address of the run of consecutive readable addresses containing
    /// `address`, or `None` when `address` may not be read.
    pub fn run(&self, address: u16) -> Option<(u16, u16)> {
        let i = self.addresses.binary_search(&address).ok()?;
        Some((
            self.addresses[self.run_start[i] as usize],
            self.addresses[self.run_end[i] as usize],
        ))
    }
}

/// Why no plan could be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// A wanted address may not be read (reserved, unmapped, write-only, broadcast-only, or a
    /// register whose `function_codes` refuse its table's read function).
    #[error(
        "{table:?} register {address:04X}h may not be read (reserved, unmapped, write-only, broadcast-only, or its function codes refuse the table's read function)"
    )]
    NotReadable {
        /// The table.
        table: Table,
        /// The address.
        address: u16,
    },
    /// The drive reads no register per request (`max_read` is 0).
    #[error("the drive's max_read is 0: nothing can be read")]
    NoReadQuantity,
    /// A 32-bit pair cannot be read in one request (`max_read` is 1).
    #[error(
        "{table:?} registers {address:04X}h-{:04X}h hold one 32-bit value, but the drive's max_read of 1 cannot read both words in one request",
        address.wrapping_add(1)
    )]
    SplitPair {
        /// The table.
        table: Table,
        /// The pair's first address.
        address: u16,
    },
}

fn sorted_unique(wanted: &[u16]) -> Vec<u16> {
    let mut w = wanted.to_vec();
    w.sort_unstable();
    w.dedup();
    w
}

/// The requests that read every address of `wanted` (one table of registers, any order, duplicates allowed)
/// in the least total `cost`, reading only addresses of `readable`, at most `max_read` (and at
/// most 125, the Modbus limit) per request. A wanted 32-bit pair of `readable` is read whole: its
/// second word is added and no request boundary falls between its words. `cost(q)` is the cost of one request for `q`
/// registers, `1 <= q <= max_read`, for example [`BusModel::read_ns`](crate::bus_time::BusModel::read_ns); any non-negative function
/// gives an optimal plan. Requests are returned in ascending address order. See the module
/// documentation for the algorithm.
pub fn plan_reads(
    wanted: &[u16],
    readable: &ReadableSet,
    max_read: u16,
    cost: impl Fn(u16) -> u64,
) -> Result<Vec<Read>, PlanError> {
    plan_table(Table::Holding, wanted, readable, max_read, cost)
}

/// [`plan_reads`] in `table`: for coils and discrete inputs `max_read` is the drive's
/// `max_read_bits` (at most 2000, the Modbus limit) and `cost` the cost of reading `q` of them
/// ([`BusModel::read_bits_ns`](crate::bus_time::BusModel::read_bits_ns)).
pub fn plan_reads_in(
    table: Table,
    wanted: &[u16],
    readable: &ReadableSet,
    max_read: u16,
    cost: impl Fn(u16) -> u64,
) -> Result<Vec<Read>, PlanError> {
    plan_table(table, wanted, readable, max_read, cost)
}

pub(super) fn plan_table(
    table: Table,
    wanted: &[u16],
    readable: &ReadableSet,
    max_read: u16,
    cost: impl Fn(u16) -> u64,
) -> Result<Vec<Read>, PlanError> {
    let cap = if table.is_bits() {
        pdu::MAX_READ_BITS
    } else {
        pdu::MAX_READ
    };
    let max_read = max_read.min(cap);
    if max_read == 0 {
        return Err(PlanError::NoReadQuantity);
    }
    let w = readable.whole_pairs(wanted);
    let k = w.len();
    let mut runs = Vec::with_capacity(k);
    for &address in &w {
        runs.push(
            readable
                .run(address)
                .ok_or(PlanError::NotReadable { table, address })?,
        );
    }
    // The longest request any wanted address allows: its readable run, at most `max_read`. No
    // request is longer, so no cost beyond it is asked (a map without coils plans its empty
    // coil table with no cost at all, not 2000 of them).
    let room_of = |(start, end): (u16, u16)| {
        (u32::from(end) - u32::from(start) + 1).min(u32::from(max_read)) as u16
    };
    let longest = runs.iter().map(|&r| room_of(r)).max().unwrap_or(0);
    // cost[q] for q in 1..=longest, asked once each.
    let costs: Vec<u64> = (0..=longest)
        .map(|q| if q == 0 { 0 } else { cost(q) })
        .collect();
    // eff[U][span] = (min cost[L] for L in span..=U, the least such L), built per U on demand.
    let mut eff: Vec<Vec<(u64, u16)>> = vec![Vec::new(); usize::from(longest) + 1];
    let mut best = vec![u64::MAX; k + 1];
    let mut choice = vec![(0usize, 0u16); k + 1];
    best[0] = 0;
    for j in 0..k {
        let (start, _) = runs[j];
        let room = room_of(runs[j]);
        let table_u = &mut eff[usize::from(room)];
        if table_u.is_empty() {
            table_u.resize(usize::from(room) + 1, (u64::MAX, 0));
            let mut m = (u64::MAX, 0u16);
            for l in (1..=room).rev() {
                if costs[usize::from(l)] <= m.0 {
                    m = (costs[usize::from(l)], l);
                }
                table_u[usize::from(l)] = m;
            }
        }
        let table_u = &eff[usize::from(room)];
        for i in (0..=j).rev() {
            if w[i] < start {
                break;
            }
            let span = u32::from(w[j]) - u32::from(w[i]) + 1;
            if span > u32::from(room) {
                break;
            }
            if i > 0 && w[i - 1].wrapping_add(1) == w[i] && readable.pair_second(w[i]) {
                continue; // a request may not begin between the words of a pair
            }
            let (c, l) = table_u[span as usize];
            let candidate = best[i].saturating_add(c);
            if candidate < best[j + 1] {
                best[j + 1] = candidate;
                choice[j + 1] = (i, l);
            }
        }
    }
    if best[k] == u64::MAX {
        let address = w
            .iter()
            .find(|a| readable.pair_second(a.wrapping_add(1)))
            .map_or(0, |a| *a);
        return Err(PlanError::SplitPair { table, address });
    }
    let mut reads = Vec::new();
    let mut j = k;
    while j > 0 {
        let (i, l) = choice[j];
        let (_, end) = runs[j - 1];
        // Start at the block's first address; where the request would run past the end of the
        // run (only when a longer read is cheaper), end it at the run's end instead.
        let first = u32::from(w[i]);
        let address = if first + u32::from(l) - 1 > u32::from(end) {
            u32::from(end) + 1 - u32::from(l)
        } else {
            first
        };
        reads.push(Read {
            address: address as u16,
            quantity: l,
        });
        j = i;
    }
    reads.reverse();
    Ok(reads)
}

/// The baseline of Telegraf's Modbus input and Home Assistant's modbus integration: strictly
/// consecutive wanted addresses share a request, split every `max_read` registers; nothing is
/// bridged. Requests in ascending address order.
pub fn plan_contiguous(wanted: &[u16], max_read: u16) -> Vec<Read> {
    let max_read = max_read.clamp(1, pdu::MAX_READ);
    let mut reads: Vec<Read> = Vec::new();
    for a in sorted_unique(wanted) {
        match reads.last_mut() {
            Some(r) if u32::from(r.last()) + 1 == u32::from(a) && r.quantity < max_read => {
                r.quantity += 1;
            }
            _ => reads.push(Read {
                address: a,
                quantity: 1,
            }),
        }
    }
    reads
}

/// One request per wanted address.
pub fn plan_single(wanted: &[u16]) -> Vec<Read> {
    sorted_unique(wanted)
        .into_iter()
        .map(|address| Read {
            address,
            quantity: 1,
        })
        .collect()
}

/// The total cost of `reads` under `cost`.
pub fn plan_cost(reads: &[Read], cost: impl Fn(u16) -> u64) -> u64 {
    reads
        .iter()
        .fold(0u64, |sum, r| sum.saturating_add(cost(r.quantity)))
}

mod poller;

pub use poller::{CycleStats, Learned, PolledError, Poller, poll_line, splits_on, wanted};

#[cfg(test)]
mod tests {
    use super::*;

    fn affine(q: u16) -> u64 {
        40 + 2 * u64::from(q)
    }

    #[test]
    fn holes_of_readable_registers_are_bridged_when_cheaper() {
        let readable = ReadableSet::new(0x20..=0x2F);
        let plan = plan_reads(&[0x20, 0x22, 0x2F], &readable, 16, affine).unwrap();
        assert_eq!(
            plan,
            vec![Read {
                address: 0x20,
                quantity: 16
            }]
        );
        // With max_read 8 the end is read alone.
        let plan = plan_reads(&[0x20, 0x22, 0x2F], &readable, 8, affine).unwrap();
        assert_eq!(
            plan,
            vec![
                Read {
                    address: 0x20,
                    quantity: 3
                },
                Read {
                    address: 0x2F,
                    quantity: 1
                }
            ]
        );
    }

    #[test]
    fn never_reads_across_an_address_that_may_not_be_read() {
        // 0x21 reserved.
        let readable = ReadableSet::new([0x20, 0x22, 0x23]);
        let plan = plan_reads(&[0x20, 0x23], &readable, 16, affine).unwrap();
        assert_eq!(plan.len(), 2);
        assert_eq!(
            plan_reads(&[0x21], &readable, 16, affine),
            Err(PlanError::NotReadable {
                table: Table::Holding,
                address: 0x21
            })
        );
        assert_eq!(
            plan_reads(&[0x20], &readable, 0, affine),
            Err(PlanError::NoReadQuantity)
        );
    }

    #[test]
    fn a_large_hole_is_not_bridged() {
        let readable = ReadableSet::new(0..100);
        // Bridging 30 registers costs 60; a second request costs 42.
        let plan = plan_reads(&[0, 31], &readable, 125, affine).unwrap();
        assert_eq!(plan.len(), 2);
        let plan = plan_reads(&[0, 15], &readable, 125, affine).unwrap();
        assert_eq!(plan.len(), 1);
    }

    #[test]
    fn a_cheaper_longer_read_is_placed_inside_the_run() {
        // Non-monotone cost: 3 registers cost less than 1.
        let cost = |q: u16| match q {
            1 => 10,
            2 => 9,
            _ => 5,
        };
        let readable = ReadableSet::new([7, 8, 9]);
        let plan = plan_reads(&[9], &readable, 4, cost).unwrap();
        assert_eq!(
            plan,
            vec![Read {
                address: 7,
                quantity: 3
            }]
        );
    }

    #[test]
    fn runs_of_the_readable_set() {
        let mut set = ReadableSet::new([5, 1, 2, 3, 9, 10]);
        assert_eq!(set.run(2), Some((1, 3)));
        assert_eq!(set.run(10), Some((9, 10)));
        assert_eq!(set.run(4), None);
        assert!(set.remove(2));
        assert!(!set.remove(2));
        assert_eq!(set.run(1), Some((1, 1)));
        assert_eq!(set.run(3), Some((3, 3)));
        assert_eq!(set.len(), 5);
        let top = ReadableSet::new([0xFFFE, 0xFFFF]);
        assert_eq!(
            plan_reads(&[0xFFFF, 0xFFFE], &top, 125, affine).unwrap(),
            vec![Read {
                address: 0xFFFE,
                quantity: 2
            }]
        );
    }

    #[test]
    fn the_whole_address_space_readable() {
        let all = ReadableSet::new(0..=u16::MAX);
        assert_eq!(all.run(0x1234), Some((0, 0xFFFF)));
        let plan = plan_reads(&[0xFFFF, 0, 0x8000], &all, 125, affine).unwrap();
        assert_eq!(plan.len(), 3);
        assert_eq!(
            plan[2],
            Read {
                address: 0xFFFF,
                quantity: 1
            }
        );
    }

    #[test]
    fn baselines() {
        let w = [3, 1, 2, 5, 6, 7, 8, 2];
        assert_eq!(
            plan_contiguous(&w, 3),
            vec![
                Read {
                    address: 1,
                    quantity: 3
                },
                Read {
                    address: 5,
                    quantity: 3
                },
                Read {
                    address: 8,
                    quantity: 1
                }
            ]
        );
        assert_eq!(plan_single(&w).len(), 7);
        assert_eq!(plan_cost(&plan_single(&w), affine), 7 * 42);
    }
}
