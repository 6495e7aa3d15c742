//! `drivemap write --drive <id> <register>=<value>... (--tcp | --rtu-tcp | --serial) ...`

use std::process::ExitCode;

use clap::Args as ClapArgs;
use drivemap_codegen::Drive;
use drivemap_codegen::ir::Register;
use drivemap_live::codec::{self, InputError};
use drivemap_runtime::ValueError;

use crate::describe;
use crate::live::Target;
use crate::live::session::{Session, value_error};

/// Arguments of `drivemap write`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    pub target: Target,
    /// `register=value` in engineering units (`accel_time_1=12.5`, `Bn-01=12.5 s`), an
    /// enumeration code, id or meaning, or bit fields (`run,reverse`, `0x0003`).
    #[arg(required = true, value_name = "REGISTER=VALUE")]
    pub assignments: Vec<String>,
    /// After writing, run this command of the map (`save_parameters`, `enter`, `accept`);
    /// a command that stores to EEPROM is counted against the runtime's hourly budget.
    #[arg(long, value_name = "COMMAND")]
    pub persist: Option<String>,
}

fn input_error(drive: &Drive, e: &InputError) -> String {
    match e {
        InputError::Value(v) => value_error(drive, v),
        InputError::Parse(m) => m.clone(),
    }
}

/// Checks every assignment, then writes them in order; exits 1 when the drive refused one.
pub fn run(args: Args) -> Result<ExitCode, String> {
    let drive = args.target.load()?;
    let mut pairs: Vec<(&Register, String)> = Vec::new();
    let mut errors = Vec::new();
    for a in &args.assignments {
        let Some((name, value)) = a.split_once('=') else {
            errors.push(format!("`{a}` is not REGISTER=VALUE"));
            continue;
        };
        match drivemap_live::lookup::find(&drive, name.trim()) {
            Ok(r) => pairs.push((r, value.trim().to_owned())),
            Err(e) => errors.push(e.to_string()),
        }
    }
    if !errors.is_empty() {
        return Err(errors.join("\n"));
    }
    let slave = args.target.link.slave(&drive);
    for (r, _) in &pairs {
        if !r.writable() {
            return Err(format!("{} is read-only", describe::register(r)));
        }
        if r.broadcast && slave != 0 {
            return Err(format!(
                "{} is broadcast-only: write it with --slave 0",
                describe::register(r)
            ));
        }
    }
    if let Some(id) = &args.persist {
        if !drive.protocol.commands.iter().any(|c| &c.id == id) {
            let known: Vec<&str> = drive
                .protocol
                .commands
                .iter()
                .map(|c| c.id.as_str())
                .collect();
            return Err(format!(
                "{} has no command `{id}`; commands: {}",
                drive.meta.id,
                if known.is_empty() {
                    "none".to_owned()
                } else {
                    known.join(", ")
                }
            ));
        }
    }
    let given = args.target.settings.resolve(&drive)?;
    // Refuse what cannot be written before connecting; values that need settings from the
    // drive are checked once those are read.
    for (r, value) in &pairs {
        match codec::parse_value(&drive, r, value, &given.settings) {
            Ok(_) | Err(InputError::Value(ValueError::MissingSetting { .. })) => {}
            Err(e) => return Err(input_error(&drive, &e)),
        }
    }
    let regs: Vec<&Register> = pairs.iter().map(|(r, _)| *r).collect();
    let mut session = Session::open(&drive, &args.target.link, given.settings)?;
    for w in session.load_dependencies(&regs, &given.fixed) {
        eprintln!("warning: {w}");
    }
    let mut raws = Vec::new();
    for (r, value) in &pairs {
        let raw = codec::parse_value(&drive, r, value, &session.settings)
            .map_err(|e| format!("{}; nothing written", input_error(&drive, &e)))?;
        raws.push(raw);
    }
    for ((r, _), raw) in pairs.iter().zip(raws) {
        let address = session.address(r);
        let shown = session
            .decode(r, raw)
            .map(|v| v.to_string())
            .unwrap_or_else(|_| format!("{raw}"));
        if let Err(e) = session.client.write_register(session.slave, address, raw) {
            eprintln!("drivemap: {e}");
            return Ok(ExitCode::FAILURE);
        }
        println!(
            "wrote {} = {shown} ({raw:04X}h) at {}",
            describe::register(r),
            describe::address(address)
        );
    }
    if let Some(id) = &args.persist {
        if let Err(e) = session.client.persist(session.slave, id) {
            eprintln!("drivemap: {e}");
            return Ok(ExitCode::FAILURE);
        }
        println!("ran command {id}");
    }
    Ok(ExitCode::SUCCESS)
}
