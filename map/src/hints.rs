//! Deserialization errors said so that the author knows what to write: serde says "invalid type:
//! string \"2001h\", expected u16" or "data did not match any variant of untagged enum Scale";
//! these add how the value is written, and "did you mean" for a misspelt key or variant.

use serde_yaml::Value;

/// The message of a deserialization error with a hint added. `value` is the value written at the
/// place of the error, when there is one.
pub(crate) fn explain(message: &str, value: Option<&Value>) -> String {
    if let Some(rest) = message
        .strip_prefix("unknown field `")
        .or_else(|| message.strip_prefix("unknown variant `"))
    {
        return did_you_mean(message, rest).unwrap_or_else(|| message.to_owned());
    }
    if let Some(hint) = value.and_then(|v| page_citation_mapping(message, v)) {
        return format!("{message}: {hint}");
    }
    if let Some(inner) = value.and_then(|v| untagged_inner(message, v)) {
        return format!("{message}: {}", explain(&inner, None));
    }
    if let Some(form) = untagged(message) {
        let quoted = match value {
            Some(Value::String(s)) if s.trim().parse::<f64>().is_ok() => {
                format!("; \"{s}\" is quoted, so it is text: write {s} without quotes")
            }
            _ => String::new(),
        };
        return format!("{message}: {form}{quoted}");
    }
    if let Some(hint) = number_hint(message) {
        return format!("{message}: {hint}");
    }
    message.to_owned()
}

/// `source: {manual: acme-um, page: 42}`: a page citation is one string, `acme-um:p42`.
fn page_citation_mapping(message: &str, value: &Value) -> Option<String> {
    if !message.starts_with("invalid type: map, expected a string") {
        return None;
    }
    let Value::Mapping(m) = value else {
        return None;
    };
    let page = m.get("page")?;
    let page = match page {
        Value::Number(n) => n.to_string(),
        Value::String(s) => s.clone(),
        _ => "<page>".to_owned(),
    };
    let manual = match m.get("manual") {
        Some(Value::String(s)) => s.as_str(),
        _ => "<manual id>",
    };
    Some(format!(
        "a page citation is one string, `<manual id>:p<page>`: write `source: \"{manual}:p{page}\"`"
    ))
}

/// The error of the one form a mapping's keys select (`relative_to` → a relative scale), which
/// an untagged enum's own error hides.
fn untagged_inner(message: &str, value: &Value) -> Option<String> {
    use crate::model;
    let name = message.strip_prefix("data did not match any variant of untagged enum ")?;
    let Value::Mapping(m) = value else {
        return None;
    };
    let has = |k: &str| m.contains_key(k);
    let v = value.clone();
    let err = |e: serde_yaml::Error| e.to_string();
    match name.trim() {
        "Scale" if has("relative_to") => serde_yaml::from_value::<model::RelativeScale>(v)
            .err()
            .map(err),
        "Scale" if has("selected_by") => serde_yaml::from_value::<model::SelectedScale>(v)
            .err()
            .map(err),
        "DefaultValue" if has("depends_on") => serde_yaml::from_value::<model::DependentDefault>(v)
            .err()
            .map(err),
        "Reference" if has("external") => serde_yaml::from_value::<model::ExternalQuantity>(v)
            .err()
            .map(err),
        _ => None,
    }
}

/// What the forms of an untagged enum of the schema are.
fn untagged(message: &str) -> Option<&'static str> {
    let name = message.strip_prefix("data did not match any variant of untagged enum ")?;
    Some(match name.trim() {
        "Scale" => {
            "a scale is a number (`scale: 0.01`), `{relative_to: <register id or parameter>, \
             full_scale: <raw value meaning 100 %>}`, or `{selected_by: <register id or \
             parameter>, cases: [{when: [<codes>], scale: <number or relative_to>}]}`"
        }
        "DefaultValue" => {
            "a default is a number (`default: 10.0`) or `{depends_on: capacity | control_method \
             | variant | setting | unknown, note: <text>}`"
        }
        "Reference" => {
            "`relative_to` is a register id or parameter number (`Cn-02`), or `{external: \
             <snake_case name>, unit: <unit>, description: <text>}`"
        }
        _ => return None,
    })
}

/// How to write a number where text (or a quoted number) was given.
fn number_hint(message: &str) -> Option<String> {
    let rest = message.strip_prefix("invalid type: string \"")?;
    let (text, expected) = rest.rsplit_once("\", expected ")?;
    let numeric = matches!(
        expected,
        "u8" | "u16" | "u32" | "u64" | "i8" | "i16" | "i32" | "i64" | "f32" | "f64"
    );
    if !numeric {
        return None;
    }
    let t = text.trim();
    if t.len() > 40 {
        return Some("write a number: decimal (`12`), or hexadecimal as `0x0C`".to_owned());
    }
    let hex_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_hexdigit());
    let hex = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .or_else(|| t.strip_suffix(['h', 'H']))
        .filter(|d| hex_digits(d));
    Some(if let Some(digits) = hex {
        format!(
            "write a hexadecimal number as 0x{digits}, without quotes (the `{digits}H` notation \
             is read only in addresses and codes)"
        )
    } else if t.parse::<f64>().is_ok() {
        format!("\"{t}\" is quoted, so it is text: write {t} without quotes")
    } else {
        "write a number: decimal (`12`), or hexadecimal as `0x0C`".to_owned()
    })
}

/// "did you mean `x`?" for an unknown key or variant, from the candidates serde lists.
fn did_you_mean(message: &str, rest: &str) -> Option<String> {
    let (given, candidates) = rest.split_once('`')?;
    let best = candidates
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|c| (distance(&given.to_lowercase(), &c.to_lowercase()), c))
        .min_by_key(|(d, _)| *d)?;
    let limit = (given.chars().count() / 3).max(1);
    if best.0 > limit {
        return None;
    }
    let head = format!("`{given}`");
    let at = message.find(&head)? + head.len();
    Some(format!(
        "{} (did you mean `{}`?){}",
        &message[..at],
        best.1,
        &message[at..]
    ))
}

/// The candidate closest to `given`, if it is close enough to be a typo of it.
pub(crate) fn closest<'a>(
    given: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    let (d, best) = candidates
        .into_iter()
        .map(|c| (distance(&given.to_lowercase(), &c.to_lowercase()), c))
        .min_by_key(|(d, _)| *d)?;
    (d <= (given.chars().count() / 3).max(1)).then_some(best)
}

/// Edit distance with adjacent transpositions counted as one edit (`scael` → `scale` is 1).
fn distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    // Keys are short; a long given key is no one's typo.
    if a.len() > 64 || b.len() > 64 {
        return usize::MAX;
    }
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    d[0] = (0..=b.len()).collect();
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = v;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_the_nearest_key() {
        let m = "unknown field `scael`, expected one of `id`, `scale`, `signed`";
        assert_eq!(
            explain(m, None),
            "unknown field `scael` (did you mean `scale`?), expected one of `id`, `scale`, `signed`"
        );
        let far = "unknown field `colour`, expected `id` or `name`";
        assert_eq!(explain(far, None), far);
        let v = "unknown variant `rwx`, expected one of `r`, `w`, `rw`";
        assert!(explain(v, None).contains("did you mean `rw`?"));
        assert_eq!(distance("scael", "scale"), 1);
        assert_eq!(distance("", "ab"), 2);
    }

    #[test]
    fn says_how_to_write_numbers() {
        let m = "invalid type: string \"2001h\", expected u16";
        assert!(explain(m, None).contains("0x2001, without quotes"));
        let q = "invalid type: string \"0.5\", expected f64";
        assert!(explain(q, None).contains("write 0.5 without quotes"));
        let s = explain(
            "data did not match any variant of untagged enum Scale",
            Some(&Value::String("0.01".into())),
        );
        assert!(s.contains("`scale: 0.01`"), "{s}");
        assert!(s.contains("write 0.01 without quotes"), "{s}");
    }
}
