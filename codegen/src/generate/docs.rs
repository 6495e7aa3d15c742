//! Rustdoc text for generated items: the manual's name, number and row, limits, notes.

use proc_macro2::TokenStream;
use quote::quote;

use crate::describe;
use crate::facts::{self, FactKey};
use drivemap_map::{Map, RegisterRef};

/// Brackets of the manual's text (`Drive Read[y]`, `[1]`) escaped so that rustdoc does not
/// read them as links; a link the generator writes (``[`Name`]``) and code spans stay as they are.
pub(super) fn escape_brackets(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::with_capacity(line.len());
    let mut in_code = false;
    for (i, &c) in chars.iter().enumerate() {
        match c {
            '`' => in_code = !in_code,
            '[' if !in_code && chars.get(i + 1) != Some(&'`') => out.push('\\'),
            ']' if !in_code && (i == 0 || chars[i - 1] != '`') => out.push('\\'),
            _ => {}
        }
        out.push(c);
    }
    out
}

/// `#[doc]` attributes, one per line (outer, for items).
pub(super) fn item(text: &str) -> TokenStream {
    let attrs = text.lines().map(|l| {
        let l = if l.is_empty() {
            String::new()
        } else {
            format!(" {}", escape_brackets(l))
        };
        quote!(#[doc = #l])
    });
    quote!(#(#attrs)*)
}

pub(super) fn module(drive: &Map) -> String {
    let m = drive.meta();
    let mut s = format!(
        "{} {} — register map `{}`.\n\n",
        m.vendor,
        m.models.join(" / "),
        m.id
    );
    if let Some(d) = &m.description {
        s += &format!("{d}\n\n");
    }
    if let Some(base) = &m.extends {
        s += &format!("A variant of `{base}`: inherits its registers and overrides them.\n\n");
    }
    s += "Transcribed from:\n";
    for manual in &m.manuals {
        s += &format!("- {}\n", manual.describe());
    }
    s += &format!(
        "\n{} registers; {}; function codes {}.",
        drive.registers().len(),
        describe::per_request(drive.protocol().max_read(), drive.protocol().max_write()),
        describe::functions(&drive.protocol().function_codes.codes)
    );
    let p = drive.protocol();
    if p.max_read_bits.is_some() || p.max_write_bits.is_some() {
        s += &format!(
            " Coils and discrete inputs: {}.",
            describe::bits_per_request(
                p.max_read_bits.as_ref().map(|_| p.max_read_bits()),
                p.max_write_bits.as_ref().map(|_| p.max_write_bits()),
            )
        );
    }
    // The protocol facts the manual does not print (`PROFILE.not_printed`), each with what the
    // runtime uses in its place.
    let unprinted = drive.not_printed();
    if !unprinted.is_empty() {
        s += "\n\nNot printed in the manual (`PROFILE.not_printed`):\n";
        for u in unprinted {
            s += &format!(
                "- {} (`{}`): {}; {} is used.\n",
                u.fact.name(),
                u.fact.key(),
                u.why,
                u.fact.fallback()
            );
        }
    }
    s
}

/// The rustdoc of a register, read from its [`facts`](crate::facts) alone: the summary line
/// prints the identity rows, the paragraphs below the others.
pub(super) fn register(r: RegisterRef<'_>) -> String {
    let f = r.facts();
    let title = match (&f.param, &f.read_param) {
        (Some(w), Some(r)) => format!("**{r} (read) / {w} (write) — {}**", f.name),
        (Some(p), None) | (None, Some(p)) => format!("**{p} — {}**", f.name),
        (None, None) => format!("**{}**", f.name),
    };
    let address = f.get(FactKey::Address).map(|a| a.value.as_str());
    let mut summary = vec![match f.get(FactKey::Width) {
        None => format!("address `{}`", address.unwrap_or_default()),
        Some(w) => format!(
            "addresses `{}` ({}{}, read and written whole)",
            address.unwrap_or_default(),
            w.value,
            w.citation
                .as_deref()
                .map(|s| format!(", `{s}`"))
                .unwrap_or_default()
        ),
    }];
    if let Some(reference) = f.get(FactKey::Reference) {
        // Only where the map records the reference the manual prints.
        summary.push(format!("Modicon reference `{}`", reference.value));
    }
    if f.data.table.is_bits() {
        // A coil or discrete input: its table and its states (`bool`: on is 1).
        summary.push(format!("{} (1 on, 0 off)", f.data.table.item()));
    }
    for row in &f.rows {
        match row.key {
            FactKey::Access | FactKey::Broadcast => summary.push(row.value.clone()),
            FactKey::SelectedBy => summary.push(format!(
                "unit {}, scale {}",
                f.get(FactKey::Unit)
                    .map(|u| u.value.as_str())
                    .unwrap_or_default(),
                row.value
            )),
            FactKey::Scale | FactKey::Range | FactKey::Default => {
                summary.push(format!("{} {}", row.label, row.value))
            }
            _ => {}
        }
    }
    let mut s = format!("{title}\n\n{}.\n", summary.join(" · "));
    if !f.cases.is_empty() {
        s += "\n| selector | scale | range |\n|---|---|---|\n";
        for c in &f.cases {
            s += &format!("| {} | {} | {} |\n", c.codes, c.scale, c.range);
        }
    }
    // The other facts as one list, an item each (a paragraph each said the same in twice the
    // lines).
    let mut items = Vec::new();
    for v in &f.variants {
        let mut parts = Vec::new();
        parts.extend(v.range.as_ref().map(|x| format!("range {x}")));
        parts.extend(v.default.as_ref().map(|x| format!("default {x}")));
        for u in &v.unknowns {
            parts.push(format!("{} unknown: {}", u.what, u.reason));
        }
        if !parts.is_empty() {
            items.push(format!("{}: {}.", v.name, parts.join(", ")));
        }
    }
    for row in &f.rows {
        match row.key {
            FactKey::RelativeLimit => items.push(format!(
                "Limited through another quantity: {}; a value above it is refused before \
                 sending (`ValueError::AboveLimit`), and one that cannot be checked because the \
                 quantity is not in the settings is refused too (`ValueError::LimitNotKnown`).",
                row.value
            )),
            FactKey::WriteRestriction => items.push(format!("Writable {}.", row.value)),
            FactKey::RepeatNeedsChange => items.push(format!(
                "Repeat needs a change: {}. `Client::write` does so, and writing the same value \
                 twice executes it twice.",
                row.value
            )),
            FactKey::FunctionCodes => items.push(format!(
                "Function codes: {}. The write gate refuses any other function on this register.",
                row.value
            )),
            FactKey::ReadParam => items.push(format!(
                "Read from another parameter than the one written: a read returns {}. A write is \
                 never verified by reading it back, and parameter sets leave the register out.",
                row.value
            )),
            FactKey::ReadValues => items.push(format!(
                "Read and written with different meanings: a read gives the read enumeration ({}); \
                 a write takes the word described above.",
                row.value
            )),
            _ => {}
        }
    }
    for alt in f.all(FactKey::AlternativeAddress) {
        items.push(format!(
            "At `{}` when {} (`{}`).",
            alt.value,
            alt.when.as_deref().unwrap_or_default(),
            alt.citation.as_deref().unwrap_or_default()
        ));
    }
    if let Some(d) = f.get(FactKey::DisplaySteps) {
        items.push(format!("{}.", capitalized(&d.value)));
    }
    for n in &f.notes {
        items.push(format!("Note: {n}"));
    }
    for c in &f.conflicts {
        let cites = c
            .citations
            .iter()
            .map(|r| format!("`{r}`"))
            .collect::<Vec<_>>()
            .join(" vs ");
        items.push(format!(
            "Conflict — {}: {cites}. Chosen: {}. {}",
            c.topic, c.chosen, c.reason
        ));
    }
    for u in &f.unknowns {
        items.push(format!("Unknown {}: {}", u.what, u.reason));
    }
    if let Some(src) = &f.source {
        items.push(format!("Source: `{src}`."));
    }
    match items.as_slice() {
        [] => {}
        [one] => s += &format!("\n{one}\n"),
        many => {
            s.push('\n');
            for item in many {
                s += &list_item(item);
            }
        }
    }
    s.truncate(s.trim_end().len());
    s
}

/// One Markdown list item: a text of several lines (or paragraphs) stays inside the item, its
/// further lines indented under the marker.
fn list_item(text: &str) -> String {
    let mut out = String::from("- ");
    for (i, line) in text.lines().enumerate() {
        if i > 0 && !line.trim().is_empty() {
            out.push_str("  ");
        }
        out.push_str(line);
        out.push('\n');
    }
    if text.is_empty() {
        out.push('\n');
    }
    out
}

fn capitalized(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

/// What rustdoc search finds a register by besides its type's name (`#[doc(alias)]`): its id,
/// its parameter number as printed (`Cn-02`, `n011`) and its address in the manual's notation
/// (`2101H` and `0x2101`, or the register number of a manual numbering them in decimal), and
/// the Modicon reference the map records (`reference: 40024`).
pub(super) fn aliases(r: RegisterRef<'_>, type_name: &str) -> Vec<String> {
    let mut out = vec![r.id().to_owned()];
    out.extend(r.param().map(str::to_owned));
    out.extend(r.read_param().map(str::to_owned));
    let addresses =
        std::iter::once(r.address()).chain(r.address_alternatives().iter().map(|a| a.address));
    for a in addresses {
        match r.map().address_format() {
            facts::AddressFormat::Decimal => out.push(a.to_string()),
            facts::AddressFormat::Hex => {
                out.push(format!("{a:04X}H"));
                out.push(format!("0x{a:04X}"));
            }
        }
    }
    // The Modicon reference the manual prints beside it (`40024`), where the map records one.
    out.extend(r.reference().map(str::to_owned));
    // rustdoc refuses an alias that is empty, the item's own name, has quotes, tabs or line
    // breaks, or starts or ends with a space.
    let mut seen = std::collections::HashSet::new();
    out.retain(|a| {
        !a.is_empty()
            && a != type_name
            && a.trim() == a
            && !a.contains(['"', '\'', '\t', '\n', '\r'])
            && seen.insert(a.clone())
    });
    out
}

#[cfg(test)]
mod tests {
    use super::escape_brackets;

    #[test]
    fn brackets_of_the_manual_are_escaped_but_links_and_code_are_not() {
        assert_eq!(
            escape_brackets("Drive Read[y] (see [`Settings`], `a[0]`)"),
            "Drive Read\\[y\\] (see [`Settings`], `a[0]`)"
        );
    }
}
