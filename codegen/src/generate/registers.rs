//! One zero-sized type per register implementing the runtime's `Register`, `Readable` and
//! `Writable` (only where the manual allows), with the conversions and range checks of its kind,
//! and the `REGISTERS` table.

use proc_macro2::{Literal, TokenStream};
use quote::quote;

use super::settings::{selector_code, setting_label};
use super::{bitfields, docs, enums, hex, ident, opt_str};
use crate::ir::{BroadcastUse, Drive, RawLimits, Register, ValueKind};
use crate::model::{
    Access, Condition, ModbusTable, Reference, Scale, TransportName, WriteRestriction,
};
use crate::names;
use crate::numbers::Dec;
use crate::validate::pascal_case;

pub fn emit(drive: &Drive, rt: &TokenStream) -> TokenStream {
    let items = drive.registers.iter().map(|r| register(drive, r, rt));
    let mut sorted: Vec<&Register> = drive.registers.iter().collect();
    sorted.sort_by_key(|r| (r.broadcast, r.def.address));
    let infos = sorted.iter().map(|r| info(r, rt));
    quote! {
        #(#items)*

        /// Every register of the map, by address (broadcast-only registers last).
        pub static REGISTERS: &[#rt::RegisterInfo] = &[#(#infos),*];
    }
}

fn table(t: ModbusTable, rt: &TokenStream) -> TokenStream {
    match t {
        ModbusTable::Holding => quote!(#rt::Table::Holding),
        ModbusTable::Input => quote!(#rt::Table::Input),
    }
}

fn info(r: &Register, rt: &TokenStream) -> TokenStream {
    let d = &r.def;
    let (id, name, addr) = (&d.id, &d.name, hex(d.address));
    let param = opt_str(&d.param);
    let source = d.source.clone().unwrap_or_default();
    let access = match r.access {
        Access::Read => quote!(#rt::Access::Read),
        Access::Write => quote!(#rt::Access::Write),
        Access::ReadWrite => quote!(#rt::Access::ReadWrite),
    };
    let t = table(r.table, rt);
    let b = r.broadcast;
    quote!(#rt::RegisterInfo { id: #id, param: #param, name: #name, address: #addr, access: #access, table: #t, broadcast_only: #b, source: #source })
}

/// The register's [`WriteRule`](crate::ir::WriteRuleFigures), as decided by the IR: a
/// constructor call, with builder calls only for what differs from the common case.
fn write_rule(drive: &Drive, r: &Register, rt: &TokenStream) -> TokenStream {
    let w = drive.write_rule(r);
    let (min, max) = (lit_i(w.raw.min), lit_i(w.raw.max));
    let mut rule = match r.access {
        Access::Write => quote!(#rt::WriteRule::write_only(Self::ID, Self::ADDRESS, #min, #max)),
        _ => quote!(#rt::WriteRule::rw(Self::ID, Self::ADDRESS, #min, #max)),
    };
    match w.broadcast {
        BroadcastUse::No => {}
        BroadcastUse::Also => rule = quote!(#rule.broadcast(#rt::Broadcast::Also)),
        BroadcastUse::Only => rule = quote!(#rule.broadcast(#rt::Broadcast::Only)),
    }
    match (w.rtu, w.tcp) {
        (true, true) => {}
        (true, false) => rule = quote!(#rule.on(#rt::Transports::RTU)),
        (false, true) => rule = quote!(#rule.on(#rt::Transports::TCP)),
        (false, false) => rule = quote!(#rule.on(#rt::Transports { rtu: false, tcp: false })),
    }
    if !w.also_at.is_empty() {
        let also = w.also_at.iter().map(|a| hex(*a));
        rule = quote!(#rule.also_at(&[#(#also),*]));
    }
    if w.reserved != 0 {
        let reserved = hex(w.reserved);
        rule = quote!(#rule.reserved(#reserved));
    }
    rule
}

fn lit_i(v: i128) -> Literal {
    Literal::i64_unsuffixed(v as i64)
}

fn raw_range(l: RawLimits, rt: &TokenStream) -> TokenStream {
    let (min, max) = (lit_i(l.min), lit_i(l.max));
    quote!(#rt::scale::RawRange { min: #min, max: #max })
}

/// The range for the variant in `settings`, for a fixed decimal factor.
fn variant_range(drive: &Drive, r: &Register, factor: Dec, rt: &TokenStream) -> TokenStream {
    let word = RawLimits::word(r.def.signed);
    let base = r.raw_limits(factor, r.def.min, r.def.max).unwrap_or(word);
    let mut arms = Vec::new();
    let mut axis_field = None;
    for k in r.def.by_variant.keys() {
        let Some((axis, option)) = drive.variant_option(k) else {
            continue;
        };
        let (min, max) = r.limits_for(k);
        let lim = r.raw_limits(factor, min, max).unwrap_or(word);
        if lim != base {
            let ty = ident(&names::axis_enum(axis));
            let v = ident(&pascal_case(&option.id));
            let range = raw_range(lim, rt);
            arms.push(quote!(#ty::#v => #range,));
            axis_field = Some(ident(&axis.id));
        }
    }
    let base = raw_range(base, rt);
    match axis_field {
        None => base,
        Some(field) => quote!(match settings.#field { #(#arms)* _ => #base }),
    }
}

fn decimal(factor: Dec, rt: &TokenStream) -> TokenStream {
    let m = Literal::i64_unsuffixed(factor.mantissa as i64);
    let e = Literal::u32_unsuffixed(factor.exponent);
    quote!(#rt::scale::Decimal::new(#m, #e))
}

/// Expression of the reference value (an `f64`) or an early `MissingSetting` return.
fn reference(drive: &Drive, reference: &Reference, rt: &TokenStream) -> (TokenStream, String) {
    let (field, label) = match reference {
        Reference::Register(name) => match drive.find(name) {
            Some(t) => (ident(t.id()), setting_label(t)),
            None => (ident(name), name.clone()),
        },
        Reference::External(q) => (ident(&q.external), q.external.clone()),
    };
    (
        quote!(settings.#field.ok_or(#rt::ValueError::MissingSetting { register: Self::ID, setting: #label })?),
        label,
    )
}

struct Bodies {
    value: TokenStream,
    decode: TokenStream,
    encode: TokenStream,
    extra: TokenStream,
}

fn bodies(drive: &Drive, r: &Register, rt: &TokenStream) -> Bodies {
    let signed = r.def.signed;
    let unit = r.def.unit.clone().unwrap_or_default();
    let one = Dec {
        mantissa: 1,
        exponent: 0,
    };
    match r.kind() {
        ValueKind::Word => {
            let range = variant_range(drive, r, one, rt);
            let (value, decode, encode) = if signed {
                (
                    quote!(i16),
                    quote!(Ok(raw as i16)),
                    quote!(#rt::scale::encode_int(Self::ID, #unit, i64::from(*value), #range)),
                )
            } else {
                (
                    quote!(u16),
                    quote!(Ok(raw)),
                    quote!(#rt::scale::encode_int(Self::ID, #unit, i64::from(*value), #range)),
                )
            };
            Bodies {
                value,
                decode,
                encode,
                extra: quote!(),
            }
        }
        ValueKind::UnitQuantity | ValueKind::Quantity(Scale::Factor(_)) => {
            let factor = r.factor().unwrap_or(one);
            let dec = decimal(factor, rt);
            let range = variant_range(drive, r, factor, rt);
            Bodies {
                value: quote!(f64),
                decode: quote!(Ok(#rt::scale::decode_decimal(raw, #signed, #dec))),
                encode: quote!(#rt::scale::encode_decimal(Self::ID, #unit, *value, #dec, #range)),
                extra: quote!(),
            }
        }
        ValueKind::Quantity(Scale::Relative(rel)) => {
            let (get, label) = reference(drive, &rel.relative_to, rt);
            let full = super::float(rel.full_scale);
            Bodies {
                value: quote!(f64),
                decode: quote! {
                    let reference = #get;
                    Ok(#rt::scale::decode_relative(raw, #signed, #full, reference))
                },
                encode: quote! {
                    let reference = #get;
                    #rt::scale::encode_relative(Self::ID, #label, #unit, *value, #full, reference, #rt::scale::RawRange::word(#signed))
                },
                extra: quote!(),
            }
        }
        ValueKind::Quantity(Scale::Selected(sel)) => {
            let Some(selector) = drive.find(&sel.selected_by) else {
                unreachable!("validated: selector resolves")
            };
            let code = selector_code(selector);
            let label = setting_label(selector);
            let mut dec_arms = Vec::new();
            let mut enc_arms = Vec::new();
            for case in &sel.cases {
                let codes: Vec<Literal> = case
                    .when
                    .iter()
                    .map(|c| Literal::u16_unsuffixed(*c))
                    .collect();
                match &case.scale {
                    Scale::Factor(f) => {
                        let factor = Dec::from_f64(*f).unwrap_or(one);
                        let dec = decimal(factor, rt);
                        let lim = r
                            .raw_limits(factor, case.min, case.max)
                            .unwrap_or(RawLimits::word(signed));
                        let range = raw_range(lim, rt);
                        dec_arms.push(quote!(#(#codes)|* => Ok(#rt::scale::decode_decimal(raw, #signed, #dec)),));
                        enc_arms.push(quote!(#(#codes)|* => #rt::scale::encode_decimal(Self::ID, #unit, *value, #dec, #range),));
                    }
                    Scale::Relative(rel) => {
                        let (get, rlabel) = reference(drive, &rel.relative_to, rt);
                        let full = super::float(rel.full_scale);
                        dec_arms.push(quote!(#(#codes)|* => { let reference = #get; Ok(#rt::scale::decode_relative(raw, #signed, #full, reference)) }));
                        enc_arms.push(quote!(#(#codes)|* => { let reference = #get; #rt::scale::encode_relative(Self::ID, #rlabel, #unit, *value, #full, reference, #rt::scale::RawRange::word(#signed)) }));
                    }
                    Scale::Selected(_) => {}
                }
            }
            let head = quote! {
                let code = #code.ok_or(#rt::ValueError::MissingSetting { register: Self::ID, setting: #label })?;
            };
            let other = quote!(other => Err(#rt::ValueError::UnsupportedSetting { register: Self::ID, setting: #label, code: other }),);
            Bodies {
                value: quote!(f64),
                decode: quote!(#head match code { #(#dec_arms)* #other }),
                encode: quote!(#head match code { #(#enc_arms)* #other }),
                extra: quote!(),
            }
        }
        ValueKind::Enum(values) => {
            let ty = ident(&names::value_enum(r));
            // Codes the manual's range admits but whose meaning it does not print.
            let unlisted = match (r.def.min, r.def.max) {
                (None, None) => quote!(false),
                (min, max) => {
                    let lo = lit_i(min.map(|m| m as i128).unwrap_or(0));
                    let hi = lit_i(max.map(|m| m as i128).unwrap_or(65535));
                    quote!((#lo..=#hi).contains(&i64::from(#rt::Code::code(value))))
                }
            };
            let what = match &r.def.param {
                Some(p) => format!("{p} {}", r.def.name),
                None => r.def.name.clone(),
            };
            Bodies {
                extra: enums::emit(&ty, values, &what, rt),
                value: quote!(#ty),
                decode: quote!(Ok(<#ty as #rt::Code>::from_code(raw))),
                encode: quote! {
                    if !#rt::Code::is_known(value) && !#unlisted {
                        return Err(#rt::ValueError::UnknownCode { register: Self::ID, code: #rt::Code::code(value) });
                    }
                    Ok(#rt::Code::code(value))
                },
            }
        }
        ValueKind::Bits(fields) => {
            let ty = ident(&names::bits_type(r));
            Bodies {
                extra: bitfields::emit(r, fields, rt),
                value: quote!(#ty),
                decode: quote!(Ok(<#ty as #rt::Bits>::from_bits(raw))),
                encode: quote!(Ok(#rt::Bits::bits(value))),
            }
        }
    }
}

fn condition(drive: &Drive, w: &Condition, rt: &TokenStream) -> TokenStream {
    if let Some(s) = &w.setting {
        if let Some(sel) = drive.find(s) {
            let code = selector_code(sel);
            let is = w.is.iter().map(|c| Literal::u16_unsuffixed(*c));
            return quote!(matches!(#code, Some(#(#is)|*)));
        }
    }
    if let Some(v) = &w.variant {
        if let Some((axis, option)) = drive.variant_option(v) {
            let field = ident(&axis.id);
            let ty = ident(&names::axis_enum(axis));
            let opt = ident(&pascal_case(&option.id));
            return quote!(settings.#field == #ty::#opt);
        }
    }
    match w.transport {
        Some(TransportName::Tcp) => quote!(transport == #rt::profile::TransportKind::Tcp),
        Some(TransportName::Rtu) => quote!(transport != #rt::profile::TransportKind::Tcp),
        None => quote!(false),
    }
}

fn register(drive: &Drive, r: &Register, rt: &TokenStream) -> TokenStream {
    let d = &r.def;
    let marker = ident(&names::register_type(r));
    let doc = docs::item(&docs::register(drive, r));
    let Bodies {
        value,
        decode,
        encode,
        extra,
    } = bodies(drive, r, rt);
    let (id, name, addr) = (&d.id, &d.name, hex(d.address));
    let param = opt_str(&d.param);
    let source = d.source.clone().unwrap_or_default();
    let t = table(r.table, rt);
    let address_fn = if d.address_alternatives.is_empty() {
        quote!()
    } else {
        let alts = d.address_alternatives.iter().map(|a| {
            let cond = condition(drive, &a.when, rt);
            let to = hex(a.address);
            quote!(if #cond { return #to; })
        });
        quote! {
            fn address(settings: &Settings, transport: #rt::profile::TransportKind) -> u16 {
                #(#alts)*
                Self::ADDRESS
            }
        }
    };
    let on_transport = match &r.transports {
        None => quote!(),
        Some(list) => {
            let kinds = list.iter().map(|t| match t {
                TransportName::Rtu => quote!(#rt::profile::TransportKind::Rtu | #rt::profile::TransportKind::RtuOverTcp),
                TransportName::Tcp => quote!(#rt::profile::TransportKind::Tcp),
            });
            quote! {
                fn on_transport(transport: #rt::profile::TransportKind) -> bool {
                    matches!(transport, #(#kinds)|*)
                }
            }
        }
    };
    let readable = if r.readable() {
        quote!(impl #rt::Readable for #marker {})
    } else {
        quote!()
    };
    let writable = if r.writable() {
        let restriction = match r.write_restriction {
            WriteRestriction::None => quote!(#rt::WriteRestriction::None),
            WriteRestriction::Stopped => quote!(#rt::WriteRestriction::Stopped),
            WriteRestriction::PrgMode => quote!(#rt::WriteRestriction::PrgMode),
        };
        let rule = write_rule(drive, r, rt);
        quote! {
            impl #rt::Writable for #marker {
                const WRITE_RESTRICTION: #rt::WriteRestriction = #restriction;
                const RULE: #rt::WriteRule = #rule;

                fn encode(value: &#value, settings: &Settings) -> Result<u16, #rt::ValueError> {
                    #encode
                }
            }
        }
    } else {
        quote!()
    };
    let bit_register = if let ValueKind::Bits(_) = r.kind() {
        let ty = ident(&names::bits_type(r));
        quote!(impl #rt::BitRegister for #marker { const FIELD_MASK: u16 = #ty::MASK; })
    } else {
        quote!()
    };
    let unit = match &d.unit {
        Some(u) => quote! {
            impl #marker {
                /// Engineering unit of the value.
                pub const UNIT: &'static str = #u;
            }
        },
        None => quote!(),
    };
    quote! {
        #extra

        #doc
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct #marker;

        #unit

        impl #rt::Register for #marker {
            type Value = #value;
            type Settings = Settings;

            const ID: &'static str = #id;
            const PARAM: Option<&'static str> = #param;
            const NAME: &'static str = #name;
            const ADDRESS: u16 = #addr;
            const TABLE: #rt::Table = #t;
            const SOURCE: &'static str = #source;

            #address_fn
            #on_transport

            fn decode(raw: u16, settings: &Settings) -> Result<#value, #rt::ValueError> {
                #decode
            }
        }

        #readable
        #writable
        #bit_register
    }
}
