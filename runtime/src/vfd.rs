//! One API for every mapped drive: [`VariableFrequencyDrive`] — run, stop, direction, frequency
//! reference, ramps, output monitors, status, fault code and reset — implemented once, by
//! [`Vfd`], over the roles a map gives ([`Roles`]) and the plan rows they name.
//!
//! An application written against the trait runs on any drive whose map has roles:
//!
//! ```
//! use drivemap_runtime::vfd::{Direction, VariableFrequencyDrive};
//! use drivemap_runtime::error::Error;
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
//! A drive acts on network run commands and references only while its source parameters
//! select the network (V7 n003 = 2 and n004 = 6 on its RTU port; the map's `command_source`
//! and `reference_source` roles). [`VariableFrequencyDrive::run`] and
//! [`VariableFrequencyDrive::set_reference`] read that parameter first and refuse with
//! [`Refusal::NotNetworkSource`] — "the drive takes run commands from \"Terminal Strip\" (n003
//! = 1); set n003 = 2 (...) for the network" — instead of sending a command the drive would
//! accept and ignore. A source found to be the network is kept (read once per [`Vfd`], until
//! [`Vfd::forget_sources`]); one that is not is read again at the next call, so setting it and
//! calling again works.
//! [`VariableFrequencyDrive::stop`] is never refused for its source. A map that gives no
//! source role for the link (or marks it not printed) is not checked.
//!
//! Command words are composed from what the [`Vfd`] last told the drive, never from hope: the
//! run command of a drive is owned by one master, and every command register starts released
//! (stopped, forward, no reset). See [the safety contract](#safety-contract).
//!
//! # Safety contract
//!
//! Each guarantee is proved by the test named after it (in `tests/tests/`); the fault-injection
//! property test `drive_contract::the_contract_holds_under_faults` checks the run-code, stop
//! and limit guarantees on random call sequences with lost, late and refused replies and
//! reconnects, on every map of `maps/`, the `acme-vf1` fixture (with two variants whose roles
//! share a register) and the command-profile fixtures (CiA 402, PROFIdrive, ABB Drives, with
//! coast, quick stop and a stop at the drive's panel among the steps), over RTU framing and
//! Modbus TCP, through the blocking [`Vfd`] and the
//! async `AsyncVfd` (feature `tokio`; one body of code for both, awaited in the async one).
//!
//! A `Vfd` borrows its client (`Vfd::connect::<D>(&mut client, ..)`) or owns it
//! (`Vfd::connect::<D>(client, ..)`, [`Vfd::into_client`] to take it back): see
//! [`HoldsClient`]. Owned, it can live next to nothing else, in a thread or a tokio task.
//!
//! - A run bit or run code is written only by [`VariableFrequencyDrive::run`], or by a later call
//!   while the last of `run()` and `stop()` called was a `run()` that succeeded (which keeps the
//!   drive running, in the direction set): `drive_contract::the_contract_holds_under_faults`.
//! - After a [`VariableFrequencyDrive::stop`] call, successful or not, no call but `run()` makes
//!   the drive run again, whatever became of the stop's frames:
//!   `drive_contract::a_stop_whose_replies_were_lost_stays_a_stop`.
//! - A run that failed is not sent again by a later, unrelated command (a master that does not
//!   know whether the drive started errs towards stop):
//!   `drive_trait::a_command_that_failed_is_not_resent_by_the_next`.
//! - After a failed write of a command register, the register is unknown: the next command
//!   re-reads it where the map lets it be read on the link (keeping the drive's other bits),
//!   and composes from the released state (stop, no reset, the direction set) where it cannot:
//!   `drive_contract::an_unknown_command_register_is_read_again_or_released`.
//! - Every value goes out through the register's conversion and the client's write gate, or
//!   not at all: `drive_contract::the_contract_holds_under_faults` checks every word that
//!   reached the wire against the limits in force.
//! - A run or a reference the drive would ignore (its source parameter, the map's
//!   `command_source` / `reference_source`, does not select the network on the link) is refused
//!   with what to set, [`Refusal::NotNetworkSource`], and nothing is sent; `stop()` is never
//!   refused for it:
//!   `drive_trait::run_is_refused_at_the_factory_setting_and_works_after_setting_the_source`.
//! - A role the map does not give on the link is refused ([`Refusal::NoRole`]) before anything
//!   is sent: `drive_trait::one_routine_runs_every_drive_over_serial_framing`.
//! - Where the map says two roles are one register (`shared_with`), a call that would give
//!   them different values is refused ([`Refusal::SharedRegister`]) before anything is sent, and
//!   `set_ramp(a, a)` writes the register once: `drive_contract::one_ramp_register_takes_one_value`.
//! - A fault reset acts where the drive acts on the edge and where the manual does not print
//!   edge or level (`edge: {unknown: ..}`, [`Edge::NotPrinted`](drivemap_core::roles::Edge)):
//!   a reset that may still be set is released first, then set, then released, so every
//!   `reset_fault()` that succeeds leaves the reset released and the drive reset, under lost,
//!   late and refused replies: `roles_in_fields::a_reset_of_unknown_edge_acts_under_faults`.
//! - A number role in a field of a register (a fault code in a status byte) is read from its
//!   bits, sign-extended where the map says `signed`; a setpoint there is written by reading
//!   the word and writing it back with the field changed only where the register is readable
//!   on the link, reads mean what writes do, and no command field shares it, else refused
//!   ([`Refusal::FieldNotWritable`]) before anything is sent:
//!   `roles_in_fields::a_setpoint_on_a_field_is_refused_where_read_modify_write_is_not_safe`.
//! - A write of some fields of a command register ([`Vfd::write_command_fields`]; `drivemap
//!   write reg=field=value` composes with [`Vfd::command_fields_word`]) never sends a run or a
//!   reset the write does not name from a word read back: the reset and every edge command
//!   released, a run kept only while this master's `run()` stands or the status shows the drive
//!   running: `roles_in_fields::a_command_field_is_written_from_the_roles_not_from_a_read_back`.
//! - On a drive with a command profile (a control-word state machine, the map's `profile:`,
//!   [`CommandProfile`](drivemap_core::command_profile::CommandProfile)), `run()` reads the status word and writes the run path's transitions in
//!   order, each verified in the status word within its time limit, else
//!   [`Error::StateMachine`] naming the state the drive is in:
//!   `drive_contract::command_profiles::run_and_stops_walk_the_machine_from_power_on`,
//!   `drive_contract::command_profiles::a_refused_transition_times_out_naming_the_state`.
//!   `stop()`, `coast()` and `quick_stop()` take their paths and never a run transition (one
//!   leading where the run path ends), and no word composed, read back or written by field asks
//!   for one unless the last of `run()` and `stop()` was a `run()` that succeeded:
//!   `drive_contract::the_contract_holds_under_faults` (which plays the profile fixtures) and
//!   `drive_contract::command_profiles::a_stop_path_through_a_run_transition_is_refused`.
//!   `reset_fault()` writes nothing outside the fault state and gives the acknowledge edge in it:
//!   `drive_contract::command_profiles::a_trip_needs_the_acknowledge_edge_in_the_fault_state`.

use std::fmt;

use drivemap_core::plan::RegisterPlan;
use drivemap_core::plan::SettingsView;
use drivemap_core::register::{DrivePlan, DriveSettings};
use drivemap_core::roles::Role;
use drivemap_core::roles::Roles;
use drivemap_core::scale::Rounding;

#[cfg(feature = "tokio")]
use crate::async_client::{AsyncClient, AsyncTransport};
use crate::client::Client;
use crate::error::{Error, Refusal};
use crate::transport::Transport;
#[cfg(feature = "tokio")]
use crate::wire::Tokio;
use crate::wire::{Blocking, block_on};

mod machine;

use machine::{CommandWord, Machine, State};

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
#[non_exhaustive]
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
#[non_exhaustive]
pub struct FaultCode {
    /// The raw code: the register's word, or the bits of the field the map names (a fault code
    /// in the status word's high byte: that byte).
    pub code: u16,
    /// The code as a number: sign-extended where the map says the register or field is signed,
    /// else `code`.
    pub value: i32,
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
    /// Runs in the direction set. Refused ([`Refusal::NotNetworkSource`]) when the drive's run
    /// command source (the map's `command_source`) is not the network on this link.
    fn run(&mut self) -> Result<(), Error>;
    /// Stops (ramp to stop, as the drive's stop command does).
    fn stop(&mut self) -> Result<(), Error>;
    /// Sets the direction; takes effect with the next run (or at once while running, where the
    /// drive's command word carries the direction).
    fn set_direction(&mut self, direction: Direction) -> Result<(), Error>;
    /// Writes the frequency reference (Hz). Refused before sending when it is not a value of
    /// the register (its range, its limit through another quantity, a whole number of its
    /// increments) or, where the map gives the `max_frequency` role, above that maximum (read
    /// from the drive first, or the external quantity from the settings).
    /// Also refused ([`Refusal::NotNetworkSource`]) when the
    /// drive's reference source (the map's `reference_source`) is not the network on this link.
    fn set_reference(&mut self, hz: f64) -> Result<(), Error>;
    /// Writes the acceleration and deceleration times (s). Where the drive has one register
    /// for both (the map's `shared_with`), different times are refused
    /// ([`Refusal::SharedRegister`]) and equal ones written once.
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
    /// The code of the active fault (the map's `fault_code`).
    fn fault_code(&mut self) -> Result<FaultCode, Error>;
    /// The code of the last fault the drive recorded, kept after a reset (the map's
    /// `last_fault`: a fault history register). Refused ([`Refusal::NoRole`]) where the map
    /// gives no such role.
    fn last_fault(&mut self) -> Result<FaultCode, Error> {
        Err(Refusal::NoRole {
            drive: self.drive_id(),
            role: Role::LastFault.id(),
            what: "register",
            transport: None,
        }
        .into())
    }
    /// Resets a fault: sets the reset command and releases it (an edge-triggered reset is
    /// released first if it was left set). On a drive with a command profile: gives the
    /// acknowledge edge of the profile's `reset_fault` path, only while the drive shows the
    /// fault state (nothing is written otherwise).
    fn reset_fault(&mut self) -> Result<(), Error>;
    /// The state of the drive's command profile the status word shows, by id
    /// (`operation_enabled`): `None` for a drive without a command profile, or a status word
    /// that shows no state of it.
    fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        Ok(None)
    }
    /// Coasts to a stop (the output off at once): the `coast` path of the drive's command
    /// profile. Refused ([`Refusal::NoRole`]) where the map gives no such path.
    fn coast(&mut self) -> Result<(), Error> {
        Err(Refusal::NoRole {
            drive: self.drive_id(),
            role: "coast",
            what: "command profile path",
            transport: None,
        }
        .into())
    }
    /// Stops on the drive's quick-stop ramp: the `quick_stop` path of the drive's command
    /// profile. Refused ([`Refusal::NoRole`]) where the map gives no such path.
    fn quick_stop(&mut self) -> Result<(), Error> {
        Err(Refusal::NoRole {
            drive: self.drive_id(),
            role: "quick_stop",
            what: "command profile path",
            transport: None,
        }
        .into())
    }
}

/// The [`VariableFrequencyDrive`] of the async client: the same calls, awaited, with the same
/// contract (see [the module](self)); implemented by [`AsyncVfd`], the same code as [`Vfd`]'s
/// over an [`AsyncClient`].
#[cfg(feature = "tokio")]
#[cfg_attr(docsrs, doc(cfg(feature = "tokio")))]
// The futures are not promised `Send` (the lint's concern): like `AsyncTransport`'s, they
// run on the task that drives the client.
#[allow(async_fn_in_trait)]
pub trait AsyncVariableFrequencyDrive {
    /// The drive's map id.
    fn drive_id(&self) -> &'static str;
    /// Whether the map gives `role` on this link.
    fn supports(&self, role: Role) -> bool;
    /// As [`VariableFrequencyDrive::run`].
    async fn run(&mut self) -> Result<(), Error>;
    /// As [`VariableFrequencyDrive::stop`].
    async fn stop(&mut self) -> Result<(), Error>;
    /// As [`VariableFrequencyDrive::set_direction`].
    async fn set_direction(&mut self, direction: Direction) -> Result<(), Error>;
    /// As [`VariableFrequencyDrive::set_reference`].
    async fn set_reference(&mut self, hz: f64) -> Result<(), Error>;
    /// As [`VariableFrequencyDrive::set_ramp`].
    async fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error>;
    /// As [`VariableFrequencyDrive::reference`].
    async fn reference(&mut self) -> Result<f64, Error>;
    /// As [`VariableFrequencyDrive::output_frequency`].
    async fn output_frequency(&mut self) -> Result<f64, Error>;
    /// As [`VariableFrequencyDrive::output_current`].
    async fn output_current(&mut self) -> Result<f64, Error>;
    /// As [`VariableFrequencyDrive::output_voltage`].
    async fn output_voltage(&mut self) -> Result<f64, Error>;
    /// As [`VariableFrequencyDrive::dc_bus_voltage`].
    async fn dc_bus_voltage(&mut self) -> Result<f64, Error>;
    /// As [`VariableFrequencyDrive::status`].
    async fn status(&mut self) -> Result<Status, Error>;
    /// As [`VariableFrequencyDrive::fault_code`].
    async fn fault_code(&mut self) -> Result<FaultCode, Error>;
    /// As [`VariableFrequencyDrive::last_fault`].
    async fn last_fault(&mut self) -> Result<FaultCode, Error> {
        Err(Refusal::NoRole {
            drive: self.drive_id(),
            role: Role::LastFault.id(),
            what: "register",
            transport: None,
        }
        .into())
    }
    /// As [`VariableFrequencyDrive::reset_fault`].
    async fn reset_fault(&mut self) -> Result<(), Error>;
    /// As [`VariableFrequencyDrive::profile_state`].
    async fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        Ok(None)
    }
    /// As [`VariableFrequencyDrive::coast`].
    async fn coast(&mut self) -> Result<(), Error> {
        Err(Refusal::NoRole {
            drive: self.drive_id(),
            role: "coast",
            what: "command profile path",
            transport: None,
        }
        .into())
    }
    /// As [`VariableFrequencyDrive::quick_stop`].
    async fn quick_stop(&mut self) -> Result<(), Error> {
        Err(Refusal::NoRole {
            drive: self.drive_id(),
            role: "quick_stop",
            what: "command profile path",
            transport: None,
        }
        .into())
    }
}

/// How a [`Vfd`] holds its blocking client: borrowed (`&mut Client<T>`) or owned (`Client<T>`,
/// `Box<Client<T>>`), so that a `Vfd` can own its client and be moved into a thread.
pub trait HoldsClient {
    /// The client's link.
    type Transport: Transport;
    /// The client.
    fn get(&self) -> &Client<Self::Transport>;
    /// The client, to use it.
    fn get_mut(&mut self) -> &mut Client<Self::Transport>;
}

/// How an [`AsyncVfd`] holds its async client: borrowed (`&mut AsyncClient<T>`) or owned
/// (`AsyncClient<T>`, `Box<AsyncClient<T>>`), so that an `AsyncVfd` can own its client and be
/// moved into a task.
#[cfg(feature = "tokio")]
#[cfg_attr(docsrs, doc(cfg(feature = "tokio")))]
pub trait HoldsAsyncClient {
    /// The client's link.
    type Transport: AsyncTransport;
    /// The client.
    fn get(&self) -> &AsyncClient<Self::Transport>;
    /// The client, to use it.
    fn get_mut(&mut self) -> &mut AsyncClient<Self::Transport>;
}

impl<T: Transport> HoldsClient for Client<T> {
    type Transport = T;
    fn get(&self) -> &Client<T> {
        self
    }
    fn get_mut(&mut self) -> &mut Client<T> {
        self
    }
}

impl<T: Transport> HoldsClient for &mut Client<T> {
    type Transport = T;
    fn get(&self) -> &Client<T> {
        self
    }
    fn get_mut(&mut self) -> &mut Client<T> {
        self
    }
}

impl<T: Transport> HoldsClient for Box<Client<T>> {
    type Transport = T;
    fn get(&self) -> &Client<T> {
        self
    }
    fn get_mut(&mut self) -> &mut Client<T> {
        self
    }
}

#[cfg(feature = "tokio")]
impl<T: AsyncTransport> HoldsAsyncClient for AsyncClient<T> {
    type Transport = T;
    fn get(&self) -> &AsyncClient<T> {
        self
    }
    fn get_mut(&mut self) -> &mut AsyncClient<T> {
        self
    }
}

#[cfg(feature = "tokio")]
impl<T: AsyncTransport> HoldsAsyncClient for &mut AsyncClient<T> {
    type Transport = T;
    fn get(&self) -> &AsyncClient<T> {
        self
    }
    fn get_mut(&mut self) -> &mut AsyncClient<T> {
        self
    }
}

#[cfg(feature = "tokio")]
impl<T: AsyncTransport> HoldsAsyncClient for Box<AsyncClient<T>> {
    type Transport = T;
    fn get(&self) -> &AsyncClient<T> {
        self
    }
    fn get_mut(&mut self) -> &mut AsyncClient<T> {
        self
    }
}

/// A drive on slave `slave` of a blocking client, read and written through its plan and roles:
/// the [`VariableFrequencyDrive`] of every drive whose map has roles. Build it from a generated
/// module with [`Vfd::new`] or [`Vfd::connect`], or from a plan lowered at run time with
/// [`Vfd::from_plan`]. It holds its client as `C` ([`HoldsClient`]): `&mut Client<T>` to borrow
/// it, `Client<T>` to own it.
pub struct Vfd<S: SettingsView, C: HoldsClient> {
    client: C,
    state: State<S>,
}

/// A drive on slave `slave` of an async client: the [`AsyncVariableFrequencyDrive`], the same
/// code as [`Vfd`] with each request awaited. It holds its client as `C` ([`HoldsAsyncClient`]):
/// `AsyncClient<T>` to own it (and move the drive into a task), `&mut AsyncClient<T>` to borrow
/// it.
#[cfg(feature = "tokio")]
#[cfg_attr(docsrs, doc(cfg(feature = "tokio")))]
pub struct AsyncVfd<S: SettingsView, C: HoldsAsyncClient> {
    client: C,
    state: State<S>,
}

/// What a [`Vfd`] or an [`AsyncVfd`] knows of its drive besides its client and settings, to
/// carry from one drive object to the next ([`Vfd::memory`], [`Vfd::with_memory`]).
#[derive(Debug, Clone)]
pub struct Memory {
    direction: Direction,
    running: Option<Direction>,
    commands: Vec<CommandWord>,
    sources: [bool; 2],
}

impl<S: SettingsView, C: HoldsClient> Vfd<S, C> {
    /// The drive of generated module `D` on `slave`, with `settings` as conversions need them
    /// (fill them with [`Client::load_settings`] and the external quantities the map names, or
    /// use [`connect`](Self::connect)).
    pub fn new<D: DrivePlan<Settings = S>>(client: C, slave: u8, settings: S) -> Self {
        Self::from_plan(client, slave, settings, D::REGISTERS, D::ROLES)
    }

    /// The drive on `slave` described by `registers` (the plan's rows, by address) and `roles`,
    /// with `settings` in force: for tools that lower a map at run time.
    pub fn from_plan(
        mut client: C,
        slave: u8,
        settings: S,
        registers: &'static [RegisterPlan],
        roles: Roles,
    ) -> Self {
        let kind = client.get_mut().transport().kind();
        Vfd {
            client,
            state: State::new(slave, settings, registers, roles, kind),
        }
    }

    /// The drive of generated module `D` on `slave`: reads the parameters its conversions
    /// depend on, and takes the external quantities (name, value) the application supplies.
    pub fn connect<D: DrivePlan<Settings = S>>(
        mut client: C,
        slave: u8,
        mut settings: S,
        externals: &[(&str, f64)],
    ) -> Result<Self, Error>
    where
        S: DriveSettings,
    {
        let session = client.get_mut().session();
        block_on(machine::load_settings(
            session,
            D::PROFILE.drive_id,
            slave,
            &mut settings,
            externals,
        ))?;
        Ok(Self::new::<D>(client, slave, settings))
    }

    /// The drive's state and the client's session, for one call.
    fn machine(&mut self) -> Machine<'_, S, Blocking<'_, C::Transport>> {
        Machine::new(self.client.get_mut().session(), &mut self.state)
    }

    /// Chooses what a reference or a ramp time that is not a whole number of its register's
    /// steps becomes: [`Rounding::Exact`] (the default) refuses it with the two nearest values
    /// ([`ValueError::NotAStep`](drivemap_core::scale::ValueError::NotAStep)); [`Rounding::Nearest`] sends the nearest. Limits are checked on
    /// the value given either way.
    pub fn rounding(mut self, rounding: Rounding) -> Self {
        self.state.rounding = rounding;
        self
    }

    /// The settings in force.
    pub fn settings(&self) -> &S {
        &self.state.settings
    }

    /// What this drive object knows of its drive besides the client and the settings: the
    /// direction set, whether its last `run()` succeeded and was not followed by a `stop()`,
    /// what each command register was last told, the sources found to be the network. For a
    /// program that keeps one drive for its life but builds the drive object around a client it
    /// shares (a bridge polling a line between commands): take the memory before giving the
    /// client back, and give it to the next drive object with [`with_memory`](Self::with_memory),
    /// so that a later command composes from what was told, never from a fresh start.
    pub fn memory(&self) -> Memory {
        self.state.memory()
    }

    /// This drive object with what an earlier one of the same map knew ([`memory`](Self::memory)).
    /// A memory of other command registers (another map's) is not taken.
    pub fn with_memory(mut self, memory: Memory) -> Self {
        self.state.remember(memory);
        self
    }

    /// Forgets what the command registers were told: the next command to each reads it back
    /// where the map lets it be read on the link (keeping the bits other masters or field
    /// writes set) and composes from the released word where it cannot, as after a failed
    /// write. For a master that starts while the drive may already hold a command word.
    pub fn forget_commands(&mut self) {
        self.state.forget_commands();
    }

    /// Takes the direction the drive reports as the direction set, for a master that has not
    /// set one, so that a later `run()` keeps the direction the drive turns in instead of
    /// reversing it: the direction field of its command register read back where the map lets
    /// it be read on this link (what the drive was last told, by any master), else the status
    /// role `reversing`. Returns the direction taken, or `None` where the drive reports none
    /// (the direction set stays).
    pub fn adopt_direction(&mut self) -> Result<Option<Direction>, Error> {
        block_on(self.machine().adopt_direction())
    }

    /// The client.
    pub fn client(&mut self) -> &mut Client<C::Transport> {
        self.client.get_mut()
    }

    /// The client as it was given (owned or borrowed), giving the drive up.
    pub fn into_client(self) -> C {
        self.client
    }

    /// Whether plan row `row` holds a command role (a field the trait's commands write): a
    /// write of its fields goes through [`Self::write_command_fields`].
    pub fn holds_command(&self, row: u16) -> bool {
        self.state.holds_command(row)
    }

    /// The word a write of the bits `mask` (set to `value`'s bits there) of command register
    /// `row` sends, composed from the roles as the trait's commands compose theirs, never from
    /// a word read back alone: every command field the write does not name is released —
    /// edge commands (the fault reset, any field the map marks `edge: true` or edge not printed)
    /// always, run fields (run, run forward, run reverse) unless the drive runs (this `Vfd`'s
    /// last `run()` succeeded, or the `running` status role reads true), where they are kept as
    /// read; other command fields (direction, mode) and bits that are no command are kept as
    /// read where the register can be read on this link, else released (0 for other bits).
    /// So a word read back never starts a drive or repeats a reset. Reads the register and
    /// the status role as needed; writes nothing.
    ///
    /// Refused ([`Refusal::FieldNotWritable`], nothing sent) when `row` holds no command role,
    /// when the drive runs but the register cannot be read here, so the run bits to keep
    /// are unknown (use `run()` / `stop()`), and when `row` is the control word of the drive's
    /// command profile and the word would ask it for a run transition while this drive object's
    /// last of `run()` and `stop()` is not a `run()` that succeeded (use `run()`, which walks
    /// the state machine).
    pub fn command_fields_word(&mut self, row: u16, mask: u16, value: u16) -> Result<u16, Error> {
        block_on(self.machine().command_fields_word(row, mask, value))
    }

    /// Writes the bits `mask` of command register `row` to `value`'s, the rest of the word
    /// composed by [`Self::command_fields_word`] (no run or reset bit the call does not ask for,
    /// unless the drive runs), through the client's write gate. Returns the word written; this
    /// master's record of the register follows it (unknown after a write that failed).
    pub fn write_command_fields(&mut self, row: u16, mask: u16, value: u16) -> Result<u16, Error> {
        block_on(self.machine().write_command_fields(row, mask, value))
    }

    /// The state of the command profile the drive shows in its status word, by id
    /// (`operation_enabled`); `None` when the word shows no state of the profile. Refused
    /// ([`Refusal::NoRole`]) for a drive whose map gives no command profile.
    pub fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        block_on(self.machine().profile_state())
    }

    /// Forgets that the drive's command and reference sources were found to be the network:
    /// the next `run()` and `set_reference()` read them again. For an application that knows
    /// someone may have changed them at the drive (the result is kept for the `Vfd`'s life
    /// otherwise, one read per source).
    pub fn forget_sources(&mut self) {
        self.state.forget_sources();
    }
}

impl<S: SettingsView, C: HoldsClient> VariableFrequencyDrive for Vfd<S, C> {
    fn drive_id(&self) -> &'static str {
        self.client.get().profile().drive_id
    }

    fn supports(&self, role: Role) -> bool {
        self.state.supports(role)
    }

    fn run(&mut self) -> Result<(), Error> {
        block_on(self.machine().run())
    }

    fn stop(&mut self) -> Result<(), Error> {
        block_on(self.machine().stop())
    }

    fn set_direction(&mut self, direction: Direction) -> Result<(), Error> {
        block_on(self.machine().set_direction(direction))
    }

    fn set_reference(&mut self, hz: f64) -> Result<(), Error> {
        block_on(self.machine().set_reference(hz))
    }

    fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error> {
        block_on(self.machine().set_ramp(accel_s, decel_s))
    }

    fn reference(&mut self) -> Result<f64, Error> {
        block_on(self.machine().reference())
    }

    fn output_frequency(&mut self) -> Result<f64, Error> {
        block_on(self.machine().output_frequency())
    }

    fn output_current(&mut self) -> Result<f64, Error> {
        block_on(self.machine().output_current())
    }

    fn output_voltage(&mut self) -> Result<f64, Error> {
        block_on(self.machine().output_voltage())
    }

    fn dc_bus_voltage(&mut self) -> Result<f64, Error> {
        block_on(self.machine().dc_bus_voltage())
    }

    fn status(&mut self) -> Result<Status, Error> {
        block_on(self.machine().status())
    }

    fn fault_code(&mut self) -> Result<FaultCode, Error> {
        block_on(self.machine().fault_code())
    }

    fn last_fault(&mut self) -> Result<FaultCode, Error> {
        block_on(self.machine().last_fault())
    }

    fn reset_fault(&mut self) -> Result<(), Error> {
        block_on(self.machine().reset_fault())
    }

    fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        block_on(self.machine().profile_state_if_any())
    }

    fn coast(&mut self) -> Result<(), Error> {
        block_on(self.machine().coast())
    }

    fn quick_stop(&mut self) -> Result<(), Error> {
        block_on(self.machine().quick_stop())
    }
}

#[cfg(feature = "tokio")]
impl<S: SettingsView, C: HoldsAsyncClient> AsyncVfd<S, C> {
    /// As [`Vfd::new`].
    pub fn new<D: DrivePlan<Settings = S>>(client: C, slave: u8, settings: S) -> Self {
        Self::from_plan(client, slave, settings, D::REGISTERS, D::ROLES)
    }

    /// As [`Vfd::from_plan`].
    pub fn from_plan(
        mut client: C,
        slave: u8,
        settings: S,
        registers: &'static [RegisterPlan],
        roles: Roles,
    ) -> Self {
        let kind = client.get_mut().transport().kind();
        AsyncVfd {
            client,
            state: State::new(slave, settings, registers, roles, kind),
        }
    }

    /// As [`Vfd::connect`].
    pub async fn connect<D: DrivePlan<Settings = S>>(
        mut client: C,
        slave: u8,
        mut settings: S,
        externals: &[(&str, f64)],
    ) -> Result<Self, Error>
    where
        S: DriveSettings,
    {
        let session = client.get_mut().session();
        machine::load_settings(
            session,
            D::PROFILE.drive_id,
            slave,
            &mut settings,
            externals,
        )
        .await?;
        Ok(Self::new::<D>(client, slave, settings))
    }

    /// The drive's state and the client's session, for one call.
    fn machine(&mut self) -> Machine<'_, S, Tokio<'_, C::Transport>> {
        Machine::new(self.client.get_mut().session(), &mut self.state)
    }

    /// As [`Vfd::rounding`].
    pub fn rounding(mut self, rounding: Rounding) -> Self {
        self.state.rounding = rounding;
        self
    }

    /// As [`Vfd::settings`].
    pub fn settings(&self) -> &S {
        &self.state.settings
    }

    /// As [`Vfd::memory`].
    pub fn memory(&self) -> Memory {
        self.state.memory()
    }

    /// As [`Vfd::with_memory`].
    pub fn with_memory(mut self, memory: Memory) -> Self {
        self.state.remember(memory);
        self
    }

    /// As [`Vfd::forget_commands`].
    pub fn forget_commands(&mut self) {
        self.state.forget_commands();
    }

    /// As [`Vfd::adopt_direction`].
    pub async fn adopt_direction(&mut self) -> Result<Option<Direction>, Error> {
        self.machine().adopt_direction().await
    }

    /// The client.
    pub fn client(&mut self) -> &mut AsyncClient<C::Transport> {
        self.client.get_mut()
    }

    /// As [`Vfd::into_client`].
    pub fn into_client(self) -> C {
        self.client
    }

    /// As [`Vfd::holds_command`].
    pub fn holds_command(&self, row: u16) -> bool {
        self.state.holds_command(row)
    }

    /// As [`Vfd::command_fields_word`].
    pub async fn command_fields_word(
        &mut self,
        row: u16,
        mask: u16,
        value: u16,
    ) -> Result<u16, Error> {
        self.machine().command_fields_word(row, mask, value).await
    }

    /// As [`Vfd::write_command_fields`].
    pub async fn write_command_fields(
        &mut self,
        row: u16,
        mask: u16,
        value: u16,
    ) -> Result<u16, Error> {
        self.machine().write_command_fields(row, mask, value).await
    }

    /// As [`Vfd::profile_state`].
    pub async fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        self.machine().profile_state().await
    }

    /// As [`Vfd::forget_sources`].
    pub fn forget_sources(&mut self) {
        self.state.forget_sources();
    }
}

#[cfg(feature = "tokio")]
impl<S: SettingsView, C: HoldsAsyncClient> AsyncVariableFrequencyDrive for AsyncVfd<S, C> {
    fn drive_id(&self) -> &'static str {
        self.client.get().profile().drive_id
    }

    fn supports(&self, role: Role) -> bool {
        self.state.supports(role)
    }

    async fn run(&mut self) -> Result<(), Error> {
        self.machine().run().await
    }

    async fn stop(&mut self) -> Result<(), Error> {
        self.machine().stop().await
    }

    async fn set_direction(&mut self, direction: Direction) -> Result<(), Error> {
        self.machine().set_direction(direction).await
    }

    async fn set_reference(&mut self, hz: f64) -> Result<(), Error> {
        self.machine().set_reference(hz).await
    }

    async fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error> {
        self.machine().set_ramp(accel_s, decel_s).await
    }

    async fn reference(&mut self) -> Result<f64, Error> {
        self.machine().reference().await
    }

    async fn output_frequency(&mut self) -> Result<f64, Error> {
        self.machine().output_frequency().await
    }

    async fn output_current(&mut self) -> Result<f64, Error> {
        self.machine().output_current().await
    }

    async fn output_voltage(&mut self) -> Result<f64, Error> {
        self.machine().output_voltage().await
    }

    async fn dc_bus_voltage(&mut self) -> Result<f64, Error> {
        self.machine().dc_bus_voltage().await
    }

    async fn status(&mut self) -> Result<Status, Error> {
        self.machine().status().await
    }

    async fn fault_code(&mut self) -> Result<FaultCode, Error> {
        self.machine().fault_code().await
    }

    async fn last_fault(&mut self) -> Result<FaultCode, Error> {
        self.machine().last_fault().await
    }

    async fn reset_fault(&mut self) -> Result<(), Error> {
        self.machine().reset_fault().await
    }

    async fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        self.machine().profile_state_if_any().await
    }

    async fn coast(&mut self) -> Result<(), Error> {
        self.machine().coast().await
    }

    async fn quick_stop(&mut self) -> Result<(), Error> {
        self.machine().quick_stop().await
    }
}
