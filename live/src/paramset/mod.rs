//! Parameter sets: a drive's settings saved to a file, compared, and restored or cloned to a
//! drive, written against the map's plan and a live [`Session`](crate::session::Session).
//!
//! - [`save`] reads every setting of the map (a readable and writable parameter with a
//!   parameter number, not a command) with the runtime's read planner and returns a
//!   [`ParameterSet`]: values in the manual's units, codes by number and id, the settings the
//!   drive would not read listed with why. [`ParameterSet::to_yaml`] writes it in the map's
//!   order, so that a set kept in git diffs line by line.
//! - [`compare()`] lists every setting two sides hold differently: two sets, a set and a drive,
//!   or either against the map's printed defaults ([`Side::defaults`]).
//! - [`restore`]: [`validate`] checks the whole set against the map first (one bad value and
//!   nothing is written, every reason listed); [`plan`] reads the drive and plans the writes of
//!   what differs in the order the plan's dependencies give ([`restore_order`]: what selects a
//!   scale or address, or bounds another setting, first); [`execute`] writes them through the
//!   write gate, runs the map's store command once, reads every written setting back and
//!   reports what was written and verified, written but not verified, and not written. Run
//!   again, it writes only what still differs.

mod compare;
mod file;
mod restore;
mod save;

use std::collections::BTreeSet;

use drivemap_map::Map;
use drivemap_map::Quantity;
use drivemap_map::RegisterRef;
use drivemap_runtime::core::plan::Dependency;
use drivemap_runtime::core::roles::RoleKind;

pub use compare::{Compared, Difference, Side, compare};
pub use file::{FORMAT, FileError, MAX_FILE, ParameterSet, SavedSetting, UnreadSetting};
pub use restore::{
    Progress, RestoreError, RestorePlan, RestoreReport, Skipped, StoreOutcome, Validated, Write,
    execute, plan, restore, store_command, validate,
};
pub use save::{SaveReport, save, save_with};

/// The settings of `drive`, in the map's order: registers that are read and written (not
/// monitors, not write-only commands), carry a parameter number, are not broadcast-only, are
/// not the place of a command role or the frequency reference (the run command is never part
/// of a set), are not coils, are not written by one of the map's commands (ENTER, save), and
/// are not read from another parameter than the one written ([`left_out`]).
pub fn settings_of(drive: &Map) -> Vec<RegisterRef<'_>> {
    let plan = drive.plan();
    let mut commands: BTreeSet<usize> = BTreeSet::new();
    for place in plan.roles.places {
        let command = matches!(place.role.kind(), RoleKind::Command)
            || place.role == drivemap_runtime::core::roles::Role::FrequencyReference;
        if command
            && let Some(row) = place.target.row()
            && let Some(r) = drive.register_of_row(usize::from(row))
        {
            commands.insert(r.index());
        }
    }
    let command_addresses: BTreeSet<u16> = plan
        .profile
        .commands
        .iter()
        .flat_map(|c| c.writes.iter().map(|(a, _)| *a))
        .collect();
    drive
        .registers()
        .filter(|r| {
            r.readable()
                && r.writable()
                && !r.broadcast_only()
                && r.param().is_some()
                // A coil is a command or a state of the drive (run, trip, jog), not a
                // parameter: a set never writes one back.
                && !r.plan().info.table.is_bits()
                // Read from another parameter than the one written (BICO): the value saved
                // would not be the value restored, nor a restore's read-back its write.
                && r.read_param().is_none()
                && !commands.contains(&r.index())
                && !command_addresses.contains(&r.address())
        })
        .collect()
}

/// The read-and-written registers with a parameter number that parameter sets leave out for a
/// reason a user would not guess, each with the reason: those read from another parameter than
/// the one written (`read_param`, Siemens BICO: a read of 0200h returns r0055.8, a write sets
/// P2200), whose saved value would be r0055.8's and be written to P2200 on restore, and whose
/// restore could not be verified by reading it back.
pub fn left_out(drive: &Map) -> Vec<(RegisterRef<'_>, String)> {
    drive
        .registers()
        .filter(|r| r.readable() && r.writable())
        .filter_map(|r| {
            let (read, write) = (r.read_param()?, r.param()?);
            Some((
                r,
                format!(
                    "{} is left out of parameter sets: a read returns {read}, a write sets {write} (a saved {read} is no value for {write}, and a restore could not be checked by reading it back)",
                    r.label()
                ),
            ))
        })
        .collect()
}

/// The registers `r` depends on through the plan: the parameters that select its scale or
/// address, the registers its scale is relative to (under every selector case), and the one
/// its relative limit is stated through (a reference at most the maximum frequency).
pub fn depends_on<'a>(drive: &'a Map, r: RegisterRef<'_>) -> Vec<RegisterRef<'a>> {
    let plan = drive.plan();
    let mut rows: Vec<usize> = Vec::new();
    let settings = crate::LiveSettings::default();
    let register_plan = r.plan();
    register_plan.depends_on(&settings.view(drive), |d| match d {
        Dependency::Code(s) => rows.extend(
            plan.settings
                .codes
                .get(usize::from(s.slot))
                .map(|c| c.register),
        ),
        Dependency::Quantity(s) => {
            if let Some(Quantity::Register(row)) = plan.settings.quantities.get(usize::from(s.slot))
            {
                rows.push(*row);
            }
        }
    });
    if let Some(Dependency::Quantity(s)) = register_plan.limit_dependency()
        && let Some(Quantity::Register(row)) = plan.settings.quantities.get(usize::from(s.slot))
    {
        rows.push(*row);
    }
    let mut out: Vec<RegisterRef<'_>> = Vec::new();
    for row in rows {
        if let Some(d) = drive.register_of_row(row)
            && d.id() != r.id()
            && !out.iter().any(|x| x.id() == d.id())
        {
            out.push(d);
        }
    }
    out
}

/// `regs` in the order a restore writes them: every register after the registers of `regs` it
/// depends on ([`depends_on`]: a selector before what it scales or moves, a limit before what
/// it bounds), otherwise in the map's order. Derived from the plan, never a list kept by hand;
/// a dependency cycle (which validation refuses) keeps the map's order among its members.
pub fn restore_order<'a>(drive: &Map, regs: &[RegisterRef<'a>]) -> Vec<RegisterRef<'a>> {
    let n = regs.len();
    let position = |id: &str| regs.iter().position(|r| r.id() == id);
    // before[i]: the members of `regs` that register i depends on.
    let before: Vec<Vec<usize>> = regs
        .iter()
        .map(|r| {
            depends_on(drive, *r)
                .iter()
                .filter_map(|d| position(d.id()))
                .collect()
        })
        .collect();
    let mut done = vec![false; n];
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        // The first register in map order whose dependencies are all placed; in a cycle, the
        // first not yet placed.
        let next = (0..n)
            .filter(|&i| !done[i])
            .find(|&i| before[i].iter().all(|&d| done[d]))
            .or_else(|| (0..n).find(|&i| !done[i]));
        let Some(i) = next else { break };
        done[i] = true;
        out.push(regs[i]);
    }
    out
}

/// A fingerprint of what a set's values mean under `drive`: FNV-1a (64 bits) over the plan rows
/// of its settings (address, conversion, ranges, limits, restrictions), in the map's order.
/// Two maps that read and write every setting alike have the same fingerprint; a set saved
/// under another fingerprint is compared and restored by id all the same, with a warning.
pub fn fingerprint(drive: &Map) -> String {
    // Computed once per loaded map. The plan's run-time profile is leaked once per lowering
    // and lives as long as the process, so its address names the loaded map for good.
    type Cache = Vec<(usize, String)>;
    static CACHE: std::sync::Mutex<Cache> = std::sync::Mutex::new(Vec::new());
    let key = std::ptr::from_ref(drive.plan().profile) as usize;
    let mut cache = match CACHE.lock() {
        Ok(c) => c,
        Err(poisoned) => poisoned.into_inner(),
    };
    if let Some((_, f)) = cache.iter().find(|(k, _)| *k == key) {
        return f.clone();
    }
    let f = compute_fingerprint(drive);
    cache.push((key, f.clone()));
    f
}

fn compute_fingerprint(drive: &Map) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for b in bytes {
            hash ^= u64::from(*b);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    feed(drive.id().as_bytes());
    for r in settings_of(drive) {
        feed(r.id().as_bytes());
        feed(format!("{:?}", r.plan()).as_bytes());
    }
    format!("fnv1a64:{hash:016x}")
}

/// A register of `drive` by its id exactly (a set names settings by id).
fn by_id<'a>(drive: &'a Map, id: &str) -> Option<RegisterRef<'a>> {
    drive.registers().find(|r| r.id() == id)
}

/// Text from a file or a drive shortened to `max` characters and escaped, for messages.
pub(crate) fn quoted(text: &str, max: usize) -> String {
    let mut out: String = text
        .chars()
        .take(max)
        .flat_map(char::escape_default)
        .collect();
    if text.chars().count() > max {
        out.push('…');
    }
    format!("`{out}`")
}
