//! Enumerations of codes, with an `Unknown(u16)` fallback so device data never panics.

use proc_macro2::{Ident, TokenStream};
use quote::quote;

use super::{docs, ident};
use crate::model::EnumValue;
use crate::validate::pascal_case;

/// An enum type named `ty` for `values`; `what` describes it in rustdoc.
pub fn emit(ty: &Ident, values: &[EnumValue], what: &str, rt: &TokenStream) -> TokenStream {
    let variants: Vec<Ident> = values.iter().map(|v| ident(&pascal_case(&v.id))).collect();
    let codes: Vec<proc_macro2::Literal> = values
        .iter()
        .map(|v| proc_macro2::Literal::u16_unsuffixed(v.value))
        .collect();
    let names: Vec<&str> = values.iter().map(|v| v.name.as_str()).collect();
    let decls = values.iter().zip(&variants).map(|(v, var)| {
        let text = match &v.source {
            Some(s) => format!("{}: {} (`{s}`)", v.value, v.name),
            None => format!("{}: {}", v.value, v.name),
        };
        let doc = docs::item(&text);
        quote!(#doc #var,)
    });
    let doc = docs::item(&format!("Codes of {what}."));
    quote! {
        #doc
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[non_exhaustive]
        pub enum #ty {
            #(#decls)*
            /// A code the manual does not list (as read from the device). Refused when written.
            Unknown(u16),
        }

        impl #ty {
            /// Every code the manual lists, in its order.
            pub const ALL: &'static [#ty] = &[#(#ty::#variants),*];

            /// The meaning as printed in the manual, or `None` for an unknown code.
            pub const fn name(&self) -> Option<&'static str> {
                match self {
                    #(#ty::#variants => Some(#names),)*
                    #ty::Unknown(_) => None,
                }
            }
        }

        impl #rt::Code for #ty {
            fn code(&self) -> u16 {
                match self {
                    #(#ty::#variants => #codes,)*
                    #ty::Unknown(code) => *code,
                }
            }

            fn from_code(code: u16) -> Self {
                match code {
                    #(#codes => #ty::#variants,)*
                    other => #ty::Unknown(other),
                }
            }

            fn is_known(&self) -> bool {
                !matches!(self, #ty::Unknown(_))
            }
        }

        impl From<#ty> for u16 {
            fn from(value: #ty) -> u16 {
                #rt::Code::code(&value)
            }
        }

        impl core::fmt::Display for #ty {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                match self.name() {
                    Some(name) => f.write_str(name),
                    None => write!(f, "unknown code {}", #rt::Code::code(self)),
                }
            }
        }
    }
}
