//! `drivemap save` on the serial line at its speed: every shipped map's settings saved with the
//! read planner through an emulated 9600-baud line (each character taking its time on the wire)
//! from a simulated drive that keeps the map's response time, against reading the same
//! settings one register per request, as vendor tools and Home Assistant do.
//!
//! Run: `cargo run --release -p drivemap-tests --example save_report [-- --baud B] [--drive ID]...`
//!
//! Prints a Markdown table: per map, the settings, the requests and the time of each way, and
//! the ratio of the times (the figures in the README's "Backing up, comparing and cloning a
//! drive").

use std::time::Instant;

use drivemap_live::LiveSettings;
use drivemap_live::paramset;
use drivemap_live::session::Session;
use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::transport::serial::SerialTransport;
use drivemap_tests::line_bench;

fn main() {
    let mut baud = 9600;
    let mut only: Vec<String> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match (a.as_str(), args.next()) {
            ("--baud", Some(b)) => baud = b.parse().expect("--baud N"),
            ("--drive", Some(d)) => only.push(d),
            _ => {
                eprintln!("usage: save_report [--baud B] [--drive ID]...");
                std::process::exit(2);
            }
        }
    }
    println!(
        "| map | settings | save: requests | save: time | one per request: requests | one per request: time | time ratio |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for m in line_bench::monitors() {
        if !only.is_empty() && !only.contains(&m.id) {
            continue;
        }
        let settings = paramset::settings_of(&m.drive);
        if settings.is_empty() {
            println!("| {} | 0 | 0 | - | 0 | - | - |", m.id);
            continue;
        }
        let line = line_bench::line_for(m.profile, baud);
        let ((planned, single), _) = line_bench::on_realtime_thread(|| {
            let (emulated, _server, slave) =
                line_bench::drive_on_line(&m, line).expect("an emulated line");
            let transport = SerialTransport::open(line_bench::serial_options(
                emulated.master_path(),
                m.profile,
                line,
            ))
            .expect("the line's master side");
            let mut s = Session::over(
                &m.drive,
                Box::new(transport),
                ClientOptions::for_line(m.profile, line),
                slave,
                line,
                LiveSettings::default(),
            );
            let t = Instant::now();
            let report = paramset::save(&mut s, "").expect("save");
            assert!(
                report.set.unread.is_empty(),
                "{}: {:?}",
                m.id,
                report.set.unread
            );
            let planned = (report.requests, t.elapsed());
            let t = Instant::now();
            let mut requests = 0u32;
            for r in &settings {
                requests += 1;
                s.read_raw(*r).expect("one register");
            }
            (planned, (requests, t.elapsed()))
        });
        println!(
            "| {} | {} | {} | {:.2} s | {} | {:.2} s | {:.2} |",
            m.id,
            settings.len(),
            planned.0,
            planned.1.as_secs_f64(),
            single.0,
            single.1.as_secs_f64(),
            planned.1.as_secs_f64() / single.1.as_secs_f64()
        );
    }
}
