//! `Settings`: what conversions depend on — the model variant, the parameters that select a
//! scale or an address, the quantities values are relative to — and the variant enums. The
//! slots come from the plan ([`SettingsPlan`]); `Settings` answers them by name.

use proc_macro2::{Literal, TokenStream};
use quote::quote;

use super::{docs, hex, ident};
use crate::describe::pascal_case;
use drivemap_core::plan::Conversion;
use drivemap_map::{Map, MapPlan, Quantity, RegisterRef, SettingsPlan};

/// What the printers of the three kinds of slot collect: the `Settings` fields with their docs,
/// and the arms of the methods that fill and answer them.
#[derive(Default)]
struct Parts {
    /// `Settings`' fields, documented.
    fields: Vec<TokenStream>,
    /// The variant enums (one per axis).
    axes: Vec<TokenStream>,
    /// `(address, statement)`: what `absorb` does with a word read from `address`.
    absorb: Vec<(u16, TokenStream)>,
    /// Arms of `set_external` (by the quantity's id).
    external: Vec<TokenStream>,
    /// Arms of `SettingsView::variant`, `code` and `quantity` (by slot).
    variant: Vec<TokenStream>,
    code: Vec<TokenStream>,
    quantity: Vec<TokenStream>,
}

/// `Settings`, its impls and the variant enums, from the plan's slots.
pub(super) fn emit(drive: &Map, plan: &MapPlan, rt: &TokenStream) -> TokenStream {
    let SettingsPlan {
        codes,
        quantities,
        axes: _,
    } = &plan.settings;
    let mut parts = Parts::default();
    for (a, axis) in drive.variants().iter().enumerate() {
        variant_axis(&mut parts, a, axis);
    }
    let mut selector_fields = Vec::new();
    for (slot, code) in codes.iter().enumerate() {
        let sel = plan_register(drive, code.register);
        if let Some(id) = code_slot(&mut parts, slot, sel, code.field.as_ref(), rt) {
            selector_fields.push(id);
        }
    }
    for (slot, q) in quantities.iter().enumerate() {
        quantity_slot(&mut parts, slot, q, drive, &selector_fields, rt);
    }
    let Parts {
        fields,
        axes,
        absorb,
        external,
        variant,
        code,
        quantity,
    } = parts;
    let set_external = set_external(&external);
    let deps = plan.dependencies().into_iter().map(hex);
    let absorb_body = absorb_body(absorb);
    let code = view_method(
        quote!(code),
        quote!(slot),
        quote!(Option<u16>),
        &code,
        quote!(None),
    );
    let quantity = view_method(
        quote!(quantity),
        quote!(slot),
        quote!(Option<f64>),
        &quantity,
        quote!(None),
    );
    let variant = view_method(
        quote!(variant),
        quote!(axis),
        quote!(u8),
        &variant,
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

        impl #rt::register::DriveSettings for Settings {
            const DEPENDENCIES: &'static [u16] = &[#(#deps),*];

            fn absorb(&mut self, address: u16, raw: u16) -> bool {
                #absorb_body
            }

            #set_external
        }

        impl #rt::plan::SettingsView for Settings {
            #code
            #quantity
            #variant
        }
    }
}

/// A variant axis: its enum, its field and its arm of `variant`.
fn variant_axis(parts: &mut Parts, a: usize, axis: &crate::facts::VariantAxis) {
    let ty = ident(&pascal_case(&axis.id));
    let field = ident(&axis.id);
    let doc = docs::item(&format!(
        "{} of the drive (base: {}).",
        axis.name, axis.options[0].name
    ));
    parts.fields.push(quote!(#doc pub #field: #ty,));
    let slot = Literal::u8_unsuffixed(a as u8);
    parts.variant.push(quote!(#slot => self.#field as u8,));
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
    parts.axes.push(quote! {
        #doc
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub enum #ty { #(#variants)* }
    });
}

/// A code slot (a selector register, or a field of one): its field, how `absorb` fills it and
/// its arm of `code`. Returns the register's id when the whole register is the selector.
fn code_slot(
    parts: &mut Parts,
    slot: usize,
    sel: RegisterRef<'_>,
    field: Option<&drivemap_core::plan::Field>,
    rt: &TokenStream,
) -> Option<String> {
    let addr = sel.address();
    let slot = Literal::u8_unsuffixed(slot as u8);
    if let Some(f) = field {
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
        parts.fields.push(quote!(#doc pub #field: Option<u16>,));
        let (lsb, mask) = (Literal::u8_unsuffixed(f.lsb), hex(f.mask() >> f.lsb));
        let value = if f.lsb == 0 {
            quote!(raw & #mask)
        } else {
            quote!((raw >> #lsb) & #mask)
        };
        parts
            .absorb
            .push((addr, quote!(self.#field = Some(#value))));
        parts.code.push(quote!(#slot => self.#field,));
        return None;
    }
    let field = ident(sel.id());
    let doc = docs::item(&format!(
        "{} (`{addr:04X}h`), which selects a scale or an address. `None` until read or set.",
        label(sel),
    ));
    match sel.plan().conversion {
        Conversion::Enum { .. } => {
            let ty = ident(&sel.value_enum_name());
            parts.fields.push(quote!(#doc pub #field: Option<#ty>,));
            parts.absorb.push((
                addr,
                quote!(self.#field = Some(<#ty as #rt::register::Code>::from_code(raw))),
            ));
            parts
                .code
                .push(quote!(#slot => self.#field.map(|v| #rt::register::Code::code(&v)),));
        }
        _ => {
            parts.fields.push(quote!(#doc pub #field: Option<u16>,));
            parts.absorb.push((addr, quote!(self.#field = Some(raw))));
            parts.code.push(quote!(#slot => self.#field,));
        }
    }
    Some(sel.id().to_owned())
}

/// A quantity slot (a register other values are relative to, or a quantity the application
/// supplies): its field, how it is filled and its arm of `quantity`.
fn quantity_slot(
    parts: &mut Parts,
    slot: usize,
    q: &Quantity,
    drive: &Map,
    selector_fields: &[String],
    rt: &TokenStream,
) {
    let slot_lit = Literal::u8_unsuffixed(slot as u8);
    match q {
        Quantity::Register(i) => {
            let reference = plan_register(drive, *i);
            let field = ident(reference.id());
            if selector_fields.iter().any(|s| s == reference.id()) {
                // Also a selector: its code is the quantity.
                parts.quantity.push(
                    quote!(#slot_lit => #rt::plan::SettingsView::code(self, #slot_lit).map(f64::from),),
                );
                return;
            }
            let addr = reference.address();
            let unit = reference.unit().unwrap_or_default();
            let doc = docs::item(&format!(
                "{} (`{:04X}h`) in {unit}: other values are scaled relative to it. `None` until read or set.",
                label(reference),
                reference.address()
            ));
            parts.fields.push(quote!(#doc pub #field: Option<f64>,));
            let index = Literal::usize_unsuffixed(*i);
            parts.absorb.push((
                addr,
                quote!(self.#field = plan::REGISTERS[#index].decode_number(u32::from(raw), self).ok()),
            ));
            parts.quantity.push(quote!(#slot_lit => self.#field,));
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
            parts.fields.push(quote!(#doc pub #field: Option<f64>,));
            parts.quantity.push(quote!(#slot_lit => self.#field,));
            parts
                .external
                .push(quote!(#id => self.#field = Some(value),));
        }
    }
}

/// `set_external`, when the drive has quantities the application supplies.
fn set_external(arms: &[TokenStream]) -> TokenStream {
    if arms.is_empty() {
        return quote!();
    }
    quote! {
        fn set_external(&mut self, name: &str, value: f64) -> bool {
            match name {
                #(#arms)*
                _ => return false,
            }
            true
        }
    }
}

/// The body of `absorb`: one arm per address, as a word may fill several slots (the register
/// and fields of it).
fn absorb_body(absorb: Vec<(u16, TokenStream)>) -> TokenStream {
    let mut by_address: Vec<(u16, Vec<TokenStream>)> = Vec::new();
    for (addr, statement) in absorb {
        match by_address.iter_mut().find(|(a, _)| *a == addr) {
            Some((_, statements)) => statements.push(statement),
            None => by_address.push((addr, vec![statement])),
        }
    }
    let arms: Vec<TokenStream> = by_address
        .into_iter()
        .map(|(addr, statements)| {
            let addr = hex(addr);
            match statements.as_slice() {
                [one] => quote!(#addr => #one,),
                many => quote!(#addr => { #(#many;)* }),
            }
        })
        .collect();
    if arms.is_empty() {
        return quote!(let _ = (address, raw); false);
    }
    quote! {
        match address {
            #(#arms)*
            _ => return false,
        }
        true
    }
}

/// A method of `SettingsView`: a match on its slot argument, or `none` when it has no arms.
fn view_method(
    name: TokenStream,
    arg: TokenStream,
    ret: TokenStream,
    arms: &[TokenStream],
    none: TokenStream,
) -> TokenStream {
    if arms.is_empty() {
        quote!(fn #name(&self, _: u8) -> #ret { #none })
    } else {
        quote!(fn #name(&self, #arg: u8) -> #ret { match #arg { #(#arms)* _ => #none } })
    }
}

/// The map index of the register at `index` of the plan's table. Every row is a register's
/// (the lowering makes `order` a permutation of the rows): a row without one is a bug of the
/// lowering, said as such, never register 0's place taken silently.
fn plan_register(drive: &Map, index: usize) -> RegisterRef<'_> {
    drive.register_of_row(index).unwrap_or_else(|| {
        panic!("plan row {index} is no register's: `order` is not a permutation")
    })
}

fn label(r: RegisterRef<'_>) -> String {
    match r.param() {
        Some(p) => format!("{p} {}", r.name()),
        None => r.name().to_owned(),
    }
}
