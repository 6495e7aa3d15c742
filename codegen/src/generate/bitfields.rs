//! Bit-field value types: one `rt::bit_fields!` invocation per register, naming the type, its
//! mask and per field its getter, its mask and shift and, for registers that can be written, its
//! setter and `with_*` builder; the accessors themselves are the runtime's macro (reserved bits
//! kept 0).
//!
//! The invocation is printed as text ([`text`]), one field a line under its rustdoc:
//! `prettyplease` would fill a macro's tokens into paragraphs. Its place among the items is a
//! one-line placeholder ([`placeholder`]) that [`super::drive_module`] replaces after printing.

use std::fmt::Write as _;

use proc_macro2::TokenStream;
use quote::quote;

use super::{docs, enums, ident};
use drivemap_core::plan::Field;
use drivemap_map::RegisterRef;

/// The macro the placeholder calls: `rt::bit_fields_placeholder!(<row>);` on one line.
pub(super) const PLACEHOLDER: &str = "bit_fields_placeholder";

/// The items of a bit-field register: the enumerations of its coded fields, then the
/// placeholder of its `rt::bit_fields!` invocation ([`text`]).
pub(super) fn emit(r: RegisterRef<'_>, index: usize, rt: &TokenStream) -> TokenStream {
    let row = proc_macro2::Literal::usize_unsuffixed(index);
    let mut field_enums = Vec::new();
    // The plan's fields (their spans decided), each with the map's record of it.
    for (fi, f) in lowered_fields(r).enumerate() {
        if f.values.is_empty() {
            continue;
        }
        let ety = ident(&r.field_enum_name(f));
        let fi = proc_macro2::Literal::usize_unsuffixed(fi);
        field_enums.push(enums::emit(
            &ety,
            &f.values,
            &format!("field `{}` of `{}`", f.id, r.id()),
            quote!(plan::REGISTERS[#row].field_labels(#fi)),
            rt,
        ));
    }
    let placeholder = ident(PLACEHOLDER);
    quote! {
        #(#field_enums)*

        #rt::#placeholder!(#row);
    }
}

/// `rt::bit_fields! { … }` of a register, as text at the top level of the module.
pub(super) fn text(r: RegisterRef<'_>, mask: u16, fields: &[Field]) -> String {
    let writable = r.writable();
    let mut lines = String::new();
    for (f, lowered) in lowered_fields(r).zip(fields) {
        let (lo, width) = (lowered.lsb, lowered.width);
        let fmask = lowered.mask();
        let where_ = if width == 1 {
            format!("bit {lo}")
        } else {
            format!("bits {lo}..={}", lo + width - 1)
        };
        let mut doc = format!("{where_}: {}", f.name);
        if let Some(s) = &f.source {
            doc += &format!(" (`{s}`)");
        }
        for n in &f.notes {
            doc += &format!("\n\nNote: {n}");
        }
        lines += &doc_lines(&doc, 4);
        let id = &f.id;
        let names = if writable {
            format!("{id}, set_{id}, with_{id}")
        } else {
            id.clone()
        };
        let max = (1u32 << width) - 1;
        let fm = super::hex_text(fmask);
        let field = if width == 1 && f.values.is_empty() {
            format!("flag {names} = {fm};")
        } else {
            let (kind, names) = if f.values.is_empty() {
                ("number", names)
            } else {
                let ety = r.field_enum_name(f);
                let names = match names.split_once(',') {
                    Some((get, rest)) => format!("{get}: {ety},{rest}"),
                    None => format!("{names}: {ety}"),
                };
                ("code", names)
            };
            if writable {
                format!("{kind} {names} = {fm} >> {lo}, max {max};")
            } else {
                format!("{kind} {names} = {fm} >> {lo};")
            }
        };
        match field.split_once(" = ") {
            Some((head, tail)) if field.len() + 4 > super::plan::WIDTH => {
                let _ = writeln!(lines, "    {head}\n        = {tail}");
            }
            _ => {
                let _ = writeln!(lines, "    {field}");
            }
        }
    }
    let mut out = String::from("rt::bit_fields! {\n");
    out += &doc_lines(
        &format!(
            "Bit fields of `{}`; bits outside `{mask:#06x}` are reserved and always 0.",
            r.name()
        ),
        4,
    );
    let _ = writeln!(
        out,
        "    pub struct {}(mask {}, register {:?});",
        r.bits_type_name(),
        super::hex_text(mask),
        r.id()
    );
    out += &lines;
    out.push_str("}\n");
    super::plan::wrap(&out)
}

/// The map's records of the fields the plan kept (those with a bit span), in the plan's
/// order.
fn lowered_fields(r: RegisterRef<'_>) -> impl Iterator<Item = &drivemap_map::facts::BitField> {
    let kept: &'static [Field] = match r.plan().conversion {
        drivemap_core::plan::Conversion::Bits { fields, .. } => fields,
        _ => &[],
    };
    r.fields()
        .iter()
        .filter(move |f| kept.iter().any(|k| k.id == f.id))
}

/// `text` as `///` lines indented by `indent`, brackets of the manual escaped as in rustdoc
/// attributes ([`docs::item`]).
fn doc_lines(text: &str, indent: usize) -> String {
    let mut out = String::new();
    for l in text.lines() {
        if l.is_empty() {
            let _ = writeln!(out, "{:indent$}///", "");
        } else {
            let _ = writeln!(out, "{:indent$}/// {}", "", docs::escape_brackets(l));
        }
    }
    out
}
