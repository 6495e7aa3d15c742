//! Behaviour of every construct the generator emits, through the fixture map.

use custom_drive::mini_drive as md;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::{
    Bits, Code, DriveSettings, Enumeration, Register, Writable,
};
use drivemap_runtime::core::scale::ValueError;

#[test]
fn bit_fields_keep_reserved_bits_zero() {
    let v = md::CommandBits::from_bits(0xFFFF);
    assert_eq!(v.bits(), md::CommandBits::MASK);
    assert!(v.run() && v.reverse());
    let mut c = md::CommandBits::new().with_run(true);
    assert_eq!(c.raw(), 0x0001);
    c.set_mode(md::CommandMode::Remote).unwrap();
    assert_eq!(c.raw(), 0x0021);
    assert_eq!(c.mode(), md::CommandMode::Remote);
    assert!(
        c.set_mode(md::CommandMode::Unknown(1)).is_err(),
        "unknown codes are refused"
    );
    assert_eq!(
        md::CommandBits::from_bits(0x0010).mode(),
        md::CommandMode::Unknown(1)
    );
}

#[test]
fn every_field_has_a_builder_and_read_only_values_have_none() {
    // Multi-bit fields build like one-bit fields; a value wider than the field is refused.
    let c = md::CommandBits::new()
        .with_run(true)
        .with_mode(md::CommandMode::Remote)
        .and_then(|c| c.with_step(5))
        .unwrap();
    assert_eq!(c.raw(), 0x0521);
    assert_eq!(c.step(), 5);
    assert!(matches!(
        md::CommandBits::new().with_step(8),
        Err(ValueError::OutOfRange { max, .. }) if max == 7.0
    ));
    // A read-only register's value is read, never built: getters only
    // (compile-fail/set_read_only_bits.rs shows that a setter does not exist).
    let status = md::StatusBits::from_bits(0xA001);
    assert!(status.running());
    assert_eq!(status.error_code(), 0xA);
}

#[test]
fn enumerations_fall_back_to_unknown_and_refuse_it_on_write() {
    let s = md::Settings::new();
    assert_eq!(
        md::FrequencyUnits::decode(2, &s),
        Ok(md::FrequencyUnitsValue::PercentOfMax)
    );
    assert_eq!(
        md::FrequencyUnits::decode(9, &s),
        Ok(md::FrequencyUnitsValue::Unknown(9))
    );
    assert!(matches!(
        md::FrequencyUnits::encode(&md::FrequencyUnitsValue::Unknown(9), &s),
        Err(ValueError::UnknownCode { code: 9, .. })
    ));
    assert_eq!(md::FrequencyUnitsValue::HundredthHz.to_string(), "0.01 Hz");
}

#[test]
fn scale_follows_the_selector() {
    let mut s = md::Settings::new();
    assert!(matches!(
        md::FrequencyReference::encode(&50.0, &s),
        Err(ValueError::MissingSetting {
            setting: "P-03",
            ..
        })
    ));
    s.frequency_units = Some(md::FrequencyUnitsValue::TenthHz);
    assert_eq!(md::FrequencyReference::encode(&50.0, &s), Ok(500));
    s.frequency_units = Some(md::FrequencyUnitsValue::HundredthHz);
    assert_eq!(md::FrequencyReference::encode(&50.0, &s), Ok(5000));
    assert!(matches!(
        md::FrequencyReference::encode(&400.01, &s),
        Err(ValueError::OutOfRange { .. })
    ));
    s.frequency_units = Some(md::FrequencyUnitsValue::PercentOfMax);
    assert!(matches!(
        md::FrequencyReference::encode(&30.0, &s),
        Err(ValueError::MissingSetting {
            setting: "P-01",
            ..
        })
    ));
    s.max_frequency = Some(60.0);
    assert_eq!(md::FrequencyReference::encode(&30.0, &s), Ok(15000));
    assert_eq!(md::FrequencyReference::decode(15000, &s), Ok(30.0));
    s.frequency_units = Some(md::FrequencyUnitsValue::Unknown(7));
    assert!(matches!(
        md::FrequencyReference::decode(1, &s),
        Err(ValueError::UnsupportedSetting { code: 7, .. })
    ));
}

#[test]
fn ranges_follow_the_variant() {
    let mut s = md::Settings::new();
    assert_eq!(md::MaxVoltage::encode(&255.0, &s), Ok(2550));
    assert!(md::MaxVoltage::encode(&300.0, &s).is_err());
    s.voltage_class = md::VoltageClass::V400;
    assert_eq!(md::MaxVoltage::encode(&300.0, &s), Ok(3000));
    assert!(md::MaxVoltage::encode(&510.1, &s).is_err());
}

#[test]
fn settings_absorb_their_dependencies() {
    let mut s = md::Settings::new();
    assert_eq!(md::Settings::DEPENDENCIES, &[0x0102, 0x0100]);
    assert!(s.absorb(0x0100, 600));
    assert!(s.absorb(0x0102, 1));
    assert!(!s.absorb(0x0020, 5));
    assert_eq!(s.max_frequency, Some(60.0));
    assert_eq!(
        s.frequency_units,
        Some(md::FrequencyUnitsValue::HundredthHz)
    );
}

#[test]
fn addresses_move_with_the_transport_and_blocks_expand() {
    let s = md::Settings::new();
    assert_eq!(
        md::FrequencyReference::address(&s, TransportKind::Rtu).unwrap(),
        0x0002
    );
    assert_eq!(
        md::FrequencyReference::address(&s, TransportKind::Tcp).unwrap(),
        0x0102
    );
    assert_eq!(<md::Preset3 as Register>::ADDRESS, 0x0105);
    assert_eq!(<md::Preset3 as Register>::PARAM, Some("P-06"));
    assert_eq!(<md::Preset3 as Register>::SOURCE, "manual.txt:45");
}

#[test]
fn relative_to_an_external_quantity_and_signed_words() {
    let mut s = md::Settings::new();
    assert!(md::OutputCurrent::decode(8192, &s).is_err());
    s.rated_current = Some(12.5);
    assert_eq!(md::OutputCurrent::decode(8192, &s), Ok(12.5));
    assert_eq!(md::Torque::decode(0xFFF6, &s), Ok(-10.0));
    assert_eq!(md::FaultCount::decode(7, &s), Ok(7u16));
}

#[test]
fn profile_and_register_table() {
    assert_eq!(md::PROFILE.max_read, 8);
    assert_eq!(md::PROFILE.command("enter").unwrap().writes, &[(0x0900, 0)]);
    assert_eq!(md::PROFILE.address_offsets.rtu, -1);
    let addrs: Vec<u16> = md::REGISTERS
        .iter()
        .filter(|r| !r.broadcast_only)
        .map(|r| r.address)
        .collect();
    let mut sorted = addrs.clone();
    sorted.sort_unstable();
    assert_eq!(addrs, sorted);
    assert_eq!(md::REGISTERS.len(), 17);
    assert_eq!(
        <md::MaxFrequency as Writable>::WRITE_RESTRICTION,
        drivemap_runtime::core::register::WriteRestriction::Stopped
    );
    assert_eq!(md::FrequencyUnitsValue::ALL.len(), 3);
    let _ = md::FrequencyUnitsValue::TenthHz.code();
}

/// `read_values`: a read decodes to the read enumeration, a write takes the word; the group's
/// `repeat_needs_change` reaches both of its registers (`tests/tests/cross_crate/automationdirect_acn.rs`
/// shows `Client::write` sending the intermediate value first).
#[test]
fn read_meanings_and_repeated_values() {
    use drivemap_runtime::core::plan::RepeatNeedsChange;
    use drivemap_runtime::core::register::Readable;
    fn readable<R: Readable>() {}
    readable::<md::Password>();
    let s = md::Settings::new();
    assert_eq!(md::Password::decode(1, &s), Ok(md::PasswordRead::Locked));
    assert_eq!(
        md::Password::decode(7, &s),
        Ok(md::PasswordRead::Unknown(7))
    );
    assert_eq!(md::PasswordRead::Unlocked.name(), Some("Unlocked"));
    assert_eq!(md::Password::encode(&1234u16, &s), Ok(1234));
    assert!(
        md::Password::encode(&10000u16, &s).is_err(),
        "the write range is 0-9999"
    );
    let rule = Some(RepeatNeedsChange {
        between: 0,
        source: "manual.txt:50",
    });
    assert_eq!(<md::Password as Writable>::REPEAT_NEEDS_CHANGE, rule);
    assert_eq!(<md::ClearHistory as Writable>::REPEAT_NEEDS_CHANGE, rule);
    assert_eq!(<md::MaxFrequency as Writable>::REPEAT_NEEDS_CHANGE, None);
}
