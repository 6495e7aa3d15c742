// A value of another register's enumeration must not compile.
use custom_drive::mini_drive as md;
use drivemap_runtime::{client::Client, core::profile::TransportKind, transport::memory::MemoryTransport};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &md::PROFILE);
    // P-03 takes its own codes, not those of the command register's mode field.
    let _ = client.write::<md::FrequencyUnits>(1, &md::CommandMode::Remote, &md::Settings::new());
}
