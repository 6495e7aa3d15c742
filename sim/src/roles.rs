//! Which register or field of a map plays each part of the drive model: run command, direction,
//! frequency reference, output frequency, accel/decel time, status bits.
//!
//! The map schema has no notion of roles, and the ids differ between drives (see the comment at
//! the top of `sim/roles.yaml`), so a small table names the map's own ids per drive. It is
//! checked against the map when a simulator starts: a table naming a register, field or code the
//! map does not have is refused with every problem listed.

use std::collections::{BTreeMap, HashMap};
use std::fmt;

use drivemap_codegen::ir::{Drive, ValueKind};
use drivemap_codegen::model::Reference;
use drivemap_codegen::validate::field_span;
use serde::Deserialize;

/// The built-in table: `sim/roles.yaml`.
pub const BUILTIN: &str = include_str!("../roles.yaml");

/// The roles of one drive, as written in the table (names not yet checked against the map).
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Roles {
    /// Registers whose writes command the drive.
    #[serde(default)]
    pub commands: Vec<CommandRole>,
    /// Registers whose value (Hz) is the frequency reference; the last one written wins.
    #[serde(default)]
    pub frequency_reference: Vec<String>,
    /// Registers that show the output frequency (Hz).
    #[serde(default)]
    pub output_frequency: Vec<String>,
    /// Registers that show the frequency reference in force (Hz).
    #[serde(default)]
    pub reference_monitor: Vec<String>,
    /// The frequency that accel/decel times are measured to (Hz). Default 60 Hz.
    #[serde(default)]
    pub max_frequency: Option<Quantity>,
    /// Time from 0 to `max_frequency` (s). Default 0: the output jumps to the reference.
    #[serde(default)]
    pub accel_time: Option<Quantity>,
    /// Time from `max_frequency` to 0 (s). Default: the accel time.
    #[serde(default)]
    pub decel_time: Option<Quantity>,
    /// Status fields the model drives.
    #[serde(default)]
    pub status: Vec<StatusRole>,
    /// PRG/DRV mode (TDS-V8).
    #[serde(default)]
    pub mode: Option<ModeRole>,
    /// Monitors that follow the output frequency.
    #[serde(default)]
    pub follow: Vec<FollowRole>,
    /// Power-on values (engineering units) where the map prints no default.
    #[serde(default)]
    pub initial: BTreeMap<String, f64>,
    /// Read-only monitors held at a plausible value.
    #[serde(default)]
    pub constants: BTreeMap<String, f64>,
    /// Values of the map's external quantities.
    #[serde(default)]
    pub externals: BTreeMap<String, f64>,
}

/// A register that commands the drive, and which of its fields mean what.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CommandRole {
    /// Register id.
    pub register: String,
    /// Field: 1 = run.
    #[serde(default)]
    pub run: Option<String>,
    /// Field: 1 = run forward (2-wire terminal).
    #[serde(default)]
    pub run_forward: Option<String>,
    /// Field: 1 = run reverse (2-wire terminal).
    #[serde(default)]
    pub run_reverse: Option<String>,
    /// Field: 1 = reverse.
    #[serde(default)]
    pub reverse: Option<String>,
    /// Field: 1 = forward, 0 = reverse.
    #[serde(default)]
    pub forward: Option<String>,
}

/// A number, or the name of a register or external quantity holding it.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Quantity {
    /// A fixed value.
    Number(f64),
    /// A register id (or parameter number), or an external quantity of the map.
    Name(String),
}

/// A status field and when it is set.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StatusRole {
    /// `register.field`.
    pub field: String,
    /// For a 1-bit field: 1 while this holds.
    #[serde(default)]
    pub when: Option<Condition>,
    /// For a multi-bit field: condition → code id of the field; the first condition that holds
    /// (in [`Condition`] order) gives the code, none gives 0.
    #[serde(default)]
    pub codes: BTreeMap<Condition, String>,
}

/// What the drive model is doing, as status fields report it. The order is the priority order
/// of `codes`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Condition {
    /// Always.
    Always,
    /// Run commanded, or the output frequency not yet 0.
    Running,
    /// Not running.
    Stopped,
    /// Running, not in reverse.
    Forward,
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
    /// Run commanded and the output at the reference (same as `speed_agree`).
    Steady,
    /// TDS-V8 DRV mode.
    DrvMode,
    /// TDS-V8 PRG mode.
    PrgMode,
}

/// PRG/DRV mode switching.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModeRole {
    /// `register.field` that switches to DRV mode (clears itself).
    pub to_drv: String,
    /// `register.field` that switches to PRG mode (clears itself).
    pub to_prg: String,
    /// Mode at power-on.
    #[serde(default)]
    pub initial: Mode,
}

/// TDS-V8 operating mode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Program mode: parameters writable.
    #[default]
    Prg,
    /// Drive mode.
    Drv,
}

/// A monitor proportional to the output frequency.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FollowRole {
    /// Register id.
    pub register: String,
    /// Value at 0 Hz while running.
    #[serde(default)]
    pub at_zero: f64,
    /// Value at the max frequency.
    pub at_max: f64,
    /// Value while stopped (default `at_zero`).
    #[serde(default)]
    pub stopped: Option<f64>,
}

/// Parses a roles table (drive id → roles).
pub fn parse_table(text: &str) -> Result<BTreeMap<String, Roles>, String> {
    serde_yaml::from_str(text).map_err(|e| format!("roles table: {e}"))
}

/// The built-in roles of a drive id, if the table has them.
pub fn builtin(drive_id: &str) -> Result<Option<Roles>, String> {
    Ok(parse_table(BUILTIN)?.remove(drive_id))
}

/// The drive ids the built-in table covers.
pub fn builtin_drives() -> Vec<String> {
    parse_table(BUILTIN)
        .map(|t| t.into_keys().collect())
        .unwrap_or_default()
}

/// A field located in the register list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Bit {
    pub register: usize,
    pub lsb: u8,
    pub width: u8,
}

impl Bit {
    pub fn mask(self) -> u16 {
        ((((1u32 << self.width) - 1) << self.lsb) & 0xFFFF) as u16
    }

    pub fn get(self, raw: u16) -> u16 {
        (raw & self.mask()) >> self.lsb
    }

    pub fn put(self, raw: u16, value: u16) -> u16 {
        (raw & !self.mask()) | ((value << self.lsb) & self.mask())
    }
}

/// Where a quantity comes from once resolved.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Source {
    Register(usize),
    Value(f64),
}

#[derive(Debug, Clone)]
pub(crate) struct ResolvedCommand {
    pub register: usize,
    pub run: Option<Bit>,
    pub run_forward: Option<Bit>,
    pub run_reverse: Option<Bit>,
    pub reverse: Option<Bit>,
    pub forward: Option<Bit>,
}

#[derive(Debug, Clone)]
pub(crate) enum Rule {
    When(Condition),
    Codes(Vec<(Condition, u16)>),
}

#[derive(Debug, Clone)]
pub(crate) struct ResolvedStatus {
    pub bit: Bit,
    pub rule: Rule,
}

#[derive(Debug, Clone)]
pub(crate) struct ResolvedMode {
    pub to_drv: Bit,
    pub to_prg: Bit,
    pub initial: Mode,
}

#[derive(Debug, Clone)]
pub(crate) struct ResolvedFollow {
    pub register: usize,
    pub at_zero: f64,
    pub at_max: f64,
    pub stopped: f64,
}

/// Roles with every name located in the drive's register list.
#[derive(Debug, Clone)]
pub(crate) struct Resolved {
    pub commands: Vec<ResolvedCommand>,
    pub frequency_reference: Vec<usize>,
    pub output_frequency: Vec<usize>,
    pub reference_monitor: Vec<usize>,
    pub max_frequency: Source,
    pub accel_time: Source,
    pub decel_time: Option<Source>,
    pub status: Vec<ResolvedStatus>,
    pub mode: Option<ResolvedMode>,
    pub follow: Vec<ResolvedFollow>,
    /// Register index → engineering value, initial then constants.
    pub initial: Vec<(usize, f64)>,
}

/// Every problem found checking a roles table against a map.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RolesError {
    /// The drive.
    pub drive: String,
    /// One line per problem.
    pub problems: Vec<String>,
}

impl fmt::Display for RolesError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the simulator's roles for {} do not match its map: {}",
            self.drive,
            self.problems.join("; ")
        )
    }
}

impl std::error::Error for RolesError {}

struct Resolver<'a> {
    drive: &'a Drive,
    index: &'a HashMap<String, usize>,
    problems: Vec<String>,
}

impl Resolver<'_> {
    fn register(&mut self, role: &str, name: &str) -> Option<usize> {
        let found = self.index.get(name).copied().or_else(|| {
            self.drive
                .find(name)
                .and_then(|r| self.index.get(r.id()).copied())
        });
        if found.is_none() {
            self.problems
                .push(format!("{role}: the map has no register `{name}`"));
        }
        found
    }

    fn field(&mut self, role: &str, path: &str) -> Option<Bit> {
        let Some((reg, field)) = path.split_once('.') else {
            self.problems
                .push(format!("{role}: `{path}` is not `register.field`"));
            return None;
        };
        let register = self.register(role, reg)?;
        self.field_of(role, register, field)
    }

    fn field_of(&mut self, role: &str, register: usize, field: &str) -> Option<Bit> {
        let r = &self.drive.registers[register];
        match r.def.fields.iter().find(|f| f.id == field) {
            Some(f) => match field_span(f) {
                Some((lsb, width)) => Some(Bit {
                    register,
                    lsb,
                    width,
                }),
                None => {
                    self.problems
                        .push(format!("{role}: field `{}.{field}` has no bits", r.id()));
                    None
                }
            },
            None => {
                self.problems.push(format!(
                    "{role}: register `{}` has no field `{field}`",
                    r.id()
                ));
                None
            }
        }
    }

    fn quantity(&mut self, role: &str, q: &Quantity, externals: &BTreeMap<String, f64>) -> Source {
        match q {
            Quantity::Number(v) => Source::Value(*v),
            Quantity::Name(name) => {
                if let Some(&i) = self.index.get(name) {
                    return Source::Register(i);
                }
                if let Some(r) = self.drive.find(name) {
                    if let Some(&i) = self.index.get(r.id()) {
                        return Source::Register(i);
                    }
                }
                let is_external = self.drive.externals().iter().any(|e| e.external == *name);
                match externals.get(name) {
                    Some(v) if is_external => Source::Value(*v),
                    _ if is_external => {
                        self.problems.push(format!(
                            "{role}: external quantity `{name}` needs a value under `externals`"
                        ));
                        Source::Value(0.0)
                    }
                    _ => {
                        self.problems.push(format!(
                            "{role}: `{name}` is neither a register nor an external quantity of the map"
                        ));
                        Source::Value(0.0)
                    }
                }
            }
        }
    }
}

/// Whether a register converts to engineering units (so it can hold a frequency or a time).
fn is_quantity(drive: &Drive, i: usize) -> bool {
    matches!(
        drive.registers[i].kind(),
        ValueKind::Quantity(_) | ValueKind::UnitQuantity | ValueKind::Word
    )
}

/// Names of the external quantities the map uses (for messages and defaults).
pub(crate) fn external_names(drive: &Drive) -> Vec<String> {
    let mut out = Vec::new();
    for r in &drive.registers {
        for s in drivemap_codegen::ir::scales_of(r) {
            if let drivemap_codegen::model::Scale::Relative(rel) = s {
                if let Reference::External(q) = &rel.relative_to {
                    if !out.contains(&q.external) {
                        out.push(q.external.clone());
                    }
                }
            }
        }
    }
    out
}

/// Checks `roles` against `drive` and locates every name.
pub(crate) fn resolve(
    drive: &Drive,
    index: &HashMap<String, usize>,
    roles: &Roles,
    externals: &BTreeMap<String, f64>,
) -> Result<Resolved, RolesError> {
    let mut rv = Resolver {
        drive,
        index,
        problems: Vec::new(),
    };
    let mut commands = Vec::new();
    for c in &roles.commands {
        let Some(register) = rv.register("commands", &c.register) else {
            continue;
        };
        let mut field = |name: &Option<String>| {
            name.as_deref()
                .and_then(|n| rv.field_of("commands", register, n))
        };
        let rc = ResolvedCommand {
            register,
            run: field(&c.run),
            run_forward: field(&c.run_forward),
            run_reverse: field(&c.run_reverse),
            reverse: field(&c.reverse),
            forward: field(&c.forward),
        };
        if c.run.is_none() && c.run_forward.is_none() && c.run_reverse.is_none() {
            rv.problems.push(format!(
                "commands: `{}` names no run field (run, run_forward or run_reverse)",
                c.register
            ));
        }
        commands.push(rc);
    }
    let list = |role: &str, names: &[String], rv: &mut Resolver<'_>| -> Vec<usize> {
        let mut out = Vec::new();
        for n in names {
            let Some(i) = rv.register(role, n) else {
                continue;
            };
            if !is_quantity(drive, i) {
                rv.problems.push(format!(
                    "{role}: `{}` is not a number register",
                    drive.registers[i].id()
                ));
            }
            out.push(i);
        }
        out
    };
    let frequency_reference = list("frequency_reference", &roles.frequency_reference, &mut rv);
    let output_frequency = list("output_frequency", &roles.output_frequency, &mut rv);
    let reference_monitor = list("reference_monitor", &roles.reference_monitor, &mut rv);
    let max_frequency = match &roles.max_frequency {
        Some(q) => rv.quantity("max_frequency", q, externals),
        None => Source::Value(60.0),
    };
    let accel_time = match &roles.accel_time {
        Some(q) => rv.quantity("accel_time", q, externals),
        None => Source::Value(0.0),
    };
    let decel_time = roles
        .decel_time
        .as_ref()
        .map(|q| rv.quantity("decel_time", q, externals));
    let mut status = Vec::new();
    for s in &roles.status {
        let Some(bit) = rv.field("status", &s.field) else {
            continue;
        };
        let rule = match (s.when, s.codes.is_empty()) {
            (Some(c), true) => {
                if bit.width != 1 {
                    rv.problems.push(format!(
                        "status: `{}` is {} bits wide; use `codes`",
                        s.field, bit.width
                    ));
                }
                Rule::When(c)
            }
            (None, false) => {
                let r = &drive.registers[bit.register];
                let field_id = s.field.split_once('.').map(|(_, f)| f).unwrap_or("");
                let field = r.def.fields.iter().find(|f| f.id == field_id);
                let mut codes = Vec::new();
                for (cond, id) in &s.codes {
                    match field.and_then(|f| f.values.iter().find(|v| v.id == *id)) {
                        Some(v) => codes.push((*cond, v.value)),
                        None => rv
                            .problems
                            .push(format!("status: `{}` has no code `{id}`", s.field)),
                    }
                }
                Rule::Codes(codes)
            }
            _ => {
                rv.problems.push(format!(
                    "status: `{}` needs exactly one of `when` and `codes`",
                    s.field
                ));
                continue;
            }
        };
        status.push(ResolvedStatus { bit, rule });
    }
    let mode = roles.mode.as_ref().and_then(|m| {
        let to_drv = rv.field("mode.to_drv", &m.to_drv);
        let to_prg = rv.field("mode.to_prg", &m.to_prg);
        Some(ResolvedMode {
            to_drv: to_drv?,
            to_prg: to_prg?,
            initial: m.initial,
        })
    });
    let mut follow = Vec::new();
    for f in &roles.follow {
        if let Some(register) = rv.register("follow", &f.register) {
            follow.push(ResolvedFollow {
                register,
                at_zero: f.at_zero,
                at_max: f.at_max,
                stopped: f.stopped.unwrap_or(f.at_zero),
            });
        }
    }
    let mut initial = Vec::new();
    for (name, v) in &roles.initial {
        if let Some(i) = rv.register("initial", name) {
            initial.push((i, *v));
        }
    }
    for (name, v) in &roles.constants {
        if let Some(i) = rv.register("constants", name) {
            if drive.registers[i].writable() {
                rv.problems.push(format!(
                    "constants: `{name}` is writable; constants are for read-only monitors (use `initial`)"
                ));
            }
            initial.push((i, *v));
        }
    }
    let known = external_names(drive);
    for name in roles.externals.keys() {
        if !known.contains(name) {
            rv.problems.push(format!(
                "externals: the map has no external quantity `{name}`"
            ));
        }
    }
    if rv.problems.is_empty() {
        Ok(Resolved {
            commands,
            frequency_reference,
            output_frequency,
            reference_monitor,
            max_frequency,
            accel_time,
            decel_time,
            status,
            mode,
            follow,
            initial,
        })
    } else {
        Err(RolesError {
            drive: drive.meta.id.clone(),
            problems: rv.problems,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_builtin_table_parses_and_names_every_shipped_drive() {
        let table = parse_table(BUILTIN).unwrap();
        for id in [
            "ptlk-tds-v8",
            "yaskawa-v7",
            "yaskawa-j7",
            "yaskawa-gpd515",
            "automationdirect-acn",
        ] {
            assert!(table.contains_key(id), "{id}");
        }
        let acn = &table["automationdirect-acn"];
        assert_eq!(acn.commands[0].forward.as_deref(), Some("forward"));
        assert_eq!(acn.max_frequency, Some(Quantity::Number(60.0)));
        assert_eq!(
            acn.status[0]
                .codes
                .get(&Condition::Forward)
                .map(String::as_str),
            Some("operating_forward")
        );
    }

    #[test]
    fn unknown_keys_are_refused() {
        let e = parse_table("x:\n  comands: []\n").unwrap_err();
        assert!(e.contains("comands"), "{e}");
    }

    #[test]
    fn bits_are_read_and_written_in_place() {
        let b = Bit {
            register: 0,
            lsb: 4,
            width: 4,
        };
        assert_eq!(b.mask(), 0x00F0);
        assert_eq!(b.get(0x1234), 3);
        assert_eq!(b.put(0x1234, 0xA), 0x12A4);
    }
}
