//! One API for every mapped drive: [`VariableFrequencyDrive`] — run, stop, direction, frequency
//! reference, ramps, output monitors, status, fault code and reset — implemented once, by
//! [`Vfd`], over the roles a map gives ([`Roles`]) and the plan rows they name.
//!
//! An application written against the trait runs on any drive whose map has roles:
//!
//! ```
//! use drivemap_runtime::vfd::{Direction, VariableFrequencyDrive};
//! use drivemap_runtime::Error;
//!
//! /// Runs the drive at `hz` in `direction` and returns the output frequency it reports.
//! fn start(drive: &mut impl VariableFrequencyDrive, hz: f64, direction: Direction) -> Result<f64, Error> {
//!     drive.set_reference(hz)?;
//!     drive.set_direction(direction)?;
//!     drive.run()?;
//!     drive.output_frequency()
//! }
//! ```
//!
//! Every write goes through the client's write gate with the register's own rule, and every
//! value through the register's conversion (the same range checks as the typed registers, the
//! drive's own errors). A role the map does not give is refused with [`Refusal::NoRole`] before
//! anything is sent, never skipped: [`VariableFrequencyDrive::supports`] tells beforehand.
//!
//! Command words are composed from a copy the [`Vfd`] keeps of what it last wrote to each command
//! register, starting from every command role released (stopped, forward, no reset): the run
//! command of a drive is owned by one master. The copy changes only when a write succeeds, so a
//! command the drive refused (or that was lost) is not sent again by a later one.

use std::fmt;

use drivemap_core::plan::RegisterPlan;
use drivemap_core::register::{DrivePlan, DriveSettings, Table};
use drivemap_core::roles::{FieldRole, Place, Role, RoleKind, Target};
use drivemap_core::rule::Broadcast;
use drivemap_core::{Roles, SettingsView};

use crate::client::Client;
use crate::error::{Error, Refusal};
use crate::profile::TransportKind;
use crate::transport::Transport;

/// Direction of rotation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Direction {
    /// Forward.
    #[default]
    Forward,
    /// Reverse.
    Reverse,
}

/// The status roles a drive reports, each `None` where its map gives no such role.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Status {
    /// Running.
    pub running: Option<bool>,
    /// Turning (or about to turn) in reverse.
    pub reversing: Option<bool>,
    /// Tripped by a fault.
    pub fault: Option<bool>,
    /// An alarm without a trip.
    pub alarm: Option<bool>,
    /// Ready to run.
    pub ready: Option<bool>,
    /// At zero speed.
    pub zero_speed: Option<bool>,
    /// At the reference.
    pub speed_agree: Option<bool>,
    /// Ramping up.
    pub accelerating: Option<bool>,
    /// Ramping down to a lower reference.
    pub decelerating: Option<bool>,
    /// Ramping down after stop.
    pub stopping: Option<bool>,
    /// In operating (DRV) mode.
    pub drive_mode: Option<bool>,
}

impl Status {
    /// The roles that hold, by role id, space-separated ("-" when none).
    pub fn flags(&self) -> String {
        let on: Vec<&str> = self
            .each()
            .filter(|(_, v)| *v == Some(true))
            .map(|(r, _)| r.id())
            .collect();
        if on.is_empty() {
            "-".into()
        } else {
            on.join(" ")
        }
    }

    /// Every status role with its value.
    pub fn each(&self) -> impl Iterator<Item = (Role, Option<bool>)> {
        [
            (Role::Running, self.running),
            (Role::Reversing, self.reversing),
            (Role::Fault, self.fault),
            (Role::Alarm, self.alarm),
            (Role::Ready, self.ready),
            (Role::ZeroSpeed, self.zero_speed),
            (Role::SpeedAgree, self.speed_agree),
            (Role::Accelerating, self.accelerating),
            (Role::Decelerating, self.decelerating),
            (Role::Stopping, self.stopping),
            (Role::DriveMode, self.drive_mode),
        ]
        .into_iter()
    }

    fn slot(&mut self, role: Role) -> Option<&mut Option<bool>> {
        Some(match role {
            Role::Running => &mut self.running,
            Role::Reversing => &mut self.reversing,
            Role::Fault => &mut self.fault,
            Role::Alarm => &mut self.alarm,
            Role::Ready => &mut self.ready,
            Role::ZeroSpeed => &mut self.zero_speed,
            Role::SpeedAgree => &mut self.speed_agree,
            Role::Accelerating => &mut self.accelerating,
            Role::Decelerating => &mut self.decelerating,
            Role::Stopping => &mut self.stopping,
            Role::DriveMode => &mut self.drive_mode,
            _ => return None,
        })
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.flags())
    }
}

/// A fault code as the drive reports it, with the map's name for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultCode {
    /// The raw code.
    pub code: u16,
    /// The map's name of the code, if it lists it.
    pub name: Option<&'static str>,
}

/// The standard parts of a variable-frequency drive, for every mapped drive.
///
/// Quantities are in the role's unit (Hz, s, A, V); each write is range-checked by the
/// register's conversion before anything is sent.
pub trait VariableFrequencyDrive {
    /// The drive's map id.
    fn drive_id(&self) -> &'static str;
    /// Whether the map gives `role` on this link.
    fn supports(&self, role: Role) -> bool;
    /// Runs in the direction set.
    fn run(&mut self) -> Result<(), Error>;
    /// Stops (ramp to stop, as the drive's stop command does).
    fn stop(&mut self) -> Result<(), Error>;
    /// Sets the direction; takes effect with the next run (or at once while running, where the
    /// drive's command word carries the direction).
    fn set_direction(&mut self, direction: Direction) -> Result<(), Error>;
    /// Writes the frequency reference (Hz).
    fn set_reference(&mut self, hz: f64) -> Result<(), Error>;
    /// Writes the acceleration and deceleration times (s).
    fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error>;
    /// The frequency reference in force (Hz).
    fn reference(&mut self) -> Result<f64, Error>;
    /// Output frequency (Hz).
    fn output_frequency(&mut self) -> Result<f64, Error>;
    /// Output current (A).
    fn output_current(&mut self) -> Result<f64, Error>;
    /// Output voltage (V).
    fn output_voltage(&mut self) -> Result<f64, Error>;
    /// DC bus voltage (V).
    fn dc_bus_voltage(&mut self) -> Result<f64, Error>;
    /// The status roles the map gives.
    fn status(&mut self) -> Result<Status, Error>;
    /// The fault code.
    fn fault_code(&mut self) -> Result<FaultCode, Error>;
    /// Resets a fault: sets the reset command and releases it (an edge-triggered reset is
    /// released first if it was left set).
    fn reset_fault(&mut self) -> Result<(), Error>;
}

/// A drive on slave `slave` of a blocking client, read and written through its plan and roles:
/// the [`VariableFrequencyDrive`] of every drive whose map has roles. Build it from a generated
/// module with [`Vfd::new`] or [`Vfd::connect`], or from a plan lowered at run time with
/// [`Vfd::from_plan`].
pub struct Vfd<'c, S: SettingsView, T: Transport> {
    client: &'c mut Client<T>,
    slave: u8,
    settings: S,
    registers: &'static [RegisterPlan],
    roles: Roles,
    kind: TransportKind,
    direction: Direction,
    /// What this master last wrote to each command register: (plan row, word).
    shadow: Vec<(u16, u16)>,
}

impl<'c, S: SettingsView, T: Transport> Vfd<'c, S, T> {
    /// The drive of generated module `D` on `slave`, with `settings` as conversions need them
    /// (fill them with [`Client::load_settings`] and the external quantities the map names, or
    /// use [`Vfd::connect`]).
    pub fn new<D: DrivePlan<Settings = S>>(
        client: &'c mut Client<T>,
        slave: u8,
        settings: S,
    ) -> Self {
        Self::from_plan(client, slave, settings, D::REGISTERS, D::ROLES)
    }

    /// The drive on `slave` described by `registers` (the plan's rows, by address) and `roles`,
    /// with `settings` in force: for tools that lower a map at run time.
    pub fn from_plan(
        client: &'c mut Client<T>,
        slave: u8,
        settings: S,
        registers: &'static [RegisterPlan],
        roles: Roles,
    ) -> Self {
        let kind = client.transport().kind();
        let mut shadow: Vec<(u16, u16)> = Vec::new();
        for p in roles.places {
            if let (RoleKind::Command, Target::Field(f)) = (p.role.kind(), p.target) {
                let word = match shadow.iter_mut().find(|(row, _)| *row == f.row) {
                    Some((_, w)) => w,
                    None => {
                        shadow.push((f.row, 0));
                        &mut shadow.last_mut().expect("just pushed").1
                    }
                };
                *word = f.put(*word, f.code(false));
            }
        }
        Vfd {
            client,
            slave,
            settings,
            registers,
            roles,
            kind,
            direction: Direction::Forward,
            shadow,
        }
    }

    /// The drive of generated module `D` on `slave`: reads the parameters its conversions
    /// depend on, and takes the external quantities (name, value) the application supplies.
    pub fn connect<D: DrivePlan<Settings = S>>(
        client: &'c mut Client<T>,
        slave: u8,
        mut settings: S,
        externals: &[(&str, f64)],
    ) -> Result<Self, Error>
    where
        S: DriveSettings,
    {
        if client.profile().drive_id != D::PROFILE.drive_id {
            return Err(Refusal::OtherDrive {
                client: client.profile().drive_id,
                drive: D::PROFILE.drive_id,
            }
            .into());
        }
        for (name, value) in externals {
            if !settings.set_external(name, *value) {
                return Err(Refusal::UnknownExternal {
                    drive: client.profile().drive_id,
                    name: (*name).to_owned(),
                }
                .into());
            }
        }
        client.load_settings(slave, &mut settings)?;
        Ok(Self::new::<D>(client, slave, settings))
    }

    fn drive(&self) -> &'static str {
        self.client.profile().drive_id
    }

    /// The settings in force.
    pub fn settings(&self) -> &S {
        &self.settings
    }

    /// The client.
    pub fn client(&mut self) -> &mut Client<T> {
        self.client
    }

    fn row(&self, row: u16) -> &'static RegisterPlan {
        &self.registers[usize::from(row)]
    }

    /// Whether a place can be used on this link to this slave.
    fn usable(&self, p: &Place) -> bool {
        match p.target.row() {
            Some(row) => {
                let r = self.row(row);
                let broadcast = self.slave == 0;
                r.transports.contains(self.kind)
                    && match r.broadcast {
                        Broadcast::Only => broadcast,
                        Broadcast::Also => true,
                        Broadcast::No => !broadcast,
                    }
            }
            None => true,
        }
    }

    /// The first place of `role` usable here, or why there is none.
    fn place(&self, role: Role, what: &'static str) -> Result<&'static Place, Error> {
        let mut any = false;
        for p in self.roles.of(role) {
            any = true;
            if self.usable(p) {
                return Ok(p);
            }
        }
        Err(Refusal::NoRole {
            drive: self.drive(),
            role: role.id(),
            what,
            transport: any.then_some(self.kind),
        }
        .into())
    }

    /// The raw value of plan row `row`: its word, or a 32-bit pair read in one request.
    fn read_raw(&mut self, row: u16) -> Result<u32, Error> {
        let r = self.row(row);
        let address = r.address_for(&self.settings, self.kind);
        let mut raw = [0u16; 2];
        let words = &mut raw[..usize::from(r.info.width.count())];
        match r.info.table {
            Table::Input => self.client.read_input(self.slave, address, words)?,
            Table::Holding => self.client.read_holding(self.slave, address, words)?,
        }
        Ok(r.info.width.join(words))
    }

    /// The word of a one-register row (bit fields and codes: the map keeps them in one word).
    fn read_word(&mut self, row: u16) -> Result<u16, Error> {
        Ok(self.read_raw(row)? as u16)
    }

    fn write_word(&mut self, row: u16, raw: u32) -> Result<(), Error> {
        let r = self.row(row);
        let address = r.address_for(&self.settings, self.kind);
        let rule = r.write_rule();
        match r.repeat_needs_change {
            // A role register whose drive executes only a changed value: its intermediate first.
            Some(x) => self
                .client
                .write_changed(self.slave, &rule, address, x.between, raw),
            None => self.client.write_rule(self.slave, &rule, address, raw),
        }
    }

    /// Reads the number role `role` in its unit.
    fn read_number(&mut self, role: Role) -> Result<f64, Error> {
        let p = self.place(role, "register")?;
        match p.target {
            Target::Register(row) => {
                let raw = self.read_raw(row)?;
                Ok(self.row(row).decode_number(raw, &self.settings)?)
            }
            Target::External { slot, name } => self.settings.quantity(slot).ok_or_else(|| {
                Refusal::ExternalNotSet {
                    drive: self.drive(),
                    name,
                }
                .into()
            }),
            Target::Field(_) => Err(self.misplaced(role, "register")),
        }
    }

    /// Writes the number role `role`, range-checked by the register's conversion.
    fn write_number(&mut self, role: Role, value: f64) -> Result<(), Error> {
        let p = self.place(role, "register")?;
        let Target::Register(row) = p.target else {
            return Err(self.misplaced(role, "writable register"));
        };
        let raw = self.row(row).encode_number(value, &self.settings)?;
        self.write_word(row, raw)
    }

    /// Sets the command fields of `changes` in their registers' words and writes each word once,
    /// in the order of `changes`. The copy of what was written is updated only after a write
    /// succeeds: a refused run is never sent again by a later, unrelated command.
    fn command(&mut self, changes: &[(FieldRole, bool)]) -> Result<(), Error> {
        let mut words: Vec<(u16, u16)> = Vec::new();
        for (f, on) in changes {
            let Some(&(_, written)) = self.shadow.iter().find(|(row, _)| *row == f.row) else {
                continue;
            };
            match words.iter_mut().find(|(row, _)| *row == f.row) {
                Some((_, word)) => *word = f.put(*word, f.code(*on)),
                None => words.push((f.row, f.put(written, f.code(*on)))),
            }
        }
        for (row, word) in words {
            self.write_word(row, u32::from(word))?;
            if let Some((_, written)) = self.shadow.iter_mut().find(|(r, _)| *r == row) {
                *written = word;
            }
        }
        Ok(())
    }

    fn field(&self, role: Role) -> Result<Option<FieldRole>, Error> {
        match self.place(role, "field") {
            Ok(Place {
                target: Target::Field(f),
                ..
            }) => Ok(Some(*f)),
            Ok(_) => Ok(None),
            Err(Error::Refused(Refusal::NoRole { .. })) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// The command fields that run (`true`) or stop in the direction set, the direction first
    /// (registers are written in this order).
    fn run_fields(&self, run: bool) -> Result<Vec<(FieldRole, bool)>, Error> {
        let reverse = self.direction == Direction::Reverse;
        let mut out = Vec::new();
        if let Some(f) = self.field(Role::Run)? {
            out.push((f, run));
            match (reverse, self.field(Role::Reverse)?) {
                // The direction goes first: where it is a register of its own, the drive must
                // not start in the old direction.
                (_, Some(r)) => out.insert(0, (r, reverse)),
                (true, None) => {
                    if let Some(rr) = self.field(Role::RunReverse)? {
                        // Run with the reverse terminal instead.
                        out[0].1 = false;
                        out.push((rr, run));
                    } else if run {
                        return Err(self.no_reverse());
                    }
                }
                (false, None) => {}
            }
            return Ok(out);
        }
        let forward = self.field(Role::RunForward)?;
        let backward = self.field(Role::RunReverse)?;
        match (forward, backward) {
            (None, None) => Err(self.place(Role::Run, "field").unwrap_err()),
            (f, b) => {
                if reverse && b.is_none() && run {
                    return Err(self.no_reverse());
                }
                if !reverse && f.is_none() && run {
                    return Err(self
                        .place(Role::RunForward, "field")
                        .err()
                        .unwrap_or_else(|| self.no_reverse()));
                }
                out.extend(f.map(|f| (f, run && !reverse)));
                out.extend(b.map(|b| (b, run && reverse)));
                Ok(out)
            }
        }
    }

    /// A plan whose role names the wrong kind of place (validation refuses such maps; a plan
    /// built by hand may still have one).
    fn misplaced(&self, role: Role, what: &'static str) -> Error {
        Refusal::NoRole {
            drive: self.drive(),
            role: role.id(),
            what,
            transport: None,
        }
        .into()
    }

    fn no_reverse(&self) -> Error {
        Refusal::NoRole {
            drive: self.drive(),
            role: Role::Reverse.id(),
            what: "way to run in reverse",
            transport: None,
        }
        .into()
    }
}

impl<S: SettingsView, T: Transport> VariableFrequencyDrive for Vfd<'_, S, T> {
    fn drive_id(&self) -> &'static str {
        self.drive()
    }

    fn supports(&self, role: Role) -> bool {
        self.roles.of(role).any(|p| self.usable(p))
    }

    fn run(&mut self) -> Result<(), Error> {
        let fields = self.run_fields(true)?;
        self.command(&fields)
    }

    fn stop(&mut self) -> Result<(), Error> {
        let fields = self.run_fields(false)?;
        self.command(&fields)
    }

    fn set_direction(&mut self, direction: Direction) -> Result<(), Error> {
        let before = self.direction;
        self.direction = direction;
        let result = match self.field(Role::Reverse)? {
            // The direction is a field of its own: write it now.
            Some(r) => self.command(&[(r, direction == Direction::Reverse)]),
            // The direction is the choice of run terminal: check there is one.
            None if direction == Direction::Reverse && !self.supports(Role::RunReverse) => {
                Err(self.no_reverse())
            }
            None => Ok(()),
        };
        if result.is_err() {
            self.direction = before;
        }
        result
    }

    fn set_reference(&mut self, hz: f64) -> Result<(), Error> {
        self.write_number(Role::FrequencyReference, hz)
    }

    fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error> {
        // Check both are writable before writing either.
        self.place(Role::AccelTime, "register")?;
        self.place(Role::DecelTime, "register")?;
        self.write_number(Role::AccelTime, accel_s)?;
        self.write_number(Role::DecelTime, decel_s)
    }

    fn reference(&mut self) -> Result<f64, Error> {
        self.read_number(Role::ReferenceMonitor)
    }

    fn output_frequency(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputFrequency)
    }

    fn output_current(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputCurrent)
    }

    fn output_voltage(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputVoltage)
    }

    fn dc_bus_voltage(&mut self) -> Result<f64, Error> {
        self.read_number(Role::DcBusVoltage)
    }

    fn status(&mut self) -> Result<Status, Error> {
        let mut status = Status::default();
        // One read per register, whichever roles share it.
        let mut words: Vec<(u16, u16)> = Vec::new();
        for &role in Role::ALL {
            if role.kind() != RoleKind::Status {
                continue;
            }
            let Ok(Place {
                target: Target::Field(f),
                ..
            }) = self.place(role, "field")
            else {
                continue;
            };
            let word = match words.iter().find(|(row, _)| *row == f.row) {
                Some(&(_, w)) => w,
                None => {
                    let w = self.read_word(f.row)?;
                    words.push((f.row, w));
                    w
                }
            };
            if let Some(slot) = status.slot(role) {
                *slot = Some(f.holds(word));
            }
        }
        Ok(status)
    }

    fn fault_code(&mut self) -> Result<FaultCode, Error> {
        let p = self.place(Role::FaultCode, "register")?;
        let Some(row) = p.target.row() else {
            return Err(self.misplaced(Role::FaultCode, "register"));
        };
        let code = self.read_word(row)?;
        Ok(FaultCode {
            code,
            name: self.row(row).label(code).map(|l| l.name),
        })
    }

    fn reset_fault(&mut self) -> Result<(), Error> {
        let p = self.place(Role::FaultReset, "field")?;
        let Target::Field(f) = p.target else {
            return Err(self.misplaced(Role::FaultReset, "field"));
        };
        let set = self
            .shadow
            .iter()
            .find(|(row, _)| *row == f.row)
            .is_some_and(|(_, w)| f.holds(*w));
        if f.edge && set {
            self.command(&[(f, false)])?;
        }
        self.command(&[(f, true)])?;
        self.command(&[(f, false)])
    }
}
