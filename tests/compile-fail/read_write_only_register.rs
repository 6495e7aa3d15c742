// Reading the EEPROM save register (write-only) must not compile.
use drivemap_drives::ptlk_tds_v8 as tds;
use drivemap_runtime::{Client, transport::memory::MemoryTransport, profile::TransportKind};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &tds::PROFILE);
    let _ = client.read::<tds::SaveParameters>(1, &tds::Settings::new());
}
