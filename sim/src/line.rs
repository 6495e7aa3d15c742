//! Several simulated drives on one link, each at its own slave address, as on an RS-485 line or
//! behind a Modbus TCP to RTU gateway.
//!
//! Every frame on a serial line reaches every drive; the one whose address it carries answers,
//! the others stay silent, and a broadcast (slave 0) is executed by every drive that allows it
//! and answered by none. A [`Line`] does just that: it reads the frame's address (the RTU
//! slave address, or the Modbus TCP unit id) and hands the frame to the drive at that address,
//! or to every drive for slave 0. A frame for an address no drive has gets no reply, as on a
//! line (a real gateway would answer 0Bh after its own timeout; this one stays silent, as the
//! line behind it does).
//!
//! ```
//! use drivemap_sim::{Line, SimOptions, Simulator};
//! use drivemap_runtime::core::profile::TransportKind;
//!
//! let maps = concat!(env!("CARGO_MANIFEST_DIR"), "/../maps/");
//! let v7 = drivemap_map::Loader::new().load(format!("{maps}yaskawa-v7.yaml").as_ref())?;
//! let tds = drivemap_map::Loader::new().load(format!("{maps}ptlk-tds-v8.yaml").as_ref())?;
//! let mut line = Line::new();
//! line.add(Simulator::new(v7, SimOptions::new().slave(1))?)?;
//! let tds = line.add(Simulator::new(tds, SimOptions::new().slave(2))?)?; // its SharedSim
//! assert_eq!(line.slaves().collect::<Vec<_>>(), [1, 2]);
//! // 02 03 0000 0001 + CRC: a read for slave 2 is answered by the TDS-V8 only.
//! let mut out = [0u8; 260];
//! let handled = line.handle(TransportKind::Rtu, &[0x02, 0x03, 0x00, 0x00, 0x00, 0x01, 0x84, 0x39], &mut out);
//! assert_eq!(handled.record.slave, 2);
//! assert_eq!(drivemap_sim::server::lock(&tds).stats().requests, 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;

use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::{rtu, tcp};

use crate::server::{SharedSim, lock, shared};
use crate::{Handled, Outcome, RequestRecord, Simulator};

/// Simulated drives sharing one link, at distinct slave addresses. Cloning a line shares its
/// drives (each is a [`SharedSim`]).
#[derive(Clone)]
pub struct Line {
    drives: Vec<SharedSim>,
    /// The index in `drives` of the drive at each slave address.
    by_slave: Vec<Option<u16>>,
}

impl fmt::Debug for Line {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list()
            .entries(self.drives.iter().map(|d| {
                let d = lock(d);
                format!("{}@{}", d.drive().id(), d.slave())
            }))
            .finish()
    }
}

/// A drive cannot join a line: another one already answers to its address.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("slave address {slave} is taken on this line by {taken_by}; cannot add {drive} there")]
pub struct SlaveTaken {
    /// The address.
    pub slave: u8,
    /// The drive already there.
    pub taken_by: String,
    /// The drive refused.
    pub drive: String,
}

impl Default for Line {
    fn default() -> Line {
        Line::new()
    }
}

impl Line {
    /// A line with no drive (every frame goes unanswered until drives are added).
    pub fn new() -> Line {
        Line {
            drives: Vec::new(),
            by_slave: vec![None; 256],
        }
    }

    /// Adds a drive at its own slave address ([`Simulator::slave`]); returns it shared, to
    /// look at or change while the line is served.
    pub fn add(&mut self, sim: Simulator) -> Result<SharedSim, SlaveTaken> {
        let sim = shared(sim);
        self.add_shared(sim.clone())?;
        Ok(sim)
    }

    /// Adds a drive already shared (one served elsewhere too, say).
    pub fn add_shared(&mut self, sim: SharedSim) -> Result<(), SlaveTaken> {
        let (slave, id) = {
            let s = lock(&sim);
            (s.slave(), s.drive().id().to_owned())
        };
        if let Some(i) = self.by_slave[usize::from(slave)] {
            return Err(SlaveTaken {
                slave,
                taken_by: lock(&self.drives[usize::from(i)]).drive().id().to_owned(),
                drive: id,
            });
        }
        self.by_slave[usize::from(slave)] = Some(self.drives.len() as u16);
        self.drives.push(sim);
        Ok(())
    }

    /// The drives, in the order added.
    pub fn drives(&self) -> &[SharedSim] {
        &self.drives
    }

    /// The drive at `slave`, if any.
    pub fn drive(&self, slave: u8) -> Option<&SharedSim> {
        let i = (*self.by_slave.get(usize::from(slave))?)?;
        self.drives.get(usize::from(i))
    }

    /// The slave addresses of the drives, in the order added.
    pub fn slaves(&self) -> impl Iterator<Item = u8> + '_ {
        self.drives.iter().map(|d| lock(d).slave())
    }

    /// How many drives.
    pub fn len(&self) -> usize {
        self.drives.len()
    }

    /// Whether the line has no drive.
    pub fn is_empty(&self) -> bool {
        self.drives.is_empty()
    }

    /// Answers one complete frame of `kind` as the line does: the drive at the frame's address
    /// answers ([`Simulator::handle`]); for slave 0 every drive executes the broadcast as its
    /// map allows and none answers (the record says `executed` when any did); a frame for an
    /// address no drive has, or too short to carry one, is seen by the first drive, which does
    /// not answer it (its record says `NotAddressed` or `Damaged`).
    pub fn handle(&self, kind: TransportKind, frame: &[u8], out: &mut [u8]) -> Handled {
        let at = if kind.is_serial_framed() {
            0
        } else {
            tcp::HEADER_LEN - 1
        };
        match frame.get(at).copied() {
            Some(rtu::BROADCAST) => {
                let mut first: Option<Handled> = None;
                let mut executed = false;
                for d in &self.drives {
                    let h = lock(d).handle(kind, frame, out);
                    executed |= matches!(h.record.outcome, Outcome::Broadcast { executed: true });
                    first.get_or_insert(h);
                }
                let mut h = first.unwrap_or_else(|| nobody(kind, frame, at));
                if let Outcome::Broadcast { .. } = h.record.outcome {
                    h.record.outcome = Outcome::Broadcast { executed };
                }
                h.reply = None;
                h
            }
            // The drive at that address; else the first drive sees the frame, as every drive
            // on a line does, and tells a damaged frame from one for another slave (and counts
            // it in its `stats`).
            slave => match slave.and_then(|s| self.drive(s)).or(self.drives.first()) {
                Some(d) => lock(d).handle(kind, frame, out),
                None => nobody(kind, frame, at),
            },
        }
    }
}

/// The record of a frame on a line with no drive.
fn nobody(kind: TransportKind, frame: &[u8], at: usize) -> Handled {
    Handled {
        reply: None,
        record: RequestRecord {
            transport: kind,
            slave: frame.get(at).copied().unwrap_or(0),
            function: frame.get(at + 1).copied(),
            address: None,
            quantity: 0,
            outcome: Outcome::NotAddressed,
        },
    }
}

impl From<SharedSim> for Line {
    /// A line of one drive.
    fn from(sim: SharedSim) -> Line {
        let mut line = Line::new();
        // An empty line has every address free.
        let _ = line.add_shared(sim);
        line
    }
}

impl From<Simulator> for Line {
    /// A line of one drive.
    fn from(sim: Simulator) -> Line {
        Line::from(shared(sim))
    }
}
