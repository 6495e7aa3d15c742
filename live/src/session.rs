//! A live drive by its map: names resolved, settings gathered, addresses chosen, words read in
//! planned requests and decoded. The `drivemap` command's `read`, `write`, `poll`, `probe` and
//! `scan` are built on [`Session`]; so can any program (`examples/read_by_name.rs`).
//!
//! A register is named at run time by a [`RegisterRef`] of the loaded map (found by name with
//! [`find_all`] or [`crate::lookup::find`]); its row of the map's plan ([`RegisterRef::plan`]) gives
//! the address, width and conversion, the same the generated code prints.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex};

use drivemap_map::Map;
use drivemap_map::Quantity;
use drivemap_map::RegisterRef;
use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::core::plan::Dependency;
use drivemap_runtime::core::plan::RegisterPlan;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::{RegisterInfo, Table};
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::core::width::Width;
use drivemap_runtime::planner::{Poller, ReadableSet};

use crate::codec::{self, InputError, Value};
use crate::draft::DraftWrites;
use crate::link::{Link, LinkError, LiveClient};
use crate::lookup::NotFound;
use crate::silence::SilenceGuard;
use crate::{LiveSettings, leak_profile, lookup};
use drivemap_map::describe;
use drivemap_runtime::client::Client;

/// What conversions depend on, as the user gives it (the command line's `--variant` and
/// `--set`).
#[derive(Debug, Clone, Default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct SettingsArgs {
    /// Model variant: `axis=option` (e.g. `voltage_class=v440`), or just the option.
    #[cfg_attr(feature = "clap", arg(long = "variant", value_name = "AXIS=OPTION"))]
    pub variants: Vec<String>,
    /// The drive's value of a register or an external quantity of the map (`n152=1`,
    /// `drive_rated_current=12.5`), taken as known instead of read: a parameter that selects a
    /// scale or serves as a reference is not read from the drive, an external quantity is the
    /// drive's. The same `--set` gives `simulate` its values. (`--external` is an older name.)
    #[cfg_attr(
        feature = "clap",
        arg(long = "set", alias = "external", value_name = "NAME=VALUE")
    )]
    pub sets: Vec<String>,
}

/// Why a `--variant` or `--set` is refused; each names the option as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// A variant for a map without variants.
    #[error("{drive} has no model variants (`--variant {given}`)")]
    NoVariants {
        /// The drive's id.
        drive: String,
        /// The option as given.
        given: String,
    },
    /// No such variant axis (or option).
    #[error("`--variant {given}`: {drive} has no such variant; choose from {known}")]
    NoSuchVariant {
        /// The option as given.
        given: String,
        /// The drive's id.
        drive: String,
        /// `axis=option|option` per axis.
        known: String,
    },
    /// An axis without that option.
    #[error("`--variant {given}`: {axis} has options {options}")]
    NoSuchOption {
        /// The option as given.
        given: String,
        /// The axis.
        axis: String,
        /// Its options.
        options: String,
    },
    /// Not `NAME=VALUE`.
    #[error("`{0}` is not NAME=VALUE")]
    NotAssignment(String),
    /// A value that is not a number where one is needed.
    #[error("`--set {given}`: `{value}` is not a number{}", unit.as_deref().map(|u| format!(" of {u}")).unwrap_or_default())]
    NotANumber {
        /// The option as given.
        given: String,
        /// The value.
        value: String,
        /// The unit expected, for an external quantity.
        unit: Option<String>,
    },
    /// No register or external quantity of that name.
    #[error("`--set {given}`: {not_found}{}", hint.as_deref().map(|h| format!(" (external quantities and what conversions depend on: {h})")).unwrap_or_default())]
    Unknown {
        /// The option as given.
        given: String,
        /// The lookup's answer, with the nearest names.
        not_found: Box<NotFound>,
        /// The names whose value matters to conversions.
        hint: Option<String>,
    },
    /// Not a value of the register.
    #[error("`--set {given}`: {error}")]
    Value {
        /// The option as given.
        given: String,
        /// Why the value is not one of the register.
        error: InputError,
    },
}

/// Names that are not registers of the drive, each with its nearest names (one per line).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))]
pub struct UnknownNames(pub Vec<NotFound>);

/// Settings from the command line, and which register ids they fix.
pub struct Given {
    /// Variants, selector codes and reference values given.
    pub settings: LiveSettings,
    /// Register ids whose value was given with `--set`.
    pub fixed: BTreeSet<String>,
    /// Every `--set` as given (name as typed, value as typed), with the register id or external
    /// quantity it names: what [`Session::check_given`] compares and the notes quote.
    pub given: Vec<GivenValue>,
}

/// One `--set NAME=VALUE` as given.
#[derive(Debug, Clone, PartialEq)]
pub struct GivenValue {
    /// The register id or external quantity name it sets.
    pub id: String,
    /// The name as typed.
    pub name: String,
    /// The value as typed.
    pub value: String,
    /// Whether it is an external quantity (the drive holds no register for it).
    pub external: bool,
}

/// The `--set` values a command's conversions rest on without the drive having confirmed
/// them: each says "assuming NAME = VALUE, given, not read".
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Assumed {
    /// Register id or external quantity name → the note.
    pub notes: Vec<(String, String)>,
}

impl Assumed {
    /// The notes of the settings `r`'s conversion or limit uses, joined with `; ` (empty when
    /// none): `assuming P2000 = 50 Hz, given, not read`.
    pub fn for_register(&self, drive: &Map, r: RegisterRef<'_>, settings: &LiveSettings) -> String {
        let used = settings_used(drive, r, settings);
        self.notes
            .iter()
            .filter(|(id, _)| used.contains(id))
            .map(|(_, n)| n.as_str())
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// The settings `r`'s conversion, address or limit uses under `settings`: register ids of
/// selectors and references, names of external quantities.
pub fn settings_used(drive: &Map, r: RegisterRef<'_>, settings: &LiveSettings) -> Vec<String> {
    let plan = drive.plan();
    let rp = r.plan();
    let mut out: Vec<String> = Vec::new();
    let mut add = |d: Dependency| {
        let id = match d {
            Dependency::Code(s) => plan
                .settings
                .codes
                .get(usize::from(s.slot))
                .map(|c| plan.registers[c.register].info.id.to_owned()),
            Dependency::Quantity(s) => match plan.settings.quantities.get(usize::from(s.slot)) {
                Some(Quantity::Register(row)) => Some(plan.registers[*row].info.id.to_owned()),
                Some(Quantity::External { id, .. }) => Some(id.clone()),
                None => None,
            },
        };
        if let Some(id) = id
            && !out.contains(&id)
        {
            out.push(id);
        }
    };
    rp.depends_on(&settings.view(drive), &mut add);
    if let Some(d) = rp.limit_dependency() {
        add(d);
    }
    out
}

fn split_assignment(text: &str) -> Result<(&str, &str), SettingError> {
    text.split_once('=')
        .map(|(a, b)| (a.trim(), b.trim()))
        .filter(|(a, b)| !a.is_empty() && !b.is_empty())
        .ok_or_else(|| SettingError::NotAssignment(codec::shorten(text)))
}

impl SettingsArgs {
    /// Checks the options against the map and builds the settings.
    pub fn resolve(&self, drive: &Map) -> Result<Given, SettingError> {
        let mut settings = LiveSettings::default();
        for v in &self.variants {
            let (axis, option) = match v.split_once('=') {
                Some((a, o)) => (a.trim(), o.trim()),
                None => match drive.variant_option(v.trim()) {
                    Some((axis, _)) => (axis.id.as_str(), v.trim()),
                    None => ("", v.trim()),
                },
            };
            let Some(ax) = drive.variants().iter().find(|a| a.id == axis) else {
                let known: Vec<String> = drive
                    .variants()
                    .iter()
                    .map(|a| {
                        let opts: Vec<&str> = a.options.iter().map(|o| o.id.as_str()).collect();
                        format!("{}={}", a.id, opts.join("|"))
                    })
                    .collect();
                return Err(if known.is_empty() {
                    SettingError::NoVariants {
                        drive: drive.id().to_owned(),
                        given: codec::shorten(v),
                    }
                } else {
                    SettingError::NoSuchVariant {
                        given: codec::shorten(v),
                        drive: drive.id().to_owned(),
                        known: known.join(", "),
                    }
                });
            };
            if !ax.options.iter().any(|o| o.id == option) {
                let opts: Vec<&str> = ax.options.iter().map(|o| o.id.as_str()).collect();
                return Err(SettingError::NoSuchOption {
                    given: codec::shorten(v),
                    axis: ax.id.clone(),
                    options: opts.join(", "),
                });
            }
            settings.variants.insert(ax.id.clone(), option.to_owned());
        }
        let mut fixed = BTreeSet::new();
        let mut given = Vec::new();
        for s in &self.sets {
            let (name, value) = split_assignment(s)?;
            let not_a_number = |unit: Option<&str>| SettingError::NotANumber {
                given: codec::shorten(s),
                value: codec::shorten(value),
                unit: unit.map(str::to_owned),
            };
            if let Some(q) = drive.externals().into_iter().find(|q| q.external == name) {
                let v = number(value, &q.unit).ok_or_else(|| not_a_number(Some(&q.unit)))?;
                settings.references.insert(q.external.clone(), v);
                given.push(GivenValue {
                    id: q.external.clone(),
                    name: name.to_owned(),
                    value: value.to_owned(),
                    external: true,
                });
                continue;
            }
            let r = lookup::find(drive, name).map_err(|not_found| SettingError::Unknown {
                given: codec::shorten(s),
                not_found: Box::new(not_found),
                hint: settable_hint(drive),
            })?;
            let bad_value = |error| SettingError::Value {
                given: codec::shorten(s),
                error,
            };
            let is_selector = drive.selectors().iter().any(|x| x.id() == r.id());
            let is_reference = drive.references().iter().any(|x| x.id() == r.id());
            if is_selector {
                let code = codec::parse_value(drive, r, value, &settings).map_err(bad_value)?;
                settings.selectors.insert(r.id().to_owned(), code as u16);
            }
            if is_reference {
                let v = number(value, r.unit().unwrap_or("")).ok_or_else(|| not_a_number(None))?;
                // Checked as a write of the register would be: a value the drive cannot hold
                // (P2000 = 5000 Hz where its range is 1-599) converts nothing.
                match codec::encode(drive, r, v, &settings) {
                    Ok(_)
                    | Err(
                        ValueError::MissingSetting { .. }
                        | ValueError::LimitNotKnown { .. }
                        | ValueError::NotAStep { .. },
                    ) => {}
                    Err(e) => return Err(bad_value(InputError::Value(e))),
                }
                settings.references.insert(r.id().to_owned(), v);
            }
            if !(is_selector || is_reference) {
                // The drive's value of a register no conversion depends on: nothing here reads
                // it in place of the drive, but it must be a value of the register (as
                // `simulate --set` takes it), so a mistyped value is not passed over.
                use drivemap_runtime::core::scale::ValueError as V;
                match codec::parse_value(drive, r, value, &settings) {
                    Ok(_)
                    | Err(codec::InputError::Value(
                        V::MissingSetting { .. }
                        | V::LimitNotKnown { .. }
                        | V::UnsupportedSetting { .. }
                        | V::BadReference { .. },
                    )) => {}
                    Err(e) => return Err(bad_value(e)),
                }
            }
            fixed.insert(r.id().to_owned());
            given.push(GivenValue {
                id: r.id().to_owned(),
                name: name.to_owned(),
                value: value.to_owned(),
                external: false,
            });
        }
        Ok(Given {
            settings,
            fixed,
            given,
        })
    }
}

/// The names whose `--set` matters to conversions: external quantities, selecting parameters
/// and references (any register may be given).
fn settable_hint(drive: &Map) -> Option<String> {
    let mut names: Vec<String> = drive
        .externals()
        .iter()
        .map(|q| q.external.clone())
        .collect();
    for r in drive.selectors().into_iter().chain(drive.references()) {
        let n = r
            .param()
            .map(str::to_owned)
            .unwrap_or_else(|| r.id().to_owned());
        if !names.contains(&n) {
            names.push(n);
        }
    }
    (!names.is_empty()).then(|| names.join(", "))
}

fn number(text: &str, unit: &str) -> Option<f64> {
    let t = text.trim();
    let t = if unit.is_empty() {
        t
    } else {
        t.strip_suffix(unit).unwrap_or(t).trim()
    };
    t.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Resolves register names (id, parameter number, printed name or address as the manual prints
/// it); all unknown names are reported at once, each with the nearest names.
pub fn find_all<'a>(
    drive: &'a Map,
    names: &[impl AsRef<str>],
) -> Result<Vec<RegisterRef<'a>>, UnknownNames> {
    let mut found = Vec::new();
    let mut errors = Vec::new();
    for n in names {
        match lookup::find(drive, n.as_ref()) {
            // A BICO register's write parameter names no value to read.
            Ok(r) => match lookup::wrong_side(r, n.as_ref(), false) {
                None => found.push(r),
                Some(why) => errors.push(lookup::NotFound {
                    name: n.as_ref().to_owned(),
                    drive: drive.id().to_owned(),
                    suggestions: Vec::new(),
                    gap: None,
                    reference: Some(why.into_boxed_str()),
                }),
            },
            Err(e) => errors.push(e),
        }
    }
    if errors.is_empty() {
        Ok(found)
    } else {
        Err(UnknownNames(errors))
    }
}

/// The parameters that select a register's scale or address, as its plan lists them.
pub fn selectors_of<'a>(drive: &'a Map, r: RegisterRef<'_>) -> Vec<RegisterRef<'a>> {
    dependencies(drive, r, &LiveSettings::default(), true)
}

/// The registers a register's value is relative to under `settings`: for a selected scale, only
/// the case the selector's known code picks (every case while it is unknown).
pub fn references_of<'a>(
    drive: &'a Map,
    r: RegisterRef<'_>,
    settings: &LiveSettings,
) -> Vec<RegisterRef<'a>> {
    dependencies(drive, r, settings, false)
}

/// The registers behind a register's settings dependencies (`RegisterPlan::depends_on`):
/// selectors (`codes`) or reference registers; external quantities are not registers.
fn dependencies<'a>(
    drive: &'a Map,
    r: RegisterRef<'_>,
    settings: &LiveSettings,
    codes: bool,
) -> Vec<RegisterRef<'a>> {
    let plan = drive.plan();
    let mut rows = Vec::new();
    r.plan().depends_on(&settings.view(drive), |d| match d {
        Dependency::Code(s) if codes => rows.extend(
            plan.settings
                .codes
                .get(usize::from(s.slot))
                .map(|c| c.register),
        ),
        Dependency::Quantity(s) if !codes => {
            if let Some(Quantity::Register(row)) = plan.settings.quantities.get(usize::from(s.slot))
            {
                rows.push(*row);
            }
        }
        _ => {}
    });
    let mut out: Vec<RegisterRef<'_>> = Vec::new();
    for row in rows {
        if let Some(d) = drive.register_of_row(row)
            && !out.iter().any(|x| x.id() == d.id())
        {
            out.push(d);
        }
    }
    out
}

/// Whether a register exists on a transport kind, as its plan says.
pub fn on_transport(drive: &Map, r: RegisterRef<'_>, kind: TransportKind) -> bool {
    debug_assert!(std::ptr::eq(drive, r.map()), "a register of another map");
    r.plan().transports.contains(kind)
}

/// The plan rows of `drive`'s registers on `kind`, each at the address `address` gives it on
/// the link (a register whose address is not known there is left out): what the read planner
/// may bridge over, with the functions each register accepts (`function_codes`), which it
/// respects. The session's and the bridge's plans both start from it.
pub fn rows_on_link(
    drive: &Map,
    kind: TransportKind,
    address: impl Fn(RegisterRef<'_>) -> Option<u16>,
) -> Vec<RegisterPlan> {
    drive
        .registers()
        .filter(|&r| on_transport(drive, r, kind))
        .filter_map(|r| {
            let plan = r.plan();
            Some(RegisterPlan {
                info: RegisterInfo {
                    address: address(r)?,
                    ..plan.info
                },
                ..*plan
            })
        })
        .collect()
}

/// The communication address of a register under `settings` on `kind`: the plan's answer
/// (`RegisterPlan::address_for`), the same the generated code and the simulator give.
pub fn address_of(
    drive: &Map,
    r: RegisterRef<'_>,
    settings: &LiveSettings,
    kind: TransportKind,
) -> u16 {
    r.plan().address_for(&settings.view(drive), kind)
}

/// For a register whose range a parameter's code selects (a selected scale, or `limits:
/// {selected_by}`), the selector and the code in force: `P1300 = 20 (Sensorless vector
/// control) selects this range`, or that the code is not known; `None` for other registers.
pub fn selected_range(drive: &Map, r: RegisterRef<'_>, settings: &LiveSettings) -> Option<String> {
    let plan = drive.plan();
    let drivemap_runtime::core::plan::Conversion::Selected { selector, .. } = r.plan().conversion
    else {
        return None;
    };
    let s = plan.settings.codes.get(usize::from(selector.slot))?;
    let reg = drive.register_of_row(s.register)?;
    Some(
        match drivemap_runtime::core::plan::SettingsView::code(&settings.view(drive), selector.slot)
        {
            Some(code) => {
                let meaning = reg
                    .plan()
                    .label(code)
                    .map(|l| format!(" ({})", l.name))
                    .unwrap_or_default();
                format!("{} = {code}{meaning} selects this range", selector.label)
            }
            None => format!(
                "{} is not known, so the range in force is not",
                selector.label
            ),
        },
    )
}

/// A conversion error, with what to do about a missing setting.
pub fn value_error(drive: &Map, e: &ValueError) -> ConversionError {
    let external = |setting: &str| {
        drive
            .externals()
            .iter()
            .find(|q| q.external == setting)
            .map(|q| (q.description.clone(), q.unit.clone()))
    };
    let external = match e {
        ValueError::MissingSetting { setting, .. } | ValueError::LimitNotKnown { setting, .. } => {
            external(setting)
        }
        _ => None,
    };
    ConversionError {
        error: Box::new(e.clone()),
        external: external.map(Box::new),
    }
}

/// A number as a message quotes it: as Rust prints it while that is short, in exponent form
/// beyond (`1e308`, not a 309-digit number).
pub(crate) fn compact(v: f64) -> String {
    let plain = format!("{v}");
    if plain.len() > 16 {
        format!("{v:e}")
    } else {
        plain
    }
}

/// A value that does not convert, said with what to do about it: a missing setting names the
/// `--set` that gives it (and the external quantity's description and unit), a value between
/// two steps names `--round`.
#[derive(Debug, Clone, PartialEq)]
pub struct ConversionError {
    /// The conversion's error.
    pub error: Box<ValueError>,
    /// The external quantity (description, unit) the error's setting is, if it is one.
    pub external: Option<Box<(String, String)>>,
}

impl std::fmt::Display for ConversionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let e = &*self.error;
        match (e, self.external.as_deref()) {
            (ValueError::MissingSetting { register, setting }, Some((description, unit))) => {
                write!(
                    f,
                    "{register}: converting needs {setting} ({description}, in {unit}), which is not \
                 a register of the drive; give it with --set {setting}=<value>"
                )
            }
            (ValueError::MissingSetting { register, setting }, None) => write!(
                f,
                "{register}: converting needs the value of {setting}, which could not be \
                 read; give it with --set {setting}=<value>"
            ),
            (
                ValueError::NotAStep {
                    register,
                    value,
                    below,
                    above,
                    step,
                    unit,
                },
                _,
            ) => write!(
                f,
                "{register}: {} {unit} is between {below} and {above} {unit}; the register counts {step} {unit} (--round sends the nearest)",
                compact(*value)
            ),
            (
                ValueError::OutOfRange {
                    register,
                    value,
                    min,
                    max,
                    unit,
                },
                _,
            ) => write!(
                f,
                "{register}: {} {unit} is out of range {min} ..= {max} {unit}",
                compact(*value)
            ),
            (
                ValueError::AboveLimit {
                    register,
                    value,
                    max,
                    unit,
                    percent,
                    reference,
                },
                _,
            ) => write!(
                f,
                "{register}: {} {unit} is above {max} {unit}, {percent} % of {reference}",
                compact(*value)
            ),
            (ValueError::NotWhole { register, value }, _) => {
                write!(f, "{register}: {} is not a whole number", compact(*value))
            }
            (ValueError::LimitNotKnown { register, setting }, Some((description, unit))) => write!(
                f,
                "{register}: its limit is a percentage of {setting} ({description}, in {unit}), \
                 which is not a register of the drive; give it with --set {setting}=<value>"
            ),
            (ValueError::LimitNotKnown { register, setting }, None) => write!(
                f,
                "{register}: its limit is a percentage of {setting}, which could not be \
                 read; give it with --set {setting}=<value>"
            ),
            (other, _) => write!(f, "{other}"),
        }
    }
}

impl std::error::Error for ConversionError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&*self.error)
    }
}

/// Why a register of a drive cannot be read on a link.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Unreadable {
    /// A broadcast-only register.
    #[error("{0} is broadcast-only: it can be written to slave 0, never read")]
    BroadcastOnly(String),
    /// A write-only register.
    #[error("{0} is write-only")]
    WriteOnly(String),
    /// A register of other transports only.
    #[error("{register} exists only on {transports}, not on this link ({link})")]
    NotOnLink {
        /// The register, as the manual names it.
        register: String,
        /// The transports it exists on.
        transports: String,
        /// This link's transport kind.
        link: &'static str,
    },
}

/// Why a register has no value from a read; each names the register or says what the drive
/// or the link answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReadError {
    /// Not readable on this link.
    #[error(transparent)]
    Unreadable(#[from] Unreadable),
    /// Its address moves with a setting that could not be read: nothing is sent to a guessed
    /// address.
    #[error(
        "{register}: its address depends on {setting}, which could not be read; give it with --set {setting}=<value>"
    )]
    AddressUnknown {
        /// The register, as the manual names it.
        register: String,
        /// The setting its address depends on.
        setting: String,
    },
    /// The request failed: the drive's exception, a timeout, a refusal to send.
    #[error("{message}")]
    Bus {
        /// What happened, as the runtime says it.
        message: String,
        /// The exception code the drive answered with, if it answered with one.
        exception: Option<u8>,
        /// Whether a request was sent.
        sent: bool,
    },
    /// The planner read nothing for it (the drive refused the request it was in).
    #[error("not read")]
    NotRead,
}

impl ReadError {
    fn bus(e: &drivemap_runtime::error::Error) -> ReadError {
        ReadError::Bus {
            message: e.to_string(),
            exception: e.exception().map(|x| x.code),
            sent: !e.is_refusal(),
        }
    }

    /// As a [`Failure`]: the message, the exception code and whether a request was sent.
    pub fn failure(&self) -> Failure {
        match self {
            ReadError::Bus {
                message,
                exception,
                sent,
            } => Failure {
                message: message.clone(),
                exception: *exception,
                sent: *sent,
            },
            other => Failure {
                message: other.to_string(),
                exception: None,
                sent: false,
            },
        }
    }
}

/// Why the session cannot do what was asked.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The link cannot be opened.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The read planner refuses the registers asked for.
    #[error(transparent)]
    Plan(#[from] drivemap_runtime::planner::PlanError),
}

/// Why a planned register has no value.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// What happened, as the runtime says it.
    pub message: String,
    /// The exception code the drive answered with, if it answered with one.
    pub exception: Option<u8>,
    /// Whether a request was sent (false: this link cannot read the register).
    pub sent: bool,
}

/// The planned reads of a set of registers, kept across poll cycles (the planner remembers
/// what the drive refused).
pub struct Polling {
    poller: Poller,
    /// Per register asked for: its index among the planned registers and its width, or why it
    /// is not read.
    slots: Vec<Result<(usize, Width, &'static str), ReadError>>,
}

/// A connected drive with its settings.
pub struct Session<'d> {
    /// The drive's map.
    pub drive: &'d Map,
    /// The client over the chosen transport.
    pub client: LiveClient,
    /// The slave address talked to (0: broadcast).
    pub slave: u8,
    /// The transport kind, which picks addresses and address offsets.
    pub kind: TransportKind,
    /// What conversions depend on: given, then read from the drive.
    pub settings: LiveSettings,
    /// The link, for headers.
    pub link: String,
    /// Stops sending once the peer is silent (every attempt of one request unanswered).
    pub silence: SilenceGuard,
    /// The serial line, for the planner's bus-time model.
    line: SerialConfig,
    /// The words of each string register (`string:`, by id) as last read: a string is not a
    /// number, so its raw value in [`Session::poll`] is its first word and [`Session::decode`]
    /// decodes the words kept here.
    texts: BTreeMap<&'static str, Vec<u16>>,
    /// The ids of `--set` values [`Session::check_given`] could not compare with the drive (a
    /// read that failed): the user's, assumed, and not read again before a write
    /// ([`Session::confirm_selectors`]).
    assumed: BTreeSet<String>,
}

impl<'d> Session<'d> {
    /// Connects to the drive described by `drive`.
    pub fn open(drive: &'d Map, link: &Link, settings: LiveSettings) -> Result<Self, LinkError> {
        Self::open_with(drive, leak_profile(drive), link, settings)
    }

    /// [`Session::open`] with the drive's run-time profile already built (it is leaked: build
    /// it once per map).
    pub fn open_with(
        drive: &'d Map,
        profile: &'static Profile,
        link: &Link,
        settings: LiveSettings,
    ) -> Result<Self, LinkError> {
        Self::open_as(drive, profile, link, settings, DraftWrites::Refused)
    }

    /// [`Session::open_with`], with writes through a draft map (`draft:`) refused unsent or
    /// allowed as `draft` says ([`crate::draft`]); a reviewed map's writes are not affected.
    pub fn open_as(
        drive: &'d Map,
        profile: &'static Profile,
        link: &Link,
        settings: LiveSettings,
        draft: DraftWrites,
    ) -> Result<Self, LinkError> {
        link.check_transport(drive)?;
        let (client, text) = link.connect_as(drive, profile, draft)?;
        let options = *client.options();
        let silence = SilenceGuard::new(u32::from(options.retries) + 1);
        let client = Client::with_options(silence.wrap(client.into_transport()), profile, options);
        Ok(Session {
            drive,
            client,
            silence,
            slave: link.slave(drive),
            kind: link.kind(),
            settings,
            link: text,
            line: link.bus_line(drive),
            texts: BTreeMap::new(),
            assumed: BTreeSet::new(),
        })
    }

    /// A session over a transport the caller made (a test's in-memory link to a simulator, a
    /// program's own port): `slave` on a link of the transport's kind, `line` the serial
    /// line's speed for the planner's bus-time model, the client with `options`.
    pub fn over(
        drive: &'d Map,
        transport: Box<dyn drivemap_runtime::transport::Transport>,
        options: drivemap_runtime::client::ClientOptions,
        slave: u8,
        line: SerialConfig,
        settings: LiveSettings,
    ) -> Self {
        let profile = leak_profile(drive);
        let kind = transport.kind();
        let silence = SilenceGuard::new(u32::from(options.retries) + 1);
        let client = Client::with_options(silence.wrap(transport), profile, options);
        Session {
            drive,
            client,
            silence,
            slave,
            kind,
            settings,
            link: format!("{} link", kind.name()),
            line,
            texts: BTreeMap::new(),
            assumed: BTreeSet::new(),
        }
    }

    /// The address of `r` on this link under the current settings, or why it cannot be known
    /// (it moves with a setting that could not be read: nothing is sent to a guessed address).
    pub fn address(&self, r: RegisterRef<'_>) -> Result<u16, ReadError> {
        r.plan()
            .locate(&self.settings.view(self.drive), self.kind)
            .map_err(|e| ReadError::AddressUnknown {
                register: r.label(),
                setting: e.setting.to_string(),
            })
    }

    /// The address of `r` to show: [`Session::address`], or where the register is when the
    /// settings it moves with are at their defaults (never used for a request).
    pub fn shown_address(&self, r: RegisterRef<'_>) -> u16 {
        address_of(self.drive, r, &self.settings, self.kind)
    }

    /// Reads what the conversions and addresses of `regs` depend on, except what `fixed` gives:
    /// first the parameters that select scales and addresses, then the references the selected
    /// scales need. Returns a warning per dependency that could not be read.
    pub fn load_dependencies(
        &mut self,
        regs: &[RegisterRef<'_>],
        fixed: &BTreeSet<String>,
    ) -> Vec<String> {
        let drive = self.drive;
        // Registers that do not exist on this link need nothing.
        let regs: Vec<RegisterRef<'_>> = regs
            .iter()
            .copied()
            .filter(|r| on_transport(self.drive, *r, self.kind))
            .collect();
        let mut warnings = Vec::new();
        let mut done: BTreeSet<String> = fixed.clone();
        let selectors: Vec<RegisterRef<'_>> =
            regs.iter().flat_map(|r| selectors_of(drive, *r)).collect();
        self.read_dependencies(&selectors, &mut done, &mut warnings, "conversions depend");
        let references: Vec<RegisterRef<'_>> = regs
            .iter()
            .flat_map(|r| references_of(drive, *r, &self.settings))
            .collect();
        self.read_dependencies(&references, &mut done, &mut warnings, "conversions depend");
        warnings
    }

    /// Checks every `--set` value of a register against the drive where the register can be
    /// read on this link: a value the drive does not hold refuses the command, naming both
    /// (`--set ref_freq=1`: the drive holds P2000 = 50.00 Hz). A value that could not be read
    /// (write-only, not on this link, a read that failed) and every external quantity is
    /// assumed: returned as a note the command prints with each result it converted with it.
    pub fn check_given(&mut self, given: &[GivenValue]) -> Result<Assumed, String> {
        let drive = self.drive;
        let mut assumed = Assumed::default();
        for g in given {
            let shown = |v: &str| {
                format!(
                    "{} = {}",
                    if g.external {
                        g.id.as_str()
                    } else {
                        g.name.as_str()
                    },
                    codec::shorten(v)
                )
            };
            let assume = |why: &str| {
                (
                    g.id.clone(),
                    format!("assuming {}, given, not read{why}", shown(&g.value)),
                )
            };
            if g.external {
                assumed.notes.push(assume(""));
                continue;
            }
            let Ok(r) = lookup::find(drive, &g.id) else {
                continue;
            };
            if let Some(why) = self.unreadable(r) {
                assumed.notes.push(assume(&format!(" ({why})")));
                continue;
            }
            if self.slave == 0 {
                assumed.notes.push(assume(" (a broadcast reads nothing)"));
                continue;
            }
            let read = match self.read_raw(r) {
                Ok(raw) => raw,
                Err(e) => {
                    assumed.notes.push(assume(&format!(" (reading it: {e})")));
                    self.assumed.insert(r.id().to_owned());
                    continue;
                }
            };
            // The given value as the drive would hold it: the nearest word (a reference given
            // between two steps agrees with the step the drive holds).
            let Ok(mine) = codec::parse_value_with(
                drive,
                r,
                &g.value,
                &self.settings,
                drivemap_runtime::core::scale::Rounding::Nearest,
            ) else {
                assumed.notes.push(assume(""));
                continue;
            };
            if mine != read {
                let held = self
                    .decode(r, read)
                    .map(|v| v.to_string())
                    .unwrap_or_else(|_| self.raw_text(r, read));
                return Err(format!(
                    "`--set {}={}`: the drive holds {}, not {}: a --set value is checked against a drive that gives it (leave the --set out to use the drive's)",
                    g.name,
                    codec::shorten(&g.value),
                    format_args!("{} = {held}", r.label()),
                    codec::shorten(&g.value)
                ));
            }
        }
        Ok(assumed)
    }

    /// Reads the quantities the limits of `regs` through other parameters depend on
    /// (`RegisterPlan::limit`: V7 n011 for the frequency reference), except what `fixed` gives:
    /// what a write checks before sending. Returns a warning per quantity that could not be
    /// read (the write is then refused, since its limit cannot be checked).
    pub fn load_limits(
        &mut self,
        regs: &[RegisterRef<'_>],
        fixed: &BTreeSet<String>,
    ) -> Vec<String> {
        let drive = self.drive;
        let plan = drive.plan();
        let mut deps: Vec<RegisterRef<'_>> = Vec::new();
        for r in regs {
            if !on_transport(drive, *r, self.kind) {
                continue;
            }
            if let Some(Dependency::Quantity(s)) = r.plan().limit_dependency()
                && let Some(Quantity::Register(row)) =
                    plan.settings.quantities.get(usize::from(s.slot))
                && let Some(d) = drive.register_of_row(*row)
            {
                deps.push(d);
            }
        }
        let mut warnings = Vec::new();
        let mut done = fixed.clone();
        // A quantity a conversion already read is read again: the limit is checked against
        // the drive's value now, and reading twice costs one request.
        self.read_dependencies(&deps, &mut done, &mut warnings, "the write's limit depends");
        warnings
    }

    /// Reads again, just before a write of `r`, every parameter that selects its scale, range
    /// or address and was read from the drive, and refuses the write when one now shows
    /// another word than the one the value was converted with (another master changed the
    /// control mode in between, or this command wrote it first), or cannot be read now: the
    /// value would be checked against the range of a case no longer in force. A selector given
    /// with `--set` and not readable here, or whose read failed when [`Session::check_given`]
    /// compared it, is the user's, and is not read.
    pub fn confirm_selectors(&mut self, r: RegisterRef<'_>) -> Result<(), String> {
        let drive = self.drive;
        for s in selectors_of(drive, r) {
            let Some(&before) = self.settings.selectors.get(s.id()) else {
                continue;
            };
            if self.unreadable(s).is_some() || self.slave == 0 || self.assumed.contains(s.id()) {
                continue;
            }
            let now = self.read_raw(s).map_err(|e| {
                format!(
                    "{}: reading {} again before writing: {e}; its value was converted with {} = {before}, which cannot be confirmed",
                    r.label(),
                    s.label(),
                    s.label()
                )
            })? as u16;
            if now != before {
                let word = |w: u16| {
                    self.decode(s, u32::from(w))
                        .map(|v| v.to_string())
                        .unwrap_or_else(|_| w.to_string())
                };
                return Err(format!(
                    "{}: {} changed from {} to {} since it was read: the value was converted and checked for {} = {}",
                    r.label(),
                    s.label(),
                    word(before),
                    word(now),
                    s.label(),
                    word(before)
                ));
            }
        }
        Ok(())
    }

    /// Reads `deps` into the settings; `what` depends on them ("conversions depend") for the
    /// warnings.
    fn read_dependencies(
        &mut self,
        deps: &[RegisterRef<'_>],
        done: &mut BTreeSet<String>,
        warnings: &mut Vec<String>,
        what: &str,
    ) {
        for d in deps {
            if !done.insert(d.id().to_owned()) {
                continue;
            }
            if let Some(why) = self.unreadable(*d) {
                warnings.push(format!(
                    "{why}, and {what} on it; give it with --set {}=<value>",
                    d.param().unwrap_or(d.id())
                ));
                continue;
            }
            match self.read_raw(*d) {
                Ok(raw) => {
                    // Selectors and references are one-word registers (the map's validation).
                    self.settings.absorb(self.drive, d.address(), raw as u16);
                }
                Err(e) => warnings.push(format!("reading {}, which {what} on: {e}", d.label())),
            }
        }
    }

    /// Reads the raw value of `r` at its address on this link: its word, or a 32-bit pair's
    /// two words in one request, joined in the map's order.
    pub fn read_raw(&mut self, r: RegisterRef<'_>) -> Result<u32, ReadError> {
        if let Some(why) = self.unreadable(r) {
            return Err(why.into());
        }
        let address = self.address(r)?;
        let info = r.plan().info;
        let mut words = vec![0u16; usize::from(info.width.count())];
        self.read_into(info.table, address, &mut words)
            .map_err(|e| ReadError::bus(&e))?;
        let raw = info.width.join(&words);
        if let Width::Text(_) = info.width {
            self.texts.insert(info.id, words);
        }
        Ok(raw)
    }

    fn read_into(
        &mut self,
        table: Table,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), drivemap_runtime::error::Error> {
        self.client.read_table(self.slave, table, address, out)
    }

    /// Why a register cannot be read on this link, if it cannot.
    pub fn unreadable(&self, r: RegisterRef<'_>) -> Option<Unreadable> {
        if r.broadcast_only() {
            Some(Unreadable::BroadcastOnly(r.label()))
        } else if !r.readable() {
            Some(Unreadable::WriteOnly(r.label()))
        } else if !on_transport(self.drive, r, self.kind) {
            Some(Unreadable::NotOnLink {
                register: r.label(),
                transports: describe::transports(r.plan().transports),
                link: self.kind.name(),
            })
        } else {
            None
        }
    }

    /// Plans the reads of `regs` with the runtime's read planner: the requests that read them in
    /// the least bus time, bridging only addresses of readable registers of the map, at most
    /// `max_read` per request. Registers this link cannot read get their reason instead.
    pub fn plan(&self, regs: &[RegisterRef<'_>]) -> Result<Polling, SessionError> {
        let readable = self.readable_on_link();
        let mut wanted = Vec::new();
        let mut slots = Vec::new();
        for r in regs {
            match self
                .unreadable(*r)
                .map_or_else(|| self.address(*r), |why| Err(why.into()))
            {
                Err(why) => slots.push(Err(why)),
                Ok(address) => {
                    let info = r.plan().info;
                    wanted.push((info.table, address));
                    slots.push(Ok((wanted.len() - 1, info.width, info.id)));
                }
            }
        }
        let profile = self.client.profile();
        let poller = Poller::over(
            profile,
            (*readable).clone(),
            wanted,
            BusModel::new(profile, self.line),
        )?;
        Ok(Polling { poller, slots })
    }

    /// The readable addresses of the map's registers on this link, by table
    /// ([`ReadableSet::tables`] of [`rows_on_link`] at the session's addresses): what every plan
    /// of the session bridges over. Built once per map, link and addresses in force (the
    /// addresses of the registers that move with a setting), and kept for the process: a
    /// restore plans several reads, each over the whole map.
    fn readable_on_link(&self) -> Arc<[ReadableSet; 4]> {
        /// The readable sets of every table ([`ReadableSet::tables`]).
        type Sets = Arc<[ReadableSet; 4]>;
        /// Readable sets of one map on one link, by the addresses of its moving registers.
        struct OnLink {
            /// The plan's rows, leaked once per lowering: their address names the loaded map
            /// for good.
            rows: usize,
            kind: TransportKind,
            /// The registers on the link whose address moves with a setting or variant.
            moving: Vec<&'static RegisterPlan>,
            /// The sets per addresses of `moving` (`None`: not known), newest last.
            sets: Vec<(Vec<Option<u16>>, Sets)>,
        }
        /// Maps and links kept, and address sets kept per map and link (oldest dropped).
        const MAPS: usize = 64;
        const ADDRESSINGS: usize = 16;
        static CACHE: Mutex<Vec<OnLink>> = Mutex::new(Vec::new());
        let drive = self.drive;
        let rows = drive.plan().registers.as_ptr() as usize;
        let mut cache = match CACHE.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        };
        let at = match cache
            .iter()
            .position(|c| c.rows == rows && c.kind == self.kind)
        {
            Some(i) => i,
            None => {
                if cache.len() >= MAPS {
                    cache.remove(0);
                }
                let moving = drive
                    .registers()
                    .filter(|&r| on_transport(drive, r, self.kind))
                    .map(|r| r.plan())
                    .filter(|p| !p.moves.is_empty())
                    .collect();
                cache.push(OnLink {
                    rows,
                    kind: self.kind,
                    moving,
                    sets: Vec::new(),
                });
                cache.len() - 1
            }
        };
        let entry = &mut cache[at];
        let view = self.settings.view(drive);
        let addresses: Vec<Option<u16>> = entry
            .moving
            .iter()
            .map(|p| p.locate(&view, self.kind).ok())
            .collect();
        if let Some((_, sets)) = entry.sets.iter().find(|(a, _)| *a == addresses) {
            return Arc::clone(sets);
        }
        let infos = rows_on_link(drive, self.kind, |r| self.address(r).ok());
        let sets = Arc::new(ReadableSet::tables(&infos));
        if entry.sets.len() >= ADDRESSINGS {
            entry.sets.remove(0);
        }
        entry.sets.push((addresses, Arc::clone(&sets)));
        sets
    }

    /// Reads every register of a plan once; returns the raw value (a word, or a pair's words
    /// joined) or the error of each, in the order the plan was made for. A request that the
    /// drive refuses with 02h or 21h is split so each register gets its own value or error;
    /// a pair is never split.
    pub fn poll(&mut self, plan: &mut Polling) -> Vec<Result<u32, ReadError>> {
        self.poll_counted(plan).0
    }

    /// [`Session::poll`], and the number of requests sent.
    pub fn poll_counted(&mut self, plan: &mut Polling) -> (Vec<Result<u32, ReadError>>, u32) {
        let stats = plan.poller.poll(&mut self.client, self.slave);
        let words = plan
            .slots
            .iter()
            .map(|slot| match slot {
                Err(why) => Err(why.clone()),
                Ok((i, width, id)) => match plan.poller.raw(*i, *width) {
                    Some(Ok(w)) => {
                        if let Width::Text(n) = *width {
                            let mut words = vec![0u16; usize::from(n)];
                            if let Some(Ok(())) = plan.poller.words(*i, &mut words) {
                                self.texts.insert(id, words);
                            }
                        }
                        Ok(w)
                    }
                    Some(Err(e)) => Err(ReadError::bus(e)),
                    None => Err(ReadError::NotRead),
                },
            })
            .collect();
        (words, stats.requests)
    }

    /// [`Session::poll`] keeping the exception code of each refusal, and the requests sent.
    pub fn poll_detailed(&mut self, plan: &mut Polling) -> (Vec<Result<u32, Failure>>, u32) {
        let (words, requests) = self.poll_counted(plan);
        let words = words
            .into_iter()
            .map(|w| w.map_err(|e| e.failure()))
            .collect();
        (words, requests)
    }

    /// Reads the raw values of `regs` once, planned (see [`Session::plan`]).
    pub fn read_words(
        &mut self,
        regs: &[RegisterRef<'_>],
    ) -> Result<Vec<Result<u32, ReadError>>, SessionError> {
        let mut plan = self.plan(regs)?;
        Ok(self.poll(&mut plan))
    }

    /// A raw value of `r` in hex as the manuals write it: four digits, eight for a pair.
    /// A string's: its words as last read, four digits each (`4C58 322D …h`, the first eight).
    pub fn raw_text(&self, r: RegisterRef<'_>, raw: u32) -> String {
        let info = r.plan().info;
        if let (Width::Text(_), Some(words)) = (info.width, self.texts.get(info.id)) {
            let shown: Vec<String> = words.iter().take(8).map(|w| format!("{w:04X}")).collect();
            let more = if words.len() > 8 { " …" } else { "" };
            return format!("{}{more}h", shown.join(" "));
        }
        let digits = 4 * usize::from(info.width.count());
        format!("{raw:0digits$X}h")
    }

    /// Decodes a raw value of `r`; a string's from its words as last read
    /// ([`Session::read_raw`], [`Session::poll`]).
    pub fn decode(&self, r: RegisterRef<'_>, raw: u32) -> Result<Value, ConversionError> {
        let plan = r.plan();
        if let Width::Text(_) = plan.info.width {
            let words = self.texts.get(plan.info.id).map_or(&[][..], Vec::as_slice);
            return codec::decode_text(plan, words).map_err(|e| value_error(self.drive, &e));
        }
        codec::decode(self.drive, r, raw, &self.settings).map_err(|e| value_error(self.drive, &e))
    }
}

/// The lines that describe each field of a bit-field value.
pub fn field_lines(value: &Value) -> Vec<String> {
    let Value::Bits { fields, .. } = value else {
        return Vec::new();
    };
    fields
        .iter()
        .map(|f| {
            let bits = describe::bit_span(f.lsb, f.width);
            let label = f
                .label
                .as_deref()
                .map(|l| format!(" ({l})"))
                .unwrap_or_default();
            format!("{} = {}{label}   [{bits}: {}]", f.id, f.value, f.name)
        })
        .collect()
}
