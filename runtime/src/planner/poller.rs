//! The poller: a plan for a fixed set of wanted registers, executed with a [`Client`], split
//! when the drive refuses a merged request, and replanned around what it learned.

use crate::bus_time::{BusModel, SerialConfig};
use crate::client::Client;
use crate::error::Error;
use crate::pdu;
use crate::transport::Transport;
use drivemap_core::profile::{Profile, TransportKind};
use drivemap_core::register::{Readable, Table};
use drivemap_core::scale::ValueError;
use drivemap_core::width::Width;
use std::fmt;

use super::{PlanError, PlannedRegister, Read, ReadableSet, plan_single, plan_table};

/// Whether an exception answering a multi-register read is a reason to split it: 02h (invalid
/// register address) or 21h (data setting error on the Yaskawa drives, busy on the TDS-V8).
pub fn splits_on(error: &Error) -> bool {
    error
        .exception()
        .is_some_and(|e| e.code == 0x02 || e.code == 0x21)
}

/// What a [`Poller`] learned from exceptions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
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
#[non_exhaustive]
pub struct CycleStats {
    /// Requests sent (including those of splits).
    pub requests: u32,
    /// Requests split after an exception.
    pub splits: u32,
    /// Modelled bus time of the requests sent, in nanoseconds (exception replies counted as
    /// normal replies).
    pub bus_ns: u64,
    /// Requests not sent because the slave had not answered an earlier one of the same poll
    /// ([`Poller::poll_between`]).
    pub skipped: u32,
}

/// A wanted register's value could not be had.
#[derive(Debug)]
#[non_exhaustive]
pub enum PolledError<'a> {
    /// The register was not read: the request failed.
    Read(&'a Error),
    /// The word was read but could not be converted.
    Value(ValueError),
    /// Where the register is depends on a setting the settings do not hold: no word read
    /// anywhere is taken for it.
    Address(drivemap_core::plan::AddressUnknown),
}

impl fmt::Display for PolledError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PolledError::Read(e) => e.fmt(f),
            PolledError::Value(e) => e.fmt(f),
            PolledError::Address(e) => e.fmt(f),
        }
    }
}

/// One cycle over several drives of one link (an RS-485 line, a gateway), each `(slave,
/// poller)` in turn through the one `client`: before each, the client is switched to that
/// poller's drive ([`Client::switch_drive`]), with the drive's timing
/// ([`ClientOptions::for_link`]) and the client's retries, reconnection and EEPROM budget as
/// they were. Returns the cycle's statistics summed; each poller holds its drive's values.
///
/// [`ClientOptions::for_link`]: crate::client::ClientOptions::for_link
pub fn poll_line<T: Transport>(client: &mut Client<T>, drives: &mut [(u8, Poller)]) -> CycleStats {
    let kind = client.transport().kind();
    let mut total = CycleStats::default();
    for (slave, poller) in drives.iter_mut() {
        let mine = *client.options();
        let options = crate::client::ClientOptions {
            retries: mine.retries,
            reconnect: mine.reconnect,
            eeprom_writes_per_hour: mine.eeprom_writes_per_hour,
            ..crate::client::ClientOptions::for_link(poller.profile, kind)
        };
        client.switch_drive(poller.profile, options);
        let s = poller.poll(client, *slave);
        total.requests += s.requests;
        total.splits += s.splits;
        total.bus_ns += s.bus_ns;
        total.skipped += s.skipped;
    }
    total
}

/// The `(table, address)` of a generated register type, for [`Poller::new`] (a 32-bit pair's
/// second word is added by the poller).
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
/// use drivemap_runtime::client::Client;
/// use drivemap_runtime::core::profile::Profile;
/// use drivemap_runtime::core::register::{Access, RegisterInfo, Table};
/// use drivemap_runtime::core::width::Width;
/// # use drivemap_runtime::{core::profile::TransportKind, transport::Transport};
/// use drivemap_sim::SimulatedSlave; // a bare simulated drive (dev-dependency)
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
///                    table: Table::Holding, width: Width::Word, broadcast_only: false, source: "" }
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
    /// Readable addresses per table (holding, input, coil, discrete input), minus what was
    /// learned.
    readable: [ReadableSet; 4],
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
        Table::Coil => 2,
        Table::DiscreteInput => 3,
    }
}

impl Poller {
    /// A poller for the `wanted` registers `(table, communication address)` of a drive with
    /// `profile` and register table `registers` (a generated module's `REGISTERS`), planned for
    /// 9600 baud 8N1 with the manual's delays. Fails when a wanted address may not be read.
    ///
    /// With generated code: `Poller::new(&v7::PROFILE, v7::REGISTERS, [wanted::<v7::OutputFrequency>(), …])`,
    /// or from the table: `v7::REGISTERS.iter().filter(…).map(|r| (r.table, r.address))`.
    pub fn new<R: PlannedRegister>(
        profile: &'static Profile,
        registers: &[R],
        wanted: impl IntoIterator<Item = (Table, u16)>,
    ) -> Result<Poller, PlanError> {
        Poller::over(
            profile,
            ReadableSet::tables(registers),
            wanted,
            BusModel::new(profile, SerialConfig::default()),
        )
    }

    /// [`Poller::new`] over readable sets already built ([`ReadableSet::tables`] of the
    /// register table; a caller that plans many reads over one table builds them once), planned
    /// for `model` ([`Poller::with_model`] without planning twice).
    pub fn over(
        profile: &'static Profile,
        readable: [ReadableSet; 4],
        wanted: impl IntoIterator<Item = (Table, u16)>,
        model: BusModel,
    ) -> Result<Poller, PlanError> {
        let mut poller = Poller {
            profile,
            model,
            readable,
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
        // A wanted 32-bit pair is read whole: its second word is wanted too, and so is every
        // later word of a wanted string (after the caller's entries, so their indices stay).
        let mut seconds: Vec<(Table, u16)> = Vec::new();
        for &(t, a) in &poller.wanted {
            let mut next = a.checked_add(1);
            while let Some(n) = next.filter(|&n| poller.readable[table_index(t)].pair_second(n)) {
                seconds.push((t, n));
                next = n.checked_add(1);
            }
        }
        for second in seconds {
            if !poller.wanted.contains(&second) {
                poller.wanted.push(second);
            }
        }
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

    /// The profile of the drive polled.
    pub fn profile(&self) -> &'static Profile {
        self.profile
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
            .map(|p| self.model.read_ns_of(p.table, p.read.quantity))
            .sum()
    }

    /// What exceptions taught, in the order learned.
    pub fn learned(&self) -> &[(Table, u16, Learned)] {
        &self.learned
    }

    /// Forgets what exceptions taught and plans from the register table again.
    pub fn forget(&mut self) {
        for &(table, address, _) in &self.learned {
            self.readable[table_index(table)].insert(address);
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
        let mut plan = Vec::new();
        for table in Table::ALL {
            let max_read = self.profile.max_read_of(table);
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
                |q| model.read_ns_of(table, q),
            )?;
            // Read alone, but a pair still in one request.
            let set = &self.readable[table_index(table)];
            reads.extend(plan_single(&alone).into_iter().filter_map(|mut r| {
                if set.pair_second(r.address) && alone.contains(&r.address.wrapping_sub(1)) {
                    return None;
                }
                if r.address.checked_add(1).is_some_and(|a| set.pair_second(a)) {
                    r.quantity = 2;
                }
                Some(r)
            }));
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
        self.poll_between(client, slave, &mut |_| {})
    }

    /// [`Poller::poll`] for a link shared with other work: `between` is called with the client
    /// before every planned request (a bridge sends its pending commands there, so polling
    /// never holds a command back for more than one request), and a slave that does not answer
    /// one request ([`Error::Timeout`] after the client's retries) is not asked again in this
    /// poll: the rest of its registers fail with that timeout ([`CycleStats::skipped`] counts
    /// the requests not sent), so one silent drive costs a line one timeout per poll, not one
    /// per request.
    pub fn poll_between<T: Transport>(
        &mut self,
        client: &mut Client<T>,
        slave: u8,
        between: &mut dyn FnMut(&mut Client<T>),
    ) -> CycleStats {
        self.replan_now();
        self.kind = client.transport().kind();
        self.errors.clear();
        let mut stats = CycleStats::default();
        let mut silent: Option<usize> = None;
        for k in 0..self.plan.len() {
            let p = self.plan[k];
            if let Some(at) = silent {
                stats.skipped += 1;
                let (from, to) = p.members;
                for &(i, _) in &self.members[from..to] {
                    self.slots[i] = Slot::Failed(at);
                }
                continue;
            }
            between(client);
            let q = usize::from(p.read.quantity);
            let words = &mut self.words[p.first_word..p.first_word + q];
            stats.requests += 1;
            stats.bus_ns += self.model.read_ns_of(p.table, p.read.quantity);
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
                    if matches!(e, Error::Timeout { .. }) {
                        silent = Some(at);
                    }
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
    // One step of a recursion over halves: the poller, the link and where results and
    // statistics go, plus the request being split; a struct would be rebuilt at every level.
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
        let runs = self.runs_whole(table, addresses);
        let whole = |&(from, to): &(usize, usize)| {
            let (first, last) = (addresses[from], addresses[to - 1]);
            failed.address == first && failed.quantity == last - first + 1
        };
        let parts: Vec<&[u16]> = if runs.len() == 1 && whole(&runs[0]) {
            // Halve near the middle, never between the words of a pair; a lone pair is not split.
            let n = addresses.len();
            let mid = (n / 2..n)
                .chain((1..n / 2).rev())
                .find(|&m| m > 0 && !self.splits_pair(table, addresses, m));
            match mid {
                Some(mid) => vec![&addresses[..mid], &addresses[mid..]],
                None => vec![addresses],
            }
        } else {
            runs.iter()
                .map(|&(from, to)| &addresses[from..to])
                .collect()
        };
        let mut refused = false;
        // Only after a refusal: a coil read may be longer than a register read's 125.
        let mut words = vec![0u16; usize::from(failed.quantity)];
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
            stats.bus_ns += self.model.read_ns_of(table, read_part.quantity);
            match read(client, slave, table, first, &mut words[..q]) {
                Ok(()) => {
                    for &a in part {
                        results.push((a, Ok(words[usize::from(a - first)])));
                    }
                }
                Err(e) if splits_on(&e) && part.len() > 1 && part != addresses => {
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

    /// [`Poller::value`] of a register of `width`: a 32-bit pair's two words joined in its
    /// order (the poller reads both in one request).
    pub fn raw(&self, index: usize, width: Width) -> Option<Result<u32, &Error>> {
        let (table, address) = *self.wanted.get(index)?;
        let first = match self.value(index)? {
            Ok(w) => w,
            Err(e) => return Some(Err(e)),
        };
        Some(match width {
            // A string's words are read by [`Poller::words`]; its first word stands here.
            Width::Word | Width::Text(_) => Ok(u32::from(first)),
            Width::Pair(_) => match self.get(table, address.wrapping_add(1))? {
                Ok(second) => Ok(width.join(&[first, second])),
                Err(e) => Err(e),
            },
        })
    }

    /// The words of the last poll from the `index`-th wanted address on, one per slot of
    /// `out` (a string's: the planner reads them in one request): `None` before the first poll,
    /// the error of the first that failed.
    pub fn words(&self, index: usize, out: &mut [u16]) -> Option<Result<(), &Error>> {
        let (table, address) = *self.wanted.get(index)?;
        for (i, word) in out.iter_mut().enumerate() {
            match self.get(table, address.wrapping_add(i as u16))? {
                Ok(w) => *word = w,
                Err(e) => return Some(Err(e)),
            }
        }
        Some(Ok(()))
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
        let address = match R::address(settings, self.kind) {
            Ok(a) => a,
            Err(e) => return Some(Err(PolledError::Address(e))),
        };
        let mut words = [0u16; Width::MAX_WORDS];
        let words = &mut words[..usize::from(R::WIDTH.count()).min(Width::MAX_WORDS)];
        for (i, word) in words
            .iter_mut()
            .enumerate()
            .take(usize::from(R::WIDTH.count()))
        {
            match self.get(R::TABLE, address.wrapping_add(i as u16))? {
                Ok(w) => *word = w,
                Err(e) => return Some(Err(PolledError::Read(e))),
            }
        }
        Some(R::decode_words(words, settings).map_err(PolledError::Value))
    }

    /// Whether a boundary before `addresses[at]` falls between the words of a pair.
    fn splits_pair(&self, table: Table, addresses: &[u16], at: usize) -> bool {
        at > 0
            && at < addresses.len()
            && addresses[at - 1].wrapping_add(1) == addresses[at]
            && self.readable[table_index(table)].pair_second(addresses[at])
    }

    /// `addresses` (sorted, unique) cut into runs of consecutive addresses of at most
    /// `max_read`, never between the words of a pair: index ranges.
    fn runs_whole(&self, table: Table, addresses: &[u16]) -> Vec<(usize, usize)> {
        let cap = if table.is_bits() {
            pdu::MAX_READ_BITS
        } else {
            pdu::MAX_READ
        };
        let max = usize::from(self.profile.max_read_of(table).clamp(2, cap));
        let n = addresses.len();
        let mut runs = Vec::new();
        let (mut start, mut i) = (0, 0);
        while i < n {
            let unit = if self.splits_pair(table, addresses, i + 1) {
                2
            } else {
                1
            };
            let end = (i + unit).min(n);
            let span = usize::from(addresses[end - 1] - addresses[start]) + 1;
            if i > start && (addresses[i - 1].wrapping_add(1) != addresses[i] || span > max) {
                runs.push((start, i));
                start = i;
            }
            i = end;
        }
        if start < n {
            runs.push((start, n));
        }
        runs
    }
}

fn read<T: Transport>(
    client: &mut Client<T>,
    slave: u8,
    table: Table,
    address: u16,
    out: &mut [u16],
) -> Result<(), Error> {
    client.read_table(slave, table, address, out)
}
