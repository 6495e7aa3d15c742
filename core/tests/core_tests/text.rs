//! Text in registers (`drivemap_core::text`): any words decode without panic, padding is
//! dropped, printable ASCII round-trips in both byte orders, and what is shown is escaped.

use drivemap_core::text::{self, ByteOrder, Text, TextError};
use proptest::prelude::*;

fn order() -> impl Strategy<Value = ByteOrder> {
    prop_oneof![Just(ByteOrder::HighFirst), Just(ByteOrder::LowFirst)]
}

#[test]
fn the_orders_put_the_first_character_where_the_manual_says() {
    let words = [0x5132, 0x2D30, 0x3430, 0x3000, 0x0000];
    let t = Text::<10>::decode(&words, ByteOrder::HighFirst);
    assert_eq!(t.as_str(), Some("Q2-0400"));
    let swapped: Vec<u16> = words.iter().map(|w| w.swap_bytes()).collect();
    assert_eq!(
        Text::<10>::decode(&swapped, ByteOrder::LowFirst).as_str(),
        Some("Q2-0400")
    );
    // Read in the wrong order it is another text, not an error.
    assert_eq!(
        Text::<10>::decode(&words, ByteOrder::LowFirst).to_string(),
        "2Q0-04\\x000"
    );
}

#[test]
fn trailing_spaces_and_nuls_are_padding_inner_ones_are_text() {
    let mut words = [0; 4];
    text::encode(b"A B", ByteOrder::HighFirst, &mut words).unwrap();
    assert_eq!(words, [0x4120, 0x4200, 0, 0]);
    let spaces = [0x4120, 0x4220, 0x2020, 0x2000];
    assert_eq!(
        Text::<8>::decode(&spaces, ByteOrder::HighFirst).as_str(),
        Some("A B")
    );
    assert!(Text::<8>::decode(&[0, 0x2020], ByteOrder::HighFirst).is_empty());
}

#[test]
fn what_is_shown_is_escaped() {
    let t = Text::<8>::decode(&[0x411B, 0x5B32, 0x4A5C, 0x22FF], ByteOrder::HighFirst);
    assert_eq!(t.as_str(), None);
    assert_eq!(t.to_string(), "A\\x1B[2J\\\\\\\"\\xFF");
    assert_eq!(format!("{t:?}"), "Text(\"A\\x1B[2J\\\\\\\"\\xFF\")");
}

#[test]
fn a_write_must_fit_and_be_printable() {
    let mut words = [0; 2];
    assert_eq!(
        text::encode(b"ABCDE", ByteOrder::HighFirst, &mut words),
        Err(TextError::TooLong {
            len: 5,
            registers: 2
        })
    );
    assert_eq!(
        text::encode(b"AB\nD", ByteOrder::HighFirst, &mut words),
        Err(TextError::NotPrintable {
            index: 2,
            byte: b'\n'
        })
    );
    assert_eq!(
        TextError::TooLong {
            len: 5,
            registers: 2
        }
        .to_string(),
        "5 characters do not fit in 2 registers (at most 4)"
    );
}

proptest! {
    #[test]
    fn any_words_decode_and_show_escaped(words in prop::collection::vec(any::<u16>(), 0..20), order in order()) {
        let t = Text::<16>::decode(&words, order);
        prop_assert!(t.as_bytes().len() <= 16.min(2 * words.len()));
        let shown = t.to_string();
        prop_assert!(shown.bytes().all(|b| (0x20..=0x7E).contains(&b)), "{shown:?}");
        if let Some(s) = t.as_str() {
            prop_assert!(!s.ends_with([' ', '\0']));
        }
        // The buffer-level decoder agrees and never reads past its output.
        let mut out = [0u8; 5];
        let n = text::decode(&words, order, &mut out);
        prop_assert!(n <= 5);
    }

    #[test]
    fn printable_ascii_round_trips(s in "[ -~]{0,16}", order in order(), registers in 8usize..12) {
        let mut words = vec![0u16; registers];
        text::encode(s.as_bytes(), order, &mut words).unwrap();
        let t = Text::<24>::decode(&words, order);
        // Trailing spaces are padding by the decoder's rule; the rest is the text.
        prop_assert_eq!(t.as_str(), Some(s.trim_end_matches(' ')));
    }
}
