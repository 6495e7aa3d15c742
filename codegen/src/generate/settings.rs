//! `Settings`: what conversions depend on — the model variant, the parameters that select a
//! scale or an address, the quantities values are relative to — and the variant enums.

use std::collections::BTreeSet;

use proc_macro2::TokenStream;
use quote::quote;

use super::{docs, hex, ident};
use crate::ir::{Drive, Register, ValueKind};
use crate::names;
use crate::validate::pascal_case;

/// Expression of type `Option<u16>`: the selector's code held in `settings`.
pub fn selector_code(selector: &Register) -> TokenStream {
    let field = ident(selector.id());
    match selector.kind() {
        ValueKind::Enum(_) => quote!(settings.#field.map(|v| v.code())),
        _ => quote!(settings.#field),
    }
}

/// How a selector's code or a reference is named in errors: the parameter number if printed.
pub fn setting_label(r: &Register) -> String {
    r.def.param.clone().unwrap_or_else(|| r.def.id.clone())
}

pub fn emit(drive: &Drive, rt: &TokenStream) -> TokenStream {
    let mut fields = Vec::new();
    let mut absorb = Vec::new();
    let mut deps = Vec::new();
    let mut seen = BTreeSet::new();
    let mut axes = Vec::new();

    for axis in &drive.variants {
        let ty = ident(&names::axis_enum(axis));
        let field = ident(&axis.id);
        seen.insert(axis.id.clone());
        let doc = docs::item(&format!(
            "{} of the drive (base: {}).",
            axis.name, axis.options[0].name
        ));
        fields.push(quote!(#doc pub #field: #ty,));
        let variants = axis.options.iter().enumerate().map(|(i, o)| {
            let v = ident(&pascal_case(&o.id));
            let doc = docs::item(&match &o.source {
                Some(s) => format!("{} (`{s}`).", o.name),
                None => format!("{}.", o.name),
            });
            if i == 0 {
                quote!(#doc #[default] #v,)
            } else {
                quote!(#doc #v,)
            }
        });
        let doc = docs::item(&format!("{}.", axis.name));
        axes.push(quote! {
            #doc
            #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
            pub enum #ty { #(#variants)* }
        });
    }
    for sel in drive.selectors() {
        if !seen.insert(sel.def.id.clone()) {
            continue;
        }
        let field = ident(sel.id());
        let marker = ident(&names::register_type(sel));
        let addr = hex(sel.def.address);
        deps.push(addr.clone());
        let doc = docs::item(&format!(
            "{} (`{:04X}h`), which selects a scale or an address. `None` until read or set.",
            label(sel),
            sel.def.address
        ));
        match sel.kind() {
            ValueKind::Enum(_) => {
                let ty = ident(&names::value_enum(sel));
                fields.push(quote!(#doc pub #field: Option<#ty>,));
                absorb.push(quote!(#addr => { self.#field = Some(<#ty as #rt::Code>::from_code(raw)); true }));
            }
            _ => {
                fields.push(quote!(#doc pub #field: Option<u16>,));
                absorb.push(quote!(#addr => { self.#field = Some(raw); true }));
            }
        }
        let _ = marker;
    }
    for reference in drive.references() {
        if !seen.insert(reference.def.id.clone()) {
            continue;
        }
        let field = ident(reference.id());
        let marker = ident(&names::register_type(reference));
        let addr = hex(reference.def.address);
        deps.push(addr.clone());
        let unit = reference.def.unit.clone().unwrap_or_default();
        let doc = docs::item(&format!(
            "{} (`{:04X}h`) in {unit}: other values are scaled relative to it. `None` until read or set.",
            label(reference),
            reference.def.address
        ));
        fields.push(quote!(#doc pub #field: Option<f64>,));
        let value = match reference.kind() {
            ValueKind::Word if reference.def.signed => quote!(Some(f64::from(raw as i16))),
            ValueKind::Word => quote!(Some(f64::from(raw))),
            _ => quote!(<#marker as #rt::Register>::decode(raw, self).ok()),
        };
        absorb.push(quote!(#addr => { self.#field = #value; true }));
    }
    for q in drive.externals() {
        if !seen.insert(q.external.clone()) {
            continue;
        }
        let field = ident(&q.external);
        let doc = docs::item(&format!(
            "{} in {}: not a register; the application supplies it (nameplate or drive rating).",
            q.description, q.unit
        ));
        fields.push(quote!(#doc pub #field: Option<f64>,));
    }
    quote! {
        #(#axes)*

        /// What value conversions of this drive depend on. Fill it from the drive with
        /// `Client::load_settings` (it reads [`Settings`]'s dependencies) or set the fields.
        #[derive(Debug, Clone, Default, PartialEq)]
        pub struct Settings {
            #(#fields)*
        }

        impl Settings {
            /// Settings of the base variant with nothing read yet.
            pub fn new() -> Self {
                Self::default()
            }
        }

        impl #rt::DriveSettings for Settings {
            const DEPENDENCIES: &'static [u16] = &[#(#deps),*];

            fn absorb(&mut self, address: u16, raw: u16) -> bool {
                match address {
                    #(#absorb)*
                    _ => false,
                }
            }
        }
    }
}

fn label(r: &Register) -> String {
    match &r.def.param {
        Some(p) => format!("{p} {}", r.def.name),
        None => r.def.name.clone(),
    }
}
