//! `drivemap write --drive <id> <register>=<value>... (--tcp | --rtu-tcp | --serial) ...`

use drivemap_runtime::core::plan::Conversion;
use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_live::codec::{self, InputError};
use drivemap_live::intern::intern;
use drivemap_map::Map;
use drivemap_map::RegisterRef;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::core::roles::{RoleKind, Target as Place};
use drivemap_runtime::core::scale::{Rounding, ValueError};
use drivemap_runtime::error::Refusal;
use drivemap_runtime::gate;
use drivemap_runtime::vfd::{VariableFrequencyDrive, Vfd};

use crate::error::Error;
use crate::live::Target;
use drivemap_live::session::{Session, value_error};
use drivemap_map::describe;

/// Arguments of `drivemap write`.
#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    #[command(flatten)]
    pub(crate) target: Target,
    /// `register=value` in engineering units (`accel_time_1=12.5`, `Bn-01=12.5 s`, `0200H=12.5`:
    /// a register by id, parameter number, printed name or address as the manual prints it), an
    /// enumeration code, id or meaning, or bit fields (`run,reverse`, `0x0003`).
    #[arg(required = true, value_name = "REGISTER=VALUE")]
    pub(crate) assignments: Vec<String>,
    /// After writing, run this command of the map (`save_parameters`, `enter`, `accept`);
    /// a command that stores to EEPROM is counted against the runtime's hourly budget.
    #[arg(long, value_name = "COMMAND")]
    pub(crate) persist: Option<String>,
    /// Send the nearest value the register can carry when a number is not a whole number of
    /// its steps (35.75 Hz to a register that counts 0.1 Hz sends 35.8 Hz); without it such a
    /// value is refused with the two nearest. Ranges and limits apply to the value given.
    #[arg(long)]
    pub(crate) round: bool,
    /// Change a setting that scales, bounds or selects other registers (`ref_freq`, `n011`)
    /// while the drive's status shows it running: without it such a write is refused, since
    /// it moves what the running drive does (its reference taken as a percentage of the
    /// setting, say).
    #[arg(long = "while-running")]
    pub(crate) while_running: bool,
}

/// The registers whose conversion, limit or address `r` takes part in, each with how: `scales
/// frequency_setpoint`, `bounds tcp_frequency_reference`, `selects the scale of x`.
pub(crate) fn dependants(
    drive: &Map,
    r: RegisterRef<'_>,
    settings: &drivemap_live::LiveSettings,
) -> Vec<String> {
    let mut out = Vec::new();
    // Only a setting (a code slot's register or a quantity) is another's dependency: any
    // other register has none, and is not searched for (a write sweep writes thousands).
    let all = drive.plan();
    let is_setting = all
        .settings
        .codes
        .iter()
        .any(|c| all.registers[c.register].info.id == r.id())
        || all.settings.quantities.iter().any(|q| match q {
            drivemap_map::Quantity::Register(row) => all.registers[*row].info.id == r.id(),
            drivemap_map::Quantity::External { id, .. } => id == r.id(),
        });
    if !is_setting {
        return out;
    }
    for x in drive.registers() {
        if x.id() == r.id() {
            continue;
        }
        let bounds = match x.plan().limit_dependency() {
            Some(drivemap_runtime::core::plan::Dependency::Quantity(s)) => matches!(
                all.settings.quantities.get(usize::from(s.slot)),
                Some(drivemap_map::Quantity::Register(row))
                    if all.registers[*row].info.id == r.id()
            ),
            _ => false,
        };
        let used = drivemap_live::session::settings_used(drive, x, settings);
        if !used.iter().any(|u| u == r.id()) {
            continue;
        }
        let selects = drivemap_live::session::selectors_of(drive, x)
            .iter()
            .any(|s| s.id() == r.id());
        let how = if selects {
            "selects the scale or address of"
        } else if bounds {
            "bounds"
        } else {
            "scales"
        };
        out.push(format!("{how} {}", x.id()));
    }
    out
}

/// A refusal of the write gate, naming the register as the map prints it; nothing was sent.
fn refused(r: RegisterRef<'_>, e: &Refusal) -> String {
    let hint = match e {
        Refusal::BroadcastOnly { .. } => "; write it with --slave 0",
        Refusal::NotOnTransport { .. } => "; it is not on this link",
        _ => "",
    };
    format!("{}: {e}{hint}; nothing written", r.label())
}

fn input_error(drive: &Map, e: &InputError) -> String {
    match e {
        InputError::Value(v) => value_error(drive, v).to_string(),
        InputError::Parse(m) => m.clone(),
    }
}

/// The word for an assignment that names some fields of a bit-field register (`run`,
/// `direction=reverse`): the fields not named keep the value read from the drive, so writing
/// one field never changes another — except in a register that holds a command role, whose
/// word is composed as the drive trait composes it (`Vfd::command_fields_word`: no run or
/// reset bit the assignment does not name, unless the drive runs). A register that cannot be read here (write-only, or a
/// broadcast) gets the named fields and 0 elsewhere, and a warning says so. `None` when the
/// value is not a field list (a number is the whole word).
fn field_word(
    drive: &Map,
    session: &mut Session<'_>,
    r: RegisterRef<'_>,
    text: &str,
) -> Result<Option<u32>, Error> {
    let Some(input) = codec::field_input(drive, r, text).map_err(|e| input_error(drive, &e))?
    else {
        return Ok(None);
    };
    let Conversion::Bits {
        mask: fields_mask, ..
    } = r.plan().conversion
    else {
        return Ok(None);
    };
    let plan = drive.plan();
    let row = u16::try_from(plan.order[r.index()]).unwrap_or(u16::MAX);
    let word = if input.mask & fields_mask == fields_mask {
        input.value
    } else if holds_command(drive, row) {
        // A command word: composed from the roles as the drive trait composes its own (no run
        // or reset bit this write does not name, unless the drive runs), never a read-back.
        let mut vfd = Vfd::from_plan(
            &mut session.client,
            session.slave,
            session.settings.view(drive),
            plan.registers,
            plan.roles,
        );
        let word = vfd
            .command_fields_word(row, input.mask, input.value)
            .map_err(|e| format!("{}: {e}; nothing written", r.label()))?;
        if session.slave == 0 || session.unreadable(r).is_some() {
            eprintln!(
                "warning: {} cannot be read here, so the fields not named are released (0 where no command)",
                r.label()
            );
        }
        word
    } else if let Some(read) = r.read_param() {
        eprintln!(
            "warning: a read of {} returns {read}, not the parameter written, so the fields not named are written as 0",
            r.label()
        );
        input.value
    } else if session.slave == 0 || session.unreadable(r).is_some() {
        eprintln!(
            "warning: {} cannot be read here, so the fields not named are written as 0",
            r.label()
        );
        input.value
    } else {
        let current = session.read_raw(r).map(|raw| raw as u16).map_err(|e| {
            format!(
                "reading {} to keep its other fields: {e}; nothing written",
                r.id()
            )
        })?;
        ((current & !input.mask) | input.value) & fields_mask
    };
    codec::encode(drive, r, f64::from(word), &session.settings)
        .map(Some)
        .map_err(|e| Error::Refused(format!("{}; nothing written", value_error(drive, &e))))
}

/// Whether plan row `row` of `drive` holds a command role (run, direction, fault reset, ...).
fn holds_command(drive: &Map, row: u16) -> bool {
    drive.plan().roles.places.iter().any(|p| {
        p.role.kind() == RoleKind::Command && matches!(p.target, Place::Field(f) if f.row == row)
    })
}

/// The warning for a number register whose range the manual does not print, directly or
/// through another parameter (`max_relative`): only its word bounds what is sent. `None` for
/// registers with a range, codes and bit fields.
pub(crate) fn no_printed_range(drive: &Map, r: RegisterRef<'_>) -> Option<String> {
    debug_assert!(std::ptr::eq(drive, r.map()), "a register of another map");
    let plan = r.plan();
    let number = matches!(
        plan.conversion,
        Conversion::Word { .. }
            | Conversion::Decimal { .. }
            | Conversion::Relative { .. }
            | Conversion::Selected { .. }
    );
    if !number || plan.limit.is_some() || plan.envelope != plan.full_range() {
        return None;
    }
    let why = r
        .unknown()
        .iter()
        .find(|u| u.what == drivemap_map::facts::UnknownItem::Range)
        .map(|u| format!(" ({})", u.reason))
        .unwrap_or_default();
    Some(format!(
        "the manual prints no range for {}{why}: only its {}-bit {} bounds the value sent",
        r.label(),
        16 * plan.info.width.count(),
        if plan.info.width.count() > 1 {
            "value"
        } else {
            "word"
        }
    ))
}

/// Checks every assignment, then writes them in order; exits 1 when the drive refused one.
pub(crate) fn run(args: Args) -> Result<ExitCode, Error> {
    let drive = args.target.load()?;
    let profile = drivemap_live::leak_profile(&drive);
    execute(&drive, profile, &args)
}

/// [`run`] with the map loaded and its run-time profile built.
pub(crate) fn execute(
    drive: &Map,
    profile: &'static Profile,
    args: &Args,
) -> Result<ExitCode, Error> {
    let mut pairs: Vec<(RegisterRef<'_>, String)> = Vec::new();
    let mut entries = Vec::new();
    let mut errors = Vec::new();
    for a in &args.assignments {
        let Some((name, value)) = a.split_once('=') else {
            errors.push(format!(
                "`{}` is not REGISTER=VALUE; nothing written",
                codec::shorten(a)
            ));
            continue;
        };
        match drivemap_live::lookup::find(drive, name.trim()) {
            // An empty value is refused, never taken as "keep what the drive holds".
            Ok(r) if value.trim().is_empty() => errors.push(format!(
                "`{}`: no value given for {}; nothing written",
                codec::shorten(a),
                r.label()
            )),
            // A BICO register's read parameter names no value to write.
            Ok(r) => match drivemap_live::lookup::wrong_side(r, name.trim(), true) {
                None => pairs.push((r, value.trim().to_owned())),
                Some(why) => errors.push(format!("{why}; nothing written")),
            },
            Err(e) => match drivemap_live::indexed::find_entry(drive, name.trim()) {
                Some(entry) => entries.push((entry, value.trim().to_owned())),
                None => errors.push(e.to_string()),
            },
        }
    }
    if !errors.is_empty() {
        return Err(Error::Refused(errors.join("\n")));
    }
    // A draft map is not written through unless --draft says so; then every write says it.
    let through = drivemap_live::draft::check_write(drive, args.target.draft_writes())?
        .map(|note| format!(" [{note}]"))
        .unwrap_or_default();
    if !entries.is_empty() {
        return super::entries::write(drive, &args.target, pairs.len(), &entries);
    }
    let slave = args.target.link.slave(drive);
    let kind = args.target.link.kind();
    // The write gate's link checks (access, transport, broadcast space), before connecting;
    // the client repeats the whole gate before each write is framed.
    for (r, _) in &pairs {
        gate::rule(profile, intern(r.id()))
            .and_then(|rule| gate::check_link(profile, kind, slave, rule))
            .map_err(|e| refused(*r, &e))?;
    }
    if let Some(id) = &args.persist
        && !drive.protocol().commands.iter().any(|c| &c.id == id)
    {
        let known: Vec<&str> = drive
            .protocol()
            .commands
            .iter()
            .map(|c| c.id.as_str())
            .collect();
        return Err(Error::Refused(format!(
            "{} has no command `{}`; commands: {}; nothing written",
            drive.id(),
            codec::shorten(id),
            if known.is_empty() {
                "none".to_owned()
            } else {
                known.join(", ")
            }
        )));
    }
    let given = args.target.settings.resolve(drive)?;
    let rounding = if args.round {
        Rounding::Nearest
    } else {
        Rounding::Exact
    };
    // Refuse what cannot be written before connecting; values that need settings from the
    // drive are checked once those are read.
    for (r, value) in &pairs {
        match codec::parse_value_with(drive, *r, value, &given.settings, rounding) {
            Ok(_)
            | Err(InputError::Value(
                ValueError::MissingSetting { .. } | ValueError::LimitNotKnown { .. },
            )) => {}
            Err(e) => {
                return Err(Error::Refused(format!(
                    "{}; nothing written",
                    input_error(drive, &e)
                )));
            }
        }
    }
    for (r, _) in &pairs {
        if let Some(w) = no_printed_range(drive, *r) {
            eprintln!("warning: {w}");
        }
    }
    let regs: Vec<RegisterRef<'_>> = pairs.iter().map(|(r, _)| *r).collect();
    crate::output::warn_unprinted(
        drive,
        &args.target.link,
        &[
            drivemap_runtime::core::stated::ProtocolFact::Serial,
            drivemap_runtime::core::stated::ProtocolFact::MaxWrite,
        ],
    );
    let mut session = Session::open_as(
        drive,
        profile,
        &args.target.link,
        given.settings.clone(),
        args.target.draft_writes(),
    )?;
    for w in session.load_dependencies(&regs, &given.fixed) {
        eprintln!("warning: {w}");
    }
    for w in session.load_limits(&regs, &given.fixed) {
        eprintln!("warning: {w}");
    }
    // Each --set of a register the drive gives is checked against it; the rest are assumed,
    // and every write converted with one says so.
    let assumed = session
        .check_given(&given.given)
        .map_err(|e| Error::Refused(format!("{e}; nothing written")))?;
    if let Some(why) = session.silence.report() {
        return Err(Error::Refused(format!(
            "{} did not answer: {why}; nothing written",
            session.link
        )));
    }
    // A setting others depend on: named, and not changed under a running drive unless asked.
    for (r, _) in &pairs {
        let deps = dependants(drive, *r, &session.settings);
        if deps.is_empty() {
            continue;
        }
        let list = deps.join(", ");
        let running = if session.slave == 0 {
            None
        } else {
            let plan = drive.plan();
            let mut vfd = Vfd::from_plan(
                &mut session.client,
                session.slave,
                session.settings.view(drive),
                plan.registers,
                plan.roles,
            );
            if vfd.supports(drivemap_runtime::core::roles::Role::Running) {
                vfd.status().ok().and_then(|s| s.running)
            } else {
                None
            }
        };
        if running == Some(true) && !args.while_running {
            return Err(Error::Refused(format!(
                "{}: the drive is running (its status shows `running`), and this setting {list}: changing it moves what the running drive does; give --while-running to change it anyway; nothing written",
                r.label()
            )));
        }
        eprintln!("note: {} {list}: their meaning changes with it", r.id());
    }
    let mut raws = Vec::new();
    for (r, value) in &pairs {
        let raw = match field_word(drive, &mut session, *r, value)? {
            Some(raw) => raw,
            None => codec::parse_value_with(drive, *r, value, &session.settings, rounding)
                .map_err(|e| {
                    // A range a parameter's code selects: which code, and that it was read.
                    let case = drivemap_live::session::selected_range(drive, *r, &session.settings)
                        .map(|c| format!(" ({c})"))
                        .unwrap_or_default();
                    format!("{}{case}; nothing written", input_error(drive, &e))
                })?,
        };
        // Said in the report: the value sent is not the one given.
        let rounded = rounding == Rounding::Nearest
            && matches!(
                codec::parse_value(drive, *r, value, &session.settings),
                Err(InputError::Value(ValueError::NotAStep { .. }))
            );
        raws.push((raw, rounded.then(|| value.clone())));
    }
    // The whole gate for every assignment before the first is sent: all or nothing.
    let mut writes = Vec::new();
    for ((r, _), (raw, rounded)) in pairs.iter().zip(raws) {
        let address = session
            .address(*r)
            .map_err(|e| format!("{e}; nothing written"))?;
        let rule = gate::rule(profile, intern(r.id()))
            .and_then(|rule| {
                let words = rule.width.split(raw);
                gate::check(
                    profile,
                    kind,
                    slave,
                    gate::WriteTarget::Rule(rule),
                    address,
                    words.iter().take(usize::from(rule.width.count())).copied(),
                )
                .map(|()| rule)
            })
            .map_err(|e| refused(*r, &e))?;
        writes.push((*r, rule, address, raw, rounded));
    }
    for (r, rule, address, raw, rounded) in writes {
        let mut shown = codec::decode_written(drive, r, raw, &session.settings)
            .map(|v| v.to_string())
            .unwrap_or_else(|_| format!("{raw}"));
        if let Some(given) = rounded {
            shown = format!("{shown}, rounded from {given} (--round)");
        }
        let mut assuming = assumed.for_register(drive, r, &session.settings);
        if !assuming.is_empty() {
            assuming.insert_str(0, "; ");
        }
        // A register whose drive executes only a changed value gets its intermediate value
        // first (`Client::write_changed`, through the same gate), so writing the same value
        // twice executes it twice.
        let between = r.plan().repeat_needs_change.map(|x| x.between);
        // The parameters that select its scale or range, read again now: the value was
        // converted and checked for the codes read before, and is not sent under another.
        session
            .confirm_selectors(r)
            .map_err(|e| Error::Refused(format!("{e}; nothing written")))?;
        let result = match between {
            Some(between) => {
                session
                    .client
                    .write_changed(session.slave, rule, address, between, raw)
            }
            None => session.client.write_rule(session.slave, rule, address, raw),
        };
        match result {
            Ok(()) => {}
            Err(drivemap_runtime::error::Error::Refused(e)) => {
                return Err(Error::Refused(refused(r, &e)));
            }
            Err(e) => {
                eprintln!("drivemap: {e}");
                return Ok(ExitCode::FAILURE);
            }
        }
        let digits = 4 * usize::from(rule.width.count());
        let first = match between {
            Some(b) if b != raw => {
                format!(" after {b} ({b:0digits$X}h): it executes only a changed value")
            }
            _ => String::new(),
        };
        outln!(
            "wrote {} = {shown} ({raw:0digits$X}h) at {}{first}{through}{assuming}",
            r.label(),
            describe::address_as(drive.address_format(), address)
        );
    }
    if let Some(id) = &args.persist {
        if let Err(e) = session.client.persist(session.slave, id) {
            eprintln!("drivemap: {e}");
            return Ok(ExitCode::FAILURE);
        }
        outln!("ran command {id}");
    }
    Ok(ExitCode::SUCCESS)
}
