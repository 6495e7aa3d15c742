//! Enumerations of codes, with an `Unknown(u16)` fallback so device data never panics; equal
//! by code (`rt::enumeration!`).

use proc_macro2::{Ident, TokenStream};
use quote::quote;

use super::{docs, ident};
use crate::describe::pascal_case;
use crate::facts::EnumValue;

/// An enum type named `ty` for `values`; `what` describes it in rustdoc; `labels` is the
/// expression of its labels in the plan (`plan::REGISTERS[3].labels()`).
pub(super) fn emit(
    ty: &Ident,
    values: &[EnumValue],
    what: &str,
    labels: TokenStream,
    rt: &TokenStream,
) -> TokenStream {
    let variants: Vec<Ident> = values.iter().map(|v| ident(&pascal_case(&v.id))).collect();
    let decls = values.iter().zip(&variants).map(|(v, var)| {
        let text = match &v.source {
            Some(s) => format!("{}: {} (`{s}`)", v.value, v.name),
            None => format!("{}: {}", v.value, v.name),
        };
        let doc = docs::item(&text);
        quote!(#doc #var,)
    });
    let doc = docs::item(&format!(
        "Codes of {what}; equal by code (`Unknown(c)` is the listed variant of code c)."
    ));
    quote! {
        #doc
        #[derive(Debug, Clone, Copy)]
        #[non_exhaustive]
        pub enum #ty {
            #(#decls)*
            /// A code the manual does not list (as read from the device). Refused when written.
            Unknown(u16),
        }

        // `Enumeration` (variants in the order of the labels), `Display`, and `PartialEq`,
        // `Eq` and `Hash` by code: `Unknown(c)` equals the listed variant whose code is c.
        #rt::enumeration!(#ty, #labels, [#(#variants),*]);
    }
}
