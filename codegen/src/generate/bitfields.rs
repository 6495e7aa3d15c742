//! Bit-field value types: a getter per field and, for registers that can be written, a setter and
//! a `with_*` builder per field; reserved bits kept 0.

use proc_macro2::TokenStream;
use quote::{format_ident, quote};

use super::{docs, enums, ident};
use crate::ir::Register;
use crate::model::Field;
use crate::names;
use crate::validate::field_span;

pub fn emit(r: &Register, fields: &[Field], index: usize, rt: &TokenStream) -> TokenStream {
    let row = proc_macro2::Literal::usize_unsuffixed(index);
    let mut field_index = 0usize;
    let ty = ident(&names::bits_type(r));
    let reg_id = r.id();
    let writable = r.writable();
    let mut mask: u16 = 0;
    let mut methods = Vec::new();
    let mut field_enums = Vec::new();
    let mut debug_fields = Vec::new();
    for f in fields {
        let Some((lo, width)) = field_span(f) else {
            continue;
        };
        let fi = proc_macro2::Literal::usize_unsuffixed(field_index);
        field_index += 1;
        let fmask: u16 = (((1u32 << width) - 1) << lo) as u16;
        mask |= fmask;
        let fm = super::hex(fmask);
        let get = ident(&f.id);
        let set = format_ident!("set_{}", f.id);
        let with = format_ident!("with_{}", f.id);
        let fname = &f.id;
        let lo_lit = proc_macro2::Literal::u8_unsuffixed(lo);
        // The field's bits brought down to bit 0 and a value put up in place, written without
        // a shift by zero for a field that starts at bit 0.
        let down = if lo == 0 {
            quote!(self.0 & #fm)
        } else {
            quote!((self.0 & #fm) >> #lo_lit)
        };
        let up = |v: TokenStream| if lo == 0 { v } else { quote!((#v << #lo_lit)) };
        let up_value = up(quote!(value));
        let up_code = up(quote!(code));
        let set_doc = format!(" Sets `{fname}`.");
        let with_doc = format!(" This value with `{fname}` set to `on`.");
        let with_wide_doc = format!(
            " This value with `{fname}` set to `value`; a value wider than the field is refused."
        );
        let with_enum_doc = format!(
            " This value with `{fname}` set to `value`; an unknown or too wide code is refused."
        );
        let set_wide_doc = format!(" Sets `{fname}`; a value wider than the field is refused.");
        let set_enum_doc = format!(" Sets `{fname}`; an unknown or too wide code is refused.");
        let where_ = if width == 1 {
            format!("bit {lo}")
        } else {
            format!("bits {lo}..={}", lo + width - 1)
        };
        let mut text = format!("{where_}: {}", f.name);
        if let Some(s) = &f.source {
            text += &format!(" (`{s}`)");
        }
        for n in &f.notes {
            text += &format!("\n\nNote: {n}");
        }
        let doc = docs::item(&text);
        if width == 1 && f.values.is_empty() {
            methods.push(quote! {
                #doc
                #[inline]
                pub const fn #get(&self) -> bool { self.0 & #fm != 0 }
            });
            if writable {
                methods.push(quote! {
                    #[doc = #set_doc]
                    #[inline]
                    pub fn #set(&mut self, on: bool) -> &mut Self {
                        if on { self.0 |= #fm } else { self.0 &= !#fm }
                        self
                    }
                    #[doc = #with_doc]
                    #[inline]
                    pub const fn #with(self, on: bool) -> Self {
                        Self(if on { self.0 | #fm } else { self.0 & !#fm })
                    }
                });
            }
            debug_fields.push(quote!(.field(#fname, &self.#get())));
        } else if f.values.is_empty() {
            let max = proc_macro2::Literal::u16_unsuffixed(((1u32 << width) - 1) as u16);
            let max_f = proc_macro2::Literal::f64_unsuffixed(((1u32 << width) - 1) as f64);
            methods.push(quote! {
                #doc
                #[inline]
                pub const fn #get(&self) -> u16 { #down }
            });
            if writable {
                methods.push(quote! {
                #[doc = #set_wide_doc]
                #[inline]
                pub fn #set(&mut self, value: u16) -> Result<&mut Self, #rt::ValueError> {
                    if value > #max {
                        return Err(#rt::ValueError::OutOfRange { register: #reg_id, value: value as f64, min: 0.0, max: #max_f, unit: "" });
                    }
                    self.0 = (self.0 & !#fm) | #up_value;
                    Ok(self)
                }
                #[doc = #with_wide_doc]
                #[inline]
                pub fn #with(mut self, value: u16) -> Result<Self, #rt::ValueError> {
                    self.#set(value)?;
                    Ok(self)
                }
            });
            }
            debug_fields.push(quote!(.field(#fname, &self.#get())));
        } else {
            let ety = ident(&names::field_enum(r, f));
            field_enums.push(enums::emit(
                &ety,
                &f.values,
                &format!("field `{}` of `{}`", f.id, reg_id),
                quote!(plan::REGISTERS[#row].field_labels(#fi)),
                rt,
            ));
            let max = proc_macro2::Literal::u16_unsuffixed(((1u32 << width) - 1) as u16);
            methods.push(quote! {
                #doc
                #[inline]
                pub fn #get(&self) -> #ety { <#ety as #rt::Code>::from_code(#down) }
            });
            if writable {
                methods.push(quote! {
                    #[doc = #set_enum_doc]
                    #[inline]
                    pub fn #set(&mut self, value: #ety) -> Result<&mut Self, #rt::ValueError> {
                        let code = #rt::Code::code(&value);
                        if !#rt::Code::is_known(&value) || code > #max {
                            return Err(#rt::ValueError::UnknownCode { register: #reg_id, code });
                        }
                        self.0 = (self.0 & !#fm) | #up_code;
                        Ok(self)
                    }
                    #[doc = #with_enum_doc]
                    #[inline]
                    pub fn #with(mut self, value: #ety) -> Result<Self, #rt::ValueError> {
                        self.#set(value)?;
                        Ok(self)
                    }
                });
            }
            debug_fields.push(quote!(.field(#fname, &self.#get())));
        }
    }
    let doc = docs::item(&format!(
        "Bit fields of `{}`; bits outside `{mask:#06x}` are reserved and always 0.",
        r.def.name
    ));
    let ty_name = ty.to_string();
    let mask_lit = super::hex(mask);
    quote! {
        #(#field_enums)*

        #doc
        #[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct #ty(u16);

        impl #ty {
            /// Bits that carry a field.
            pub const MASK: u16 = #mask_lit;

            /// All fields 0.
            #[inline]
            pub const fn new() -> Self { Self(0) }

            /// The raw word (reserved bits 0).
            #[inline]
            pub const fn raw(&self) -> u16 { self.0 }

            #(#methods)*
        }

        impl #rt::Code for #ty {
            #[inline]
            fn code(&self) -> u16 { self.0 }
            #[inline]
            fn from_code(code: u16) -> Self { Self(code & Self::MASK) }
            #[inline]
            fn is_known(&self) -> bool { true }
        }

        impl #rt::Bits for #ty {
            const MASK: u16 = #mask_lit;
        }

        impl core::fmt::Debug for #ty {
            #[inline]
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.debug_struct(#ty_name)#(#debug_fields)*.finish()
            }
        }
    }
}
