// Reading the ENTER command register (write-only in the map) must not compile.
use custom_drive::mini_drive as md;
use drivemap_runtime::{client::Client, core::profile::TransportKind, transport::memory::MemoryTransport};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &md::PROFILE);
    let _ = client.read::<md::Enter>(1, &md::Settings::new());
}
