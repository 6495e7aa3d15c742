//! `Settings`: what conversions depend on — the model variant, the parameters that select a
//! scale or an address, the quantities values are relative to — and the variant enums. The
//! slots come from the plan ([`SettingsPlan`]); `Settings` answers them by name.

use proc_macro2::{Literal, TokenStream};
use quote::quote;

use super::{docs, hex, ident};
use crate::ir::{Drive, ValueKind};
use crate::lower::{DrivePlan, Quantity, SettingsPlan};
use crate::names::{self, pascal_case};

pub fn emit(drive: &Drive, plan: &DrivePlan, rt: &TokenStream) -> TokenStream {
    let SettingsPlan {
        codes,
        quantities,
        axes: _,
    } = &plan.settings;
    let mut fields = Vec::new();
    let mut absorb = Vec::new();
    let mut external_arms = Vec::new();
    let mut axes = Vec::new();
    let mut variant_arms = Vec::new();
    let mut code_arms = Vec::new();
    let mut quantity_arms = Vec::new();
    let by_index = |i: usize| &drive.registers[plan_to_map(plan, i)];

    for (a, axis) in drive.variants.iter().enumerate() {
        let ty = ident(&names::axis_enum(axis));
        let field = ident(&axis.id);
        let doc = docs::item(&format!(
            "{} of the drive (base: {}).",
            axis.name, axis.options[0].name
        ));
        fields.push(quote!(#doc pub #field: #ty,));
        let slot = Literal::u8_unsuffixed(a as u8);
        variant_arms.push(quote!(#slot => self.#field as u8,));
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
    let mut selector_fields = Vec::new();
    for (slot, code) in codes.iter().enumerate() {
        let sel = by_index(code.register);
        let addr = sel.def.address;
        let slot = Literal::u8_unsuffixed(slot as u8);
        if let Some(f) = &code.field {
            // A field of the selector's word: the code is the field's value.
            let field = ident(&format!("{}_{}", sel.id(), f.id));
            let last = f.lsb + f.width - 1;
            let bits = if f.width == 1 {
                format!("bit {}", f.lsb)
            } else {
                format!("bits {}-{last}", f.lsb)
            };
            let doc = docs::item(&format!(
                "Field `{}` ({bits}) of {} (`{addr:04X}h`), which selects a scale or an address. `None` until read or set.",
                f.id,
                label(sel),
            ));
            fields.push(quote!(#doc pub #field: Option<u16>,));
            let (lsb, mask) = (Literal::u8_unsuffixed(f.lsb), hex(f.mask() >> f.lsb));
            let value = if f.lsb == 0 {
                quote!(raw & #mask)
            } else {
                quote!((raw >> #lsb) & #mask)
            };
            absorb.push((addr, quote!(self.#field = Some(#value))));
            code_arms.push(quote!(#slot => self.#field,));
            continue;
        }
        let field = ident(sel.id());
        let doc = docs::item(&format!(
            "{} (`{addr:04X}h`), which selects a scale or an address. `None` until read or set.",
            label(sel),
        ));
        match sel.kind() {
            ValueKind::Enum(_) => {
                let ty = ident(&names::value_enum(sel));
                fields.push(quote!(#doc pub #field: Option<#ty>,));
                absorb.push((
                    addr,
                    quote!(self.#field = Some(<#ty as #rt::Code>::from_code(raw))),
                ));
                code_arms.push(quote!(#slot => self.#field.map(|v| #rt::Code::code(&v)),));
            }
            _ => {
                fields.push(quote!(#doc pub #field: Option<u16>,));
                absorb.push((addr, quote!(self.#field = Some(raw))));
                code_arms.push(quote!(#slot => self.#field,));
            }
        }
        selector_fields.push(sel.def.id.clone());
    }
    for (slot, q) in quantities.iter().enumerate() {
        let slot_lit = Literal::u8_unsuffixed(slot as u8);
        match q {
            Quantity::Register(i) => {
                let reference = by_index(*i);
                let field = ident(reference.id());
                if selector_fields.contains(&reference.def.id) {
                    // Also a selector: its code is the quantity.
                    quantity_arms.push(quote!(#slot_lit => #rt::SettingsView::code(self, #slot_lit).map(f64::from),));
                    continue;
                }
                let addr = reference.def.address;
                let unit = reference.def.unit.clone().unwrap_or_default();
                let doc = docs::item(&format!(
                    "{} (`{:04X}h`) in {unit}: other values are scaled relative to it. `None` until read or set.",
                    label(reference),
                    reference.def.address
                ));
                fields.push(quote!(#doc pub #field: Option<f64>,));
                let index = Literal::usize_unsuffixed(*i);
                absorb.push((
                    addr,
                    quote!(self.#field = plan::REGISTERS[#index].decode_number(u32::from(raw), self).ok()),
                ));
                quantity_arms.push(quote!(#slot_lit => self.#field,));
            }
            Quantity::External {
                id,
                description,
                unit,
            } => {
                let field = ident(id);
                let doc = docs::item(&format!(
                    "{description} in {unit}: not a register; the application supplies it (nameplate or drive rating)."
                ));
                fields.push(quote!(#doc pub #field: Option<f64>,));
                quantity_arms.push(quote!(#slot_lit => self.#field,));
                external_arms.push(quote!(#id => self.#field = Some(value),));
            }
        }
    }
    let set_external = if external_arms.is_empty() {
        quote!()
    } else {
        quote! {
            fn set_external(&mut self, name: &str, value: f64) -> bool {
                match name {
                    #(#external_arms)*
                    _ => return false,
                }
                true
            }
        }
    };
    let deps = plan.dependencies().into_iter().map(hex);
    // One arm per address: a word may fill several slots (the register and fields of it).
    let mut by_address: Vec<(u16, Vec<TokenStream>)> = Vec::new();
    for (addr, statement) in absorb {
        match by_address.iter_mut().find(|(a, _)| *a == addr) {
            Some((_, statements)) => statements.push(statement),
            None => by_address.push((addr, vec![statement])),
        }
    }
    let absorb: Vec<TokenStream> = by_address
        .into_iter()
        .map(|(addr, statements)| {
            let addr = hex(addr);
            match statements.as_slice() {
                [one] => quote!(#addr => #one,),
                many => quote!(#addr => { #(#many;)* }),
            }
        })
        .collect();
    let absorb_body = if absorb.is_empty() {
        quote!(let _ = (address, raw); false)
    } else {
        quote! {
            match address {
                #(#absorb)*
                _ => return false,
            }
            true
        }
    };
    let method = |name: TokenStream,
                  arg: TokenStream,
                  ret: TokenStream,
                  arms: &[TokenStream],
                  none: TokenStream| {
        if arms.is_empty() {
            quote!(fn #name(&self, _: u8) -> #ret { #none })
        } else {
            quote!(fn #name(&self, #arg: u8) -> #ret { match #arg { #(#arms)* _ => #none } })
        }
    };
    let code = method(
        quote!(code),
        quote!(slot),
        quote!(Option<u16>),
        &code_arms,
        quote!(None),
    );
    let quantity = method(
        quote!(quantity),
        quote!(slot),
        quote!(Option<f64>),
        &quantity_arms,
        quote!(None),
    );
    let variant = method(
        quote!(variant),
        quote!(axis),
        quote!(u8),
        &variant_arms,
        quote!(0),
    );
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
                #absorb_body
            }

            #set_external
        }

        impl #rt::SettingsView for Settings {
            #code
            #quantity
            #variant
        }
    }
}

/// The map index of the register at `index` of the plan's table. Every row is a register's
/// (the lowering makes `order` a permutation of the rows): a row without one is a bug of the
/// lowering, said as such, never register 0's place taken silently.
fn plan_to_map(plan: &DrivePlan, index: usize) -> usize {
    plan.order
        .iter()
        .position(|&p| p == index)
        .unwrap_or_else(|| {
            panic!("plan row {index} is no register's: `order` is not a permutation")
        })
}

fn label(r: &crate::ir::Register) -> String {
    match &r.def.param {
        Some(p) => format!("{p} {}", r.def.name),
        None => r.def.name.clone(),
    }
}
