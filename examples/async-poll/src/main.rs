//! A tokio application on one drive: connects to a Yaskawa V7 over Modbus TCP, moves the drive
//! (which owns its client) into a task, writes the frequency reference, runs, polls the output
//! frequency and status, stops, and reports the reference the drive holds.
//!
//! ```text
//! async-poll HOST:PORT [SLAVE] [HZ] [POLLS]
//! ```
//!
//! Against the simulator: `drivemap simulate --drive yaskawa-v7 --tcp 127.0.0.1:1502` (with
//! the network selected as the drive's source), then `async-poll 127.0.0.1:1502 1 30 5`.
#![doc = include_str!("../README.md")]

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use drivemap_drives::yaskawa_v7 as v7;
use drivemap_runtime::async_client::{AsyncClient, AsyncTcpTransport};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::vfd::{AsyncVariableFrequencyDrive, AsyncVfd};

const USAGE: &str = "usage: async-poll HOST:PORT [SLAVE] [HZ] [POLLS]";

/// Argument `what` parsed, or `default` when absent.
fn arg<T: std::str::FromStr>(given: Option<String>, default: T, what: &str) -> Result<T, String> {
    match given {
        None => Ok(default),
        Some(s) => s
            .parse()
            .map_err(|_| format!("{what} {s:?} is not a number; {USAGE}")),
    }
}

/// The V7 on an async Modbus TCP connection, owning its client.
type Drive = AsyncVfd<v7::Settings, AsyncClient<AsyncTcpTransport>>;

/// Writes the reference, runs, polls `polls` times, stops; the reference the drive holds.
async fn control(
    mut drive: Drive,
    hz: f64,
    polls: u32,
) -> Result<f64, drivemap_runtime::error::Error> {
    drive.set_reference(hz).await?;
    drive.run().await?;
    let mut every = tokio::time::interval(Duration::from_millis(100));
    for poll in 1..=polls {
        every.tick().await;
        let output = drive.output_frequency().await?;
        let status = drive.status().await?;
        println!("poll {poll}: output {output:.2} Hz, status {status}");
    }
    drive.stop().await?;
    drive.reference().await
}

#[tokio::main(flavor = "current_thread")]
async fn main() -> ExitCode {
    match run().await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("async-poll: {e}");
            ExitCode::FAILURE
        }
    }
}

async fn run() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let addr = args.next().ok_or(USAGE)?;
    let slave: u8 = arg(args.next(), 1, "SLAVE")?;
    let hz: f64 = arg(args.next(), 30.0, "HZ")?;
    let polls: u32 = arg(args.next(), 5, "POLLS")?;

    // An io::Error and the drive's errors both go through `?`.
    let link =
        AsyncTcpTransport::connect(&addr, TransportKind::Tcp, Duration::from_secs(1)).await?;
    let client = AsyncClient::new(link, &v7::PROFILE);
    // Reads the parameters the V7's conversions depend on.
    let drive = AsyncVfd::connect::<v7::Drive>(client, slave, v7::Settings::default(), &[]).await?;

    // The drive owns its client: it moves into a task of its own.
    let task = tokio::spawn(control(drive, hz, polls));
    let reference = task.await??;
    println!("stopped; reference {reference} Hz");
    Ok(())
}
