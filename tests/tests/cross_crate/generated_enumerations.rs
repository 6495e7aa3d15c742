//! Generated enumerations are equal by code, as the drive sees them: `Unknown(c)` (a code
//! made by a caller or read raw) equals the listed variant whose code is `c`, and hashes the
//! same, so a value compares the same however it was made.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

use drivemap_drives::runtime::core::register::{Code, Enumeration};
use drivemap_drives::{ptlk_tds_v8 as v8, yaskawa_v7 as v7};

fn hash<T: Hash>(v: &T) -> u64 {
    let mut h = DefaultHasher::new();
    v.hash(&mut h);
    h.finish()
}

/// Every code of the word: `Unknown(code)` equals `from_code(code)` (a listed variant where
/// the manual lists the code), with the same hash; values of different codes differ.
fn equal_by_code<T: Enumeration + Code + Hash + Eq + std::fmt::Debug>() {
    for code in 0..=u16::MAX {
        let made = T::unknown(code);
        let read = T::from_code(code);
        assert_eq!(made, read, "code {code}");
        assert_eq!(hash(&made), hash(&read), "code {code}");
        assert_eq!(made.code(), code);
    }
    for pair in T::ALL.windows(2) {
        assert_ne!(pair[0], pair[1]);
    }
}

#[test]
fn unknown_0_is_the_variant_whose_code_is_0() {
    type Unit = v7::ModbusFrequencyReferenceUnitSelectionValue;
    assert_eq!(Unit::Unknown(0), Unit::Unit01Hz);
    assert_eq!(Unit::Unknown(3), Unit::Unit01Percent);
    assert_ne!(Unit::Unknown(4), Unit::Unit01Hz);
    // The label is still the listed variant's.
    assert_eq!(Unit::Unit01Hz.to_string(), "1 = 0.1Hz");
    assert_eq!(Unit::Unknown(9).to_string(), "unknown code 9");
}

#[test]
fn every_code_compares_and_hashes_by_code() {
    equal_by_code::<v7::ModbusFrequencyReferenceUnitSelectionValue>();
    equal_by_code::<v7::AccelDecelTimeUnitSelectionValue>();
    equal_by_code::<v8::RunSourceValue>();
}
