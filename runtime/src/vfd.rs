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
//!   [`CommandProfile`]), `run()` reads the status word and writes the run path's transitions in
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

use drivemap_core::command_profile::{CommandProfile, Path, PathKind, Transition};
use drivemap_core::plan::{Conversion, RegisterPlan};
use drivemap_core::register::{DrivePlan, DriveSettings, Table};
use drivemap_core::roles::{FieldRole, NumberField, Place, Role, RoleKind, Target};
use drivemap_core::rule::Broadcast;
use drivemap_core::{Roles, Rounding, SettingsView, ValueError};

#[cfg(feature = "tokio")]
use crate::async_client::{AsyncClient, AsyncTransport};
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

macro_rules! holds {
    ($holds:ident, $client:ident, $link:ident) => {
        impl<T: $link> $holds for $client<T> {
            type Transport = T;
            fn get(&self) -> &$client<T> {
                self
            }
            fn get_mut(&mut self) -> &mut $client<T> {
                self
            }
        }

        impl<T: $link> $holds for &mut $client<T> {
            type Transport = T;
            fn get(&self) -> &$client<T> {
                self
            }
            fn get_mut(&mut self) -> &mut $client<T> {
                self
            }
        }

        impl<T: $link> $holds for Box<$client<T>> {
            type Transport = T;
            fn get(&self) -> &$client<T> {
                self
            }
            fn get_mut(&mut self) -> &mut $client<T> {
                self
            }
        }
    };
}

holds!(HoldsClient, Client, Transport);
#[cfg(feature = "tokio")]
holds!(HoldsAsyncClient, AsyncClient, AsyncTransport);

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

/// What a [`Vfd`] or an [`AsyncVfd`] knows of its drive besides the client.
struct State<S> {
    slave: u8,
    settings: S,
    registers: &'static [RegisterPlan],
    roles: Roles,
    kind: TransportKind,
    direction: Direction,
    /// The direction of the last `run()`, if it succeeded and was the last of `run()` and
    /// `stop()` called.
    running: Option<Direction>,
    /// Every command register, with what this master last told it.
    commands: Vec<CommandWord>,
    /// The run command source and the reference source were read and select the network.
    sources: [bool; 2],
    /// What a reference or ramp between two steps of its register becomes (refused unless
    /// `rounding` says otherwise).
    rounding: Rounding,
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

/// A command register and what this master last told it.
#[derive(Debug, Clone, Copy)]
struct CommandWord {
    /// The plan row.
    row: u16,
    /// Every command role of the register released (stop, forward, no reset), other bits 0.
    released: u16,
    /// The word last written, or `None` before the first write and after a write that failed
    /// (the drive may hold the new word, the old one, or anything in between).
    told: Option<u16>,
}

/// The methods of [`Vfd`] and [`AsyncVfd`], one body for both: `[async] [.await]` for the
/// async drive, `[] []` for the blocking one.
macro_rules! vfd_impl {
    ($name:ident, $holder:ident, $trait:ident, $client:ident, [$($asy:tt)*] [$($aw:tt)*]) => {
impl<S: SettingsView, C: $holder> $name<S, C> {
    /// The drive of generated module `D` on `slave`, with `settings` as conversions need them
    /// (fill them with [`Client::load_settings`] and the external quantities the map names, or
    /// use [`connect`](Self::connect)).
    pub fn new<D: DrivePlan<Settings = S>>(
        client: C,
        slave: u8,
        settings: S,
    ) -> Self {
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
        let mut commands: Vec<CommandWord> = Vec::new();
        for p in roles.places {
            if let (RoleKind::Command, Target::Field(f)) = (p.role.kind(), p.target) {
                let c = match commands.iter_mut().find(|c| c.row == f.row) {
                    Some(c) => c,
                    None => {
                        commands.push(CommandWord {
                            row: f.row,
                            released: 0,
                            told: None,
                        });
                        commands.last_mut().expect("just pushed")
                    }
                };
                c.released = f.put(c.released, f.code(false));
            }
        }
        // A command profile's control word is a command register of its own.
        if let Some(p) = roles.profile
            && !commands.iter().any(|c| c.row == p.control)
        {
            commands.push(CommandWord {
                row: p.control,
                released: 0,
                told: None,
            });
        }
        // At the start the drive is taken as released: the first command composes from that.
        for c in &mut commands {
            c.told = Some(c.released);
        }
        $name {
            client,
            state: State {
            slave,
            settings,
            registers,
            roles,
            kind,
            direction: Direction::Forward,
            running: None,
            commands,
            sources: [false; 2],
            rounding: Rounding::Exact,
            },
        }
    }

    /// The drive of generated module `D` on `slave`: reads the parameters its conversions
    /// depend on, and takes the external quantities (name, value) the application supplies.
    pub $($asy)* fn connect<D: DrivePlan<Settings = S>>(
        mut client: C,
        slave: u8,
        mut settings: S,
        externals: &[(&str, f64)],
    ) -> Result<Self, Error>
    where
        S: DriveSettings,
    {
        if client.get().profile().drive_id != D::PROFILE.drive_id {
            return Err(Refusal::OtherDrive {
                client: client.get().profile().drive_id,
                drive: D::PROFILE.drive_id,
            }
            .into());
        }
        for (name, value) in externals {
            if !settings.set_external(name, *value) {
                return Err(Refusal::UnknownExternal {
                    drive: client.get().profile().drive_id,
                    name: (*name).to_owned(),
                }
                .into());
            }
        }
        client.get_mut().load_settings(slave, &mut settings) $($aw)*?;
        Ok(Self::new::<D>(client, slave, settings))
    }

    fn drive(&self) -> &'static str {
        self.client.get().profile().drive_id
    }

    /// Chooses what a reference or a ramp time that is not a whole number of its register's
    /// steps becomes: [`Rounding::Exact`] (the default) refuses it with the two nearest values
    /// ([`ValueError::NotAStep`]); [`Rounding::Nearest`] sends the nearest. Limits are checked on
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
        Memory {
            direction: self.state.direction,
            running: self.state.running,
            commands: self.state.commands.clone(),
            sources: self.state.sources,
        }
    }

    /// This drive object with what an earlier one of the same map knew ([`memory`](Self::memory)).
    /// A memory of other command registers (another map's) is not taken.
    pub fn with_memory(mut self, memory: Memory) -> Self {
        let same = memory.commands.len() == self.state.commands.len()
            && memory
                .commands
                .iter()
                .zip(&self.state.commands)
                .all(|(a, b)| a.row == b.row && a.released == b.released);
        if same {
            self.state.direction = memory.direction;
            self.state.running = memory.running;
            self.state.commands = memory.commands;
            self.state.sources = memory.sources;
        }
        self
    }

    /// Forgets what the command registers were told: the next command to each reads it back
    /// where the map lets it be read on the link (keeping the bits other masters or field
    /// writes set) and composes from the released word where it cannot, as after a failed
    /// write. For a master that starts while the drive may already hold a command word.
    pub fn forget_commands(&mut self) {
        for c in &mut self.state.commands {
            c.told = None;
        }
    }

    /// Takes the direction the drive reports as the direction set, for a master that has not
    /// set one, so that a later `run()` keeps the direction the drive turns in instead of
    /// reversing it: the direction field of its command register read back where the map lets
    /// it be read on this link (what the drive was last told, by any master), else the status
    /// role `reversing`. Returns the direction taken, or `None` where the drive reports none
    /// (the direction set stays).
    pub $($asy)* fn adopt_direction(&mut self) -> Result<Option<Direction>, Error> {
        let told = match self.field(Role::Reverse)? {
            Some(r) => self.read_back(r.row) $($aw)*.map(|w| r.holds(w)),
            None => None,
        };
        let reverse = match (told, self.place(Role::Reversing, "field")) {
            (Some(t), _) => Some(t),
            (
                None,
                Ok(Place {
                    target: Target::Field(f),
                    ..
                }),
            ) => {
                let f = *f;
                Some(f.holds(self.read_word(f.row) $($aw)*?))
            }
            (None, _) => None,
        };
        let taken = reverse.map(|r| if r { Direction::Reverse } else { Direction::Forward });
        if let Some(d) = taken {
            self.state.direction = d;
        }
        Ok(taken)
    }

    /// The client.
    pub fn client(&mut self) -> &mut $client<C::Transport> {
        self.client.get_mut()
    }

    /// The client as it was given (owned or borrowed), giving the drive up.
    pub fn into_client(self) -> C {
        self.client
    }

    fn row(&self, row: u16) -> &'static RegisterPlan {
        &self.state.registers[usize::from(row)]
    }

    /// Whether a place can be used on this link to this slave.
    fn usable(&self, p: &Place) -> bool {
        match p.target.row() {
            Some(row) => {
                let r = self.row(row);
                let broadcast = self.state.slave == 0;
                r.transports.contains(self.state.kind)
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
        for p in self.state.roles.of(role) {
            any = true;
            if self.usable(p) {
                return Ok(p);
            }
        }
        Err(Refusal::NoRole {
            drive: self.drive(),
            role: role.id(),
            what,
            transport: any.then_some(self.state.kind),
        }
        .into())
    }

    /// The raw value of plan row `row`: its word, or a 32-bit pair read in one request.
    $($asy)* fn read_raw(&mut self, row: u16) -> Result<u32, Error> {
        let r = self.row(row);
        let address = r.locate(&self.state.settings, self.state.kind)?;
        let mut raw = [0u16; 2];
        let words = &mut raw[..usize::from(r.info.width.count())];
        match r.info.table {
            Table::Input => self.client.get_mut().read_input(self.state.slave, address, words) $($aw)*?,
            Table::Holding => self.client.get_mut().read_holding(self.state.slave, address, words) $($aw)*?,
        }
        Ok(r.info.width.join(words))
    }

    /// The word of a one-register row (bit fields and codes: the map keeps them in one word).
    $($asy)* fn read_word(&mut self, row: u16) -> Result<u16, Error> {
        Ok(self.read_raw(row) $($aw)*? as u16)
    }

    $($asy)* fn write_word(&mut self, row: u16, raw: u32) -> Result<(), Error> {
        let r = self.row(row);
        let address = r.locate(&self.state.settings, self.state.kind)?;
        let rule = r.write_rule();
        match r.repeat_needs_change {
            // A role register whose drive executes only a changed value: its intermediate first.
            Some(x) => self
                .client
                .get_mut()
                .write_changed(self.state.slave, &rule, address, x.between, raw) $($aw)*,
            None => self.client.get_mut().write_rule(self.state.slave, &rule, address, raw) $($aw)*,
        }
    }

    /// Reads the number role `role` in its unit.
    $($asy)* fn read_number(&mut self, role: Role) -> Result<f64, Error> {
        let p = self.place(role, "register")?;
        match p.target {
            Target::Register(row) => {
                let raw = self.read_raw(row) $($aw)*?;
                Ok(self.row(row).decode_number(raw, &self.state.settings)?)
            }
            Target::External { slot, name } => self.state.settings.quantity(slot).ok_or_else(|| {
                Refusal::ExternalNotSet {
                    drive: self.drive(),
                    name,
                }
                .into()
            }),
            Target::NumberField(f) => {
                let word = self.read_word(f.row) $($aw)*?;
                Ok(f.value(word))
            }
            Target::Field(_) => Err(self.misplaced(role, "register")),
        }
    }

    /// Writes the number role `role`, range-checked by the register's conversion.
    $($asy)* fn write_number(&mut self, role: Role, value: f64) -> Result<(), Error> {
        let p = self.place(role, "register")?;
        if let Target::NumberField(f) = p.target {
            return self.write_number_field(role, f, value) $($aw)*;
        }
        let Target::Register(row) = p.target else {
            return Err(self.misplaced(role, "writable register"));
        };
        let raw = self
            .row(row)
            .encode_number_with(value, &self.state.settings, self.state.rounding)?;
        self.write_word(row, raw) $($aw)*
    }

    /// Writes a number role that is a field of a register: reads the word, puts the value's
    /// count into the field, writes the word back — only where that keeps the rest of the word
    /// as the drive has it: the register is readable here and reads mean what writes do, it is
    /// not a broadcast, and no command role lives in it (a read-back command word could send
    /// a run bit again). Elsewhere refused, with why, before anything is sent.
    $($asy)* fn write_number_field(&mut self, role: Role, f: NumberField, value: f64) -> Result<(), Error> {
        let r = self.row(f.row);
        let why = if !r.info.access.readable() || !r.transports.contains(self.state.kind) {
            Some("the register cannot be read on this link, so the rest of its word is unknown")
        } else if !r.read_values.is_empty() {
            Some("the register reads back other values than are written, so the rest of its word cannot be kept")
        } else if self.state.slave == 0 || r.broadcast == Broadcast::Only {
            Some("a broadcast cannot read the word first")
        } else if self
            .state
            .roles
            .places
            .iter()
            .any(|p| p.role.kind() == RoleKind::Command && p.target.row() == Some(f.row))
        {
            Some("command fields share the register: writing back what was read could repeat a run or reset")
        } else {
            None
        };
        if let Some(why) = why {
            return Err(Refusal::FieldNotWritable {
                drive: self.drive(),
                role: role.id(),
                register: r.info.id,
                why,
            }
            .into());
        }
        let count = drivemap_core::scale::encode_decimal_with(
            r.info.id,
            role.unit().unwrap_or(""),
            value,
            f.scale,
            f.range(),
            self.state.rounding,
        )?;
        let word = self.read_word(f.row) $($aw)*?;
        let Some(word) = f.put(word, count) else {
            // encode_decimal_with keeps the count in the field's range.
            return Err(self.misplaced(role, "field that holds the value"));
        };
        self.write_word(f.row, u32::from(word)) $($aw)*
    }

    /// Sets the command fields of `changes` in their registers' words and writes each word once,
    /// in the order of `changes` with releases before sets (so a stop goes out before a
    /// direction, and a run after it). Each word is composed from what this master last told the
    /// register (`base`) with the run and direction fields as the last successful `run()`
    /// or `stop()` and the direction set say, then `changes` on top. A write that fails makes
    /// its register unknown.
    $($asy)* fn command(&mut self, changes: &[(FieldRole, bool)]) -> Result<(), Error> {
        let mut words: Vec<(u16, u16)> = Vec::new();
        // Within a word, releases go first: where two roles share bits (run forward and run
        // reverse as the codes of one field), the one set wins.
        let ordered = changes
            .iter()
            .filter(|(_, on)| !on)
            .chain(changes.iter().filter(|(_, on)| *on));
        for (f, on) in ordered {
            if !self.state.commands.iter().any(|c| c.row == f.row) {
                continue;
            }
            let word = match words.iter().position(|(row, _)| *row == f.row) {
                Some(i) => &mut words[i].1,
                None => {
                    let base = self.base(f.row) $($aw)*?;
                    words.push((f.row, base));
                    &mut words.last_mut().expect("just pushed").1
                }
            };
            *word = f.put(*word, f.code(*on));
        }
        for (row, word) in words {
            let result = self.write_word(row, u32::from(word)) $($aw)*;
            if let Some(c) = self.state.commands.iter_mut().find(|c| c.row == row) {
                c.told = result.is_ok().then_some(word);
            }
            result?;
        }
        Ok(())
    }

    /// The word a command to register `row` starts from: what this master last told it, or,
    /// when that is unknown, the word read back from the drive where the map lets it be read
    /// here (its defined bits only) and the released word where it cannot; then every command
    /// role of the register released except the run and direction fields, which follow the last
    /// successful `run()` / `stop()` and the direction set. So no word carries a run code unless
    /// `run()` asks for it or succeeded last.
    $($asy)* fn base(&mut self, row: u16) -> Result<u16, Error> {
        let Some(c) = self.state.commands.iter().find(|c| c.row == row).copied() else {
            return Ok(0);
        };
        let mut word = match c.told {
            Some(w) => w,
            None => match self.read_back(row) $($aw)* {
                Some(read) => read,
                None => c.released,
            },
        };
        for p in self.state.roles.places {
            if let (RoleKind::Command, Target::Field(f)) = (p.role.kind(), p.target) {
                if f.row == row {
                    word = f.put(word, f.code(false));
                }
            }
        }
        // Run fields can be refused only when the map has none: then there is nothing to keep.
        // A drive run by terminals keeps the terminal of the direction it was run in.
        let (run, direction) = match self.state.running {
            Some(d) => (true, d),
            None => (false, self.state.direction),
        };
        if let Ok(fields) = self.run_fields(run, direction) {
            for on in [false, true] {
                for (f, _) in fields.iter().filter(|(f, o)| f.row == row && *o == on) {
                    word = f.put(word, f.code(on));
                }
            }
        }
        if let Ok(Some(r)) = self.field(Role::Reverse) {
            if r.row == row {
                word = r.put(word, r.code(self.state.direction == Direction::Reverse));
            }
        }
        Ok(self.no_run_word(row, word))
    }

    /// `word` for register `row`, with a control word that asks the command profile for a run
    /// transition replaced by the stop path's first word (its kept bits as they were), unless
    /// the last of `run()` and `stop()` was a `run()` that succeeded: no word read back or
    /// composed asks a drive to run that was not told to.
    fn no_run_word(&self, row: u16, word: u16) -> u16 {
        let Some(p) = self.state.roles.profile else {
            return word;
        };
        if row != p.control || self.state.running.is_some() || !p.word_runs(word) {
            return word;
        }
        let stop = p
            .path(PathKind::Stop)
            .or_else(|| p.path(PathKind::Coast))
            .and_then(|path| path.via.first())
            .and_then(|&t| p.transition(t));
        match stop {
            Some(t) => t.compose(word),
            // A profile without a stop or coast path: every bit but the kept ones released.
            None => 0,
        }
    }

    /// The word of command register `row` read from the drive, where the map lets it be read
    /// on this link and reads mean what writes do; only the bits of its fields are kept. `None`
    /// when it cannot be read or the read fails (the caller composes from the released state).
    $($asy)* fn read_back(&mut self, row: u16) -> Option<u16> {
        let r = self.row(row);
        let readable = r.info.access.readable()
            && r.read_values.is_empty()
            && r.transports.contains(self.state.kind)
            && r.broadcast != Broadcast::Only
            && self.state.slave != 0;
        if !readable {
            return None;
        }
        let mask = match r.conversion {
            Conversion::Bits { mask, .. } => mask,
            _ => u16::MAX,
        };
        self.read_word(row) $($aw)*.ok().map(|w| w & mask)
    }

    /// Whether plan row `row` holds a command role (a field the trait's commands write): a
    /// write of its fields goes through [`Self::write_command_fields`].
    pub fn holds_command(&self, row: u16) -> bool {
        self.state.commands.iter().any(|c| c.row == row)
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
    pub $($asy)* fn command_fields_word(&mut self, row: u16, mask: u16, value: u16) -> Result<u16, Error> {
        let r = self.row(row);
        let Some(c) = self.state.commands.iter().find(|c| c.row == row).copied() else {
            return Err(Refusal::FieldNotWritable {
                drive: self.drive(),
                role: "command",
                register: r.info.id,
                why: "it holds no command role: write it as a whole register",
            }
            .into());
        };
        let fields_mask = match r.conversion {
            Conversion::Bits { mask, .. } => mask,
            _ => u16::MAX,
        };
        let readable = r.info.access.readable()
            && r.read_values.is_empty()
            && r.transports.contains(self.state.kind)
            && r.broadcast != Broadcast::Only
            && self.state.slave != 0;
        let runs = |role: Role| matches!(role, Role::Run | Role::RunForward | Role::RunReverse);
        let places: Vec<(Role, FieldRole)> = self
            .state
            .roles
            .places
            .iter()
            .filter_map(|p| match (p.role.kind(), p.target) {
                (RoleKind::Command, Target::Field(f)) if f.row == row && f.mask() & mask == 0 => {
                    Some((p.role, f))
                }
                _ => None,
            })
            .collect();
        let has_run = places.iter().any(|(role, _)| runs(*role));
        let read = if readable {
            Some(self.read_word(row) $($aw)*? & fields_mask)
        } else {
            None
        };
        let running = has_run
            && (self.state.running.is_some()
                || (self.state.slave != 0
                    && self.supports(Role::Running)
                    && self.status() $($aw)*?.running == Some(true)));
        if running && read.is_none() && self.state.running.is_none() {
            return Err(Refusal::FieldNotWritable {
                drive: self.drive(),
                role: "run",
                register: r.info.id,
                why: "the drive runs and the register cannot be read on this link, so the run bits to keep are unknown: use the drive trait's run() or stop()",
            }
            .into());
        }
        let mut word = read.unwrap_or(c.released & fields_mask);
        for (role, f) in &places {
            let keep = match role {
                Role::FaultReset => false,
                _ if f.edge.needs_release_first() => false,
                role if runs(*role) => running,
                _ => read.is_some(),
            };
            if !keep {
                word = f.put(word, f.code(false));
            }
        }
        if running && read.is_none() {
            // Known from this master's own run(): its run fields, as base() composes them.
            if let Some(d) = self.state.running {
                if let Ok(fields) = self.run_fields(true, d) {
                    for (f, on) in fields.iter().filter(|(f, on)| f.row == row && *on) {
                        word = f.put(word, f.code(*on));
                    }
                }
            }
        }
        let word = ((word & !mask) | (value & mask)) & fields_mask;
        if let Some(p) = self.state.roles.profile
            && row == p.control
            && self.state.running.is_none()
            && p.word_runs(word)
        {
            // A word that asks the command profile for a run transition: only run() walks there.
            return Err(Refusal::FieldNotWritable {
                drive: self.drive(),
                role: "run",
                register: r.info.id,
                why: "the word asks the drive's command profile for a run transition: run the drive with the drive trait's run(), which walks its state machine",
            }
            .into());
        }
        Ok(self.no_run_word(row, word))
    }

    /// Writes the bits `mask` of command register `row` to `value`'s, the rest of the word
    /// composed by [`Self::command_fields_word`] (no run or reset bit the call does not ask for,
    /// unless the drive runs), through the client's write gate. Returns the word written; this
    /// master's record of the register follows it (unknown after a write that failed).
    pub $($asy)* fn write_command_fields(&mut self, row: u16, mask: u16, value: u16) -> Result<u16, Error> {
        let word = self.command_fields_word(row, mask, value) $($aw)*?;
        let result = self.write_word(row, u32::from(word)) $($aw)*;
        if let Some(c) = self.state.commands.iter_mut().find(|c| c.row == row) {
            c.told = result.is_ok().then_some(word);
        }
        result.map(|()| word)
    }

    /// The state of the command profile the drive shows in its status word, by id
    /// (`operation_enabled`); `None` when the word shows no state of the profile. Refused
    /// ([`Refusal::NoRole`]) for a drive whose map gives no command profile.
    pub $($asy)* fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        let p = self.profile(PathKind::Run.id())?;
        let word = self.read_word(p.status) $($aw)*?;
        Ok(p.state_of(word).map(|s| p.state_id(s)))
    }

    fn profile(&self, role: &'static str) -> Result<&'static CommandProfile, Error> {
        self.state.roles.profile.ok_or_else(|| {
            Refusal::NoRole {
                drive: self.drive(),
                role,
                what: "command profile",
                transport: None,
            }
            .into()
        })
    }

    /// The state the status word shows (index), or the error naming the word.
    $($asy)* fn read_state(&mut self, p: &'static CommandProfile, path: &Path) -> Result<u8, Error> {
        let word = self.read_word(p.status) $($aw)*?;
        p.state_of(word).ok_or_else(|| Error::StateMachine {
            drive: self.drive(),
            path: path.kind.id(),
            state: format!("none (status word {word:#06X} shows no state of the profile)"),
            why: "the status word shows no state of the profile".into(),
        })
    }

    /// Writes transition `t`'s control word (its kept bits from this master's composition),
    /// with the bits `clear` cleared; the register's record follows (unknown after a failed
    /// write).
    $($asy)* fn write_transition(&mut self, p: &'static CommandProfile, t: &Transition, clear: u16) -> Result<(), Error> {
        let base = self.base(p.control) $($aw)*?;
        let word = t.compose(base) & !clear;
        let result = self.write_word(p.control, u32::from(word)) $($aw)*;
        if let Some(c) = self.state.commands.iter_mut().find(|c| c.row == p.control) {
            c.told = result.is_ok().then_some(word);
        }
        result
    }

    /// Waits until the drive shows `t.to` (or a state that ends `path`), reading the status
    /// word until `t.limit_ms` has passed; a drive that shows the fault state instead (it
    /// tripped) ends the wait at once.
    $($asy)* fn await_transition(&mut self, p: &'static CommandProfile, path: &Path, t: &Transition) -> Result<(), Error> {
        let start = std::time::Instant::now();
        let limit = std::time::Duration::from_millis(u64::from(t.limit_ms));
        let faults: Vec<u8> = p
            .path(PathKind::ResetFault)
            .map(|r| r.via.iter().filter_map(|&i| p.transition(i)).flat_map(|x| x.from.iter().copied()).collect())
            .unwrap_or_default();
        loop {
            let s = self.read_state(p, path) $($aw)*?;
            if s == t.to || path.to.contains(&s) {
                return Ok(());
            }
            let why = if faults.contains(&s) && path.kind != PathKind::ResetFault {
                Some(format!("the drive tripped after `{}` ({:#06X})", t.id, t.word))
            } else if start.elapsed() >= limit {
                Some(format!(
                    "the drive did not show `{}` within {} ms of `{}` ({:#06X})",
                    p.state_id(t.to),
                    t.limit_ms,
                    t.id,
                    t.word
                ))
            } else {
                None
            };
            if let Some(why) = why {
                return Err(Error::StateMachine {
                    drive: self.drive(),
                    path: path.kind.id(),
                    state: p.state_id(s).to_owned(),
                    why,
                });
            }
            let left = limit.saturating_sub(start.elapsed());
            self.pause(left.min(std::time::Duration::from_millis(10))) $($aw)*;
        }
    }

    /// Walks path `kind` of the command profile: reads the state, writes the first transition
    /// of the path that leaves it, waits for the state it leads to, until the drive shows a
    /// state that ends the path. A stop, coast or quick stop that finds the drive already
    /// there writes the path's first word once all the same (so the control word holds no
    /// run), and one whose status cannot be read writes it before returning the error. No path
    /// but `run` writes a run transition.
    $($asy)* fn walk(&mut self, kind: PathKind) -> Result<(), Error> {
        let p = self.profile(kind.id())?;
        let Some(path) = p.path(kind) else {
            return Err(Refusal::NoRole {
                drive: self.drive(),
                role: kind.id(),
                what: "command profile path",
                transport: None,
            }
            .into());
        };
        let first = path.via.first().and_then(|&t| p.transition(t)).filter(|t| !p.runs(t));
        let stopping = matches!(kind, PathKind::Stop | PathKind::Coast | PathKind::QuickStop);
        let mut wrote = false;
        for _ in 0..=path.via.len() + 1 {
            let s = match self.read_state(p, path) $($aw)* {
                Ok(s) => s,
                Err(e) => {
                    if stopping && !wrote && let Some(t) = first {
                        // Whatever the drive shows, the stop word goes out.
                        let _ = self.write_transition(p, t, 0) $($aw)*;
                    }
                    return Err(e);
                }
            };
            if path.to.contains(&s) {
                if stopping && !wrote && let Some(t) = first {
                    self.write_transition(p, t, 0) $($aw)*?;
                }
                return Ok(());
            }
            let Some(t) = p.next(path, s) else {
                if stopping && !wrote && let Some(t) = first {
                    let _ = self.write_transition(p, t, 0) $($aw)*;
                }
                return Err(Error::StateMachine {
                    drive: self.drive(),
                    path: kind.id(),
                    state: p.state_id(s).to_owned(),
                    why: format!("no transition of the `{}` path leaves this state", kind.id()),
                });
            };
            if kind != PathKind::Run && p.runs(t) {
                // Validation refuses such a map; a plan built by hand may still have one.
                return Err(self.misplaced(Role::Run, "path that does not run the drive"));
            }
            self.write_transition(p, t, 0) $($aw)*?;
            wrote = true;
            self.await_transition(p, path, t) $($aw)*?;
        }
        let s = self.read_state(p, path) $($aw)*?;
        if path.to.contains(&s) {
            return Ok(());
        }
        Err(Error::StateMachine {
            drive: self.drive(),
            path: kind.id(),
            state: p.state_id(s).to_owned(),
            why: format!("the drive did not reach the end of the `{}` path", kind.id()),
        })
    }

    /// The profile's fault acknowledge: only while the drive shows a state the `reset_fault`
    /// path's transitions leave (the fault state), its edge bits cleared first where they may
    /// be set, then set, the state awaited, then cleared.
    $($asy)* fn acknowledge(&mut self) -> Result<(), Error> {
        let p = self.profile(Role::FaultReset.id())?;
        let Some(path) = p.path(PathKind::ResetFault) else {
            return Err(self.misplaced(Role::FaultReset, "command profile path"));
        };
        let s = self.read_state(p, path) $($aw)*?;
        let Some(t) = p.next(path, s) else {
            // Not in the fault state: nothing to acknowledge, nothing written.
            return Ok(());
        };
        let told = self
            .state
            .commands
            .iter()
            .find(|c| c.row == p.control)
            .and_then(|c| c.told);
        if t.edge != 0 && told.is_none_or(|w| w & t.edge != 0) {
            self.write_transition(p, t, t.edge) $($aw)*?;
        }
        self.write_transition(p, t, 0) $($aw)*?;
        let reached = self.await_transition(p, path, t) $($aw)*;
        let released = if t.edge != 0 {
            self.write_transition(p, t, t.edge) $($aw)*
        } else {
            Ok(())
        };
        reached.and(released)
    }

    /// A fault code role (`fault_code`, `last_fault`): the register's word or the field's bits,
    /// with the map's name for it.
    $($asy)* fn read_fault(&mut self, role: Role) -> Result<FaultCode, Error> {
        let p = self.place(role, "register")?;
        if let Target::NumberField(f) = p.target {
            let word = self.read_word(f.row) $($aw)*?;
            let code = f.bits(word);
            let r = self.row(f.row);
            let name = match &r.conversion {
                Conversion::Bits { fields, .. } => fields
                    .iter()
                    .find(|x| x.lsb == f.lsb && x.width == f.width)
                    .and_then(|x| x.values.iter().find(|v| v.code == code))
                    .map(|v| v.name),
                _ => None,
            };
            return Ok(FaultCode {
                code,
                value: f.get(word) as i32,
                name,
            });
        }
        let Some(row) = p.target.row() else {
            return Err(self.misplaced(role, "register"));
        };
        let code = self.read_word(row) $($aw)*?;
        let r = self.row(row);
        Ok(FaultCode {
            code,
            value: if r.signed() { i32::from(code as i16) } else { i32::from(code) },
            name: r.label(code).map(|l| l.name),
        })
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

    /// The command fields that run (`true`) or stop in `direction`, the direction first
    /// (registers are written in this order).
    fn run_fields(&self, run: bool, direction: Direction) -> Result<Vec<(FieldRole, bool)>, Error> {
        let reverse = direction == Direction::Reverse;
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

    /// Refuses a reference above the drive's maximum frequency where the map gives the
    /// `max_frequency` role: the register is read first (an external quantity comes from the
    /// settings), so a reference the drive cannot output is never sent. A maximum that cannot
    /// be read refuses the reference too.
    $($asy)* fn check_max_frequency(&mut self, hz: f64) -> Result<(), Error> {
        if self.state.roles.of(Role::MaxFrequency).next().is_none() || !hz.is_finite() {
            return Ok(());
        }
        let place = self.place(Role::FrequencyReference, "register")?;
        let register = place
            .target
            .row()
            .map_or(Role::FrequencyReference.id(), |row| self.row(row).info.id);
        let max = self.read_number(Role::MaxFrequency) $($aw)*?;
        if hz > max {
            return Err(ValueError::AboveLimit {
                register,
                value: hz,
                max,
                unit: "Hz",
                percent: 100.0,
                reference: Role::MaxFrequency.id(),
            }
            .into());
        }
        Ok(())
    }

    /// Forgets that the drive's command and reference sources were found to be the network:
    /// the next `run()` and `set_reference()` read them again. For an application that knows
    /// someone may have changed them at the drive (the result is kept for the `Vfd`'s life
    /// otherwise, one read per source).
    pub fn forget_sources(&mut self) {
        self.state.sources = [false; 2];
    }

    /// Checks that the drive takes what `role` (a source role) selects from the network on
    /// this link: reads the parameter (or status field) the map names, once; a network source
    /// is kept, another is refused and read again next time.
    $($asy)* fn network_source(&mut self, role: Role) -> Result<(), Error> {
        let slot = usize::from(role == Role::ReferenceSource);
        if self.state.sources[slot] {
            return Ok(());
        }
        let kind = self.state.kind;
        let Some(p) = self
            .state
            .roles
            .of(role)
            .find(|p| p.transports.contains(kind) && self.usable(p))
        else {
            // No source parameter for this link in the map: nothing to check.
            return Ok(());
        };
        let Target::Field(f) = p.target else {
            return Ok(());
        };
        let word = self.read_word(f.row) $($aw)*?;
        if f.holds(word) {
            self.state.sources[slot] = true;
            return Ok(());
        }
        Err(self.not_network(role, p, f, word))
    }

    /// Why the drive would ignore a network command: its source setting, and what to set.
    fn not_network(&self, role: Role, p: &Place, f: FieldRole, word: u16) -> Error {
        let r = self.row(f.row);
        let code = f.get(word);
        let what = if role == Role::CommandSource {
            "run commands"
        } else {
            "the frequency reference"
        };
        let (now, fix) = if f.width == 16 {
            // The source parameter itself: its codes are its values.
            let param = r.info.param.unwrap_or(r.info.id);
            let now = match r.label(code) {
                Some(l) => format!("\"{}\" ({param} = {code})", l.name),
                None => format!("another source ({param} = {code}, a code the map does not name)"),
            };
            let on: Vec<String> =
                f.on.iter()
                    .map(|&c| match r.label(c) {
                        Some(l) => format!("{param} = {c} (\"{}\")", l.name),
                        None => format!("{param} = {c}"),
                    })
                    .collect();
            let fix = format!(
                "set {} for the network on this link ({:?}; {})",
                on.join(" or "),
                self.state.kind,
                p.source
            );
            (now, fix)
        } else {
            // A status field that reports the source.
            let field = match &r.conversion {
                drivemap_core::plan::Conversion::Bits { fields, .. } => fields
                    .iter()
                    .find(|x| x.lsb == f.lsb && x.width == f.width)
                    .map(|x| x.name),
                _ => None,
            };
            let now = format!(
                "elsewhere than the network ({} reports {code}{})",
                r.info.id,
                field.map(|n| format!(": \"{n}\"")).unwrap_or_default()
            );
            let fix = format!(
                "select the network as the drive's source at the drive ({})",
                p.source
            );
            (now, fix)
        };
        Refusal::NotNetworkSource {
            drive: self.drive(),
            what,
            now,
            fix,
        }
        .into()
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

impl<S: SettingsView, C: $holder> $trait for $name<S, C> {
    fn drive_id(&self) -> &'static str {
        self.drive()
    }

    fn supports(&self, role: Role) -> bool {
        if let Some(p) = self.state.roles.profile {
            match role {
                Role::Run => return p.path(PathKind::Run).is_some(),
                Role::FaultReset => return p.path(PathKind::ResetFault).is_some(),
                _ => {}
            }
        }
        self.state.roles.of(role).any(|p| self.usable(p))
    }

    $($asy)* fn run(&mut self) -> Result<(), Error> {
        if self.state.roles.profile.is_some() {
            self.state.running = None;
            self.network_source(Role::CommandSource) $($aw)*?;
            self.walk(PathKind::Run) $($aw)*?;
            self.state.running = Some(self.state.direction);
            return Ok(());
        }
        let fields = self.run_fields(true, self.state.direction)?;
        // Until the run is confirmed, every other command composes with run released.
        self.state.running = None;
        // A run the drive would ignore (not the network's to give) is refused, not sent.
        self.network_source(Role::CommandSource) $($aw)*?;
        self.command(&fields) $($aw)*?;
        self.state.running = Some(self.state.direction);
        Ok(())
    }

    $($asy)* fn stop(&mut self) -> Result<(), Error> {
        // From now on no word carries a run code until the next run(), whatever becomes of
        // this one.
        self.state.running = None;
        if self.state.roles.profile.is_some() {
            return self.walk(PathKind::Stop) $($aw)*;
        }
        let fields = self.run_fields(false, self.state.direction)?;
        self.command(&fields) $($aw)*
    }

    $($asy)* fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        if self.state.roles.profile.is_none() {
            return Ok(None);
        }
        $name::profile_state(self) $($aw)*
    }

    $($asy)* fn coast(&mut self) -> Result<(), Error> {
        self.state.running = None;
        self.walk(PathKind::Coast) $($aw)*
    }

    $($asy)* fn quick_stop(&mut self) -> Result<(), Error> {
        self.state.running = None;
        self.walk(PathKind::QuickStop) $($aw)*
    }

    $($asy)* fn set_direction(&mut self, direction: Direction) -> Result<(), Error> {
        let before = self.state.direction;
        self.state.direction = direction;
        let result = match self.field(Role::Reverse)? {
            // The direction is a field of its own: write it now.
            Some(r) => self.command(&[(r, direction == Direction::Reverse)]) $($aw)*,
            // The direction is the choice of run terminal: check there is one.
            None if direction == Direction::Reverse && !self.supports(Role::RunReverse) => {
                Err(self.no_reverse())
            }
            None => Ok(()),
        };
        if result.is_err() {
            self.state.direction = before;
        }
        result
    }

    $($asy)* fn set_reference(&mut self, hz: f64) -> Result<(), Error> {
        self.place(Role::FrequencyReference, "register")?;
        self.network_source(Role::ReferenceSource) $($aw)*?;
        self.check_max_frequency(hz) $($aw)*?;
        self.write_number(Role::FrequencyReference, hz) $($aw)*
    }

    $($asy)* fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error> {
        // Check both are writable before writing either.
        let accel = self.place(Role::AccelTime, "register")?;
        let decel = self.place(Role::DecelTime, "register")?;
        let shared = accel.shared_with == Some(Role::DecelTime)
            || decel.shared_with == Some(Role::AccelTime)
            || (accel.target.row().is_some() && accel.target.row() == decel.target.row());
        if shared {
            // One ramp register for both: one value, written once.
            if accel_s != decel_s {
                return Err(Refusal::SharedRegister {
                    drive: self.drive(),
                    role: Role::AccelTime.id(),
                    other: Role::DecelTime.id(),
                    register: accel.target.row().map_or("", |row| self.row(row).info.id),
                    asked: format!("{accel_s} s and {decel_s} s"),
                }
                .into());
            }
            return self.write_number(Role::AccelTime, accel_s) $($aw)*;
        }
        self.write_number(Role::AccelTime, accel_s) $($aw)*?;
        self.write_number(Role::DecelTime, decel_s) $($aw)*
    }

    $($asy)* fn reference(&mut self) -> Result<f64, Error> {
        self.read_number(Role::ReferenceMonitor) $($aw)*
    }

    $($asy)* fn output_frequency(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputFrequency) $($aw)*
    }

    $($asy)* fn output_current(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputCurrent) $($aw)*
    }

    $($asy)* fn output_voltage(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputVoltage) $($aw)*
    }

    $($asy)* fn dc_bus_voltage(&mut self) -> Result<f64, Error> {
        self.read_number(Role::DcBusVoltage) $($aw)*
    }

    $($asy)* fn status(&mut self) -> Result<Status, Error> {
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
                    let w = self.read_word(f.row) $($aw)*?;
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

    $($asy)* fn fault_code(&mut self) -> Result<FaultCode, Error> {
        self.read_fault(Role::FaultCode) $($aw)*
    }

    $($asy)* fn last_fault(&mut self) -> Result<FaultCode, Error> {
        self.read_fault(Role::LastFault) $($aw)*
    }

    $($asy)* fn reset_fault(&mut self) -> Result<(), Error> {
        if self.state.roles.profile.is_some() {
            return self.acknowledge() $($aw)*;
        }
        let p = self.place(Role::FaultReset, "field")?;
        let Target::Field(f) = p.target else {
            return Err(self.misplaced(Role::FaultReset, "field"));
        };
        // An unknown register may hold the reset: released first too.
        let set = self
            .state
            .commands
            .iter()
            .find(|c| c.row == f.row)
            .is_some_and(|c| c.told.is_none_or(|w| f.holds(w)));
        // On an edge, and where the manual does not print edge or level (safe for both), a reset
        // that may be set is released first, so the drive sees the off → on transition.
        if f.edge.needs_release_first() && set {
            self.command(&[(f, false)]) $($aw)*?;
        }
        self.command(&[(f, true)]) $($aw)*?;
        self.command(&[(f, false)]) $($aw)*
    }
}

    };
}

vfd_impl!(Vfd, HoldsClient, VariableFrequencyDrive, Client, [] []);

impl<S: SettingsView, C: HoldsClient> Vfd<S, C> {
    /// Waits between two reads of a command profile's status word.
    fn pause(&self, d: std::time::Duration) {
        std::thread::sleep(d);
    }
}

#[cfg(feature = "tokio")]
impl<S: SettingsView, C: HoldsAsyncClient> AsyncVfd<S, C> {
    /// Waits between two reads of a command profile's status word.
    async fn pause(&self, d: std::time::Duration) {
        tokio::time::sleep(d).await;
    }
}
#[cfg(feature = "tokio")]
vfd_impl!(AsyncVfd, HoldsAsyncClient, AsyncVariableFrequencyDrive, AsyncClient, [async] [.await]);
