// A register read and written with different meanings takes its write form (a word): the value
// a read gives (the read enumeration) must not compile as a write.
use custom_drive::mini_drive as md;
use drivemap_runtime::{client::Client, core::profile::TransportKind, transport::memory::MemoryTransport};

fn main() {
    let (link, _drive) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &md::PROFILE);
    let _ = client.write::<md::Password>(1, &md::PasswordRead::Locked, &md::Settings::new());
}
