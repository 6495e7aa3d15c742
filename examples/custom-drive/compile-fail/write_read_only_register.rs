// Writing a monitor register (read-only in the map) must not compile.
use custom_drive::mini_drive as md;
use drivemap_runtime::{client::Client, core::profile::TransportKind, transport::memory::MemoryTransport};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &md::PROFILE);
    let _ = client.write::<md::Torque>(1, &50.0, &md::Settings::new());
}
