//! `drivemap demo`: a simulated drive on loopback, driven through the one drive API.
//!
//! Starts a `drivemap-sim` simulator of the chosen drive in this process, serving RTU frames over
//! loopback TCP as a serial gateway would, then runs one routine written against
//! [`VariableFrequencyDrive`] — set the ramp times and the reference, choose the direction, run,
//! watch the status and monitors while the output ramps, stop, watch it ramp down — exactly as an
//! application would. Every drive whose map has `roles:` runs it with no code of its own: a drive
//! compiled into `drivemap-drives` through its generated module ([`Vfd::connect`]), any other map
//! through the plan lowered at run time ([`Vfd::from_plan`]). Simulated time runs `--time-scale`
//! times faster than real time.

use std::process::ExitCode;
use std::thread;
use std::time::{Duration, Instant};

use clap::Args as ClapArgs;
use drivemap_runtime::core::roles::Role;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::ascii_over_tcp::AsciiOverTcpTransport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::vfd::{Direction, VariableFrequencyDrive, Vfd};
use drivemap_runtime::{client::Client, client::ClientOptions, error::Error};

use crate::error::Error as CliError;
use drivemap_sim::{Simulator, server::TcpFraming, server::TcpServer};

use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub(crate) struct Args {
    /// Drive to simulate: the id of any map with `roles:` (shipped, or in --maps DIR).
    #[arg(long, default_value = "ptlk-tds-v8")]
    pub(crate) drive: String,
    /// Frequency reference to run at (Hz, 0 to 1000).
    #[arg(long, default_value_t = 48.0, value_parser = drivemap_live::duration::number(0.0, 1000.0))]
    pub(crate) frequency: f64,
    /// Accel and decel time written before running (s, 0 to 6000), where the map has the registers.
    #[arg(long, default_value_t = 4.0, value_parser = drivemap_live::duration::number(0.0, 6000.0))]
    pub(crate) ramp: f64,
    /// Run in reverse.
    #[arg(long)]
    pub(crate) reverse: bool,
    /// Simulated time runs this many times faster than real time (0.1 to 1000).
    #[arg(long = "time-scale", default_value_t = 4.0, value_parser = drivemap_live::duration::number(0.1, 1000.0))]
    pub(crate) time_scale: f64,
    /// Simulated seconds between rows of the table (0.01 to 5).
    #[arg(long, default_value_t = 0.5, value_parser = drivemap_live::duration::number(0.01, 5.0))]
    pub(crate) step: f64,
    /// The simulated drive's value of a register or an external quantity of the map, as
    /// `simulate --set` takes it (`--set p2000=50`: a reference scale resting on a parameter
    /// without a printed default); the client reads the register from the simulated drive.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub(crate) set: Vec<String>,
    /// Drive a draft map (`draft:`, not yet reviewed against its manual): without it a draft
    /// is refused, since the demo writes through the map.
    #[arg(long)]
    pub(crate) draft: bool,
    /// Talk Modbus ASCII to the simulated drive (ASCII frames over TCP), as to a drive set to
    /// ASCII; the default for a map whose `protocol.transports` lists `ascii` and not `rtu`.
    /// Refused for a map that does not list `ascii`.
    #[arg(long)]
    pub(crate) ascii: bool,
    #[command(flatten)]
    pub(crate) dir: MapsDir,
}

/// What the routine does.
pub(crate) struct Plan {
    pub(crate) frequency: f64,
    pub(crate) ramp: f64,
    pub(crate) reverse: bool,
    pub(crate) step: Duration,
    pub(crate) time_scale: f64,
}

/// One row of the table: a reading the drive does not support is shown as `-`.
fn row(t: f64, status: &str, values: [Result<f64, Error>; 4]) {
    let cell = |v: &Result<f64, Error>, width: usize, decimals: usize| match v {
        Ok(v) => format!("{v:>width$.decimals$}"),
        Err(_) => format!("{:>width$}", "-"),
    };
    outln!(
        "{t:>7.1} s  {status:<44} {} {} {} {}",
        cell(&values[0], 7, 2),
        cell(&values[1], 7, 2),
        cell(&values[2], 9, 2),
        cell(&values[3], 9, 1),
    );
}

/// A reading the drive lacks is `Err(NoRole)`; any other error ends the demo.
fn optional(v: Result<f64, Error>) -> Result<Result<f64, Error>, CliError> {
    match v {
        Err(Error::Refused(drivemap_runtime::error::Refusal::NoRole { .. })) | Ok(_) => Ok(v),
        Err(e) => Err(CliError::Refused(format!("reading the drive: {e}"))),
    }
}

/// The demo proper: one routine for every drive, through the drive trait only.
pub(crate) fn drive_it(d: &mut impl VariableFrequencyDrive, plan: &Plan) -> Result<(), CliError> {
    let fail = |what: &str, e: Error| format!("{what}: {e}");
    if d.supports(Role::AccelTime) && d.supports(Role::DecelTime) {
        d.set_ramp(plan.ramp, plan.ramp)
            .map_err(|e| fail("writing ramp times", e))?;
        outln!(
            "written: accel and decel time {:.1} s (roles accel_time, decel_time)",
            plan.ramp
        );
    } else {
        outln!("the map gives no accel/decel time registers: the drive ramps at its own setting");
    }
    d.set_reference(plan.frequency)
        .map_err(|e| fail("writing the frequency reference", e))?;
    let direction = if plan.reverse {
        Direction::Reverse
    } else {
        Direction::Forward
    };
    d.set_direction(direction)
        .map_err(|e| fail("setting the direction", e))?;
    outln!(
        "written: frequency reference {:.2} Hz, then run {}",
        plan.frequency,
        if plan.reverse { "reverse" } else { "forward" }
    );
    outln!();
    outln!(
        "{:>9}  {:<44} {:>7} {:>7} {:>9} {:>9}",
        "time",
        "status (roles that hold)",
        "ref Hz",
        "out Hz",
        "current A",
        "voltage V"
    );
    let start = Instant::now();
    let sim_time = || start.elapsed().as_secs_f64() * plan.time_scale;
    let pause = Duration::from_secs_f64(plan.step.as_secs_f64() / plan.time_scale);
    let deadline = start + Duration::from_secs(45);
    let sample = |d: &mut _| -> Result<Option<f64>, CliError> {
        let (status, values) = read_row(d, plan)?;
        let out = values[1].as_ref().ok().copied();
        row(sim_time(), &status, values);
        Ok(out)
    };
    d.run().map_err(|e| fail("run", e))?;
    // Up the ramp, then two rows at the reference.
    let mut steady = 0;
    while steady < 3 {
        let out = sample(d)?;
        if out.is_some_and(|o| (o - plan.frequency).abs() < 0.05) {
            steady += 1;
        }
        if Instant::now() > deadline {
            return Err(CliError::Refused(
                "the output did not reach the reference within 45 s".into(),
            ));
        }
        thread::sleep(pause);
    }
    d.stop().map_err(|e| fail("stop", e))?;
    outln!("{:>9}  stop", "");
    loop {
        let out = sample(d)?;
        if out == Some(0.0) {
            break;
        }
        if Instant::now() > deadline {
            return Err(CliError::Refused(
                "the output did not reach 0 Hz within 45 s".into(),
            ));
        }
        thread::sleep(pause);
    }
    Ok(())
}

fn read_row(
    d: &mut impl VariableFrequencyDrive,
    plan: &Plan,
) -> Result<(String, [Result<f64, Error>; 4]), CliError> {
    let fail = |what: &str, e: Error| format!("{what}: {e}");
    let reference = if d.supports(Role::ReferenceMonitor) {
        optional(d.reference())?
    } else {
        Ok(plan.frequency)
    };
    let output = d
        .output_frequency()
        .map_err(|e| fail("reading the output frequency", e))?;
    let current = optional(d.output_current())?;
    let voltage = optional(d.output_voltage())?;
    // Last, so that the status is never older than the output frequency beside it.
    let status = d.status().map_err(|e| fail("reading the status", e))?;
    // A drive run through a command profile: the state it shows first.
    let flags = match d
        .profile_state()
        .map_err(|e| fail("reading the profile state", e))?
    {
        Some(state) => format!("[{state}] {}", status.flags()),
        None => status.flags(),
    };
    Ok((flags, [reference, Ok(output), current, voltage]))
}

/// Runs the routine on the drive compiled in as module `$m`, if `$id` is the one asked for.
macro_rules! through_module {
    ($m:ident, $id:literal) => {
        fn $m<T: Transport>(
            c: &mut Client<T>,
            slave: u8,
            externals: &[(&str, f64)],
            plan: &Plan,
        ) -> Result<(), CliError> {
            use drivemap_drives::$m as module;
            let mut d =
                Vfd::connect::<module::Drive>(c, slave, module::Settings::default(), externals)
                    .map_err(|e| format!("reading settings: {e}"))?;
            drive_it(&mut d, plan)
        }
    };
}
drivemap_drives::for_each_drive!(through_module);

/// The routine through the generated module of `id`, if it is compiled in.
fn compiled<T: Transport>(
    id: &str,
    c: &mut Client<T>,
    slave: u8,
    externals: &[(&str, f64)],
    plan: &Plan,
) -> Option<Result<(), CliError>> {
    macro_rules! pick {
        ($m:ident, $id:literal) => {
            if id == $id {
                outln!(
                    "driven through drivemap_drives::{} (the generated module) and the VariableFrequencyDrive trait",
                    stringify!($m)
                );
                return Some($m(c, slave, externals, plan));
            }
        };
    }
    drivemap_drives::for_each_drive!(pick);
    None
}

pub(crate) fn run(args: Args) -> Result<ExitCode, CliError> {
    if !(args.time_scale.is_finite() && args.time_scale > 0.0) {
        return Err(CliError::Refused(
            "--time-scale: give a positive number".into(),
        ));
    }
    if !(args.step.is_finite() && args.step > 0.0) {
        return Err(CliError::Refused(
            "--step: give a positive number of seconds".into(),
        ));
    }
    let started = Instant::now();
    let drive = super::simulate::load_drive(&args.dir, &args.drive)?;
    if drive.plan().roles.is_empty() {
        return Err(CliError::Refused(format!(
            "the map of {} gives no `roles:`, so there is no drive to run; add them (maps/README.md, \"Roles\")",
            args.drive
        )));
    }
    let through = drivemap_live::draft::check_write(
        &drive,
        drivemap_live::draft::DraftWrites::from_flag(args.draft),
    )?;
    if let Some(note) = &through {
        outln!("note: writes go {note}");
    }
    let ascii = {
        use drivemap_map::facts::TransportName;
        let listed = &drive.protocol().transports;
        if args.ascii && !listed.contains(&TransportName::Ascii) {
            return Err(CliError::Refused(format!(
                "the map of {} does not list Modbus ASCII in protocol.transports: leave --ascii out",
                args.drive
            )));
        }
        args.ascii
            || (listed.contains(&TransportName::Ascii) && !listed.contains(&TransportName::Rtu))
    };
    let (kind, framing, words) = if ascii {
        (
            drivemap_runtime::core::profile::TransportKind::AsciiOverTcp,
            TcpFraming::AsciiOverTcp,
            "Modbus ASCII frames over TCP",
        )
    } else {
        (
            drivemap_runtime::core::profile::TransportKind::RtuOverTcp,
            TcpFraming::RtuOverTcp,
            "RTU frames over TCP",
        )
    };
    let options = super::simulate::options(&drive, None, &args.set, &[], args.time_scale)?;
    let mut sim = Simulator::new(drive, options).map_err(|e| e.to_string())?;
    // The simulated drive starts at its manual's factory setting, where it ignores network run
    // commands and references: the demo selects the network first, as an installer would.
    let selected = sim.select_network_source(kind);
    let slave = sim.slave();
    let title = format!(
        "{} {}",
        sim.drive().meta().vendor,
        sim.drive().meta().models.join(" / ")
    );
    // The simulator's values of the map's external quantities, told to the client as an
    // application would (a nameplate, a drive setting).
    let externals: Vec<(String, f64)> = sim.externals().clone().into_iter().collect();
    let drive = sim.drive().clone();
    let shared = drivemap_sim::server::shared(sim);
    let server = TcpServer::spawn(shared.clone(), "127.0.0.1:0", framing, None)
        .map_err(|e| format!("cannot start the simulator on loopback: {e}"))?;
    let addr = server.local_addr();
    outln!(
        "drivemap demo: simulated {} ({title}), slave {slave}, {words} {addr}, time x{}",
        args.drive,
        args.time_scale
    );
    for (name, v) in &externals {
        let unit = drive
            .externals()
            .iter()
            .find(|q| q.external == *name)
            .map(|q| q.unit.clone())
            .unwrap_or_default();
        outln!("external quantity {name} = {v} {unit} (supplied by the application)");
    }
    if selected.is_empty() {
        outln!(
            "the map names no source parameter for this link: the drive is taken to accept network commands"
        );
    } else {
        outln!(
            "set at the simulated drive first (its factory setting ignores network commands): {}",
            selected.join(", ")
        );
    }
    let plan = Plan {
        frequency: args.frequency,
        ramp: args.ramp,
        reverse: args.reverse,
        step: Duration::from_secs_f64(args.step),
        time_scale: args.time_scale,
    };
    let result = (|| {
        let link: Box<dyn Transport> = if ascii {
            Box::new(
                AsciiOverTcpTransport::connect(addr, Duration::from_secs(2))
                    .map_err(|e| format!("cannot connect to the simulator at {addr}: {e}"))?,
            )
        } else {
            Box::new(
                RtuOverTcpTransport::connect(addr, Duration::from_secs(2))
                    .map_err(|e| format!("cannot connect to the simulator at {addr}: {e}"))?,
            )
        };
        let profile = drive.plan().profile;
        let mut c = Client::with_options(
            link,
            profile,
            ClientOptions {
                timeout: Duration::from_millis(500),
                ..ClientOptions::for_profile(profile)
            },
        );
        let ext: Vec<(&str, f64)> = externals.iter().map(|(k, v)| (k.as_str(), *v)).collect();
        if let Some(done) = compiled(&args.drive, &mut c, slave, &ext, &plan) {
            return done;
        }
        outln!(
            "{} is not compiled into drivemap-drives: driven through its plan lowered at run time and the VariableFrequencyDrive trait",
            args.drive
        );
        let mut settings = drivemap_live::LiveSettings::default();
        for (k, v) in &externals {
            settings.references.insert(k.clone(), *v);
        }
        for address in drivemap_live::LiveSettings::dependencies(&drive) {
            let mut raw = [0u16];
            c.read_holding(slave, address, &mut raw)
                .map_err(|e| format!("reading settings: {e}"))?;
            settings.absorb(&drive, address, raw[0]);
        }
        let view = settings.view(&drive);
        let p = drive.plan();
        let mut d = Vfd::from_plan(&mut c, slave, view, p.registers, p.roles);
        drive_it(&mut d, &plan)
    })();
    server.stop();
    result?;
    let stats = drivemap_sim::server::lock(&shared).stats();
    outln!();
    outln!(
        "done in {:.1} s: {} requests served, {} exceptions",
        started.elapsed().as_secs_f64(),
        stats.requests,
        stats.exceptions
    );
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {

    use super::*;

    fn args(drive: &str) -> Args {
        Args {
            drive: drive.into(),
            frequency: 30.0,
            ramp: 2.0,
            reverse: false,
            time_scale: 50.0,
            step: 0.5,
            set: Vec::new(),
            draft: false,
            ascii: false,
            dir: MapsDir { maps: None },
        }
    }

    #[test]
    fn the_demo_runs_every_compiled_drive_through_the_trait() {
        for (id, _) in drivemap_drives::DRIVES {
            assert_eq!(run(args(id)).unwrap(), ExitCode::SUCCESS, "{id}");
        }
        let reverse = Args {
            reverse: true,
            ..args("automationdirect-acn")
        };
        assert_eq!(run(reverse).unwrap(), ExitCode::SUCCESS);
    }

    #[test]
    fn what_the_demo_cannot_do_is_said() {
        let e = run(args("no-such-drive")).unwrap_err().to_string();
        assert!(e.contains("no map for drive `no-such-drive`"), "{e}");
        let e = run(Args {
            time_scale: 0.0,
            ..args("ptlk-tds-v8")
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("--time-scale"), "{e}");
    }
}
