//! A drive whose manual scales frequencies by a ratio (the fictional Borealis BF6: "60.0 Hz =
//! 3600", one count is 1/60 Hz), generated from its map and driven through the drive trait
//! against its own simulator: a reference that is a whole number of counts is set and read back
//! exactly (also one that is no decimal, 3599/60 Hz), one between two counts is refused before
//! anything is written, and the generated plan holds the ratio.

use drivemap_test_support::paths;

use std::sync::Arc;
use std::time::Duration;

use custom_drive::borealis_bf6 as bf6;
use drivemap_runtime::core::plan::Conversion;
use drivemap_runtime::core::ratio::Ratio;
use drivemap_runtime::core::register::{DrivePlan, Register, Writable};
use drivemap_runtime::core::scale::Decimal;
use drivemap_runtime::core::scale::ValueError;
use drivemap_runtime::transport::rtu_over_tcp::RtuOverTcpTransport;
use drivemap_runtime::vfd::{VariableFrequencyDrive, Vfd};
use drivemap_runtime::{client::Client, error::Error};
use drivemap_sim::{
    SimOptions, Simulator, clock::ManualClock, server::TcpFraming, server::TcpServer,
};

fn map() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(paths::fixture("borealis-bf6/borealis-bf6.yaml").as_ref())
        .unwrap()
}

#[test]
fn the_generated_plan_holds_the_ratio() {
    let plan = bf6::FrequencyReference::PLAN;
    let Conversion::Ratio { ratio, range, .. } = plan.conversion else {
        panic!("{:?}", plan.conversion)
    };
    assert_eq!(ratio, Ratio::new(3600, Decimal::new(60, 0)));
    assert_eq!(bf6::FrequencyReference::RATIO, Some(ratio));
    assert_eq!(bf6::OutputCurrent::RATIO, None);
    assert_eq!((range.base.min, range.base.max), (0, 24000));
    assert_eq!(
        bf6::FrequencyReference::encode(&59.9, &bf6::Settings::default()),
        Ok(3594)
    );
    assert_eq!(
        bf6::OutputFrequency::decode(3599, &bf6::Settings::default()),
        Ok(3599.0 / 60.0)
    );
    assert!(matches!(
        bf6::FrequencyReference::encode(&59.99, &bf6::Settings::default()),
        Err(ValueError::NotACount { .. })
    ));
}

#[test]
fn frequency_set_and_read_back_exactly_through_the_drive_trait() {
    let clock = ManualClock::new();
    let sim = Simulator::new(map(), SimOptions::new().clock(Arc::new(clock.clone()))).unwrap();
    assert!(sim.has_model(), "its map gives roles");
    let slave = sim.slave();
    let server = TcpServer::spawn(
        drivemap_sim::server::shared(sim),
        "127.0.0.1:0",
        TcpFraming::RtuOverTcp,
        None,
    )
    .unwrap();
    let link = RtuOverTcpTransport::connect(server.local_addr(), Duration::from_secs(2)).unwrap();
    let mut client = Client::new(link, <bf6::Drive as DrivePlan>::PROFILE);
    let mut d =
        Vfd::connect::<bf6::Drive>(&mut client, slave, bf6::Settings::default(), &[]).unwrap();
    d.set_ramp(1.0, 1.0).unwrap();
    // Up to the maximum frequency (60 Hz at the factory setting), which the trait checks.
    for hz in [59.9, 3599.0 / 60.0, 1.0 / 60.0, 0.0, 100.0 / 3.0] {
        d.set_reference(hz).unwrap();
        d.run().unwrap();
        clock.advance(Duration::from_secs(60));
        assert_eq!(d.output_frequency().unwrap(), hz, "output at the reference");
    }
    // Between two counts: refused, and the reference written before stands.
    match d.set_reference(59.99) {
        Err(Error::Value(e @ ValueError::NotACount { below, .. })) => {
            assert_eq!(below, 3599);
            assert!(
                e.to_string()
                    .ends_with("the nearest legal values are 3599/60 (≈59.983333) and 60 Hz"),
                "{e}"
            );
        }
        other => panic!("59.99 Hz: {other:?}"),
    }
    clock.advance(Duration::from_secs(60));
    assert_eq!(d.output_frequency().unwrap(), 100.0 / 3.0);
    d.stop().unwrap();
    clock.advance(Duration::from_secs(60));
    assert_eq!(d.output_frequency().unwrap(), 0.0);
    drop(d);
    let read = client.read::<bf6::FrequencyReference>(slave, &bf6::Settings::default());
    assert_eq!(read.unwrap(), 100.0 / 3.0);
}
