//! The drive model's view of a map's roles: which registers and fields it reads commands from and
//! writes its state to, resolved once from the drive plan (`roles:` of the map, lowered by
//! `drivemap_map::lower`) to register indices, bit positions and codes.
//!
//! Nothing here knows a drive by name, and nothing here is a second reading of the map: the
//! places are the plan's. What the map cannot say because the manual does not print it — the
//! power-on value of a register without a printed default, the output current of an unknown
//! motor — the simulator fills with plausible values, the same for every drive, listed in
//! [`Plausible`] and `sim/README.md`.

use drivemap_map::Map;
use drivemap_runtime::core::command_profile::{CommandProfile, PathKind, Transition};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::roles::{FieldRole, NumberField, Role, RoleKind, Target};
use drivemap_runtime::core::rule::Transports;

/// What the drive model is doing, as status fields report it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Condition {
    /// Never (the simulated drive raises no alarms).
    Never,
    /// Ready: always, except when tripped or in program (PRG) mode (the TDS-V8's example reply
    /// shows Ready clear for a stopped drive in PRG mode; the simulator still takes a run
    /// command there, as the manual does not say it refuses one).
    Ready,
    /// Tripped ([`Simulator::trip`](crate::Simulator::trip)) and not yet reset.
    Fault,
    /// Run commanded, or the output frequency not yet 0.
    Running,
    /// Running in reverse (or about to, at 0 Hz).
    Reverse,
    /// Output frequency 0.
    ZeroSpeed,
    /// Run commanded and the output at the reference.
    SpeedAgree,
    /// Run commanded, the output moving away from 0 towards the reference.
    Accelerating,
    /// Run commanded, the output moving towards 0 (lower reference or direction change).
    Decelerating,
    /// Stop commanded, the output ramping down.
    Stopping,
    /// Operating (DRV) mode.
    DrvMode,
}

impl Condition {
    /// The condition a status role reports.
    pub fn of(role: Role) -> Condition {
        match role {
            Role::Running => Condition::Running,
            Role::Reversing => Condition::Reverse,
            Role::Ready => Condition::Ready,
            Role::ZeroSpeed => Condition::ZeroSpeed,
            Role::SpeedAgree => Condition::SpeedAgree,
            Role::Accelerating => Condition::Accelerating,
            Role::Decelerating => Condition::Decelerating,
            Role::Stopping => Condition::Stopping,
            Role::DriveMode => Condition::DrvMode,
            Role::Fault => Condition::Fault,
            _ => Condition::Never,
        }
    }
}

/// Operating mode of a drive with mode switching (TDS-V8 PRG/DRV).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Mode {
    /// Program mode: parameters writable.
    #[default]
    Prg,
    /// Drive mode.
    Drv,
}

/// Values the manuals do not print, used for every drive alike.
#[derive(Debug, Clone, Copy)]
pub struct Plausible;

impl Plausible {
    /// Maximum frequency (Hz) where the map has no `max_frequency` role, or its register has no
    /// printed default, or its external quantity is not supplied.
    pub const MAX_FREQUENCY: f64 = 60.0;
    /// Accel and decel time (s) of a role register with no printed default, or of a drive whose
    /// map gives no accel/decel time role (the J7's n16/n17 have no register in its sources).
    pub const RAMP_TIME: f64 = 10.0;
    /// Output voltage at the maximum frequency (V/f), V.
    pub const RATED_VOLTAGE: f64 = 230.0;
    /// Output current (A) at 0 Hz and at the maximum frequency while running; 0 when stopped.
    pub const CURRENT: (f64, f64) = (1.0, 2.5);
    /// DC bus voltage (V): the peak of a 230 V line.
    pub const DC_BUS: f64 = 325.0;
    /// Any other external quantity not supplied (in its own unit).
    pub const EXTERNAL: f64 = 1.0;
}

/// A field in the simulator's register list (map order), with its role codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Bit {
    /// Map index of the register.
    pub register: usize,
    pub field: FieldRole,
}

impl Bit {
    /// Whether the field holds its `on` code in the register's raw value (a bit-field
    /// register: one word).
    pub(crate) fn holds(self, raw: u32) -> bool {
        self.field.holds(raw as u16)
    }

    /// The register's raw value with the field set to `code`.
    pub(crate) fn put(self, raw: u32, code: u16) -> u32 {
        u32::from(self.field.put(raw as u16, code))
    }
}

/// A source parameter (or the status field reporting it): the drive acts on network commands
/// arriving on `transports` only while it holds one of the field's `on` codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SourcePlace {
    /// Map index of the register.
    pub register: usize,
    /// The codes (a whole parameter: `lsb` 0, `width` 16).
    pub field: FieldRole,
    pub transports: Transports,
}

/// Whether the drive takes commands from the network on `kind`, given each register's raw
/// value: a source place for the link that holds, or none for the link (nothing to check).
pub(crate) fn network_selected(places: &[SourcePlace], raw: &[u32], kind: TransportKind) -> bool {
    let mut here = places
        .iter()
        .filter(|p| p.transports.contains(kind))
        .peekable();
    here.peek().is_none() || here.any(|p| p.field.holds(raw[p.register] as u16))
}

/// Where a quantity comes from once resolved.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Source {
    Register(usize),
    Value(f64),
}

/// A command field and what it commands.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Command {
    pub role: Role,
    pub bit: Bit,
}

/// The status fields of one register field (several roles may share a multi-bit field): the
/// code shown is the first consistent with every role's condition.
#[derive(Debug, Clone)]
pub(crate) struct StatusField {
    pub register: usize,
    pub lsb: u8,
    pub width: u8,
    /// (condition, codes meaning it holds, code shown when it does not).
    pub roles: Vec<(Condition, &'static [u16], Option<u16>)>,
    /// Candidate codes in order: every `on` code, every `off` code, then 0.
    pub candidates: Vec<u16>,
}

impl StatusField {
    /// The code to show, given which conditions hold; `None` when no code is consistent.
    pub(crate) fn code(&self, holds: impl Fn(Condition) -> bool) -> Option<u16> {
        self.candidates.iter().copied().find(|&c| {
            self.roles.iter().all(|&(cond, on, off)| {
                if holds(cond) {
                    on.contains(&c)
                } else {
                    !on.contains(&c) && off.is_none_or(|off| off == c || on.is_empty())
                }
            })
        })
    }

    /// The register's raw value (one word) with the field set to `code`.
    pub(crate) fn put(&self, raw: u32, code: u16) -> u32 {
        let mask = ((((1u32 << self.width) - 1) << self.lsb) & 0xFFFF) as u16;
        u32::from((raw as u16 & !mask) | ((code << self.lsb) & mask))
    }
}

/// A monitor the model drives, and what it shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Follow {
    /// The output frequency.
    Output,
    /// The reference in force.
    Reference,
    /// Output voltage: V/f up to [`Plausible::RATED_VOLTAGE`].
    Voltage,
    /// Output current: [`Plausible::CURRENT`], 0 when stopped.
    Current,
    /// DC bus voltage: [`Plausible::DC_BUS`].
    DcBus,
    /// The fault code while tripped, the register's power-on word otherwise.
    FaultCode,
    /// The fault code in a field of the register (a status word's byte) while tripped, the
    /// field's power-on bits otherwise.
    FaultCodeField(NumberField),
    /// The last fault's code (a fault history): its power-on word until the first trip, then
    /// the code of the last trip, kept after the reset.
    LastFault,
}

impl Follow {
    /// Whether it shows the fault code.
    pub(crate) fn is_fault_code(self) -> bool {
        matches!(self, Follow::FaultCode | Follow::FaultCodeField(_))
    }

    /// The bits of the register's word it shows (the whole word but for a field).
    pub(crate) fn mask(self) -> u32 {
        match self {
            Follow::FaultCodeField(f) => u32::from(f.mask()),
            _ => u32::MAX,
        }
    }
}

/// The roles of a map, resolved to the simulator's register indices.
#[derive(Debug, Clone)]
pub(crate) struct Resolved {
    pub commands: Vec<Command>,
    pub frequency_reference: Vec<usize>,
    pub follow: Vec<(usize, Follow)>,
    pub max_frequency: Source,
    pub accel_time: Source,
    pub decel_time: Option<Source>,
    pub status: Vec<StatusField>,
    /// The drive has mode switching: it powers on in program mode.
    pub modes: bool,
    /// Register index → plausible power-on value, for role registers without a printed default.
    pub initial: Vec<(usize, f64)>,
    /// Where the drive takes run commands from (`command_source`).
    pub command_source: Vec<SourcePlace>,
    /// Where the drive takes its frequency reference from (`reference_source`).
    pub reference_source: Vec<SourcePlace>,
    /// The command profile, for a drive run through a control-word state machine.
    pub profile: Option<ProfileSim>,
}

/// A command profile with its control and status words as the simulator's register indices.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ProfileSim {
    /// Map index of the control word.
    pub control: usize,
    /// Map index of the status word.
    pub status: usize,
    pub profile: &'static CommandProfile,
}

impl ProfileSim {
    /// The state the drive is in after a write of control word `word` (it was `before`) in
    /// state `state`: the transition that leaves `state` and that the word asks for (an edge
    /// transition only where its edge bits rose), else `state`: a word that skips a state
    /// moves nothing.
    pub(crate) fn next(&self, state: u8, before: u16, word: u16) -> Option<&'static Transition> {
        self.profile.transitions.iter().find(|t| {
            t.leaves(state) && t.asked_by(word) && (t.edge == 0 || (before & t.edge) != t.edge)
        })
    }

    /// Whether `t` moves the drive towards running: a transition of the run path that no stop,
    /// coast or quick stop path takes.
    pub(crate) fn towards_run(&self, t: &Transition) -> bool {
        let p = self.profile;
        let index = |x: &Transition| p.transitions.iter().position(|y| y == x);
        let Some(i) = index(t) else {
            return false;
        };
        let taken = |kind: PathKind| {
            p.path(kind)
                .is_some_and(|path| path.via.contains(&(i as u8)))
        };
        taken(PathKind::Run)
            && ![PathKind::Stop, PathKind::Coast, PathKind::QuickStop]
                .into_iter()
                .any(taken)
    }

    /// The state a trip leads to: the one the `reset_fault` path leaves.
    pub(crate) fn fault_state(&self) -> Option<u8> {
        let p = self.profile;
        let path = p.path(PathKind::ResetFault)?;
        path.via
            .iter()
            .filter_map(|&t| p.transition(t))
            .find_map(|t| t.from.first().copied())
    }
}

/// The map index of the register at plan row `row`.
fn map_index(map: &Map, row: u16) -> Option<usize> {
    map.register_of_row(usize::from(row)).map(|r| r.index())
}

/// Resolves the plan's roles of `drive`; `None` when the map gives none (a register store).
pub(crate) fn resolve(drive: &Map, externals: &dyn Fn(&str) -> Option<f64>) -> Option<Resolved> {
    let roles = drive.plan().roles;
    if roles.is_empty() {
        return None;
    }
    let mut r = Resolved {
        commands: Vec::new(),
        frequency_reference: Vec::new(),
        follow: Vec::new(),
        max_frequency: Source::Value(Plausible::MAX_FREQUENCY),
        accel_time: Source::Value(Plausible::RAMP_TIME),
        decel_time: None,
        status: Vec::new(),
        modes: false,
        initial: Vec::new(),
        command_source: Vec::new(),
        reference_source: Vec::new(),
        profile: None,
    };
    if let Some(p) = roles.profile
        && let (Some(control), Some(status)) =
            (map_index(drive, p.control), map_index(drive, p.status))
    {
        r.profile = Some(ProfileSim {
            control,
            status,
            profile: p,
        });
    }
    let quantity = |role: Role, fallback: f64, initial: &mut Vec<(usize, f64)>| {
        let p = roles.of(role).next()?;
        Some(match p.target {
            Target::Register(row) => match map_index(drive, row) {
                Some(i) => {
                    if drive
                        .register_at(i)
                        .and_then(|r| r.default_value())
                        .is_none()
                    {
                        initial.push((i, fallback));
                    }
                    Source::Register(i)
                }
                None => Source::Value(fallback),
            },
            Target::External { name, .. } => Source::Value(externals(name).unwrap_or(fallback)),
            Target::Field(_) | Target::NumberField(_) => Source::Value(fallback),
        })
    };
    if let Some(s) = quantity(Role::MaxFrequency, Plausible::MAX_FREQUENCY, &mut r.initial) {
        r.max_frequency = s;
    }
    if let Some(s) = quantity(Role::AccelTime, Plausible::RAMP_TIME, &mut r.initial) {
        r.accel_time = s;
    }
    r.decel_time = quantity(Role::DecelTime, Plausible::RAMP_TIME, &mut r.initial);
    for p in roles.places {
        let row_index = p.target.row().and_then(|row| map_index(drive, row));
        match (p.role.kind(), p.target, row_index) {
            (RoleKind::Command, Target::Field(field), Some(register)) => {
                r.modes |= matches!(p.role, Role::ToDriveMode | Role::ToProgramMode);
                r.commands.push(Command {
                    role: p.role,
                    bit: Bit { register, field },
                });
            }
            (RoleKind::Source, Target::Field(field), Some(register)) => {
                let place = SourcePlace {
                    register,
                    field,
                    transports: p.transports,
                };
                if p.role == Role::CommandSource {
                    r.command_source.push(place);
                } else {
                    r.reference_source.push(place);
                }
            }
            (RoleKind::Status, Target::Field(f), Some(register)) => {
                let cond = Condition::of(p.role);
                match r
                    .status
                    .iter_mut()
                    .find(|s| s.register == register && s.lsb == f.lsb && s.width == f.width)
                {
                    Some(s) => s.roles.push((cond, f.on, f.off)),
                    None => r.status.push(StatusField {
                        register,
                        lsb: f.lsb,
                        width: f.width,
                        roles: vec![(cond, f.on, f.off)],
                        candidates: Vec::new(),
                    }),
                }
            }
            (_, Target::Register(_), Some(i)) => match p.role {
                Role::FrequencyReference => r.frequency_reference.push(i),
                Role::OutputFrequency => r.follow.push((i, Follow::Output)),
                Role::ReferenceMonitor => r.follow.push((i, Follow::Reference)),
                Role::OutputVoltage => r.follow.push((i, Follow::Voltage)),
                Role::OutputCurrent => r.follow.push((i, Follow::Current)),
                Role::DcBusVoltage => r.follow.push((i, Follow::DcBus)),
                Role::FaultCode => r.follow.push((i, Follow::FaultCode)),
                Role::LastFault => r.follow.push((i, Follow::LastFault)),
                _ => {}
            },
            (_, Target::NumberField(f), Some(i)) if p.role == Role::FaultCode => {
                r.follow.push((i, Follow::FaultCodeField(f)));
            }
            _ => {}
        }
    }
    for s in &mut r.status {
        let mut c: Vec<u16> = Vec::new();
        for (_, on, _) in &s.roles {
            c.extend(on.iter().filter(|x| !c.contains(x)).collect::<Vec<_>>());
        }
        for (_, _, off) in &s.roles {
            if let Some(off) = off
                && !c.contains(off)
            {
                c.push(*off);
            }
        }
        if !c.contains(&0) {
            c.push(0);
        }
        s.candidates = c;
    }
    Some(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(roles: Vec<(Condition, &'static [u16], Option<u16>)>) -> StatusField {
        let mut s = StatusField {
            register: 0,
            lsb: 0,
            width: 4,
            roles,
            candidates: Vec::new(),
        };
        let mut c = Vec::new();
        for (_, on, _) in &s.roles {
            for x in on.iter() {
                if !c.contains(x) {
                    c.push(*x);
                }
            }
        }
        for (_, _, off) in &s.roles {
            if let Some(o) = off
                && !c.contains(o)
            {
                c.push(*o);
            }
        }
        c.push(0);
        s.candidates = c;
        s
    }

    #[test]
    fn a_shared_code_field_shows_the_code_consistent_with_every_role() {
        // ACN run_direction_state: 0 stopped, 1 forward, 2 reverse.
        let s = field(vec![
            (Condition::Running, &[1, 2], Some(0)),
            (Condition::Reverse, &[2], None),
        ]);
        let at = |running: bool, reverse: bool| {
            s.code(|c| match c {
                Condition::Running => running,
                Condition::Reverse => reverse,
                _ => false,
            })
        };
        assert_eq!(at(false, false), Some(0));
        assert_eq!(at(true, false), Some(1));
        assert_eq!(at(true, true), Some(2));
    }

    #[test]
    fn a_bit_is_one_while_its_condition_holds() {
        let s = field(vec![(Condition::ZeroSpeed, &[1], Some(0))]);
        assert_eq!(s.code(|_| true), Some(1));
        assert_eq!(s.code(|_| false), Some(0));
    }
}
