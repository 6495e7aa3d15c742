//! Reading the citations outside the registers ([`Map::other_citations`]: roles, protocol
//! items, readings of conflicts, gaps) against the manual's line: whether the line shows what
//! each [`CitationRule`] asks.

use drivemap_map::Map;
use drivemap_map::facts::AddressFormat;
use drivemap_map::facts::CitationRule;

use super::matching::{AddressForms, Line, name_found, number_found, param_found, word_found};

/// Whether the line shows what `rule` asks (`Register` is decided by the register check, not
/// here).
pub(crate) fn found(
    rule: &CitationRule,
    map: &Map,
    offsets: Option<(i32, i32)>,
    line: &Line,
) -> bool {
    let decimal = map.address_format() == AddressFormat::Decimal;
    let forms = |a: u16| {
        let f = AddressForms::new(a, offsets);
        if decimal { f.with_decimal(a) } else { f }
    };
    match rule {
        CitationRule::Register(_) => false,
        CitationRule::Field {
            register,
            field,
            codes,
        } => {
            let Some(r) = map.register_at(*register) else {
                return false;
            };
            let Some(f) = r.fields().get(*field) else {
                return false;
            };
            super::citations::field_found(f, line)
                || f.values
                    .iter()
                    .filter(|v| codes.contains(&v.value))
                    .any(|v| super::citations::value_found(v, line))
                || r.param().is_some_and(|p| param_found(p, line))
                || r.read_param().is_some_and(|p| param_found(p, line))
                || forms(r.address())
                    .with_reference(r.modicon())
                    .found_in(line)
                || name_found(r.name(), line)
        }
        CitationRule::Any {
            words,
            params,
            numbers,
            codes,
            addresses,
            names,
            registers,
        } => {
            registers
                .iter()
                .filter_map(|i| map.register_at(*i))
                .any(|r| {
                    r.param().is_some_and(|p| param_found(p, line))
                        || forms(r.address())
                            .with_reference(r.modicon())
                            .found_in(line)
                })
                || words.iter().any(|w| word_found(w, line))
                || params.iter().any(|p| param_found(p, line))
                || numbers.iter().any(|n| decimal_found(n, line))
                || codes.iter().any(|c| number_found(*c, line))
                || addresses.iter().any(|a| forms(*a).found_in(line))
                || names.iter().any(|n| name_found(n, line))
        }
    }
}

/// Whether the line prints a number as written (`3.5`, `100000`, `100,000`, `0008H`), not
/// inside a longer number; a token of letters and digits (`8th`) also with OCR spaces inside.
fn decimal_found(n: &str, line: &Line) -> bool {
    let text = line.upper.replace(',', "");
    let n = n.to_uppercase().replace(',', "");
    let mixed = n.chars().any(|c| c.is_ascii_alphabetic()) && n.chars().count() >= 3;
    if mixed && line.squashed.contains(&n.to_lowercase()) {
        return true;
    }
    text.match_indices(n.as_str()).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let rest = &text[i + n.len()..];
        let mut after = rest.chars();
        let a1 = after.next();
        let a2 = after.next();
        let left = before.is_none_or(|c| !c.is_ascii_digit() && c != '.');
        let right = match a1 {
            None => true,
            Some('.') => a2.is_none_or(|c| !c.is_ascii_digit()),
            Some(c) => !c.is_ascii_digit(),
        };
        left && right
    })
}
