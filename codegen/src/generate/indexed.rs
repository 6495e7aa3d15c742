//! Indexed access in the generated module: the plan's index/value pairs as `const` data
//! (`INDEXED`) and a typed handle per listed entry (`entries::<ID>`, an `EntryRef` for the
//! clients' `read_entry`/`write_entry`). Emitted only for a map with `indexed:`.

use proc_macro2::{Literal, TokenStream};
use quote::{format_ident, quote};

use drivemap_core::indexed::Entry;
use drivemap_core::register::{Access, Table};
use drivemap_map::MapPlan;

fn access(a: Access, rt: &TokenStream) -> TokenStream {
    match a {
        Access::Read => quote!(#rt::register::Access::Read),
        Access::Write => quote!(#rt::register::Access::Write),
        Access::ReadWrite => quote!(#rt::register::Access::ReadWrite),
    }
}

fn opt_str(s: Option<&str>) -> TokenStream {
    match s {
        Some(s) => quote!(Some(#s)),
        None => quote!(None),
    }
}

fn entry(e: &Entry, rt: &TokenStream) -> TokenStream {
    let (id, name, unit, source) = (e.id, e.name, e.unit, e.source);
    let index = Literal::u16_unsuffixed(e.index);
    let signed = e.signed;
    let (mantissa, exponent) = (
        Literal::i64_unsuffixed(e.scale.mantissa),
        Literal::u32_unsuffixed(e.scale.exponent),
    );
    let (min, max) = (
        Literal::i64_unsuffixed(e.range.min),
        Literal::i64_unsuffixed(e.range.max),
    );
    let acc = access(e.access, rt);
    let address = super::hex(e.rule.address);
    let (rtu, tcp) = (e.rule.transports.rtu, e.rule.transports.tcp);
    let f = &e.rule.functions;
    let functions = if f.restricted() {
        let codes = f.codes.iter().map(|c| Literal::u8_unsuffixed(*c));
        let (refused, fsource) = (Literal::u8_unsuffixed(f.refused_with), f.source);
        quote!(#rt::functions::Functions::only(&[#(#codes),*], #refused, #fsource))
    } else {
        quote!(#rt::functions::Functions::ANY)
    };
    quote! {
        #rt::indexed::Entry {
            id: #id,
            name: #name,
            index: #index,
            unit: #unit,
            signed: #signed,
            scale: #rt::scale::Decimal { mantissa: #mantissa, exponent: #exponent },
            range: #rt::scale::RawRange { min: #min, max: #max },
            access: #acc,
            rule: #rt::rule::WriteRule {
                register: #id,
                access: #acc,
                broadcast: #rt::rule::Broadcast::No,
                transports: #rt::rule::Transports { rtu: #rtu, tcp: #tcp },
                address: #address,
                also_at: &[],
                raw: #rt::scale::RawRange { min: #min, max: #max },
                reserved: 0,
                width: #rt::width::Width::Word,
                functions: #functions,
                table: #rt::register::Table::Holding,
            },
            source: #source,
        }
    }
}

/// The items, or nothing for a drive without indexed access.
pub(super) fn emit(plan: &MapPlan, rt: &TokenStream) -> TokenStream {
    if plan.indexed.is_empty() {
        return TokenStream::new();
    }
    let pairs = plan.indexed.iter().map(|p| {
        let entries = p.entries.iter().map(|e| entry(e, rt));
        let (register, index_register, source) = (p.register, p.index_register, p.source);
        let (value_address, index_address) =
            (super::hex(p.value_address), super::hex(p.index_address));
        let table = match p.table {
            Table::Holding => quote!(#rt::register::Table::Holding),
            Table::Input => quote!(#rt::register::Table::Input),
            Table::Coil => quote!(#rt::register::Table::Coil),
            Table::DiscreteInput => quote!(#rt::register::Table::DiscreteInput),
        };
        let readable = p.index_readable;
        let (min, max) = (
            Literal::i64_unsuffixed(p.index_range.min),
            Literal::i64_unsuffixed(p.index_range.max),
        );
        let unknown = opt_str(p.unknown);
        quote! {
            #rt::indexed::Indexed {
                register: #register,
                value_address: #value_address,
                table: #table,
                index_register: #index_register,
                index_address: #index_address,
                index_readable: #readable,
                index_range: #rt::scale::RawRange { min: #min, max: #max },
                entries: &[#(#entries),*],
                unknown: #unknown,
                source: #source,
            }
        }
    });
    let handles = plan.indexed.iter().enumerate().flat_map(|(i, p)| {
        p.entries.iter().enumerate().map(move |(k, e)| {
            let name = format_ident!("{}", e.id.to_uppercase());
            let unit = if e.unit.is_empty() { String::new() } else { format!(", {}", e.unit) };
            let doc = format!(
                " {} (index {} of `{}` through `{}`{unit}; {}): `client.read_entry(slave, {})`. Source: `{}`.",
                e.name,
                e.index,
                p.register,
                p.index_register,
                match e.access {
                    Access::Read => "read-only",
                    Access::Write => "write-only",
                    Access::ReadWrite => "read/write",
                },
                name,
                e.source
            );
            let (i, k) = (Literal::usize_unsuffixed(i), Literal::usize_unsuffixed(k));
            quote! {
                #[doc = #doc]
                pub const #name: #rt::indexed::EntryRef = #rt::indexed::EntryRef {
                    pair: &super::INDEXED[#i],
                    entry: &super::INDEXED[#i].entries[#k],
                };
            }
        })
    });
    quote! {
        /// Index/value register pairs (`indexed:` in the map): each value register shows the
        /// entry whose index is written to its index register. The clients' `read_entry` and
        /// `write_entry` take an entry's handle from [`entries`].
        pub const INDEXED: &[#rt::indexed::Indexed] = &[#(#pairs),*];

        /// A typed handle for each entry of an indexed register the manual lists.
        pub mod entries {
            use super::rt;
            #(#handles)*
        }
    }
}
