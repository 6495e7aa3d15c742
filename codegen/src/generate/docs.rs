//! Rustdoc text for generated items: the manual's name, number and row, limits, notes.

use proc_macro2::TokenStream;
use quote::quote;

use drivemap_core::register::WriteRestriction;

use crate::describe;
use crate::ir::{Drive, Register, ValueKind};
use crate::model::Scale;

/// Brackets of the manual's text (`Drive Read[y]`, `[1]`) escaped so that rustdoc does not
/// read them as links; a link the generator writes (``[`Name`]``) and code spans stay as they are.
pub fn escape_brackets(line: &str) -> String {
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
pub fn item(text: &str) -> TokenStream {
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

pub fn module(drive: &Drive) -> String {
    let m = &drive.meta;
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
        drive.registers.len(),
        describe::per_request(
            drive.protocol.max_read.value,
            drive.protocol.max_write.value
        ),
        describe::functions(&drive.protocol.function_codes.codes)
    );
    s
}

pub fn register(drive: &Drive, r: &Register) -> String {
    let d = &r.def;
    let plan = drive.register_plan(r);
    let title = match &d.param {
        Some(p) => format!("**{p} — {}**", d.name),
        None => format!("**{}**", d.name),
    };
    let mut facts = vec![match &d.pair {
        None => format!("address `{}`", describe::address(d.address)),
        Some(p) => format!(
            "addresses `{}` ({}{}, read and written whole)",
            describe::address_span(d.address, d.address.wrapping_add(1)),
            describe::width(r.width()),
            p.source
                .as_deref()
                .map(|s| format!(", `{s}`"))
                .unwrap_or_default()
        ),
    }];
    facts.push(describe::access(plan.info.access).to_owned());
    if r.broadcast {
        facts.push("broadcast only (slave 0)".into());
    }
    let unit = d.unit.clone().unwrap_or_default();
    match r.kind() {
        ValueKind::Quantity(Scale::Selected(sel)) => facts.push(format!(
            "unit {unit}, scale {}",
            describe::selected_by(drive, &sel.selected_by)
        )),
        ValueKind::Quantity(scale) => {
            facts.push(format!("scale {}", describe::scale(drive, scale, &unit)))
        }
        ValueKind::UnitQuantity => facts.push(format!(
            "scale {}",
            describe::scale(drive, &Scale::Factor(1.0), &unit)
        )),
        _ => {}
    }
    let range = describe::range(d.min, d.max, &unit);
    if !range.is_empty() {
        facts.push(format!("range {range}"));
    }
    if let Some(v) = &d.default {
        facts.push(format!("default {}", describe::default(v)));
    }
    let mut s = format!("{title}\n\n{}.\n", facts.join(" · "));
    if let Some(Scale::Selected(sel)) = &d.scale {
        s += "\n| selector | scale | range |\n|---|---|---|\n";
        for c in &sel.cases {
            s += &format!(
                "| {} | {} | {} |\n",
                describe::codes(&c.when),
                describe::scale(drive, &c.scale, &unit),
                describe::range(c.min, c.max, &unit)
            );
        }
    }
    for (k, o) in &d.by_variant {
        let (min, max) = r.limits_for(k);
        let name = drive
            .variant_option(k)
            .map(|(_, o)| o.name.clone())
            .unwrap_or_else(|| k.clone());
        let mut parts = Vec::new();
        if o.min.is_some() || o.max.is_some() {
            parts.push(format!("range {}", describe::range(min, max, &unit)));
        }
        if let Some(v) = &o.default {
            parts.push(format!("default {}", describe::default(v)));
        }
        for u in &o.unknown {
            parts.push(format!(
                "{} unknown: {}",
                describe::unknown_item(u.what),
                u.reason
            ));
        }
        if !parts.is_empty() {
            s += &format!("\n{name}: {}.\n", parts.join(", "));
        }
    }
    if let Some(l) = &d.max_relative {
        s += &format!(
            "\nLimited through another quantity: {}; a value above it is refused before \
             sending (`ValueError::AboveLimit`), and one that cannot be checked because the \
             quantity is not in the settings is refused too (`ValueError::LimitNotKnown`).\n",
            describe::relative_limit(drive, l)
        );
    }
    if plan.restriction != WriteRestriction::None {
        s += &format!(
            "\nWritable {}.\n",
            describe::write_restriction(plan.restriction)
        );
    }
    if let Some((rule, _)) = &r.repeat_needs_change {
        s += &format!(
            "\nRepeat needs a change: {}. `Client::write` does so, and writing the same value \
             twice executes it twice.\n",
            describe::repeat_needs_change(rule)
        );
    }
    if !d.read_values.is_empty() {
        s += &format!(
            "\nRead and written with different meanings: a read gives the read enumeration ({}); \
             a write takes the word described above.\n",
            describe::read_values(&d.read_values)
        );
    }
    for alt in &d.address_alternatives {
        s += &format!(
            "\nAt `{}` when {} (`{}`).\n",
            describe::address(alt.address),
            describe::condition(&alt.when),
            alt.source
        );
    }
    if !d.display_steps.is_empty() {
        s += &format!(
            "\n{}.\n",
            capitalized(&describe::display_steps(&d.display_steps))
        );
    }
    for n in &d.notes {
        s += &format!("\nNote: {n}\n");
    }
    for c in &d.conflicts {
        let cites = c
            .readings
            .iter()
            .map(|r| format!("`{}`", r.source))
            .collect::<Vec<_>>()
            .join(" vs ");
        s += &format!(
            "\nConflict — {}: {cites}. Chosen: {}. {}\n",
            c.topic, c.chosen, c.reason
        );
    }
    for u in &d.unknown {
        s += &format!(
            "\nUnknown {}: {}\n",
            describe::unknown_item(u.what),
            u.reason
        );
    }
    if let Some(src) = &d.source {
        s += &format!("\nSource: `{src}`.");
    }
    s
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
/// (`2101H` and `0x2101`, or the register number of a manual numbering them in decimal).
pub fn aliases(drive: &Drive, r: &Register, type_name: &str) -> Vec<String> {
    let mut out = vec![r.def.id.clone()];
    out.extend(r.def.param.clone());
    let addresses =
        std::iter::once(r.def.address).chain(r.def.address_alternatives.iter().map(|a| a.address));
    for a in addresses {
        match drive.address_format {
            crate::model::AddressFormat::Decimal => out.push(a.to_string()),
            crate::model::AddressFormat::Hex => {
                out.push(format!("{a:04X}H"));
                out.push(format!("0x{a:04X}"));
            }
        }
    }
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
