//! Rustdoc text for generated items: the manual's name, number and row, limits, notes.

use proc_macro2::TokenStream;
use quote::quote;

use crate::ir::{Drive, Register, ValueKind};
use crate::model::{Access, DefaultValue, Reference, Scale, WriteRestriction};

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
        "\n{} registers; at most {} per read, {} per write; function codes {}.",
        drive.registers.len(),
        drive.protocol.max_read,
        drive.protocol.max_write,
        drive
            .protocol
            .function_codes
            .iter()
            .map(|f| format!("{f:02X}h"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    s
}

fn num(v: f64) -> String {
    format!("{v}")
}

fn reference(drive: &Drive, r: &Reference) -> String {
    match r {
        Reference::Register(name) => drive
            .find(name)
            .map(|t| match &t.def.param {
                Some(p) => format!("{p} ({})", t.def.name),
                None => t.def.name.clone(),
            })
            .unwrap_or_else(|| name.clone()),
        Reference::External(q) => format!("{} ({})", q.description, q.unit),
    }
}

fn scale_text(drive: &Drive, scale: &Scale, unit: &str) -> String {
    match scale {
        Scale::Factor(f) => format!("{} {unit} per count", num(*f)),
        Scale::Relative(rel) => format!(
            "{} = 100 % of {}",
            num(rel.full_scale),
            reference(drive, &rel.relative_to)
        ),
        Scale::Selected(_) => String::new(),
    }
}

pub fn register(drive: &Drive, r: &Register) -> String {
    let d = &r.def;
    let title = match &d.param {
        Some(p) => format!("**{p} — {}**", d.name),
        None => format!("**{}**", d.name),
    };
    let access = match r.access {
        Access::Read => "read-only",
        Access::Write => "write-only",
        Access::ReadWrite => "read/write",
    };
    let mut facts = vec![format!("address `{:04X}h`", d.address), access.to_owned()];
    if r.broadcast {
        facts.push("broadcast only (slave 0)".into());
    }
    let unit = d.unit.clone().unwrap_or_default();
    match r.kind() {
        ValueKind::Quantity(Scale::Selected(sel)) => {
            let selector = drive
                .selector(&sel.selected_by)
                .map_or_else(|| sel.selected_by.clone(), |s| s.prose());
            facts.push(format!("unit {unit}, scale selected by {selector}"));
        }
        ValueKind::Quantity(scale) => facts.push(scale_text(drive, scale, &unit)),
        ValueKind::UnitQuantity => facts.push(format!("1 {unit} per count")),
        _ => {}
    }
    if d.min.is_some() || d.max.is_some() {
        let min = d.min.map(num).unwrap_or_else(|| "…".into());
        let max = d.max.map(num).unwrap_or_else(|| "…".into());
        facts.push(
            format!("range {min} ..= {max} {unit}")
                .trim_end()
                .to_owned(),
        );
    }
    match &d.default {
        Some(DefaultValue::Value(v)) => facts.push(format!("default {}", num(*v))),
        Some(DefaultValue::Depends(dep)) => facts.push(format!(
            "default depends on {}",
            serde_json::to_value(dep.depends_on)
                .ok()
                .and_then(|v| v.as_str().map(|s| s.replace('_', " ")))
                .unwrap_or_default()
        )),
        None => {}
    }
    let mut s = format!("{title}\n\n{}.\n", facts.join(" · "));
    if let Scale::Selected(sel) = d.scale.as_ref().unwrap_or(&Scale::Factor(1.0)) {
        s += "\n| selector | scale | range |\n|---|---|---|\n";
        for c in &sel.cases {
            let range = match (c.min, c.max) {
                (None, None) => String::new(),
                (a, b) => format!(
                    "{} ..= {} {unit}",
                    a.map(num).unwrap_or_else(|| "…".into()),
                    b.map(num).unwrap_or_else(|| "…".into())
                ),
            };
            s += &format!(
                "| {} | {} | {range} |\n",
                c.when
                    .iter()
                    .map(u16::to_string)
                    .collect::<Vec<_>>()
                    .join(", "),
                scale_text(drive, &c.scale, &unit)
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
            parts.push(format!(
                "range {} ..= {} {unit}",
                min.map(num).unwrap_or_else(|| "…".into()),
                max.map(num).unwrap_or_else(|| "…".into())
            ));
        }
        if let Some(DefaultValue::Value(v)) = &o.default {
            parts.push(format!("default {}", num(*v)));
        }
        for u in &o.unknown {
            parts.push(format!("{:?} unknown: {}", u.what, u.reason).to_lowercase());
        }
        if !parts.is_empty() {
            s += &format!("\n{name}: {}.\n", parts.join(", "));
        }
    }
    match r.write_restriction {
        WriteRestriction::None => {}
        WriteRestriction::Stopped => s += "\nWritable only while the motor is stopped.\n",
        WriteRestriction::PrgMode => s += "\nWritable only in PRG (program) mode.\n",
    }
    for alt in &d.address_alternatives {
        let cond = &alt.when;
        s += &format!(
            "\nAt `{:04X}h` when {cond} (`{}`).\n",
            alt.address, alt.source
        );
    }
    if !d.display_steps.is_empty() {
        let bands = d
            .display_steps
            .iter()
            .map(|b| format!("from {} in steps of {}", num(b.from), num(b.step)))
            .collect::<Vec<_>>()
            .join(", ");
        s += &format!("\nThe keypad shows it {bands}; the register carries the full resolution.\n");
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
            format!("{:?}", u.what).to_lowercase(),
            u.reason
        );
    }
    if let Some(src) = &d.source {
        s += &format!("\nSource: `{src}`.");
    }
    s
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
