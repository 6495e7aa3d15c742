// A value of another register's enumeration must not compile.
use drivemap_drives::ptlk_tds_v8 as tds;
use drivemap_runtime::{Client, transport::memory::MemoryTransport, profile::TransportKind};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &tds::PROFILE);
    let settings = tds::Settings::new();
    // Sn-38 parity takes its own codes, not Sn-37's baud rates.
    let _ = client.write::<tds::Parity>(1, &tds::BaudRateValue::Baud9600, &settings);
}
