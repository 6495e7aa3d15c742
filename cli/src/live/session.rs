//! A live drive by its map: names resolved, settings gathered, addresses chosen, words read in
//! planned requests and decoded.

use std::collections::BTreeSet;

use clap::Args as ClapArgs;
use drivemap_codegen::Drive;
use drivemap_codegen::ir::Register;
use drivemap_codegen::lower::Quantity;
use drivemap_live::codec::{self, Value};
use drivemap_live::{LiveSettings, leak_profile, lookup};
use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::plan::Dependency;
use drivemap_runtime::planner::Poller;
use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::{Profile, RegisterInfo, Table, ValueError, Width};

use super::link::{LinkArgs, LiveClient};
use super::silence::SilenceGuard;
use drivemap_codegen::describe;
use drivemap_runtime::Client;

/// What conversions depend on, given on the command line.
#[derive(ClapArgs, Debug, Clone, Default)]
pub struct SettingsArgs {
    /// Model variant: `axis=option` (e.g. `voltage_class=v440`), or just the option.
    #[arg(long = "variant", value_name = "AXIS=OPTION")]
    pub variants: Vec<String>,
    /// The drive's value of a register or an external quantity of the map (`n152=1`,
    /// `drive_rated_current=12.5`), taken as known instead of read: a parameter that selects a
    /// scale or serves as a reference is not read from the drive, an external quantity is the
    /// drive's. The same `--set` gives `simulate` its values. (`--external` is an older name.)
    #[arg(long = "set", alias = "external", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
}

/// Settings from the command line, and which register ids they fix.
pub struct Given {
    /// Variants, selector codes and reference values given.
    pub settings: LiveSettings,
    /// Register ids whose value was given with `--set`.
    pub fixed: BTreeSet<String>,
}

fn split_assignment<'a>(text: &'a str, what: &str) -> Result<(&'a str, &'a str), String> {
    text.split_once('=')
        .map(|(a, b)| (a.trim(), b.trim()))
        .filter(|(a, b)| !a.is_empty() && !b.is_empty())
        .ok_or_else(|| format!("`{text}` is not {what}"))
}

impl SettingsArgs {
    /// Checks the options against the map and builds the settings.
    pub fn resolve(&self, drive: &Drive) -> Result<Given, String> {
        let mut settings = LiveSettings::default();
        for v in &self.variants {
            let (axis, option) = match v.split_once('=') {
                Some((a, o)) => (a.trim(), o.trim()),
                None => match drive.variant_option(v.trim()) {
                    Some((axis, _)) => (axis.id.as_str(), v.trim()),
                    None => ("", v.trim()),
                },
            };
            let Some(ax) = drive.variants.iter().find(|a| a.id == axis) else {
                let known: Vec<String> = drive
                    .variants
                    .iter()
                    .map(|a| {
                        let opts: Vec<&str> = a.options.iter().map(|o| o.id.as_str()).collect();
                        format!("{}={}", a.id, opts.join("|"))
                    })
                    .collect();
                return Err(if known.is_empty() {
                    format!("{} has no model variants (`--variant {v}`)", drive.meta.id)
                } else {
                    format!(
                        "`--variant {v}`: {} has no such variant; choose from {}",
                        drive.meta.id,
                        known.join(", ")
                    )
                });
            };
            if !ax.options.iter().any(|o| o.id == option) {
                let opts: Vec<&str> = ax.options.iter().map(|o| o.id.as_str()).collect();
                return Err(format!(
                    "`--variant {v}`: {} has options {}",
                    ax.id,
                    opts.join(", ")
                ));
            }
            settings.variants.insert(ax.id.clone(), option.to_owned());
        }
        let mut fixed = BTreeSet::new();
        for s in &self.sets {
            let (name, value) = split_assignment(s, "NAME=VALUE")?;
            if let Some(q) = drive.externals().into_iter().find(|q| q.external == name) {
                let v = number(value, &q.unit).ok_or_else(|| {
                    format!("`--set {s}`: `{value}` is not a number of {}", q.unit)
                })?;
                settings.references.insert(q.external.clone(), v);
                continue;
            }
            let r = lookup::find(drive, name).map_err(|e| {
                format!(
                    "`--set {s}`: {e}{}",
                    settable_hint(drive)
                        .map(|h| format!(
                            " (external quantities and what conversions depend on: {h})"
                        ))
                        .unwrap_or_default()
                )
            })?;
            let is_selector = drive.selectors().iter().any(|x| x.def.id == r.def.id);
            let is_reference = drive.references().iter().any(|x| x.def.id == r.def.id);
            if is_selector {
                let code = codec::parse_value(drive, r, value, &settings)
                    .map_err(|e| format!("`--set {s}`: {e}"))?;
                settings.selectors.insert(r.def.id.clone(), code as u16);
            }
            if is_reference {
                let v = number(value, r.def.unit.as_deref().unwrap_or(""))
                    .ok_or_else(|| format!("`--set {s}`: `{value}` is not a number"))?;
                settings.references.insert(r.def.id.clone(), v);
            }
            if !(is_selector || is_reference) {
                // The drive's value of a register no conversion depends on: nothing here reads
                // it in place of the drive, but it must be a value of the register (as
                // `simulate --set` takes it), so a mistyped value is not passed over.
                use drivemap_runtime::ValueError as V;
                match codec::parse_value(drive, r, value, &settings) {
                    Ok(_)
                    | Err(codec::InputError::Value(
                        V::MissingSetting { .. }
                        | V::LimitNotKnown { .. }
                        | V::UnsupportedSetting { .. }
                        | V::BadReference { .. },
                    )) => {}
                    Err(e) => return Err(format!("`--set {s}`: {e}")),
                }
            }
            fixed.insert(r.def.id.clone());
        }
        Ok(Given { settings, fixed })
    }
}

/// The names whose `--set` matters to conversions: external quantities, selecting parameters
/// and references (any register may be given).
fn settable_hint(drive: &Drive) -> Option<String> {
    let mut names: Vec<String> = drive
        .externals()
        .iter()
        .map(|q| q.external.clone())
        .collect();
    for r in drive.selectors().into_iter().chain(drive.references()) {
        let n = r.def.param.clone().unwrap_or_else(|| r.def.id.clone());
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
pub fn find_all<'a>(drive: &'a Drive, names: &[String]) -> Result<Vec<&'a Register>, String> {
    let mut found = Vec::new();
    let mut errors = Vec::new();
    for n in names {
        match lookup::find(drive, n) {
            Ok(r) => found.push(r),
            Err(e) => errors.push(e.to_string()),
        }
    }
    if errors.is_empty() {
        Ok(found)
    } else {
        Err(errors.join("\n"))
    }
}

/// The parameters that select a register's scale or address, as its plan lists them.
pub fn selectors_of<'a>(drive: &'a Drive, r: &Register) -> Vec<&'a Register> {
    dependencies(drive, r, &LiveSettings::default(), true)
}

/// The registers a register's value is relative to under `settings`: for a selected scale, only
/// the case the selector's known code picks (every case while it is unknown).
pub fn references_of<'a>(
    drive: &'a Drive,
    r: &Register,
    settings: &LiveSettings,
) -> Vec<&'a Register> {
    dependencies(drive, r, settings, false)
}

/// The registers behind a register's settings dependencies (`RegisterPlan::depends_on`):
/// selectors (`codes`) or reference registers; external quantities are not registers.
fn dependencies<'a>(
    drive: &'a Drive,
    r: &Register,
    settings: &LiveSettings,
    codes: bool,
) -> Vec<&'a Register> {
    let plan = drive.plan();
    let mut rows = Vec::new();
    drive
        .register_plan(r)
        .depends_on(&settings.view(drive), |d| match d {
            Dependency::Code(s) if codes => rows.extend(
                plan.settings
                    .codes
                    .get(usize::from(s.slot))
                    .map(|c| c.register),
            ),
            Dependency::Quantity(s) if !codes => {
                if let Some(Quantity::Register(row)) =
                    plan.settings.quantities.get(usize::from(s.slot))
                {
                    rows.push(*row);
                }
            }
            _ => {}
        });
    let mut out: Vec<&Register> = Vec::new();
    for row in rows {
        if let Some(d) = drive.register_of_row(row) {
            if !out.iter().any(|x| x.def.id == d.def.id) {
                out.push(d);
            }
        }
    }
    out
}

/// Whether a register exists on a transport kind, as its plan says.
pub fn on_transport(drive: &Drive, r: &Register, kind: TransportKind) -> bool {
    drive.register_plan(r).transports.contains(kind)
}

/// The communication address of a register under `settings` on `kind`: the plan's answer
/// (`RegisterPlan::address_for`), the same the generated code and the simulator give.
pub fn address_of(
    drive: &Drive,
    r: &Register,
    settings: &LiveSettings,
    kind: TransportKind,
) -> u16 {
    drive
        .register_plan(r)
        .address_for(&settings.view(drive), kind)
}

/// A conversion error, with what to do about a missing setting.
pub fn value_error(drive: &Drive, e: &ValueError) -> String {
    match e {
        ValueError::MissingSetting { register, setting } => {
            match drive.externals().iter().find(|q| q.external == *setting) {
                Some(q) => format!(
                    "{register}: converting needs {setting} ({}, in {}), which is not a register \
                     of the drive; give it with --set {setting}=<value>",
                    q.description, q.unit
                ),
                None => format!(
                    "{register}: converting needs the value of {setting}, which could not be \
                     read; give it with --set {setting}=<value>"
                ),
            }
        }
        ValueError::NotAStep { .. } => format!("{e} (--round sends the nearest)"),
        ValueError::LimitNotKnown { register, setting } => {
            match drive.externals().iter().find(|q| q.external == *setting) {
                Some(q) => format!(
                    "{register}: its limit is a percentage of {setting} ({}, in {}), which is \
                     not a register of the drive; give it with --set {setting}=<value>",
                    q.description, q.unit
                ),
                None => format!(
                    "{register}: its limit is a percentage of {setting}, which could not be \
                     read; give it with --set {setting}=<value>"
                ),
            }
        }
        other => other.to_string(),
    }
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
    slots: Vec<Result<(usize, Width), String>>,
}

/// A connected drive with its settings.
pub struct Session<'d> {
    /// The drive's map.
    pub drive: &'d Drive,
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
}

impl<'d> Session<'d> {
    /// Connects to the drive described by `drive`.
    pub fn open(drive: &'d Drive, link: &LinkArgs, settings: LiveSettings) -> Result<Self, String> {
        Self::open_with(drive, leak_profile(drive), link, settings)
    }

    /// [`Session::open`] with the drive's run-time profile already built (it is leaked: build
    /// it once per map).
    pub fn open_with(
        drive: &'d Drive,
        profile: &'static Profile,
        link: &LinkArgs,
        settings: LiveSettings,
    ) -> Result<Self, String> {
        link.check_transport(drive)?;
        let (client, text) = link.connect(drive, profile)?;
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
        })
    }

    /// The address of `r` on this link under the current settings, or why it cannot be known
    /// (it moves with a setting that could not be read: nothing is sent to a guessed address).
    pub fn address(&self, r: &Register) -> Result<u16, String> {
        self.drive
            .register_plan(r)
            .locate(&self.settings.view(self.drive), self.kind)
            .map_err(|e| {
                format!(
                    "{}: its address depends on {}, which could not be read; give it with --set {}=<value>",
                    describe::register(r),
                    e.setting,
                    e.setting
                )
            })
    }

    /// The address of `r` to show: [`Session::address`], or where the register is when the
    /// settings it moves with are at their defaults (never used for a request).
    pub fn shown_address(&self, r: &Register) -> u16 {
        address_of(self.drive, r, &self.settings, self.kind)
    }

    /// Reads what the conversions and addresses of `regs` depend on, except what `fixed` gives:
    /// first the parameters that select scales and addresses, then the references the selected
    /// scales need. Returns a warning per dependency that could not be read.
    pub fn load_dependencies(
        &mut self,
        regs: &[&Register],
        fixed: &BTreeSet<String>,
    ) -> Vec<String> {
        let drive = self.drive;
        // Registers that do not exist on this link need nothing.
        let regs: Vec<&Register> = regs
            .iter()
            .copied()
            .filter(|r| on_transport(self.drive, r, self.kind))
            .collect();
        let mut warnings = Vec::new();
        let mut done: BTreeSet<String> = fixed.clone();
        let selectors: Vec<&Register> = regs.iter().flat_map(|r| selectors_of(drive, r)).collect();
        self.read_dependencies(&selectors, &mut done, &mut warnings, "conversions depend");
        let references: Vec<&Register> = regs
            .iter()
            .flat_map(|r| references_of(drive, r, &self.settings))
            .collect();
        self.read_dependencies(&references, &mut done, &mut warnings, "conversions depend");
        warnings
    }

    /// Reads the quantities the limits of `regs` through other parameters depend on
    /// (`RegisterPlan::limit`: V7 n011 for the frequency reference), except what `fixed` gives:
    /// what a write checks before sending. Returns a warning per quantity that could not be
    /// read (the write is then refused, since its limit cannot be checked).
    pub fn load_limits(&mut self, regs: &[&Register], fixed: &BTreeSet<String>) -> Vec<String> {
        let drive = self.drive;
        let plan = drive.plan();
        let mut deps: Vec<&Register> = Vec::new();
        for r in regs {
            if !on_transport(drive, r, self.kind) {
                continue;
            }
            if let Some(Dependency::Quantity(s)) = drive.register_plan(r).limit_dependency() {
                if let Some(Quantity::Register(row)) =
                    plan.settings.quantities.get(usize::from(s.slot))
                {
                    if let Some(d) = drive.register_of_row(*row) {
                        deps.push(d);
                    }
                }
            }
        }
        let mut warnings = Vec::new();
        let mut done = fixed.clone();
        // A quantity a conversion already read is read again: the limit is checked against
        // the drive's value now, and reading twice costs one request.
        self.read_dependencies(&deps, &mut done, &mut warnings, "the write's limit depends");
        warnings
    }

    /// Reads `deps` into the settings; `what` depends on them ("conversions depend") for the
    /// warnings.
    fn read_dependencies(
        &mut self,
        deps: &[&Register],
        done: &mut BTreeSet<String>,
        warnings: &mut Vec<String>,
        what: &str,
    ) {
        for d in deps {
            if !done.insert(d.def.id.clone()) {
                continue;
            }
            if let Some(why) = self.unreadable(d) {
                warnings.push(format!(
                    "{why}, and {what} on it; give it with --set {}=<value>",
                    d.def.param.as_deref().unwrap_or(&d.def.id)
                ));
                continue;
            }
            match self.read_raw(d) {
                Ok(raw) => {
                    // Selectors and references are one-word registers (the map's validation).
                    self.settings.absorb(self.drive, d.def.address, raw as u16);
                }
                Err(e) => warnings.push(format!(
                    "reading {}, which {what} on: {e}",
                    describe::register(d)
                )),
            }
        }
    }

    /// Reads the raw value of `r` at its address on this link: its word, or a 32-bit pair's
    /// two words in one request, joined in the map's order.
    pub fn read_raw(&mut self, r: &Register) -> Result<u32, String> {
        if let Some(why) = self.unreadable(r) {
            return Err(why);
        }
        let address = self.address(r)?;
        let info = self.drive.register_plan(r).info;
        let mut w = [0u16; 2];
        let words = &mut w[..usize::from(info.width.count())];
        self.read_into(info.table, address, words)
            .map_err(|e| e.to_string())?;
        Ok(info.width.join(words))
    }

    fn read_into(
        &mut self,
        table: Table,
        address: u16,
        out: &mut [u16],
    ) -> Result<(), drivemap_runtime::Error> {
        match table {
            Table::Holding => self.client.read_holding(self.slave, address, out),
            Table::Input => self.client.read_input(self.slave, address, out),
        }
    }

    /// Why a register cannot be read on this link, if it cannot.
    pub fn unreadable(&self, r: &Register) -> Option<String> {
        if r.broadcast {
            Some(format!(
                "{} is broadcast-only: it can be written to slave 0, never read",
                describe::register(r)
            ))
        } else if !r.readable() {
            Some(format!("{} is write-only", describe::register(r)))
        } else if !on_transport(self.drive, r, self.kind) {
            Some(format!(
                "{} exists only on {}, not on this link ({})",
                describe::register(r),
                describe::transports(self.drive.register_plan(r).transports),
                self.kind.name()
            ))
        } else {
            None
        }
    }

    /// Plans the reads of `regs` with the runtime's read planner: the requests that read them in
    /// the least bus time, bridging only addresses of readable registers of the map, at most
    /// `max_read` per request. Registers this link cannot read get their reason instead.
    pub fn plan(&self, regs: &[&Register]) -> Result<Polling, String> {
        let drive = self.drive;
        let infos: Vec<RegisterInfo> = drive
            .registers
            .iter()
            .filter(|r| on_transport(self.drive, r, self.kind))
            // The plan's own row, at the address this link and these settings put it (a
            // register whose address is not known is not bridged over).
            .filter_map(|r| {
                Some(RegisterInfo {
                    address: self.address(r).ok()?,
                    ..drive.register_plan(r).info
                })
            })
            .collect();
        let mut wanted = Vec::new();
        let mut slots = Vec::new();
        for r in regs {
            match self.unreadable(r).map_or_else(|| self.address(r), Err) {
                Err(why) => slots.push(Err(why)),
                Ok(address) => {
                    let info = drive.register_plan(r).info;
                    wanted.push((info.table, address));
                    slots.push(Ok((wanted.len() - 1, info.width)));
                }
            }
        }
        let profile = self.client.profile();
        let poller = Poller::new(profile, &infos, wanted)
            .map_err(|e| e.to_string())?
            .with_model(BusModel::new(profile, self.line));
        Ok(Polling { poller, slots })
    }

    /// Reads every register of a plan once; returns the raw value (a word, or a pair's words
    /// joined) or the error of each, in the order the plan was made for. A request that the
    /// drive refuses with 02h or 21h is split so each register gets its own value or error;
    /// a pair is never split.
    pub fn poll(&mut self, plan: &mut Polling) -> Vec<Result<u32, String>> {
        plan.poller.poll(&mut self.client, self.slave);
        plan.slots
            .iter()
            .map(|slot| match slot {
                Err(why) => Err(why.clone()),
                Ok((i, width)) => match plan.poller.raw(*i, *width) {
                    Some(Ok(w)) => Ok(w),
                    Some(Err(e)) => Err(e.to_string()),
                    None => Err("not read".into()),
                },
            })
            .collect()
    }

    /// [`Session::poll`] keeping the exception code of each refusal, and the requests sent.
    pub fn poll_detailed(&mut self, plan: &mut Polling) -> (Vec<Result<u32, Failure>>, u32) {
        let stats = plan.poller.poll(&mut self.client, self.slave);
        let words = plan
            .slots
            .iter()
            .map(|slot| match slot {
                Err(why) => Err(Failure {
                    message: why.clone(),
                    exception: None,
                    sent: false,
                }),
                Ok((i, width)) => match plan.poller.raw(*i, *width) {
                    Some(Ok(w)) => Ok(w),
                    Some(Err(e)) => Err(Failure {
                        message: e.to_string(),
                        exception: e.exception().map(|x| x.code),
                        sent: !e.is_refusal(),
                    }),
                    None => Err(Failure {
                        message: "not read".into(),
                        exception: None,
                        sent: false,
                    }),
                },
            })
            .collect();
        (words, stats.requests)
    }

    /// Reads the raw values of `regs` once, planned (see [`Session::plan`]).
    pub fn read_words(&mut self, regs: &[&Register]) -> Result<Vec<Result<u32, String>>, String> {
        let mut plan = self.plan(regs)?;
        Ok(self.poll(&mut plan))
    }

    /// A raw value of `r` in hex as the manuals write it: four digits, eight for a pair.
    pub fn raw_text(&self, r: &Register, raw: u32) -> String {
        let digits = 4 * usize::from(self.drive.register_plan(r).info.width.count());
        format!("{raw:0digits$X}h")
    }

    /// Decodes a raw value of `r`.
    pub fn decode(&self, r: &Register, raw: u32) -> Result<Value, String> {
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
