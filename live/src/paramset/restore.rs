//! Restoring: the whole set validated first, a plan of the writes of what differs in the order
//! of the plan's dependencies, each write through the write gate, the map's store command once,
//! every written setting read back.

use std::collections::BTreeSet;

use drivemap_map::Map;
use drivemap_map::Quantity;
use drivemap_map::RegisterRef;
use drivemap_runtime::core::plan::Conversion;
use drivemap_runtime::core::profile::{CommandInfo, CommandKind};
use drivemap_runtime::core::register::WriteRestriction;
use drivemap_runtime::core::roles::{Role, Target};
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::gate::{self, WriteTarget};

use super::file::ParameterSet;
use super::save::read_all;
use super::{by_id, fingerprint, restore_order, settings_of};
use crate::LiveSettings;
use crate::codec::{self, InputError};
use crate::intern::intern;
use crate::session::{Session, SessionError, value_error};

/// A set checked against the map: every value a value of its setting under the set's own
/// selectors and limits, in the order a restore writes them.
#[derive(Debug, Clone)]
pub struct Validated<'d> {
    /// Each setting and its value text, in [`restore_order`].
    pub entries: Vec<(RegisterRef<'d>, String)>,
    /// The set's own selector codes and reference values, and its variant.
    pub settings: LiveSettings,
    /// What does not stop a restore but is worth saying (another fingerprint).
    pub warnings: Vec<String>,
}

/// Why nothing was written.
#[derive(Debug, thiserror::Error)]
pub enum RestoreError {
    /// The set, or a value in it, is refused; every reason, one a line.
    #[error("{}\nnothing written", .0.join("\n"))]
    Refused(Vec<String>),
    /// The drive could not be read.
    #[error(transparent)]
    Session(#[from] SessionError),
}

/// One planned write.
#[derive(Debug, Clone)]
pub struct Write<'d> {
    /// The setting.
    pub register: RegisterRef<'d>,
    /// The value the drive holds, as read (`None`: it could not be read).
    pub from: Option<String>,
    /// The set's value.
    pub to: String,
    /// The raw value written.
    pub raw: u32,
}

/// A setting not written, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Skipped {
    /// The register id.
    pub id: String,
    /// Why.
    pub reason: String,
}

/// What a restore will do: the writes in order, what already holds the set's value, the store
/// command to run after them.
#[derive(Debug, Clone)]
pub struct RestorePlan<'d> {
    /// The writes, in [`restore_order`].
    pub writes: Vec<Write<'d>>,
    /// Settings that already hold the set's value.
    pub unchanged: Vec<RegisterRef<'d>>,
    /// The map's command that stores written values (ENTER, save), run once after the writes
    /// when they all went through; `None` when nothing is written (or the map has none).
    pub store: Option<&'static CommandInfo>,
    /// The settings in force after the writes (the drive's, with the set's selectors and
    /// references): what the writes are encoded, addressed and verified under.
    pub settings: LiveSettings,
    /// Requests sent to read the drive.
    pub requests: u32,
    /// What the plan noticed (the drive's state, a fingerprint).
    pub warnings: Vec<String>,
}

/// What happened to the store command.
#[derive(Debug, Clone, PartialEq)]
pub enum StoreOutcome {
    /// Nothing written, or the map has no store command.
    NotNeeded,
    /// Run; `wear` says what it cost the EEPROM.
    Stored {
        /// The command's id.
        command: String,
        /// One EEPROM write of its rated endurance, and the writes of this session.
        wear: String,
    },
    /// Not run: the writes did not all go through (run the restore again).
    NotRun(String),
    /// Sent and not confirmed, or refused.
    Failed(String),
}

/// What a restore did.
#[derive(Debug, Clone)]
pub struct RestoreReport {
    /// Written, and read back holding the set's value.
    pub verified: Vec<String>,
    /// Written (or sent without a reply), and not read back holding the set's value: why.
    pub not_verified: Vec<Skipped>,
    /// Not written: why.
    pub not_written: Vec<Skipped>,
    /// Settings that already held the set's value.
    pub unchanged: usize,
    /// The store command.
    pub store: StoreOutcome,
    /// Requests sent by the writes, the store and the read-back.
    pub requests: u32,
}

impl RestoreReport {
    /// Whether the drive now holds the whole set, verified.
    pub fn complete(&self) -> bool {
        self.not_verified.is_empty()
            && self.not_written.is_empty()
            && !matches!(
                self.store,
                StoreOutcome::Failed(_) | StoreOutcome::NotRun(_)
            )
    }
}

/// How far a restore has got, for a progress display.
#[derive(Debug, Clone, PartialEq)]
pub enum Progress {
    /// Writing setting `done + 1` of `total`.
    Writing {
        /// Writes done.
        done: usize,
        /// Writes planned.
        total: usize,
        /// The setting being written.
        id: String,
    },
    /// Running the store command.
    Storing(String),
    /// Reading the written settings back.
    Verifying(usize),
}

/// The set's selector codes and the values of the registers scales and limits are relative
/// to, from the set itself (an entry that is not a value of its register is left out: its own
/// check reports it).
fn set_settings(drive: &Map, set: &ParameterSet, base: &LiveSettings) -> LiveSettings {
    let mut settings = base.clone();
    for (a, o) in &set.variant {
        settings
            .variants
            .entry(a.clone())
            .or_insert_with(|| o.clone());
    }
    for r in drive.selectors() {
        if let Some(s) = set.get(r.id())
            && let Ok(raw) = codec::parse_value(drive, r, &s.value, &settings)
        {
            settings.selectors.insert(r.id().to_owned(), raw as u16);
        }
    }
    for q in &drive.plan().settings.quantities {
        if let Quantity::Register(row) = q
            && let Some(r) = drive.register_of_row(*row)
            && let Some(s) = set.get(r.id())
            && let Ok(v) = s.value.trim().parse::<f64>()
        {
            settings.references.insert(r.id().to_owned(), v);
        }
    }
    settings
}

/// Checks the whole set against `drive` before anything is sent: its map and variant (another
/// is refused unless `other_allowed`), every entry a setting of the map, once, and a value of
/// it (range, step, code, relative limit under the set's own values; a limit through a setting
/// the set does not hold is checked against the drive's value by [`plan`]). `given` holds the
/// link's variants and external quantities. All reasons are returned at once.
pub fn validate<'d>(
    drive: &'d Map,
    set: &ParameterSet,
    given: &LiveSettings,
    other_allowed: bool,
) -> Result<Validated<'d>, RestoreError> {
    let mut reasons = Vec::new();
    let mut warnings = Vec::new();
    if set.drive != drive.id() {
        let what = format!(
            "the set is of map {}, the drive's is {}",
            super::quoted(&set.drive, 60),
            drive.id()
        );
        if other_allowed {
            warnings.push(what);
        } else {
            reasons.push(format!("{what}; restore it anyway with --other"));
        }
    }
    for (axis, option) in &set.variant {
        match drive.variants().iter().find(|a| &a.id == axis) {
            None => reasons.push(format!(
                "variant {}: {} has no such variant axis",
                super::quoted(axis, 40),
                drive.id()
            )),
            Some(a) if !a.options.iter().any(|o| &o.id == option) => reasons.push(format!(
                "variant {axis}={}: not an option of {axis}",
                super::quoted(option, 40)
            )),
            Some(_) => {
                if let Some(chosen) = given.variants.get(axis)
                    && chosen != option
                {
                    let what =
                        format!("the set is of variant {axis}={option}, the drive {axis}={chosen}");
                    if other_allowed {
                        warnings.push(what);
                    } else {
                        reasons.push(format!("{what}; restore it anyway with --other"));
                    }
                }
            }
        }
    }
    if set.fingerprint != fingerprint(drive) {
        warnings.push(format!(
            "the set was saved with another version of the {} map (fingerprint {}); its values are checked against this one",
            drive.id(),
            super::quoted(&set.fingerprint, 40)
        ));
    }
    let settings_list = settings_of(drive);
    // By index: `by_id` below gives the register of an entry's id (ids are unique in a map).
    let is_setting: BTreeSet<usize> = settings_list.iter().map(|r| r.index()).collect();
    let settings = set_settings(drive, set, given);
    let mut seen = BTreeSet::new();
    let mut entries = Vec::new();
    for s in &set.settings {
        let Some(r) = by_id(drive, &s.id) else {
            reasons.push(format!(
                "{}: not a register of {}",
                super::quoted(&s.id, 60),
                drive.id()
            ));
            continue;
        };
        let name = r.label();
        if !seen.insert(s.id.clone()) {
            reasons.push(format!("{name}: given twice"));
            continue;
        }
        if !is_setting.contains(&r.index()) {
            reasons.push(format!(
                "{name}: not a setting a set restores ({})",
                if !r.writable() {
                    "read-only"
                } else if r.param().is_none() {
                    "a command register, not a parameter"
                } else if r.read_param().is_some() {
                    "a read returns another parameter than the one a write sets (`read_param`), so neither its saved value nor a read-back means the value written"
                } else {
                    "a command, or the place of a command role"
                }
            ));
            continue;
        }
        if let Some(code) = &s.code {
            let plan = r.plan();
            let listed = match plan.conversion {
                Conversion::Enum { .. } => s
                    .value
                    .trim()
                    .parse::<u16>()
                    .ok()
                    .and_then(|c| plan.label(c))
                    .map(|l| l.id),
                _ => None,
            };
            if listed != Some(code.as_str()) {
                reasons.push(format!(
                    "{name}: code {} is not {} ({})",
                    s.value,
                    super::quoted(code, 40),
                    listed.map_or("not a listed code".to_owned(), |l| format!(
                        "{} is {l}",
                        s.value
                    ))
                ));
                continue;
            }
        }
        match codec::parse_value(drive, r, &s.value, &settings) {
            Ok(_)
            | Err(InputError::Value(
                ValueError::MissingSetting { .. } | ValueError::LimitNotKnown { .. },
            )) => entries.push((r, s.value.clone())),
            Err(InputError::Value(e)) => {
                reasons.push(format!("{name}: {}", value_error(drive, &e)));
            }
            Err(InputError::Parse(m)) => reasons.push(format!("{name}: {m}")),
        }
    }
    if !reasons.is_empty() {
        return Err(RestoreError::Refused(reasons));
    }
    let regs: Vec<RegisterRef<'_>> = entries.iter().map(|(r, _)| *r).collect();
    let order = restore_order(drive, &regs);
    let entries = order
        .into_iter()
        .filter_map(|r| {
            entries
                .iter()
                .find(|(e, _)| e.id() == r.id())
                .map(|(r, t)| (*r, t.clone()))
        })
        .collect();
    Ok(Validated {
        entries,
        settings,
        warnings,
    })
}

/// Whether the drive shows a status role (read now): `Ok(holds)`, or why it is not known (the
/// map gives the role no place on this link, or reading it failed).
fn status(session: &mut Session<'_>, role: Role) -> Result<bool, String> {
    let drive = session.drive;
    let places: Vec<_> = drive
        .plan()
        .roles
        .of(role)
        .filter(|p| p.transports.contains(session.kind))
        .collect();
    let mut why = format!("its map gives no {} status on this link", role.id());
    for place in places {
        let Target::Field(f) = place.target else {
            continue;
        };
        let Some(r) = drive.register_of_row(usize::from(f.row)) else {
            continue;
        };
        match session.read_raw(r) {
            Ok(word) => return Ok(f.holds(word as u16)),
            Err(e) => why = format!("reading {}: {e}", r.label()),
        }
    }
    Err(why)
}

/// Reads the drive and plans the writes of what differs from `set`, in its order. Refused,
/// with every reason and nothing written, when a value is not one of its setting under the
/// drive's settings, the write gate would refuse a write, or a setting the map lets be written
/// only while the motor is stopped (or in PRG mode) is to be written and the drive's status
/// does not show it so.
pub fn plan<'d>(
    session: &mut Session<'d>,
    set: &Validated<'d>,
) -> Result<RestorePlan<'d>, RestoreError> {
    let drive = session.drive;
    let mut regs: Vec<RegisterRef<'_>> = set.entries.iter().map(|(r, _)| *r).collect();
    let count = regs.len();
    // What the set's settings depend on and the set does not hold (a selector of a scale, a
    // maximum): read with them, in the same planned requests, for the drive's value.
    for r in set
        .entries
        .iter()
        .flat_map(|(r, _)| super::depends_on(drive, *r))
    {
        if !regs.iter().any(|x| x.id() == r.id()) {
            regs.push(r);
        }
    }
    let (mut words, requests) = read_all(session, &regs)?;
    words.truncate(count);
    if let Some(why) = session.silence.report() {
        return Err(RestoreError::Refused(vec![format!(
            "{} did not answer: {why}",
            session.link
        )]));
    }
    // The drive's settings, with the set's selectors and references: those are written first.
    let drives = session.settings.clone();
    let mut settings = drives.clone();
    for (k, v) in &set.settings.selectors {
        settings.selectors.insert(k.clone(), *v);
    }
    for (k, v) in &set.settings.references {
        settings.references.insert(k.clone(), *v);
    }
    let profile = session.client.profile();
    let mut reasons = Vec::new();
    let mut writes = Vec::new();
    let mut unchanged = Vec::new();
    for ((r, text), current) in set.entries.iter().zip(&words) {
        let name = r.label();
        let raw = match codec::parse_value(drive, *r, text, &settings) {
            Ok(raw) => raw,
            Err(InputError::Value(e)) => {
                reasons.push(format!("{name}: {}", value_error(drive, &e)));
                continue;
            }
            Err(InputError::Parse(m)) => {
                reasons.push(format!("{name}: {m}"));
                continue;
            }
        };
        if current.as_ref().is_ok_and(|c| *c == raw) {
            unchanged.push(*r);
            continue;
        }
        let from = current.as_ref().ok().map(|c| {
            codec::decode(drive, *r, *c, &drives)
                .map(|v| v.to_string())
                .unwrap_or_else(|_| session.raw_text(*r, *c))
        });
        writes.push(Write {
            register: *r,
            from,
            to: text.clone(),
            raw,
        });
    }
    // The write gate for every write before the first is sent.
    let saved = std::mem::replace(&mut session.settings, settings.clone());
    for w in &writes {
        let checked = session
            .address(w.register)
            .map_err(|e| e.to_string())
            .and_then(|address| {
                let rule =
                    gate::rule(profile, intern(w.register.id())).map_err(|e| e.to_string())?;
                let words = rule.width.split(w.raw);
                gate::check(
                    profile,
                    session.kind,
                    session.slave,
                    WriteTarget::Rule(rule),
                    address,
                    words.iter().take(usize::from(rule.width.count())).copied(),
                )
                .map_err(|e| e.to_string())
            });
        if let Err(e) = checked {
            reasons.push(format!("{}: {e}", w.register.label()));
        }
    }
    session.settings = saved;
    let mut warnings = set.warnings.clone();
    let restricted = |what: WriteRestriction| {
        writes
            .iter()
            .filter(|w| w.register.plan().restriction == what)
            .map(|w| w.register.label())
            .collect::<Vec<_>>()
    };
    let stopped_only = restricted(WriteRestriction::Stopped);
    if !stopped_only.is_empty() {
        match status(session, Role::Running) {
            Ok(false) => warnings.push("the drive shows stopped".to_owned()),
            Ok(true) => reasons.push(format!(
                "the drive shows running, and {} may be written only while it is stopped: {}",
                if stopped_only.len() == 1 { "this setting" } else { "these settings" },
                stopped_only.join(", ")
            )),
            Err(why) => reasons.push(format!(
                "{} may be written only while the drive is stopped, and whether it is is not known ({why}): {}",
                if stopped_only.len() == 1 { "this setting" } else { "these settings" },
                stopped_only.join(", ")
            )),
        }
    }
    let prg_only = restricted(WriteRestriction::PrgMode);
    if !prg_only.is_empty() {
        match status(session, Role::DriveMode) {
            Ok(false) => {}
            Ok(true) => reasons.push(format!(
                "the drive is in DRV mode, and these settings may be written only in PRG mode: {}",
                prg_only.join(", ")
            )),
            Err(why) => reasons.push(format!(
                "these settings may be written only in PRG mode, and the drive's mode is not known ({why}): {}",
                prg_only.join(", ")
            )),
        }
    }
    if !reasons.is_empty() {
        return Err(RestoreError::Refused(reasons));
    }
    let store = (!writes.is_empty()).then(|| store_command(drive)).flatten();
    Ok(RestorePlan {
        writes,
        unchanged,
        store,
        settings,
        requests,
        warnings,
    })
}

/// The map's command that stores written values to the drive's memory (kind `persist`: the
/// V7's ENTER, the ACN's and TDS-V8's save), if it has one. [`plan`] puts it in a plan with
/// writes; a caller that wants the drive's values stored when nothing differs (the store of an
/// earlier restore failed) sets [`RestorePlan::store`] to it.
pub fn store_command(drive: &Map) -> Option<&'static CommandInfo> {
    drive
        .plan()
        .profile
        .commands
        .iter()
        .find(|c| c.kind == CommandKind::Persist)
}

/// Whether a failed write may have reached the drive: a request sent whose reply did not come
/// (a refusal by the gate, or an exception the drive answered with, did not write).
fn maybe_written(e: &drivemap_runtime::error::Error) -> bool {
    !e.is_refusal() && e.exception().is_none()
}

/// Writes the plan in order through the write gate, stopping at the first write that fails;
/// runs the store command once when every write went through; reads every written setting
/// back. `progress` is told each step.
pub fn execute<'d>(
    session: &mut Session<'d>,
    plan: &RestorePlan<'d>,
    progress: &mut dyn FnMut(&Progress),
) -> RestoreReport {
    let profile = session.client.profile();
    session.settings = plan.settings.clone();
    let mut sent: Vec<(&Write<'d>, Option<String>)> = Vec::new();
    let mut not_written = Vec::new();
    let total = plan.writes.len();
    let mut failed = false;
    let mut requests = 0u32;
    for (i, w) in plan.writes.iter().enumerate() {
        let r = w.register;
        if failed {
            not_written.push(Skipped {
                id: r.id().to_owned(),
                reason: "not reached: an earlier write failed".to_owned(),
            });
            continue;
        }
        progress(&Progress::Writing {
            done: i,
            total,
            id: r.id().to_owned(),
        });
        let result = session
            .address(r)
            .map_err(|e| e.to_string())
            .and_then(|address| {
                let rule = gate::rule(profile, intern(r.id())).map_err(|e| e.to_string())?;
                let between = r.plan().repeat_needs_change.map(|x| x.between);
                requests += 1;
                let done = match between {
                    Some(b) => session
                        .client
                        .write_changed(session.slave, rule, address, b, w.raw),
                    None => session
                        .client
                        .write_rule(session.slave, rule, address, w.raw),
                };
                done.map_err(|e| {
                    if maybe_written(&e) {
                        format!("sent, no reply: {e}")
                    } else {
                        e.to_string()
                    }
                })
            });
        match result {
            Ok(()) => sent.push((w, None)),
            Err(e) if e.starts_with("sent, no reply") => {
                failed = true;
                sent.push((w, Some(e)));
            }
            Err(e) => {
                failed = true;
                not_written.push(Skipped {
                    id: r.id().to_owned(),
                    reason: e,
                });
            }
        }
    }
    let store = match plan.store {
        None => StoreOutcome::NotNeeded,
        Some(c) if failed => StoreOutcome::NotRun(format!(
            "{} not run: the restore did not finish; run it again",
            c.id
        )),
        Some(c) => {
            progress(&Progress::Storing(c.id.to_owned()));
            requests += c.writes.len() as u32;
            match session.client.persist(session.slave, c.id) {
                Ok(()) => StoreOutcome::Stored {
                    command: c.id.to_owned(),
                    wear: wear(session, c),
                },
                Err(e) => StoreOutcome::Failed(format!("{}: {e}", c.id)),
            }
        }
    };
    // Read back, once more after a silence: what was written is worth a try.
    session.silence.rearm();
    let regs: Vec<RegisterRef<'_>> = sent.iter().map(|(w, _)| w.register).collect();
    progress(&Progress::Verifying(regs.len()));
    let mut verified = Vec::new();
    let mut not_verified = Vec::new();
    if !regs.is_empty() {
        let read = read_all(session, &regs);
        let words = match read {
            Ok((words, n)) => {
                requests += n;
                words
                    .into_iter()
                    .map(|w| w.map_err(|e| e.to_string()))
                    .collect()
            }
            Err(e) => vec![Err(e.to_string()); regs.len()],
        };
        for ((w, note), got) in sent.iter().zip(words) {
            let id = w.register.id().to_owned();
            match got {
                Ok(raw) if raw == w.raw => verified.push(id),
                Ok(raw) => not_verified.push(Skipped {
                    id,
                    reason: format!(
                        "reads {}, not {}{}",
                        session.raw_text(w.register, raw),
                        session.raw_text(w.register, w.raw),
                        note.as_deref()
                            .map(|n| format!(" ({n})"))
                            .unwrap_or_default()
                    ),
                }),
                Err(e) => not_verified.push(Skipped {
                    id,
                    reason: format!(
                        "not read back: {e}{}",
                        note.as_deref()
                            .map(|n| format!(" ({n})"))
                            .unwrap_or_default()
                    ),
                }),
            }
        }
    }
    RestoreReport {
        verified,
        not_verified,
        not_written,
        unchanged: plan.unchanged.len(),
        store,
        requests,
    }
}

/// What one store command cost the EEPROM, as the map's endurance says.
fn wear(session: &Session<'_>, c: &CommandInfo) -> String {
    let total = session.client.eeprom().total();
    match session.client.profile().eeprom_write_endurance {
        Some(n) => format!(
            "{} ({}): one EEPROM write of the {n} the manual rates it for; {total} in this session",
            c.id, c.name
        ),
        None => format!(
            "{} ({}): one EEPROM write (the manual rates no endurance); {total} in this session",
            c.id, c.name
        ),
    }
}

/// [`validate`], [`plan`] and [`execute`] in one: the report, or why nothing was written.
pub fn restore<'d>(
    session: &mut Session<'d>,
    set: &ParameterSet,
    other_allowed: bool,
    progress: &mut dyn FnMut(&Progress),
) -> Result<(RestorePlan<'d>, RestoreReport), RestoreError> {
    let given = session.settings.clone();
    let validated = validate(session.drive, set, &given, other_allowed)?;
    let plan = plan(session, &validated)?;
    let report = execute(session, &plan, progress);
    Ok((plan, report))
}
