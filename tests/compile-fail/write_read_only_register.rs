// Writing a monitor register (read-only in the manual) must not compile.
use drivemap_drives::ptlk_tds_v8 as tds;
use drivemap_runtime::{Client, transport::memory::MemoryTransport, profile::TransportKind};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &tds::PROFILE);
    let settings = tds::Settings::new();
    let _ = client.write::<tds::OutputFrequency>(1, &50.0, &settings);
}
