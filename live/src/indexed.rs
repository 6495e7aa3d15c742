//! Indexed access at run time: an entry of an index/value register pair (`indexed:` in the map)
//! found by the name a user types, and read or written through a [`Session`] in one call of the
//! client (index written, then the value read or written, verified where the index register is
//! readable: `drivemap_runtime::indexed`).

use drivemap_map::Map;
use drivemap_runtime::core::indexed::EntryRef;

use crate::session::Session;

fn norm(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// The entry named `name`: its id, its parameter number as printed, or its printed name
/// (case and punctuation ignored). `None` when no entry of the map has that name.
pub fn find_entry(drive: &Map, name: &str) -> Option<EntryRef> {
    let plan = drive.plan();
    let wanted = norm(name);
    for r in drive.registers() {
        let Some(ix) = r.indexed() else { continue };
        let Some(pair) = plan.indexed.iter().find(|p| p.register == r.id()) else {
            continue;
        };
        for e in &ix.entries {
            let hit = e.id == name
                || e.param.as_deref() == Some(name)
                || (!wanted.is_empty() && norm(&e.name) == wanted);
            if hit && let Some(entry) = pair.entry(&e.id) {
                return Some(EntryRef { pair, entry });
            }
        }
    }
    None
}

impl Session<'_> {
    /// Reads `entry` as its engineering value (the index written, then the value read, in one
    /// call of the client).
    pub fn read_entry(&mut self, entry: EntryRef) -> Result<f64, drivemap_runtime::error::Error> {
        self.client.read_entry(self.slave, entry)
    }

    /// Writes `value` (engineering units) to `entry`: checked against the entry's range and
    /// access, then the index written and the value written in one call of the client.
    pub fn write_entry(
        &mut self,
        entry: EntryRef,
        value: f64,
    ) -> Result<(), drivemap_runtime::error::Error> {
        self.client.write_entry(self.slave, entry, value)
    }
}
