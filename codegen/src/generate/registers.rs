//! One type per register: an alias of the vocabulary crate's `Reg` that names the register's
//! row of the plan, its value type and its access (`Readable` / `Writable` follow from the
//! access, so writing a read-only register does not compile). Enumeration and bit-field value
//! types are emitted beside their register.

use proc_macro2::{Literal, TokenStream};
use quote::quote;

use super::{bitfields, docs, enums, ident};
use crate::ir::{Drive, Register, ValueKind};
use crate::lower::DrivePlan;
use crate::model::Access;
use crate::names;

pub fn emit(drive: &Drive, plan: &DrivePlan, rt: &TokenStream) -> TokenStream {
    let items = drive
        .registers
        .iter()
        .zip(&plan.order)
        .map(|(r, &index)| register(drive, r, index, rt));
    quote! {
        /// This drive: its settings and the plan of its registers, for the generic register
        /// type [`rt::Reg`].
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct Drive;

        impl #rt::DrivePlan for Drive {
            type Settings = Settings;
            const REGISTERS: &'static [#rt::RegisterPlan] = plan::REGISTERS;
            const PROFILE: &'static #rt::Profile = &PROFILE;
            const ROLES: #rt::Roles = plan::ROLES;
        }

        /// Every register of the map, by address (broadcast-only registers last).
        pub static REGISTERS: &[#rt::RegisterPlan] = plan::REGISTERS;

        #(#items)*
    }
}

/// The value type of a register and the items that define it (enumerations, bit fields).
fn value(r: &Register, index: usize, rt: &TokenStream) -> (TokenStream, TokenStream) {
    let row = Literal::usize_unsuffixed(index);
    match r.kind() {
        ValueKind::Word => match (r.def.pair.is_some(), r.def.signed) {
            (false, true) => (quote!(i16), quote!()),
            (false, false) => (quote!(u16), quote!()),
            (true, true) => (quote!(i32), quote!()),
            (true, false) => (quote!(u32), quote!()),
        },
        ValueKind::UnitQuantity | ValueKind::Quantity(_) => (quote!(f64), quote!()),
        ValueKind::Enum(values) => {
            let ty = ident(&names::value_enum(r));
            let what = match &r.def.param {
                Some(p) => format!("{p} {}", r.def.name),
                None => r.def.name.clone(),
            };
            let labels = quote!(plan::REGISTERS[#row].labels());
            let extra = enums::emit(&ty, values, &what, labels, rt);
            (quote!(#ty), extra)
        }
        ValueKind::Bits(fields) => {
            let ty = ident(&names::bits_type(r));
            (quote!(#ty), bitfields::emit(r, fields, index, rt))
        }
    }
}

fn register(drive: &Drive, r: &Register, index: usize, rt: &TokenStream) -> TokenStream {
    let type_name = names::register_type(r);
    let marker = ident(&type_name);
    let doc = docs::item(&docs::register(drive, r));
    let aliases = docs::aliases(drive, r, &type_name);
    // One attribute for all of them (rustdoc's list form), not one line each.
    let aliases = (!aliases.is_empty()).then(|| quote!(#[doc(alias(#(#aliases),*))]));
    let (mut value, mut extra) = value(r, index, rt);
    let mut access = match r.access {
        Access::Read => quote!(ReadOnly),
        Access::Write => quote!(WriteOnly),
        Access::ReadWrite => quote!(ReadWrite),
    };
    if !r.def.read_values.is_empty() {
        // Reads decode to the read enumeration; writes take the word (`ReadWriteAs`).
        let ty = ident(&names::read_enum(r));
        let row = Literal::usize_unsuffixed(index);
        let what = match &r.def.param {
            Some(p) => format!("{p} {} as read", r.def.name),
            None => format!("{} as read", r.def.name),
        };
        let labels = quote!(plan::REGISTERS[#row].read_values);
        let read = enums::emit(&ty, &r.def.read_values, &what, labels, rt);
        access = quote!(#rt::ReadWriteAs<#value>);
        value = quote!(#ty);
        extra = quote!(#extra #read);
    }
    let index = Literal::usize_unsuffixed(index);
    quote! {
        #extra

        #doc
        #aliases
        pub type #marker = Reg<Drive, #value, #access, #index>;
    }
}
