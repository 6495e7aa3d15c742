//! One type per register: an alias of the vocabulary crate's `Reg` that names the register's
//! row of the plan, its value type and its access (`Readable` / `Writable` follow from the
//! access, so writing a read-only register does not compile). Enumeration and bit-field value
//! types are emitted beside their register.

use proc_macro2::{Literal, TokenStream};
use quote::quote;

use super::{bitfields, docs, enums, ident};
use drivemap_core::plan::ValueShape;
use drivemap_core::register::Access;
use drivemap_map::{Map, MapPlan, RegisterRef};

pub(super) fn emit(drive: &Map, plan: &MapPlan, rt: &TokenStream) -> TokenStream {
    let items = drive
        .registers()
        .zip(&plan.order)
        .map(|(r, &index)| register(r, index, rt));
    quote! {
        /// This drive: its settings and the plan of its registers, for the generic register
        /// type [`rt::register::Reg`].
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct Drive;

        impl #rt::register::DrivePlan for Drive {
            type Settings = Settings;
            const REGISTERS: &'static [#rt::plan::RegisterPlan] = plan::REGISTERS;
            const PROFILE: &'static #rt::profile::Profile = &PROFILE;
            const ROLES: #rt::roles::Roles = plan::ROLES;
        }

        /// Every register of the map, by address (broadcast-only registers last).
        pub static REGISTERS: &[#rt::plan::RegisterPlan] = plan::REGISTERS;

        #(#items)*
    }
}

/// The value type of a register and the items that define it (enumerations, bit fields).
fn value(r: RegisterRef<'_>, index: usize, rt: &TokenStream) -> (TokenStream, TokenStream) {
    let row = Literal::usize_unsuffixed(index);
    let plan = r.plan();
    if plan.info.table.is_bits() {
        // A coil or discrete input: on or off.
        return (quote!(bool), quote!());
    }
    match plan.conversion.shape() {
        ValueShape::Word { signed } => match (plan.info.width.count() == 2, signed) {
            (false, true) => (quote!(i16), quote!()),
            (false, false) => (quote!(u16), quote!()),
            (true, true) => (quote!(i32), quote!()),
            (true, false) => (quote!(u32), quote!()),
        },
        ValueShape::Number => (quote!(f64), quote!()),
        // Text: two characters per register, decoded from all of them in one read.
        ValueShape::Text { .. } => {
            let chars = Literal::usize_unsuffixed(2 * usize::from(plan.info.width.count()));
            (quote!(#rt::text::Text<#chars>), quote!())
        }
        ValueShape::Codes(_) => {
            let ty = ident(&r.value_enum_name());
            let what = match r.param() {
                Some(p) => format!("{p} {}", r.name()),
                None => r.name().to_owned(),
            };
            let labels = quote!(plan::REGISTERS[#row].labels());
            let extra = enums::emit(&ty, r.values(), &what, labels, rt);
            (quote!(#ty), extra)
        }
        ValueShape::Bits { .. } => {
            let ty = ident(&r.bits_type_name());
            (quote!(#ty), bitfields::emit(r, index, rt))
        }
    }
}

fn register(r: RegisterRef<'_>, index: usize, rt: &TokenStream) -> TokenStream {
    let type_name = r.type_name();
    let marker = ident(&type_name);
    let doc = docs::item(&docs::register(r));
    let aliases = docs::aliases(r, &type_name);
    // One attribute for all of them (rustdoc's list form), not one line each.
    let aliases = (!aliases.is_empty()).then(|| quote!(#[doc(alias(#(#aliases),*))]));
    let (mut value, mut extra) = value(r, index, rt);
    let mut access = match r.plan().info.access {
        Access::Read => quote!(ReadOnly),
        Access::Write => quote!(WriteOnly),
        Access::ReadWrite => quote!(ReadWrite),
    };
    if !r.read_values().is_empty() {
        // Reads decode to the read enumeration; writes take the word (`ReadWriteAs`).
        let ty = ident(&r.read_enum_name());
        let row = Literal::usize_unsuffixed(index);
        let what = match r.param() {
            Some(p) => format!("{p} {} as read", r.name()),
            None => format!("{} as read", r.name()),
        };
        let labels = quote!(plan::REGISTERS[#row].read_values);
        let read = enums::emit(&ty, r.read_values(), &what, labels, rt);
        access = quote!(#rt::register::ReadWriteAs<#value>);
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
