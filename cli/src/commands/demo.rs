//! `drivemap demo`: a simulated drive on loopback, driven through the generated typed API.
//!
//! Starts a `drivemap-sim` simulator of the chosen drive (TDS-V8 by default) in this process,
//! serving RTU frames over loopback TCP as a serial gateway would, then uses the generated
//! module of `drivemap-drives` exactly as an application does: reads the settings the scales
//! depend on, writes accel/decel times and the frequency reference, sets the run bit, reads the
//! status bits by name and the monitors while the output ramps, stops, and prints the ramp down.
//! Simulated time runs `--time-scale` times faster than real time.

use std::process::ExitCode;
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use clap::Args as ClapArgs;
use drivemap_drives::{
    automationdirect_acn as acn, ptlk_tds_v8 as tds, yaskawa_gpd515 as gpd, yaskawa_j7 as j7,
    yaskawa_v7 as v7,
};
use drivemap_runtime::transport::Transport;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::{Client, ClientOptions, DriveSettings, Error, Profile};
use drivemap_sim::{SimOptions, Simulator, SystemClock, TcpFraming, TcpServer};

use crate::maps::MapsDir;

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Drive to simulate: ptlk-tds-v8, yaskawa-v7, yaskawa-j7, yaskawa-gpd515, automationdirect-acn.
    #[arg(long, default_value = "ptlk-tds-v8")]
    pub drive: String,
    /// Frequency reference to run at (Hz, 0 to 1000).
    #[arg(long, default_value_t = 48.0, value_parser = crate::duration::number(0.0, 1000.0))]
    pub frequency: f64,
    /// Accel and decel time written before running (s, 0 to 6000), where the map has the registers.
    #[arg(long, default_value_t = 4.0, value_parser = crate::duration::number(0.0, 6000.0))]
    pub ramp: f64,
    /// Run in reverse.
    #[arg(long)]
    pub reverse: bool,
    /// Simulated time runs this many times faster than real time (0.1 to 1000).
    #[arg(long = "time-scale", default_value_t = 4.0, value_parser = crate::duration::number(0.1, 1000.0))]
    pub time_scale: f64,
    /// Simulated seconds between rows of the table (0.01 to 5).
    #[arg(long, default_value_t = 0.5, value_parser = crate::duration::number(0.01, 5.0))]
    pub step: f64,
    #[command(flatten)]
    pub dir: MapsDir,
}

/// One row of the table.
struct Sample {
    status: String,
    reference: f64,
    output: f64,
    current: f64,
    voltage: f64,
}

/// What the demo does with one drive, through its generated module.
trait DemoDrive {
    type Settings: DriveSettings + Default;
    /// Whether the map has a way to command reverse.
    const REVERSE: bool = true;
    fn profile() -> &'static Profile;
    /// Settings the application supplies (external quantities); the rest is read from the drive.
    fn settings(externals: &[(String, f64)]) -> Self::Settings {
        let _ = externals;
        Self::Settings::default()
    }
    /// Writes accel/decel times; returns what was written, for the header.
    fn prepare<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &Self::Settings,
        ramp: f64,
    ) -> Result<String, Error>;
    fn reference<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &Self::Settings,
        hz: f64,
    ) -> Result<(), Error>;
    fn run<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &Self::Settings,
        run: bool,
        reverse: bool,
    ) -> Result<(), String>;
    fn sample<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &Self::Settings,
    ) -> Result<Sample, Error>;
}

fn names(bits: &[(&str, bool)]) -> String {
    let on: Vec<&str> = bits.iter().filter(|(_, b)| *b).map(|(n, _)| *n).collect();
    if on.is_empty() {
        "-".into()
    } else {
        on.join(" ")
    }
}

struct Tds;

impl DemoDrive for Tds {
    type Settings = tds::Settings;
    fn profile() -> &'static Profile {
        &tds::PROFILE
    }
    fn prepare<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &tds::Settings,
        ramp: f64,
    ) -> Result<String, Error> {
        c.write::<tds::AccelTime1>(slave, &ramp, s)?;
        c.write::<tds::DecelTime1>(slave, &ramp, s)?;
        Ok(format!(
            "Bn-01 accel time {ramp:.1} s, Bn-02 decel time {ramp:.1} s"
        ))
    }
    fn reference<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &tds::Settings,
        hz: f64,
    ) -> Result<(), Error> {
        c.write::<tds::FrequencyCommand>(slave, &hz, s)
    }
    fn run<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &tds::Settings,
        run: bool,
        reverse: bool,
    ) -> Result<(), String> {
        let bits = tds::OperationCommandBits::new()
            .with_run(run)
            .with_reverse(reverse);
        c.write::<tds::OperationCommand>(slave, &bits, s)
            .map_err(|e| e.to_string())
    }
    fn sample<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &tds::Settings,
    ) -> Result<Sample, Error> {
        let st = c.read::<tds::InverterStatus>(slave, s)?;
        let (reference, output, voltage, current) = c.read_many::<(
            tds::FrequencyCommandMonitor,
            tds::OutputFrequency,
            tds::OutputVoltage,
            tds::OutputCurrent,
        )>(slave, s)?;
        Ok(Sample {
            status: names(&[
                ("running", st.running()),
                ("zero_speed", st.zero_speed()),
                ("reverse", st.reverse()),
                ("drv_mode", st.drv_mode()),
                ("alarm", st.alarm()),
                ("fault", st.fault()),
            ]),
            reference,
            output,
            current,
            voltage,
        })
    }
}

/// Frequency reference, run command and status of the V7 family: the J7 map inherits the V7's
/// register ids, so the same code drives both through their own generated modules.
macro_rules! v7_family_io {
    ($m:ident) => {
        fn reference<T: Transport>(
            c: &mut Client<T>,
            slave: u8,
            s: &$m::Settings,
            hz: f64,
        ) -> Result<(), Error> {
            c.write::<$m::FrequencyReference>(slave, &hz, s)
        }
        fn run<T: Transport>(
            c: &mut Client<T>,
            slave: u8,
            s: &$m::Settings,
            run: bool,
            reverse: bool,
        ) -> Result<(), String> {
            let bits = $m::DigitalInputCommandBits::new()
                .with_run_command(run)
                .with_reverse(reverse);
            c.write::<$m::DigitalInputCommand>(slave, &bits, s)
                .map_err(|e| e.to_string())
        }
        fn sample<T: Transport>(
            c: &mut Client<T>,
            slave: u8,
            s: &$m::Settings,
        ) -> Result<Sample, Error> {
            let st = c.read::<$m::StatusSignal1>(slave, s)?;
            let (reference, output) =
                c.read_many::<($m::FrequencyReferenceMonitor, $m::OutputFrequency)>(slave, s)?;
            let (current, voltage) =
                c.read_many::<($m::OutputCurrent, $m::OutputVoltage)>(slave, s)?;
            Ok(Sample {
                status: names(&[
                    ("during_run", st.during_run()),
                    ("reverse_direction", st.reverse_direction()),
                    ("inverter_ready", st.inverter_ready()),
                    ("fault", st.fault()),
                ]),
                reference,
                output,
                current,
                voltage,
            })
        }
    };
}

struct V7;

impl DemoDrive for V7 {
    type Settings = v7::Settings;
    fn profile() -> &'static Profile {
        &v7::PROFILE
    }
    fn prepare<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &v7::Settings,
        ramp: f64,
    ) -> Result<String, Error> {
        c.write::<v7::AccelTime1>(slave, &ramp, s)?;
        c.write::<v7::DecelTime1>(slave, &ramp, s)?;
        // Written parameters take effect after ACCEPT (RAM only; ENTER would wear the EEPROM).
        c.persist(slave, "accept")?;
        Ok(format!(
            "n019 accel time {ramp:.1} s, n020 decel time {ramp:.1} s, ACCEPT"
        ))
    }
    v7_family_io!(v7);
}

struct J7;

impl DemoDrive for J7 {
    type Settings = j7::Settings;
    fn profile() -> &'static Profile {
        &j7::PROFILE
    }
    fn settings(externals: &[(String, f64)]) -> j7::Settings {
        j7::Settings {
            max_output_frequency: externals
                .iter()
                .find(|(k, _)| k == "max_output_frequency")
                .map(|(_, v)| *v),
            ..j7::Settings::default()
        }
    }
    fn prepare<T: Transport>(
        _: &mut Client<T>,
        _: u8,
        _: &j7::Settings,
        _: f64,
    ) -> Result<String, Error> {
        Ok("the J7's accel/decel times have no register in the sources: the simulator ramps 10 s to max frequency".into())
    }
    v7_family_io!(j7);
}

struct Gpd;

impl DemoDrive for Gpd {
    type Settings = gpd::Settings;
    const REVERSE: bool = false;
    fn profile() -> &'static Profile {
        &gpd::PROFILE
    }
    fn settings(externals: &[(String, f64)]) -> gpd::Settings {
        gpd::Settings {
            drive_rated_current: externals
                .iter()
                .find(|(k, _)| k == "drive_rated_current")
                .map(|(_, v)| *v),
            ..gpd::Settings::default()
        }
    }
    fn prepare<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &gpd::Settings,
        ramp: f64,
    ) -> Result<String, Error> {
        c.write::<gpd::AccelTime1>(slave, &ramp, s)?;
        c.write::<gpd::DecelTime1>(slave, &ramp, s)?;
        c.persist(slave, "accept")?;
        Ok(format!(
            "C1-01 accel time {ramp:.1} s, C1-02 decel time {ramp:.1} s, ACCEPT"
        ))
    }
    fn reference<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &gpd::Settings,
        hz: f64,
    ) -> Result<(), Error> {
        c.write::<gpd::FrequencyReference>(slave, &hz, s)
    }
    fn run<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &gpd::Settings,
        run: bool,
        reverse: bool,
    ) -> Result<(), String> {
        if reverse {
            return Err("the GPD 515 map knows only the forward run bit".into());
        }
        let bits = gpd::OperationCommandBits::new().with_forward_run(run);
        c.write::<gpd::OperationCommand>(slave, &bits, s)
            .map_err(|e| e.to_string())
    }
    fn sample<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &gpd::Settings,
    ) -> Result<Sample, Error> {
        let st = c.read::<gpd::StatusSignal>(slave, s)?;
        let (reference, output, current) = c.read_many::<(
            gpd::MonitorFrequencyReference,
            gpd::OutputFrequency,
            gpd::OutputCurrent,
        )>(slave, s)?;
        let voltage = c.read::<gpd::OutputVoltage>(slave, s)?;
        Ok(Sample {
            status: names(&[
                ("run_command", st.run_command()),
                ("at_zero_speed", st.at_zero_speed()),
                ("reverse_operation", st.reverse_operation()),
                ("speed_agreed", st.speed_agreed()),
                ("drive_ready", st.drive_ready()),
                ("major_fault", st.major_fault()),
            ]),
            reference,
            output,
            current,
            voltage,
        })
    }
}

struct Acn;

impl DemoDrive for Acn {
    type Settings = acn::Settings;
    fn profile() -> &'static Profile {
        &acn::PROFILE
    }
    fn prepare<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &acn::Settings,
        ramp: f64,
    ) -> Result<String, Error> {
        c.write::<acn::AccelerationTime>(slave, &ramp, s)?;
        c.write::<acn::DecelerationTime>(slave, &ramp, s)?;
        Ok(format!(
            "0h0383 acceleration time {ramp:.1} s, 0h0384 deceleration time {ramp:.1} s"
        ))
    }
    fn reference<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &acn::Settings,
        hz: f64,
    ) -> Result<(), Error> {
        c.write::<acn::FrequencyCommand>(slave, &hz, s)
    }
    fn run<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &acn::Settings,
        run: bool,
        reverse: bool,
    ) -> Result<(), String> {
        let bits = acn::OperationCommandBits::new()
            .with_run(run)
            .with_forward(!reverse);
        c.write::<acn::OperationCommand>(slave, &bits, s)
            .map_err(|e| e.to_string())
    }
    fn sample<T: Transport>(
        c: &mut Client<T>,
        slave: u8,
        s: &acn::Settings,
    ) -> Result<Sample, Error> {
        use acn::DriveOperationStateOperationState as Op;
        use acn::DriveOperationStateRunDirectionState as Dir;
        let st = c.read::<acn::DriveOperationState>(slave, s)?;
        let direction = match st.run_direction_state() {
            Dir::Stopped => "stopped".to_string(),
            Dir::OperatingForward => "forward".into(),
            Dir::OperatingReverse => "reverse".into(),
            Dir::DcOperating => "dc_operating".into(),
            other => format!("direction={}", drivemap_runtime::Code::code(&other)),
        };
        let operation = match st.operation_state() {
            Op::Accelerating => "accelerating".to_string(),
            Op::ConstantRate => "constant_rate".into(),
            Op::Decelerating => "decelerating".into(),
            Op::DeceleratingToStop => "decelerating_to_stop".into(),
            Op::Unknown(0) => String::new(),
            other => format!("{other}"),
        };
        let (current, output) =
            c.read_many::<(acn::OutputCurrent, acn::OutputFrequency)>(slave, s)?;
        let voltage = c.read::<acn::OutputVoltage>(slave, s)?;
        let reference = c.read::<acn::FrequencyCommand>(slave, s)?;
        Ok(Sample {
            status: format!("{direction} {operation}").trim().to_string(),
            reference,
            output,
            current,
            voltage,
        })
    }
}

struct Plan {
    frequency: f64,
    ramp: f64,
    reverse: bool,
    step: Duration,
    time_scale: f64,
}

fn row(t: f64, s: &Sample) {
    outln!(
        "{t:>7.1} s  {:<38} {:>7.2} {:>7.2} {:>9.1} {:>9.1}",
        s.status,
        s.reference,
        s.output,
        s.current,
        s.voltage
    );
}

/// The demo proper, through drive `D`'s generated module.
fn drive_it<D: DemoDrive>(
    addr: std::net::SocketAddr,
    slave: u8,
    externals: &[(String, f64)],
    plan: &Plan,
) -> Result<(), String> {
    if plan.reverse && !D::REVERSE {
        return Err(
            "the GPD 515 map knows only the forward run bit of its command register; run without --reverse".into(),
        );
    }
    let link = RtuOverTcpTransport::connect(addr, Duration::from_secs(2))
        .map_err(|e| format!("cannot connect to the simulator at {addr}: {e}"))?;
    let mut c = Client::with_options(
        link,
        D::profile(),
        ClientOptions {
            timeout: Duration::from_millis(500),
            ..ClientOptions::default()
        },
    );
    let fail = |what: &str, e: Error| format!("{what}: {e}");
    let mut s = D::settings(externals);
    c.load_settings(slave, &mut s)
        .map_err(|e| fail("reading settings", e))?;
    let prepared =
        D::prepare(&mut c, slave, &s, plan.ramp).map_err(|e| fail("writing ramp times", e))?;
    D::reference(&mut c, slave, &s, plan.frequency)
        .map_err(|e| fail("writing the frequency reference", e))?;
    outln!("written: {prepared}");
    outln!(
        "written: frequency reference {:.2} Hz, then run {}",
        plan.frequency,
        if plan.reverse { "reverse" } else { "forward" }
    );
    outln!();
    outln!(
        "{:>9}  {:<38} {:>7} {:>7} {:>9} {:>9}",
        "time",
        "status bits",
        "ref Hz",
        "out Hz",
        "current A",
        "voltage V"
    );
    let start = Instant::now();
    let sim_time = || start.elapsed().as_secs_f64() * plan.time_scale;
    let pause = Duration::from_secs_f64(plan.step.as_secs_f64() / plan.time_scale);
    let deadline = start + Duration::from_secs(45);
    D::run(&mut c, slave, &s, true, plan.reverse).map_err(|e| format!("run: {e}"))?;
    // Up the ramp, then two rows at the reference.
    let mut steady = 0;
    while steady < 3 {
        let x = D::sample(&mut c, slave, &s).map_err(|e| fail("reading status", e))?;
        row(sim_time(), &x);
        if (x.output - x.reference).abs() < 0.05 {
            steady += 1;
        }
        if Instant::now() > deadline {
            return Err("the output did not reach the reference within 45 s".into());
        }
        thread::sleep(pause);
    }
    D::run(&mut c, slave, &s, false, plan.reverse).map_err(|e| format!("stop: {e}"))?;
    outln!("{:>9}  stop", "");
    loop {
        let x = D::sample(&mut c, slave, &s).map_err(|e| fail("reading status", e))?;
        row(sim_time(), &x);
        if x.output == 0.0 {
            break;
        }
        if Instant::now() > deadline {
            return Err("the output did not reach 0 Hz within 45 s".into());
        }
        thread::sleep(pause);
    }
    Ok(())
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    if !(args.time_scale.is_finite() && args.time_scale > 0.0) {
        return Err("--time-scale: give a positive number".into());
    }
    if !(args.step.is_finite() && args.step > 0.0) {
        return Err("--step: give a positive number of seconds".into());
    }
    let started = Instant::now();
    let drive = super::simulate::load_drive(&args.dir, &args.drive)?;
    let clock = Arc::new(SystemClock::scaled(args.time_scale));
    let sim = Simulator::new(drive, SimOptions::new().clock(clock)).map_err(|e| e.to_string())?;
    if !sim.has_model() {
        return Err(format!(
            "{} has no drive model in the simulator's roles table; choose one of: {}",
            args.drive,
            drivemap_sim::roles::builtin_drives().join(", ")
        ));
    }
    let slave = sim.slave();
    let title = format!(
        "{} {}",
        sim.drive().meta.vendor,
        sim.drive().meta.models.join(" / ")
    );
    let externals: Vec<(String, f64)> = drivemap_sim::roles::builtin(&args.drive)
        .ok()
        .flatten()
        .map(|r| r.externals.into_iter().collect())
        .unwrap_or_default();
    let shared = drivemap_sim::shared(sim);
    let server = TcpServer::spawn(shared.clone(), "127.0.0.1:0", TcpFraming::RtuOverTcp, None)
        .map_err(|e| format!("cannot start the simulator on loopback: {e}"))?;
    let addr = server.local_addr();
    outln!(
        "drivemap demo: simulated {} ({title}), slave {slave}, RTU frames over TCP {addr}, time x{}",
        args.drive,
        args.time_scale
    );
    outln!(
        "driven through drivemap_drives::{} (the generated typed API)",
        drivemap_codegen::ir::module_name(&args.drive)
    );
    let plan = Plan {
        frequency: args.frequency,
        ramp: args.ramp,
        reverse: args.reverse,
        step: Duration::from_secs_f64(args.step),
        time_scale: args.time_scale,
    };
    let result = match args.drive.as_str() {
        "ptlk-tds-v8" => drive_it::<Tds>(addr, slave, &externals, &plan),
        "yaskawa-v7" => drive_it::<V7>(addr, slave, &externals, &plan),
        "yaskawa-j7" => drive_it::<J7>(addr, slave, &externals, &plan),
        "yaskawa-gpd515" => drive_it::<Gpd>(addr, slave, &externals, &plan),
        "automationdirect-acn" => drive_it::<Acn>(addr, slave, &externals, &plan),
        other => Err(format!(
            "the demo has no typed-API script for {other}; choose one of: ptlk-tds-v8, yaskawa-v7, yaskawa-j7, yaskawa-gpd515, automationdirect-acn"
        )),
    };
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
            dir: MapsDir { maps: None },
        }
    }

    #[test]
    fn the_demo_runs_every_drive_through_its_generated_module() {
        for id in [
            "ptlk-tds-v8",
            "yaskawa-v7",
            "yaskawa-j7",
            "yaskawa-gpd515",
            "automationdirect-acn",
        ] {
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
        let e = run(Args {
            reverse: true,
            ..args("yaskawa-gpd515")
        })
        .unwrap_err();
        assert!(e.contains("forward run bit"), "{e}");
        let e = run(args("no-such-drive")).unwrap_err();
        assert!(e.contains("no map for drive `no-such-drive`"), "{e}");
        let e = run(Args {
            time_scale: 0.0,
            ..args("ptlk-tds-v8")
        })
        .unwrap_err();
        assert!(e.contains("--time-scale"), "{e}");
    }
}
