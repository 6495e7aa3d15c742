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
//! steps: O(k · max_read) time. `runtime/tests/planner_exhaustive.rs` compares it with an
//! exhaustive search over all sets of requests on tens of thousands of random cases.
//!
//! ## At run time
//!
//! [`Poller`] keeps a plan for a fixed set of wanted registers and executes it with a
//! [`Client`]. When a request that bridges or merges several registers is answered with
//! exception 02h (invalid address) or 21h, it is split: the wanted registers are read without
//! bridging, halving on further exceptions, so each wanted register gets its own value or its own
//! error. The poller remembers what it learned (a wanted register that fails alone; the bridged
//! addresses of a request whose wanted registers all read fine on their own) and plans around it
//! from the next cycle on.

use std::fmt;

use crate::bus_time::{BusModel, SerialConfig};
use crate::client::Client;
use crate::error::Error;
use crate::pdu;
use crate::profile::{Profile, TransportKind};
use crate::register::{Readable, RegisterInfo, Table};
use crate::scale::ValueError;
use crate::transport::Transport;

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
        };
        set.index_runs();
        set
    }

    /// The addresses of `table` that a register of `registers` lets you read: readable and not
    /// broadcast-only. Reserved, unmapped and write-only addresses are left out.
    pub fn from_registers<R: AsRef<RegisterInfo>>(registers: &[R], table: Table) -> ReadableSet {
        ReadableSet::new(
            registers
                .iter()
                .map(AsRef::as_ref)
                .filter(|r| r.table == table && r.access.readable() && !r.broadcast_only)
                .map(|r| r.address),
        )
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
pub enum PlanError {
    /// A wanted address may not be read (reserved, unmapped, write-only or broadcast-only).
    #[error(
        "{table:?} register {address:04X}h may not be read (reserved, unmapped, write-only or broadcast-only)"
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
}

fn sorted_unique(wanted: &[u16]) -> Vec<u16> {
    let mut w = wanted.to_vec();
    w.sort_unstable();
    w.dedup();
    w
}

/// The requests that read every address of `wanted` (one table, any order, duplicates allowed)
/// in the least total `cost`, reading only addresses of `readable`, at most `max_read` (and at
/// most 125, the Modbus limit) per request. `cost(q)` is the cost of one request for `q`
/// registers, `1 <= q <= max_read`, for example [`BusModel::read_ns`]; any non-negative function
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

fn plan_table(
    table: Table,
    wanted: &[u16],
    readable: &ReadableSet,
    max_read: u16,
    cost: impl Fn(u16) -> u64,
) -> Result<Vec<Read>, PlanError> {
    let max_read = max_read.min(pdu::MAX_READ);
    if max_read == 0 {
        return Err(PlanError::NoReadQuantity);
    }
    let w = sorted_unique(wanted);
    let k = w.len();
    let mut runs = Vec::with_capacity(k);
    for &address in &w {
        runs.push(
            readable
                .run(address)
                .ok_or(PlanError::NotReadable { table, address })?,
        );
    }
    // cost[q] for q in 1..=max_read, asked once each.
    let costs: Vec<u64> = (0..=max_read)
        .map(|q| if q == 0 { 0 } else { cost(q) })
        .collect();
    // eff[U][span] = (min cost[L] for L in span..=U, the least such L), built per U on demand.
    let mut eff: Vec<Vec<(u64, u16)>> = vec![Vec::new(); usize::from(max_read) + 1];
    let mut best = vec![u64::MAX; k + 1];
    let mut choice = vec![(0usize, 0u16); k + 1];
    best[0] = 0;
    for j in 0..k {
        let (start, end) = runs[j];
        let room = (u32::from(end) - u32::from(start) + 1).min(u32::from(max_read)) as u16;
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
            let (c, l) = table_u[span as usize];
            let candidate = best[i].saturating_add(c);
            if candidate < best[j + 1] {
                best[j + 1] = candidate;
                choice[j + 1] = (i, l);
            }
        }
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

/// Whether an exception answering a multi-register read is a reason to split it: 02h (invalid
/// register address) or 21h (data setting error on the Yaskawa drives, busy on the TDS-V8).
pub fn splits_on(error: &Error) -> bool {
    error
        .exception()
        .is_some_and(|e| e.code == 0x02 || e.code == 0x21)
}

/// What a [`Poller`] learned from exceptions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Learned {
    /// A wanted register that is refused when read alone: read alone from now on, never
    /// bridged or merged.
    Refused,
    /// An address bridged by a request that was refused while its wanted registers read fine
    /// on their own: not bridged any more.
    NotBridged,
}

/// What one poll cycle did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CycleStats {
    /// Requests sent (including those of splits).
    pub requests: u32,
    /// Requests split after an exception.
    pub splits: u32,
    /// Modelled bus time of the requests sent, in nanoseconds (exception replies counted as
    /// normal replies).
    pub bus_ns: u64,
}

/// A wanted register's value could not be had.
#[derive(Debug)]
pub enum PolledError<'a> {
    /// The register was not read: the request failed.
    Read(&'a Error),
    /// The word was read but could not be converted.
    Value(ValueError),
}

impl fmt::Display for PolledError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PolledError::Read(e) => e.fmt(f),
            PolledError::Value(e) => e.fmt(f),
        }
    }
}

/// The `(table, address)` of a generated register type, for [`Poller::new`].
pub fn wanted<R: Readable>() -> (Table, u16) {
    (R::TABLE, R::ADDRESS)
}

/// A planned request and the wanted registers it serves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Planned {
    table: Table,
    read: Read,
    /// Start of its words in `Poller::words`.
    first_word: usize,
    /// Range of its members in `Poller::members`.
    members: (usize, usize),
}

/// Per wanted register: not read yet, a word, or the index of an error in `Poller::errors`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    Unread,
    Word(u16),
    Failed(usize),
}

/// Polls a fixed set of registers with a planned set of requests, splitting merged requests
/// that the drive refuses and remembering why.
///
/// ```
/// use drivemap_runtime::planner::Poller;
/// use drivemap_runtime::{Access, Client, Profile, RegisterInfo, Table};
/// # use drivemap_runtime::{profile::TransportKind, slave::SimulatedSlave, transport::Transport};
/// # struct Link(SimulatedSlave, Vec<u8>);
/// # impl Transport for Link {
/// #     fn kind(&self) -> TransportKind { TransportKind::Rtu }
/// #     fn send(&mut self, frame: &[u8]) -> std::io::Result<()> {
/// #         let mut out = [0u8; 256];
/// #         let n = self.0.respond_rtu(frame, &mut out).unwrap_or(0);
/// #         self.1 = out[..n].to_vec();
/// #         Ok(())
/// #     }
/// #     fn recv(&mut self, buf: &mut [u8], _: std::time::Instant) -> std::io::Result<usize> {
/// #         let n = self.1.len().min(buf.len());
/// #         buf[..n].copy_from_slice(&self.1[..n]);
/// #         self.1.drain(..n);
/// #         Ok(n)
/// #     }
/// # }
///
/// static PROFILE: Profile = Profile { max_read: 8, ..Profile::GENERIC };
/// const fn monitor(id: &'static str, address: u16) -> RegisterInfo {
///     RegisterInfo { id, param: None, name: id, address, access: Access::Read,
///                    table: Table::Holding, broadcast_only: false, source: "" }
/// }
/// static REGISTERS: &[RegisterInfo] =
///     &[monitor("a", 0x20), monitor("b", 0x21), monitor("c", 0x22), monitor("d", 0x24)];
///
/// let mut poller =
///     Poller::new(&PROFILE, REGISTERS, [(Table::Holding, 0x20), (Table::Holding, 0x22)])?;
/// // 0021h is readable, so one request for 0020h..=0022h is cheaper than two.
/// assert_eq!(poller.plan().count(), 1);
///
/// let mut drive = SimulatedSlave::new(1, &PROFILE);
/// drive.set_holding(0x22, 600);
/// # let link = Link(drive, Vec::new());
/// let mut client = Client::new(link, &PROFILE); // `link`: any Transport to the drive
/// let stats = poller.poll(&mut client, 1);
/// assert_eq!(stats.requests, 1);
/// assert_eq!(poller.get(Table::Holding, 0x22).unwrap().unwrap(), 600);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct Poller {
    profile: &'static Profile,
    model: BusModel,
    /// Readable addresses per table (holding, input), minus what was learned.
    readable: [ReadableSet; 2],
    learned: Vec<(Table, u16, Learned)>,
    wanted: Vec<(Table, u16)>,
    plan: Vec<Planned>,
    /// (wanted index, offset in the request), grouped by request.
    members: Vec<(usize, u16)>,
    words: Vec<u16>,
    slots: Vec<Slot>,
    errors: Vec<Error>,
    kind: TransportKind,
    replan: bool,
}

fn table_index(table: Table) -> usize {
    match table {
        Table::Holding => 0,
        Table::Input => 1,
    }
}

impl Poller {
    /// A poller for the `wanted` registers `(table, communication address)` of a drive with
    /// `profile` and register table `registers` (a generated module's `REGISTERS`), planned for
    /// 9600 baud 8N1 with the manual's delays. Fails when a wanted address may not be read.
    ///
    /// With generated code: `Poller::new(&v7::PROFILE, v7::REGISTERS, [wanted::<v7::OutputFrequency>(), …])`,
    /// or from the table: `v7::REGISTERS.iter().filter(…).map(|r| (r.table, r.address))`.
    pub fn new<R: AsRef<RegisterInfo>>(
        profile: &'static Profile,
        registers: &[R],
        wanted: impl IntoIterator<Item = (Table, u16)>,
    ) -> Result<Poller, PlanError> {
        let mut poller = Poller {
            profile,
            model: BusModel::new(profile, SerialConfig::default()),
            readable: [
                ReadableSet::from_registers(registers, Table::Holding),
                ReadableSet::from_registers(registers, Table::Input),
            ],
            learned: Vec::new(),
            wanted: wanted.into_iter().collect(),
            plan: Vec::new(),
            members: Vec::new(),
            words: Vec::new(),
            slots: Vec::new(),
            errors: Vec::new(),
            kind: TransportKind::Rtu,
            replan: false,
        };
        poller.make_plan()?;
        Ok(poller)
    }

    /// Plans for another bus-time model (the line's baud and parity, the configured delay).
    pub fn with_model(mut self, model: BusModel) -> Poller {
        self.model = model;
        self.replan = true;
        self.replan_now();
        self
    }

    /// The bus-time model in use.
    pub fn model(&self) -> &BusModel {
        &self.model
    }

    /// The wanted registers, in the order given.
    pub fn wanted(&self) -> &[(Table, u16)] {
        &self.wanted
    }

    /// The requests of the current plan.
    pub fn plan(&self) -> impl Iterator<Item = (Table, Read)> + '_ {
        self.plan.iter().map(|p| (p.table, p.read))
    }

    /// Modelled bus time of one cycle of the current plan, in nanoseconds.
    pub fn plan_ns(&self) -> u64 {
        self.plan
            .iter()
            .map(|p| self.model.read_ns(p.read.quantity))
            .sum()
    }

    /// What exceptions taught, in the order learned.
    pub fn learned(&self) -> &[(Table, u16, Learned)] {
        &self.learned
    }

    /// Forgets what exceptions taught and plans from the register table again.
    pub fn forget(&mut self) {
        for &(table, address, _) in &self.learned {
            let set = &mut self.readable[table_index(table)];
            let mut all = set.addresses().to_vec();
            all.push(address);
            *set = ReadableSet::new(all);
        }
        self.learned.clear();
        self.replan = true;
        self.replan_now();
    }

    fn refused_alone(&self, table: Table, address: u16) -> bool {
        self.learned
            .iter()
            .any(|&(t, a, l)| t == table && a == address && l == Learned::Refused)
    }

    /// Learns that the wanted register at `address` is refused alone: it is read alone from
    /// now on, and no request bridges it.
    fn refuse_alone(&mut self, table: Table, address: u16) {
        if !self.refused_alone(table, address) {
            self.learned.push((table, address, Learned::Refused));
            self.readable[table_index(table)].remove(address);
            self.replan = true;
        }
    }

    fn make_plan(&mut self) -> Result<(), PlanError> {
        let model = self.model;
        let max_read = self.profile.max_read;
        let mut plan = Vec::new();
        for table in [Table::Holding, Table::Input] {
            let mut merged = Vec::new();
            let mut alone = Vec::new();
            for &(t, a) in &self.wanted {
                if t != table {
                    continue;
                }
                if self.refused_alone(t, a) {
                    alone.push(a);
                } else {
                    merged.push(a);
                }
            }
            let mut reads = plan_table(
                table,
                &merged,
                &self.readable[table_index(table)],
                max_read,
                |q| model.read_ns(q),
            )?;
            reads.extend(plan_single(&alone));
            reads.sort_unstable();
            plan.extend(reads.into_iter().map(|read| Planned {
                table,
                read,
                first_word: 0,
                members: (0, 0),
            }));
        }
        let mut members = Vec::with_capacity(self.wanted.len());
        let mut next_word = 0;
        for p in &mut plan {
            p.first_word = next_word;
            next_word += usize::from(p.read.quantity);
            let from = members.len();
            for (i, &(t, a)) in self.wanted.iter().enumerate() {
                if t == p.table
                    && p.read.contains(a)
                    && !members[..from].iter().any(|&(m, _)| m == i)
                {
                    members.push((i, a - p.read.address));
                }
            }
            p.members = (from, members.len());
        }
        self.plan = plan;
        self.members = members;
        self.words = vec![0; next_word];
        self.slots = vec![Slot::Unread; self.wanted.len()];
        self.replan = false;
        Ok(())
    }

    fn replan_now(&mut self) {
        if self.replan {
            // Every wanted address was readable when the poller was made, and learning only
            // moves wanted addresses to the read-alone list or takes addresses nobody wants out
            // of the readable set, so this does not fail; if it did, the old plan stays.
            self.replan = false;
            let _ = self.make_plan();
        }
    }

    /// Reads every wanted register once, with the planned requests. Each wanted register ends
    /// with a word or an error ([`Poller::value`]); a merged request refused with 02h or 21h is
    /// split (see the module documentation). Allocates nothing unless a request fails.
    pub fn poll<T: Transport>(&mut self, client: &mut Client<T>, slave: u8) -> CycleStats {
        self.replan_now();
        self.kind = client.transport().kind();
        self.errors.clear();
        let mut stats = CycleStats::default();
        for k in 0..self.plan.len() {
            let p = self.plan[k];
            let q = usize::from(p.read.quantity);
            let words = &mut self.words[p.first_word..p.first_word + q];
            stats.requests += 1;
            stats.bus_ns += self.model.read_ns(p.read.quantity);
            let result = read(client, slave, p.table, p.read.address, words);
            let (from, to) = p.members;
            match result {
                Ok(()) => {
                    for &(i, offset) in &self.members[from..to] {
                        self.slots[i] = Slot::Word(self.words[p.first_word + usize::from(offset)]);
                    }
                }
                Err(e) if splits_on(&e) && q > 1 => {
                    stats.splits += 1;
                    self.split(client, slave, k, &mut stats);
                }
                Err(e) => {
                    if splits_on(&e) {
                        self.refuse_alone(p.table, p.read.address);
                    }
                    let at = self.errors.len();
                    self.errors.push(e);
                    for &(i, _) in &self.members[from..to] {
                        self.slots[i] = Slot::Failed(at);
                    }
                }
            }
        }
        stats
    }

    /// Splits planned request `k` after it was refused.
    fn split<T: Transport>(
        &mut self,
        client: &mut Client<T>,
        slave: u8,
        k: usize,
        stats: &mut CycleStats,
    ) {
        let p = self.plan[k];
        let (from, to) = p.members;
        let mut addresses: Vec<u16> = self.members[from..to]
            .iter()
            .map(|&(i, _)| self.wanted[i].1)
            .collect();
        addresses.sort_unstable();
        addresses.dedup();
        let mut results: Vec<(u16, Result<u16, usize>)> = Vec::new();
        let refused = self.read_apart(
            client,
            slave,
            p.table,
            p.read,
            &addresses,
            &mut results,
            stats,
        );
        if !refused {
            // The wanted registers read fine on their own: blame the bridged addresses.
            for offset in 0..p.read.quantity {
                let a = p.read.address + offset;
                let wanted_elsewhere = self.wanted.contains(&(p.table, a));
                if !wanted_elsewhere && self.readable[table_index(p.table)].remove(a) {
                    self.learned.push((p.table, a, Learned::NotBridged));
                    self.replan = true;
                }
            }
        }
        for &(i, _) in &self.members[from..to] {
            let a = self.wanted[i].1;
            if let Some((_, r)) = results.iter().find(|(ra, _)| *ra == a) {
                self.slots[i] = match *r {
                    Ok(w) => Slot::Word(w),
                    Err(e) => Slot::Failed(e),
                };
            }
        }
    }

    /// Reads the wanted `addresses` (sorted, unique) of `failed`, a request the drive refused,
    /// without bridging: runs of consecutive wanted addresses, or halves when `failed` was one
    /// such run. Returns whether a register was refused alone.
    #[allow(clippy::too_many_arguments)]
    fn read_apart<T: Transport>(
        &mut self,
        client: &mut Client<T>,
        slave: u8,
        table: Table,
        failed: Read,
        addresses: &[u16],
        results: &mut Vec<(u16, Result<u16, usize>)>,
        stats: &mut CycleStats,
    ) -> bool {
        let runs = plan_contiguous(addresses, self.profile.max_read);
        let parts: Vec<&[u16]> = if runs.len() == 1 && runs[0] == failed {
            let mid = addresses.len() / 2;
            vec![&addresses[..mid], &addresses[mid..]]
        } else {
            let mut parts = Vec::with_capacity(runs.len());
            let mut rest = addresses;
            for r in &runs {
                let n = usize::from(r.quantity);
                parts.push(&rest[..n]);
                rest = &rest[n..];
            }
            parts
        };
        let mut refused = false;
        let mut words = [0u16; pdu::MAX_READ as usize];
        for part in parts {
            let (Some(&first), Some(&last)) = (part.first(), part.last()) else {
                continue;
            };
            let read_part = Read {
                address: first,
                quantity: last - first + 1,
            };
            let q = usize::from(read_part.quantity);
            stats.requests += 1;
            stats.bus_ns += self.model.read_ns(read_part.quantity);
            match read(client, slave, table, first, &mut words[..q]) {
                Ok(()) => {
                    for &a in part {
                        results.push((a, Ok(words[usize::from(a - first)])));
                    }
                }
                Err(e) if splits_on(&e) && part.len() > 1 => {
                    stats.splits += 1;
                    refused |=
                        self.read_apart(client, slave, table, read_part, part, results, stats);
                }
                Err(e) => {
                    if splits_on(&e) {
                        refused = true;
                        self.refuse_alone(table, first);
                    }
                    let at = self.errors.len();
                    self.errors.push(e);
                    for &a in part {
                        results.push((a, Err(at)));
                    }
                }
            }
        }
        refused
    }

    /// The outcome of the last poll for wanted register `index` (in the order given): `None`
    /// before the first poll or for an index out of range.
    pub fn value(&self, index: usize) -> Option<Result<u16, &Error>> {
        match *self.slots.get(index)? {
            Slot::Unread => None,
            Slot::Word(w) => Some(Ok(w)),
            Slot::Failed(e) => self.errors.get(e).map(Err),
        }
    }

    /// The outcome of the last poll for the register at `address` of `table`, if wanted.
    pub fn get(&self, table: Table, address: u16) -> Option<Result<u16, &Error>> {
        let i = self.wanted.iter().position(|&w| w == (table, address))?;
        self.value(i)
    }

    /// The typed value of generated register `R` from the last poll, if it is wanted and was
    /// polled. Its address is `R::address(settings, transport kind of the last poll)`.
    pub fn register<R: Readable>(
        &self,
        settings: &R::Settings,
    ) -> Option<Result<R::Value, PolledError<'_>>> {
        let address = R::address(settings, self.kind);
        Some(match self.get(R::TABLE, address)? {
            Ok(raw) => R::decode(raw, settings).map_err(PolledError::Value),
            Err(e) => Err(PolledError::Read(e)),
        })
    }
}

fn read<T: Transport>(
    client: &mut Client<T>,
    slave: u8,
    table: Table,
    address: u16,
    out: &mut [u16],
) -> Result<(), Error> {
    match table {
        Table::Holding => client.read_holding(slave, address, out),
        Table::Input => client.read_input(slave, address, out),
    }
}

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
