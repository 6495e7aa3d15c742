//! What carries out a drive's commands on its link: one per drive for the bridge's life, so that
//! every command composes from what the bridge told the drive before (the drive trait's memory:
//! the run and direction it gave, each command register's word), never from a fresh start.
//!
//! - `run` keeps the direction the drive turns in (the bridge has no direction command): the
//!   direction is taken from the drive's status (`reversing`) or its command word before the run.
//! - `stop` is the drive trait's stop.
//! - `fault_reset` acts only on a drive that reports a fault (the map's `fault` status role), or,
//!   where the map has none, on a drive that does not report running: on a drive running without
//!   a fault it is refused, since the manuals' reset acts on a trip and the word that carries it
//!   would otherwise release the run command.
//! - `set/<register>` writes through the write gate, as `drivemap write` does; fields of a
//!   command register are written through the drive object (the word composed from what the
//!   bridge told the drive, never from a word read back), so later runs and stops keep them; a
//!   whole command word written makes the next run or stop read the register back first.

use std::collections::BTreeSet;

use drivemap_live::LiveSettings;
use drivemap_live::codec;
use drivemap_live::intern::intern;
use drivemap_live::lookup;
use drivemap_map::Map;
use drivemap_map::Quantity;
use drivemap_map::RegisterRef;
use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::core::plan::{Conversion, Dependency};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::roles::RoleKind;
use drivemap_runtime::core::scale::Rounding;
use drivemap_runtime::gate;
use drivemap_runtime::vfd::{Memory, VariableFrequencyDrive, Vfd};

use crate::link::{Action, Command, LinkClient};
use crate::{CommandFailure, PollFailure};

/// Carries out one drive's commands (see the [module](self)).
pub(crate) struct Commander {
    /// The drive's index in the bridge.
    pub(crate) index: usize,
    /// Its name (topics, logs).
    pub(crate) name: String,
    pub(crate) drive: &'static Map,
    pub(crate) slave: u8,
    pub(crate) options: ClientOptions,
    pub(crate) kind: TransportKind,
    /// Register ids whose value was given, not read.
    pub(crate) fixed: BTreeSet<String>,
    /// Register ids the polled reads depend on (a write to one plans the reads again).
    pub(crate) deps: Vec<String>,
    /// The settings the link's last poll read.
    pub(crate) settings: LiveSettings,
    /// What the drive trait knew after the last command.
    pub(crate) memory: Option<Memory>,
    /// The next command reads the command registers back first (at start, after a set).
    pub(crate) forget: bool,
    /// A command wrote what the polled reads depend on.
    pub(crate) replan: bool,
    /// Writes through the drive's map: refused (a draft without `--draft`, why), said to go
    /// through a draft (the note), or a reviewed map's (`None`).
    pub(crate) draft: Result<Option<String>, String>,
}

impl Commander {
    /// Takes the settings the link's last poll of the drive read.
    pub(crate) fn update_settings(&mut self, settings: &LiveSettings) {
        if &self.settings != settings {
            self.settings = settings.clone();
        }
    }

    /// Whether a command wrote what the drive's polled reads depend on (cleared by the call).
    pub(crate) fn take_replan(&mut self) -> bool {
        std::mem::take(&mut self.replan)
    }

    /// Carries out `command`: the drive trait's calls (run, stop, reference, fault reset) or a
    /// register write through the write gate. Returns what was done, or why nothing was.
    pub(crate) fn execute(
        &mut self,
        client: &mut LinkClient,
        command: &Command,
    ) -> Result<String, CommandFailure> {
        client.switch_drive(self.drive.plan().profile, self.options);
        if let Err(why) = &self.draft {
            return Err(CommandFailure::Draft { why: why.clone() });
        }
        let value = command.payload.trim();
        let action = match &command.action {
            Action::Set { register } => {
                return self.write(client, register, value).map(|d| self.said(d));
            }
            a => a.clone(),
        };
        let drive = self.drive;
        let plan = drive.plan();
        let mut d = Vfd::from_plan(
            &mut *client,
            self.slave,
            self.settings.view(drive),
            plan.registers,
            plan.roles,
        );
        if let Some(m) = self.memory.take() {
            d = d.with_memory(m);
        }
        let unknown = std::mem::take(&mut self.forget);
        if unknown {
            d.forget_commands();
        }
        let result = match action {
            // The direction the drive turns in, read before every run: the bridge commands no
            // direction, so a run never reverses a drive another master runs in reverse.
            Action::Run => d
                .adopt_direction()
                .and_then(|_| d.run())
                .map(|()| "running".to_owned())
                .map_err(CommandFailure::from),
            Action::Stop => {
                if unknown {
                    // Keeps the direction in the word the stop writes; a failed read holds
                    // no stop back (the direction set stays).
                    let _ = d.adopt_direction();
                }
                d.stop()
                    .map(|()| "stopped".to_owned())
                    .map_err(CommandFailure::from)
            }
            Action::FaultReset => match d.status() {
                Err(e) => Err(e.into()),
                Ok(s) if s.fault == Some(false) => Err(CommandFailure::NoFault {
                    running: s.running == Some(true),
                }),
                Ok(s) if s.fault.is_none() && s.running == Some(true) => {
                    Err(CommandFailure::RunningWithoutFaultRole)
                }
                Ok(_) => d
                    .reset_fault()
                    .map(|()| "fault reset".to_owned())
                    .map_err(CommandFailure::from),
            },
            Action::Reference => match frequency(value) {
                Ok(hz) => d
                    .set_reference(hz)
                    .map(|()| format!("frequency reference {hz} Hz"))
                    .map_err(CommandFailure::from),
                Err(e) => Err(e),
            },
            Action::Set { .. } => unreachable!("handled above"),
        };
        self.memory = Some(d.memory());
        result.map(|done| self.said(done))
    }

    /// What was done, with the draft's note where the map is a draft written through.
    fn said(&self, done: String) -> String {
        match &self.draft {
            Ok(Some(note)) => format!("{done} ({note})"),
            _ => done,
        }
    }

    /// Writes `value` to the register named `name`, as `drivemap write` does: parsed by the
    /// register's conversion (range, steps, limits through other parameters read first), the
    /// gate checked, other bit fields kept.
    fn write(
        &mut self,
        client: &mut LinkClient,
        name: &str,
        value: &str,
    ) -> Result<String, CommandFailure> {
        let drive = self.drive;
        let profile = drive.plan().profile;
        let slave = self.slave;
        let kind = self.kind;
        let r = lookup::find(drive, name)?;
        if value.is_empty() {
            return Err(CommandFailure::NoValue {
                register: r.label(),
            });
        }
        let rule = gate::rule(profile, intern(r.id()))
            .and_then(|rule| gate::check_link(profile, kind, slave, rule).map(|()| rule))
            .map_err(|source| CommandFailure::Refused {
                register: r.label(),
                source,
            })?;
        // What its scale and limits depend on, read now (V7's reference against n011).
        let settings = self.settings_now(client, r)?;
        let row = r.plan();
        let at = u16::try_from(drive.plan().order[r.index()]).ok();
        let command_register = drive
            .plan()
            .roles
            .places
            .iter()
            .any(|p| p.role.kind() == RoleKind::Command && p.target.row() == at);
        let raw = match codec::field_input(drive, r, value)? {
            Some(input) => {
                let Conversion::Bits { mask, .. } = row.conversion else {
                    return Err(CommandFailure::NoFields {
                        register: r.label(),
                    });
                };
                if command_register && let Some(at) = at {
                    // Composed as the drive trait composes command words (what the bridge told
                    // the drive, no run or reset bit the payload does not set unless the drive
                    // runs), never from a word read back; the drive object remembers it, so
                    // later runs and stops keep these fields.
                    return self.write_command_fields(
                        client,
                        r,
                        at,
                        input.mask & mask,
                        input.value,
                    );
                }
                let word = if input.mask & mask == mask || !r.readable() {
                    input.value
                } else {
                    let current =
                        self.read_raw(client, r)
                            .map_err(|source| CommandFailure::OtherFields {
                                id: r.id().to_owned(),
                                source: Box::new(source),
                            })? as u16;
                    ((current & !input.mask) | input.value) & mask
                };
                codec::encode(drive, r, f64::from(word), &settings)?
            }
            None => codec::parse_value_with(drive, r, value, &settings, Rounding::Exact)?,
        };
        let address = self.address(r).map_err(CommandFailure::Address)?;
        let words = rule.width.split(raw);
        gate::check(
            profile,
            kind,
            slave,
            gate::WriteTarget::Rule(rule),
            address,
            words.iter().take(usize::from(rule.width.count())).copied(),
        )
        .map_err(|source| CommandFailure::Refused {
            register: r.label(),
            source,
        })?;
        let between = row.repeat_needs_change.map(|x| x.between);
        if command_register {
            // Whatever becomes of the write, the next run or stop reads the word back first.
            self.forget = true;
        }
        match between {
            Some(b) => client.write_changed(slave, rule, address, b, raw),
            None => client.write_rule(slave, rule, address, raw),
        }?;
        let shown = codec::decode_written(drive, r, raw, &settings)
            .map(|v| v.to_string())
            .unwrap_or_else(|_| raw.to_string());
        // A written dependency changes conversions: read it again with the next cycle.
        if self.deps.iter().any(|d| d == r.id()) {
            self.replan = true;
        }
        Ok(format!("wrote {} = {shown}", r.label()))
    }

    /// Writes the fields `mask` of command register `r` (plan row `row`) through the drive
    /// object ([`Vfd::write_command_fields`]).
    fn write_command_fields(
        &mut self,
        client: &mut LinkClient,
        r: RegisterRef<'_>,
        row: u16,
        mask: u16,
        value: u16,
    ) -> Result<String, CommandFailure> {
        let drive = self.drive;
        let plan = drive.plan();
        let mut d = Vfd::from_plan(
            &mut *client,
            self.slave,
            self.settings.view(drive),
            plan.registers,
            plan.roles,
        );
        if let Some(m) = self.memory.take() {
            d = d.with_memory(m);
        }
        if std::mem::take(&mut self.forget) {
            d.forget_commands();
        }
        let result = d.write_command_fields(row, mask, value);
        self.memory = Some(d.memory());
        let word = result?;
        let shown = codec::decode_written(drive, r, u32::from(word), &self.settings)
            .map(|v| v.to_string())
            .unwrap_or_else(|_| word.to_string());
        Ok(format!("wrote {} = {shown}", r.label()))
    }

    fn address(&self, r: RegisterRef<'_>) -> Result<u16, PollFailure> {
        self.address_with(r, &self.settings)
    }

    fn address_with(
        &self,
        r: RegisterRef<'_>,
        settings: &drivemap_live::LiveSettings,
    ) -> Result<u16, PollFailure> {
        let drive = self.drive;
        r.plan()
            .locate(&settings.view(drive), self.kind)
            .map_err(|e| PollFailure::AddressUnknown {
                register: r.label(),
                setting: e.setting,
            })
    }

    /// The settings `r`'s conversion and limits depend on, read from the drive now (the
    /// selecting parameters first, then the quantities they pick; at most three rounds), over
    /// what the link's polls last read; given ones (`--set`) kept. A write converted with them
    /// means what the drive will take it for.
    pub(crate) fn settings_now(
        &self,
        client: &mut LinkClient,
        r: RegisterRef<'_>,
    ) -> Result<drivemap_live::LiveSettings, CommandFailure> {
        let drive = self.drive;
        let plan = drive.plan();
        let mut settings = self.settings.clone();
        for _ in 0..3 {
            let mut rows = Vec::new();
            r.plan().depends_on(&settings.view(drive), |dep| match dep {
                Dependency::Code(s) => {
                    rows.extend(
                        plan.settings
                            .codes
                            .get(usize::from(s.slot))
                            .map(|c| c.register),
                    );
                }
                Dependency::Quantity(s) => {
                    if let Some(Quantity::Register(row)) =
                        plan.settings.quantities.get(usize::from(s.slot))
                    {
                        rows.push(*row);
                    }
                }
            });
            if let Some(Dependency::Quantity(s)) = r.plan().limit_dependency()
                && let Some(Quantity::Register(row)) =
                    plan.settings.quantities.get(usize::from(s.slot))
            {
                rows.push(*row);
            }
            let before = settings.clone();
            for row in rows {
                let Some(dep) = drive.register_of_row(row) else {
                    continue;
                };
                if self.fixed.contains(dep.id()) {
                    continue;
                }
                let raw = self
                    .read_raw_with(client, dep, &settings)
                    .map_err(|source| CommandFailure::Dependency {
                        register: dep.label(),
                        source: Box::new(source),
                    })?;
                settings.absorb(drive, dep.address(), raw as u16);
            }
            if settings == before {
                break;
            }
        }
        Ok(settings)
    }

    fn read_raw(&self, client: &mut LinkClient, r: RegisterRef<'_>) -> Result<u32, PollFailure> {
        self.read_raw_with(client, r, &self.settings)
    }

    fn read_raw_with(
        &self,
        client: &mut LinkClient,
        r: RegisterRef<'_>,
        settings: &drivemap_live::LiveSettings,
    ) -> Result<u32, PollFailure> {
        let address = self.address_with(r, settings)?;
        let info = r.plan().info;
        let mut w = [0u16; 2];
        let words = &mut w[..usize::from(info.width.count())];
        client.read_table(self.slave, info.table, address, words)?;
        Ok(info.width.join(words))
    }
}

/// A reference payload in Hz (`30`, `30.5`, `30 Hz`), finite.
fn frequency(value: &str) -> Result<f64, CommandFailure> {
    value
        .trim_end_matches("Hz")
        .trim()
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite())
        .ok_or_else(|| CommandFailure::NotAFrequency {
            value: crate::log::quote(value),
        })
}
