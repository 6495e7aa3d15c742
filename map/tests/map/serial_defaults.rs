//! The map's serial defaults as the command line's link and the simulator read them
//! (`Drive::serial_defaults`), without the serde model.

use drivemap_test_support::paths;

use std::path::PathBuf;

use drivemap_map::facts::{Parity, SerialDefaults};

fn defaults(map: PathBuf) -> SerialDefaults {
    let ctx = drivemap_map::Loader::new();
    ctx.load(&map)
        .unwrap_or_else(|d| panic!("{d}"))
        .serial_defaults()
}

#[test]
fn tds_v8_fixes_eleven_bit_characters_so_no_parity_means_two_stop_bits() {
    let d = defaults(paths::shipped_map("ptlk-tds-v8"));
    assert_eq!(
        d,
        SerialDefaults {
            baud: 9600,
            parity: Parity::None,
            char_bits: Some(11),
            format_stop_bits: [None; 3],
        }
    );
    assert_eq!(d.stop_bits(false), 2);
    assert_eq!(d.stop_bits(true), 1);
}

#[test]
fn v7_defaults_come_from_the_map_with_one_stop_bit() {
    let d = defaults(paths::shipped_map("yaskawa-v7"));
    assert_eq!((d.baud, d.parity, d.char_bits), (9600, Parity::None, None));
    assert_eq!(d.stop_bits(false), 1);
}

/// The ACN lists the formats CM.04 selects (8N1, 8N2, 8E1, 8O1): even and odd parity go with
/// 1 stop bit only; no parity has two formats, so the usual 1 stays the default.
#[test]
fn acn_formats_give_the_stop_bits_of_a_parity() {
    let d = defaults(paths::shipped_map("automationdirect-acn"));
    assert_eq!(d.format_stop_bits, [None, Some(1), Some(1)]);
    assert_eq!(d.stop_bits_for(Parity::Even), 1);
    assert_eq!(d.stop_bits_for(Parity::None), 1);
}
