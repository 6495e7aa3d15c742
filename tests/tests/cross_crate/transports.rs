//! Registers that exist on one transport only are refused on the others before anything is
//! sent: the V7's RTU command registers (Table 4.1) and its Modbus TCP option card's own command
//! registers (Table 4.5) share addresses with different layouts (`000_032dced3a1e91a75.txt:851`).

use drivemap_drives::yaskawa_v7 as v7;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Register;
use drivemap_runtime::transport::memory::MemoryTransport;
use drivemap_runtime::{client::Client, error::Error, error::Refusal};

#[test]
fn rtu_command_register_is_refused_over_modbus_tcp() {
    let (link, peer) = MemoryTransport::pair(TransportKind::Tcp);
    let mut client = Client::new(link, &v7::PROFILE);
    let settings = v7::Settings::new();
    let run = v7::DigitalInputCommandBits::new().with_run_command(true);
    let err = client
        .write::<v7::DigitalInputCommand>(1, &run, &settings)
        .unwrap_err();
    assert!(
        matches!(
            err,
            Error::Refused(Refusal::NotOnTransport {
                register: "digital_input_command",
                transport: TransportKind::Tcp
            })
        ),
        "{err}"
    );
    assert_eq!(peer.pending(), 0, "nothing was sent");
    assert!(v7::DigitalInputCommand::on_transport(TransportKind::Rtu));
    assert!(v7::DigitalInputCommand::on_transport(
        TransportKind::RtuOverTcp
    ));
    // Registers without a transport restriction exist everywhere.
    assert!(v7::OutputFrequency::on_transport(TransportKind::Tcp));
}

#[test]
fn option_card_register_is_refused_over_rtu() {
    let (link, peer) = MemoryTransport::pair(TransportKind::Rtu);
    let mut client = Client::new(link, &v7::PROFILE);
    let err = client
        .read::<v7::TcpDigitalInputCommand>(1, &v7::Settings::new())
        .unwrap_err();
    assert!(
        matches!(err, Error::Refused(Refusal::NotOnTransport { .. })),
        "{err}"
    );
    assert_eq!(peer.pending(), 0, "nothing was sent");
    assert!(v7::TcpDigitalInputCommand::on_transport(TransportKind::Tcp));
}
