//! The drive's state machine, written once for the blocking [`Vfd`](super::Vfd) and the async
//! `AsyncVfd`: [`State`], what a drive object knows of its drive, and [`Machine`], the drive's
//! calls over a client's [`Session`], `async` over a [`Wire`] (awaited by the async drive, run
//! by [`block_on`](crate::wire::block_on) by the blocking one). See [the safety
//! contract](super#safety-contract).

use drivemap_core::command_profile::{CommandProfile, Path, PathKind, Transition};
use drivemap_core::plan::SettingsView;
use drivemap_core::plan::{Conversion, RegisterPlan};
use drivemap_core::register::DriveSettings;
use drivemap_core::roles::Roles;
use drivemap_core::roles::{FieldRole, NumberField, Place, Role, RoleKind, Target};
use drivemap_core::rule::Broadcast;
use drivemap_core::scale::{Rounding, ValueError};

use super::{Direction, FaultCode, Memory, Status};
use crate::client::Session;
use crate::error::{Error, Refusal};
use crate::wire::Wire;
use drivemap_core::profile::TransportKind;

/// What a [`Vfd`](super::Vfd) or an `AsyncVfd` knows of its drive besides the client.
pub(super) struct State<S> {
    slave: u8,
    pub(super) settings: S,
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
    pub(super) rounding: Rounding,
}

/// A command register and what this master last told it.
#[derive(Debug, Clone, Copy)]
pub(super) struct CommandWord {
    /// The plan row.
    row: u16,
    /// Every command role of the register released (stop, forward, no reset), other bits 0.
    released: u16,
    /// The word last written, or `None` before the first write and after a write that failed
    /// (the drive may hold the new word, the old one, or anything in between).
    told: Option<u16>,
}

impl<S> State<S> {
    /// The drive on `slave` over a link of `kind`, described by `registers` and `roles`, with
    /// `settings` in force: every command register taken as released.
    pub(super) fn new(
        slave: u8,
        settings: S,
        registers: &'static [RegisterPlan],
        roles: Roles,
        kind: TransportKind,
    ) -> Self {
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
        State {
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
        }
    }

    /// [`Vfd::memory`](super::Vfd::memory).
    pub(super) fn memory(&self) -> Memory {
        Memory {
            direction: self.direction,
            running: self.running,
            commands: self.commands.clone(),
            sources: self.sources,
        }
    }

    /// Takes what an earlier drive object of the same map knew, unless `memory` is of other
    /// command registers (another map's): [`Vfd::with_memory`](super::Vfd::with_memory).
    pub(super) fn remember(&mut self, memory: Memory) {
        let same = memory.commands.len() == self.commands.len()
            && memory
                .commands
                .iter()
                .zip(&self.commands)
                .all(|(a, b)| a.row == b.row && a.released == b.released);
        if same {
            self.direction = memory.direction;
            self.running = memory.running;
            self.commands = memory.commands;
            self.sources = memory.sources;
        }
    }

    /// [`Vfd::forget_commands`](super::Vfd::forget_commands).
    pub(super) fn forget_commands(&mut self) {
        for c in &mut self.commands {
            c.told = None;
        }
    }

    /// [`Vfd::forget_sources`](super::Vfd::forget_sources).
    pub(super) fn forget_sources(&mut self) {
        self.sources = [false; 2];
    }

    /// [`Vfd::holds_command`](super::Vfd::holds_command).
    pub(super) fn holds_command(&self, row: u16) -> bool {
        self.commands.iter().any(|c| c.row == row)
    }

    /// Whether the map gives `role` on this link (the drive trait's `supports`).
    pub(super) fn supports(&self, role: Role) -> bool {
        if let Some(p) = self.roles.profile {
            match role {
                Role::Run => return p.path(PathKind::Run).is_some(),
                Role::FaultReset => return p.path(PathKind::ResetFault).is_some(),
                _ => {}
            }
        }
        self.roles.of(role).any(|p| self.usable(p))
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
}

/// Checks that a client of `client_drive`'s profile serves drive `drive`, takes the external
/// quantities (name, value) into `settings` and reads the parameters its conversions depend on:
/// [`Vfd::connect`](super::Vfd::connect) before the drive object is made.
pub(super) async fn load_settings<S: DriveSettings, W: Wire>(
    mut session: Session<'_, W>,
    drive: &'static str,
    slave: u8,
    settings: &mut S,
    externals: &[(&str, f64)],
) -> Result<(), Error> {
    if session.core.profile.drive_id != drive {
        return Err(Refusal::OtherDrive {
            client: session.core.profile.drive_id,
            drive,
        }
        .into());
    }
    for (name, value) in externals {
        if !settings.set_external(name, *value) {
            return Err(Refusal::UnknownExternal {
                drive: session.core.profile.drive_id,
                name: (*name).to_owned(),
            }
            .into());
        }
    }
    session.load_settings(slave, settings).await
}

/// A drive object's state and its client's session, for one call of the drive.
pub(super) struct Machine<'a, S, W> {
    session: Session<'a, W>,
    state: &'a mut State<S>,
}

impl<'a, S: SettingsView, W: Wire> Machine<'a, S, W> {
    /// The drive `state` describes, over `session`.
    pub(super) fn new(session: Session<'a, W>, state: &'a mut State<S>) -> Self {
        Machine { session, state }
    }

    fn drive(&self) -> &'static str {
        self.session.core.profile.drive_id
    }

    fn row(&self, row: u16) -> &'static RegisterPlan {
        self.state.row(row)
    }

    fn usable(&self, p: &Place) -> bool {
        self.state.usable(p)
    }

    fn supports(&self, role: Role) -> bool {
        self.state.supports(role)
    }

    /// [`Vfd::adopt_direction`](super::Vfd::adopt_direction).
    pub(super) async fn adopt_direction(&mut self) -> Result<Option<Direction>, Error> {
        let told = match self.field(Role::Reverse)? {
            Some(r) => self.read_back(r.row).await.map(|w| r.holds(w)),
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
                Some(f.holds(self.read_word(f.row).await?))
            }
            (None, _) => None,
        };
        let taken = reverse.map(|r| {
            if r {
                Direction::Reverse
            } else {
                Direction::Forward
            }
        });
        if let Some(d) = taken {
            self.state.direction = d;
        }
        Ok(taken)
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
    async fn read_raw(&mut self, row: u16) -> Result<u32, Error> {
        let r = self.row(row);
        let address = r.locate(&self.state.settings, self.state.kind)?;
        let mut raw = [0u16; 2];
        let words = &mut raw[..usize::from(r.info.width.count())];
        self.session
            .read_table(self.state.slave, r.info.table, address, words)
            .await?;
        Ok(r.info.width.join(words))
    }

    /// The word of a one-register row (bit fields and codes: the map keeps them in one word).
    async fn read_word(&mut self, row: u16) -> Result<u16, Error> {
        Ok(self.read_raw(row).await? as u16)
    }

    async fn write_word(&mut self, row: u16, raw: u32) -> Result<(), Error> {
        let r = self.row(row);
        let address = r.locate(&self.state.settings, self.state.kind)?;
        let rule = r.write_rule();
        match r.repeat_needs_change {
            // A role register whose drive executes only a changed value: its intermediate first.
            Some(x) => {
                self.session
                    .write_changed(self.state.slave, &rule, address, x.between, raw)
                    .await
            }
            None => {
                self.session
                    .write_rule(self.state.slave, &rule, address, raw)
                    .await
            }
        }
    }

    /// Reads the number role `role` in its unit.
    async fn read_number(&mut self, role: Role) -> Result<f64, Error> {
        let p = self.place(role, "register")?;
        match p.target {
            Target::Register(row) => {
                let raw = self.read_raw(row).await?;
                Ok(self.row(row).decode_number(raw, &self.state.settings)?)
            }
            Target::External { slot, name } => {
                self.state.settings.quantity(slot).ok_or_else(|| {
                    Refusal::ExternalNotSet {
                        drive: self.drive(),
                        name,
                    }
                    .into()
                })
            }
            Target::NumberField(f) => {
                let word = self.read_word(f.row).await?;
                Ok(f.value(word))
            }
            Target::Field(_) => Err(self.misplaced(role, "register")),
        }
    }

    /// Writes the number role `role`, range-checked by the register's conversion.
    async fn write_number(&mut self, role: Role, value: f64) -> Result<(), Error> {
        let p = self.place(role, "register")?;
        if let Target::NumberField(f) = p.target {
            return self.write_number_field(role, f, value).await;
        }
        let Target::Register(row) = p.target else {
            return Err(self.misplaced(role, "writable register"));
        };
        let raw =
            self.row(row)
                .encode_number_with(value, &self.state.settings, self.state.rounding)?;
        self.write_word(row, raw).await
    }

    /// Writes a number role that is a field of a register: reads the word, puts the value's
    /// count into the field, writes the word back — only where that keeps the rest of the word
    /// as the drive has it: the register is readable here and reads mean what writes do, it is
    /// not a broadcast, and no command role lives in it (a read-back command word could send
    /// a run bit again). Elsewhere refused, with why, before anything is sent.
    async fn write_number_field(
        &mut self,
        role: Role,
        f: NumberField,
        value: f64,
    ) -> Result<(), Error> {
        let r = self.row(f.row);
        let why = if !r.info.access.readable() || !r.transports.contains(self.state.kind) {
            Some("the register cannot be read on this link, so the rest of its word is unknown")
        } else if !r.read_values.is_empty() || r.read_param.is_some() {
            Some(
                "the register reads back other values than are written, so the rest of its word cannot be kept",
            )
        } else if self.state.slave == 0 || r.broadcast == Broadcast::Only {
            Some("a broadcast cannot read the word first")
        } else if self
            .state
            .roles
            .places
            .iter()
            .any(|p| p.role.kind() == RoleKind::Command && p.target.row() == Some(f.row))
        {
            Some(
                "command fields share the register: writing back what was read could repeat a run or reset",
            )
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
        let word = self.read_word(f.row).await?;
        let Some(word) = f.put(word, count) else {
            // encode_decimal_with keeps the count in the field's range.
            return Err(self.misplaced(role, "field that holds the value"));
        };
        self.write_word(f.row, u32::from(word)).await
    }

    /// Sets the command fields of `changes` in their registers' words and writes each word once,
    /// in the order of `changes` with releases before sets (so a stop goes out before a
    /// direction, and a run after it). Each word is composed from what this master last told the
    /// register (`base`) with the run and direction fields as the last successful `run()`
    /// or `stop()` and the direction set say, then `changes` on top. A write that fails makes
    /// its register unknown.
    async fn command(&mut self, changes: &[(FieldRole, bool)]) -> Result<(), Error> {
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
                    let base = self.base(f.row).await?;
                    words.push((f.row, base));
                    &mut words.last_mut().expect("just pushed").1
                }
            };
            *word = f.put(*word, f.code(*on));
        }
        for (row, word) in words {
            let result = self.write_word(row, u32::from(word)).await;
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
    async fn base(&mut self, row: u16) -> Result<u16, Error> {
        let Some(c) = self.state.commands.iter().find(|c| c.row == row).copied() else {
            return Ok(0);
        };
        let mut word = match c.told {
            Some(w) => w,
            None => match self.read_back(row).await {
                Some(read) => read,
                None => c.released,
            },
        };
        for p in self.state.roles.places {
            if let (RoleKind::Command, Target::Field(f)) = (p.role.kind(), p.target)
                && f.row == row
            {
                word = f.put(word, f.code(false));
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
        if let Ok(Some(r)) = self.field(Role::Reverse)
            && r.row == row
        {
            word = r.put(word, r.code(self.state.direction == Direction::Reverse));
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
    async fn read_back(&mut self, row: u16) -> Option<u16> {
        let r = self.row(row);
        let readable = r.info.access.readable()
            && r.read_values.is_empty()
            && r.read_param.is_none()
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
        self.read_word(row).await.ok().map(|w| w & mask)
    }

    /// [`Vfd::command_fields_word`](super::Vfd::command_fields_word).
    pub(super) async fn command_fields_word(
        &mut self,
        row: u16,
        mask: u16,
        value: u16,
    ) -> Result<u16, Error> {
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
            && r.read_param.is_none()
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
            Some(self.read_word(row).await? & fields_mask)
        } else {
            None
        };
        let running = has_run
            && (self.state.running.is_some()
                || (self.state.slave != 0
                    && self.supports(Role::Running)
                    && self.status().await?.running == Some(true)));
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
            if let Some(d) = self.state.running
                && let Ok(fields) = self.run_fields(true, d)
            {
                for (f, on) in fields.iter().filter(|(f, on)| f.row == row && *on) {
                    word = f.put(word, f.code(*on));
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

    /// [`Vfd::write_command_fields`](super::Vfd::write_command_fields).
    pub(super) async fn write_command_fields(
        &mut self,
        row: u16,
        mask: u16,
        value: u16,
    ) -> Result<u16, Error> {
        let word = self.command_fields_word(row, mask, value).await?;
        let result = self.write_word(row, u32::from(word)).await;
        if let Some(c) = self.state.commands.iter_mut().find(|c| c.row == row) {
            c.told = result.is_ok().then_some(word);
        }
        result.map(|()| word)
    }

    /// [`Vfd::profile_state`](super::Vfd::profile_state).
    pub(super) async fn profile_state(&mut self) -> Result<Option<&'static str>, Error> {
        let p = self.profile(PathKind::Run.id())?;
        let word = self.read_word(p.status).await?;
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
    async fn read_state(&mut self, p: &'static CommandProfile, path: &Path) -> Result<u8, Error> {
        let word = self.read_word(p.status).await?;
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
    async fn write_transition(
        &mut self,
        p: &'static CommandProfile,
        t: &Transition,
        clear: u16,
    ) -> Result<(), Error> {
        let base = self.base(p.control).await?;
        let word = t.compose(base) & !clear;
        let result = self.write_word(p.control, u32::from(word)).await;
        if let Some(c) = self.state.commands.iter_mut().find(|c| c.row == p.control) {
            c.told = result.is_ok().then_some(word);
        }
        result
    }

    /// Waits until the drive shows `t.to` (or a state that ends `path`), reading the status
    /// word until `t.limit_ms` has passed; a drive that shows the fault state instead (it
    /// tripped) ends the wait at once.
    async fn await_transition(
        &mut self,
        p: &'static CommandProfile,
        path: &Path,
        t: &Transition,
    ) -> Result<(), Error> {
        let start = std::time::Instant::now();
        let limit = std::time::Duration::from_millis(u64::from(t.limit_ms));
        let faults: Vec<u8> = p
            .path(PathKind::ResetFault)
            .map(|r| {
                r.via
                    .iter()
                    .filter_map(|&i| p.transition(i))
                    .flat_map(|x| x.from.iter().copied())
                    .collect()
            })
            .unwrap_or_default();
        loop {
            let s = self.read_state(p, path).await?;
            if s == t.to || path.to.contains(&s) {
                return Ok(());
            }
            let why = if faults.contains(&s) && path.kind != PathKind::ResetFault {
                Some(format!(
                    "the drive tripped after `{}` ({:#06X})",
                    t.id, t.word
                ))
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
            self.session
                .wire
                .pause(left.min(std::time::Duration::from_millis(10)))
                .await;
        }
    }

    /// Walks path `kind` of the command profile: reads the state, writes the first transition
    /// of the path that leaves it, waits for the state it leads to, until the drive shows a
    /// state that ends the path. A stop, coast or quick stop that finds the drive already
    /// there writes the path's first word once all the same (so the control word holds no
    /// run), and one whose status cannot be read writes it before returning the error. No path
    /// but `run` writes a run transition.
    async fn walk(&mut self, kind: PathKind) -> Result<(), Error> {
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
        let first = path
            .via
            .first()
            .and_then(|&t| p.transition(t))
            .filter(|t| !p.runs(t));
        let stopping = matches!(kind, PathKind::Stop | PathKind::Coast | PathKind::QuickStop);
        let mut wrote = false;
        for _ in 0..=path.via.len() + 1 {
            let s = match self.read_state(p, path).await {
                Ok(s) => s,
                Err(e) => {
                    if stopping
                        && !wrote
                        && let Some(t) = first
                    {
                        // Whatever the drive shows, the stop word goes out.
                        let _ = self.write_transition(p, t, 0).await;
                    }
                    return Err(e);
                }
            };
            if path.to.contains(&s) {
                if stopping
                    && !wrote
                    && let Some(t) = first
                {
                    self.write_transition(p, t, 0).await?;
                }
                return Ok(());
            }
            let Some(t) = p.next(path, s) else {
                if stopping
                    && !wrote
                    && let Some(t) = first
                {
                    let _ = self.write_transition(p, t, 0).await;
                }
                return Err(Error::StateMachine {
                    drive: self.drive(),
                    path: kind.id(),
                    state: p.state_id(s).to_owned(),
                    why: format!(
                        "no transition of the `{}` path leaves this state",
                        kind.id()
                    ),
                });
            };
            if kind != PathKind::Run && p.runs(t) {
                // Validation refuses such a map; a plan built by hand may still have one.
                return Err(self.misplaced(Role::Run, "path that does not run the drive"));
            }
            self.write_transition(p, t, 0).await?;
            wrote = true;
            self.await_transition(p, path, t).await?;
        }
        let s = self.read_state(p, path).await?;
        if path.to.contains(&s) {
            return Ok(());
        }
        Err(Error::StateMachine {
            drive: self.drive(),
            path: kind.id(),
            state: p.state_id(s).to_owned(),
            why: format!(
                "the drive did not reach the end of the `{}` path",
                kind.id()
            ),
        })
    }

    /// The profile's fault acknowledge: only while the drive shows a state the `reset_fault`
    /// path's transitions leave (the fault state), its edge bits cleared first where they may
    /// be set, then set, the state awaited, then cleared.
    async fn acknowledge(&mut self) -> Result<(), Error> {
        let p = self.profile(Role::FaultReset.id())?;
        let Some(path) = p.path(PathKind::ResetFault) else {
            return Err(self.misplaced(Role::FaultReset, "command profile path"));
        };
        let s = self.read_state(p, path).await?;
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
            self.write_transition(p, t, t.edge).await?;
        }
        self.write_transition(p, t, 0).await?;
        let reached = self.await_transition(p, path, t).await;
        let released = if t.edge != 0 {
            self.write_transition(p, t, t.edge).await
        } else {
            Ok(())
        };
        reached.and(released)
    }

    /// A fault code role (`fault_code`, `last_fault`): the register's word or the field's bits,
    /// with the map's name for it.
    async fn read_fault(&mut self, role: Role) -> Result<FaultCode, Error> {
        let p = self.place(role, "register")?;
        if let Target::NumberField(f) = p.target {
            let word = self.read_word(f.row).await?;
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
        let code = self.read_word(row).await?;
        let r = self.row(row);
        Ok(FaultCode {
            code,
            value: if r.signed() {
                i32::from(code as i16)
            } else {
                i32::from(code)
            },
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
    async fn check_max_frequency(&mut self, hz: f64) -> Result<(), Error> {
        if self.state.roles.of(Role::MaxFrequency).next().is_none() || !hz.is_finite() {
            return Ok(());
        }
        let place = self.place(Role::FrequencyReference, "register")?;
        let register = place
            .target
            .row()
            .map_or(Role::FrequencyReference.id(), |row| self.row(row).info.id);
        let max = self.read_number(Role::MaxFrequency).await?;
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

    /// Checks that the drive takes what `role` (a source role) selects from the network on
    /// this link: reads the parameter (or status field) the map names, once; a network source
    /// is kept, another is refused and read again next time.
    async fn network_source(&mut self, role: Role) -> Result<(), Error> {
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
        let word = self.read_word(f.row).await?;
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

    // The drive trait's calls.

    pub(super) async fn run(&mut self) -> Result<(), Error> {
        if self.state.roles.profile.is_some() {
            self.state.running = None;
            self.network_source(Role::CommandSource).await?;
            self.walk(PathKind::Run).await?;
            self.state.running = Some(self.state.direction);
            return Ok(());
        }
        let fields = self.run_fields(true, self.state.direction)?;
        // Until the run is confirmed, every other command composes with run released.
        self.state.running = None;
        // A run the drive would ignore (not the network's to give) is refused, not sent.
        self.network_source(Role::CommandSource).await?;
        self.command(&fields).await?;
        self.state.running = Some(self.state.direction);
        Ok(())
    }

    pub(super) async fn stop(&mut self) -> Result<(), Error> {
        // From now on no word carries a run code until the next run(), whatever becomes of
        // this one.
        self.state.running = None;
        if self.state.roles.profile.is_some() {
            return self.walk(PathKind::Stop).await;
        }
        let fields = self.run_fields(false, self.state.direction)?;
        self.command(&fields).await
    }

    pub(super) async fn profile_state_if_any(&mut self) -> Result<Option<&'static str>, Error> {
        if self.state.roles.profile.is_none() {
            return Ok(None);
        }
        self.profile_state().await
    }

    pub(super) async fn coast(&mut self) -> Result<(), Error> {
        self.state.running = None;
        self.walk(PathKind::Coast).await
    }

    pub(super) async fn quick_stop(&mut self) -> Result<(), Error> {
        self.state.running = None;
        self.walk(PathKind::QuickStop).await
    }

    pub(super) async fn set_direction(&mut self, direction: Direction) -> Result<(), Error> {
        let before = self.state.direction;
        self.state.direction = direction;
        let result = match self.field(Role::Reverse)? {
            // The direction is a field of its own: write it now.
            Some(r) => self.command(&[(r, direction == Direction::Reverse)]).await,
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

    pub(super) async fn set_reference(&mut self, hz: f64) -> Result<(), Error> {
        self.place(Role::FrequencyReference, "register")?;
        self.network_source(Role::ReferenceSource).await?;
        self.check_max_frequency(hz).await?;
        self.write_number(Role::FrequencyReference, hz).await
    }

    pub(super) async fn set_ramp(&mut self, accel_s: f64, decel_s: f64) -> Result<(), Error> {
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
            return self.write_number(Role::AccelTime, accel_s).await;
        }
        self.write_number(Role::AccelTime, accel_s).await?;
        self.write_number(Role::DecelTime, decel_s).await
    }

    pub(super) async fn reference(&mut self) -> Result<f64, Error> {
        self.read_number(Role::ReferenceMonitor).await
    }

    pub(super) async fn output_frequency(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputFrequency).await
    }

    pub(super) async fn output_current(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputCurrent).await
    }

    pub(super) async fn output_voltage(&mut self) -> Result<f64, Error> {
        self.read_number(Role::OutputVoltage).await
    }

    pub(super) async fn dc_bus_voltage(&mut self) -> Result<f64, Error> {
        self.read_number(Role::DcBusVoltage).await
    }

    pub(super) async fn status(&mut self) -> Result<Status, Error> {
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
                    let w = self.read_word(f.row).await?;
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

    pub(super) async fn fault_code(&mut self) -> Result<FaultCode, Error> {
        self.read_fault(Role::FaultCode).await
    }

    pub(super) async fn last_fault(&mut self) -> Result<FaultCode, Error> {
        self.read_fault(Role::LastFault).await
    }

    pub(super) async fn reset_fault(&mut self) -> Result<(), Error> {
        if self.state.roles.profile.is_some() {
            return self.acknowledge().await;
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
            self.command(&[(f, false)]).await?;
        }
        self.command(&[(f, true)]).await?;
        self.command(&[(f, false)]).await
    }
}
