//! The drive's protocol profile as a `static PROFILE: Profile`, printed from the plan's profile
//! ([`MapPlan::profile`], which the lowering pass builds once and `drivemap-live` uses as it
//! is); its write table is derived from the plan rows at compile time
//! (`rt::plan::write_rules`), not listed.

use proc_macro2::TokenStream;
use quote::quote;

use super::hex;
use drivemap_core::profile::{CommandKind, Parity};
use drivemap_map::MapPlan;

pub(super) fn emit(plan: &MapPlan, rt: &TokenStream) -> TokenStream {
    let p = plan.profile;
    let id = p.drive_id;
    let fcs = p.function_codes.iter().map(|f| hex2(*f));
    let max_read = proc_macro2::Literal::u16_unsuffixed(p.max_read);
    let max_write = proc_macro2::Literal::u16_unsuffixed(p.max_write);
    let max_read_bits = proc_macro2::Literal::u16_unsuffixed(p.max_read_bits);
    let max_write_bits = proc_macro2::Literal::u16_unsuffixed(p.max_write_bits);
    let slave_min = proc_macro2::Literal::u8_unsuffixed(p.slave_min);
    let slave_max = proc_macro2::Literal::u8_unsuffixed(p.slave_max);
    let broadcast = match &p.broadcast {
        None => quote!(None),
        Some(b) => match b.not_printed {
            Some(why) => quote!(Some(#rt::profile::BroadcastInfo::not_printed(#why))),
            None => {
                let addrs = b.addresses.iter().map(|a| hex(*a));
                let fns = b.functions.iter().map(|f| hex2(*f));
                quote!(Some(#rt::profile::BroadcastInfo::new(&[#(#fns),*], &[#(#addrs),*])))
            }
        },
    };
    let exceptions = p.exceptions.iter().map(|e| {
        let (code, name, desc) = (hex2(e.code), e.name, e.description);
        quote!(#rt::profile::ExceptionInfo { code: #code, name: #name, description: #desc })
    });
    let commands = p.commands.iter().map(|c| {
        let (cid, name, source) = (c.id, c.name, c.source);
        let kind = match c.kind {
            CommandKind::Accept => quote!(#rt::profile::CommandKind::Accept),
            CommandKind::Persist => quote!(#rt::profile::CommandKind::Persist),
        };
        let writes = c.writes.iter().map(|(a, v)| {
            let (a, v) = (hex(*a), hex(*v));
            quote!((#a, #v))
        });
        quote!(#rt::profile::CommandInfo { id: #cid, name: #name, kind: #kind, writes: &[#(#writes),*], source: #source })
    });
    let rtu_off = proc_macro2::Literal::i32_unsuffixed(p.address_offsets.rtu);
    let tcp_off = proc_macro2::Literal::i32_unsuffixed(p.address_offsets.tcp);
    let t = &p.timing;
    let gap = super::float(t.frame_gap_chars);
    let gap_min_us = opt_u32(t.frame_gap_us);
    let ict_us = opt_u32(t.inter_char_timeout_us);
    let ict_bits = opt_u32(t.inter_char_timeout_bits);
    let resp = opt_u32(t.response_delay_us);
    let resp_param = match t.response_delay_param {
        Some(s) => quote!(Some(#s)),
        None => quote!(None),
    };
    let resp_bits = opt_u32(t.response_delay_bits);
    let resp_param_default = opt_u32(t.response_delay_param_default_us);
    let gap_bits = opt_u32(t.request_gap_bits);
    let gap_us = opt_u32(t.request_gap_us);
    let char_bits = match t.char_bits {
        Some(c) => {
            let c = proc_macro2::Literal::u8_unsuffixed(c);
            quote!(Some(#c))
        }
        None => quote!(None),
    };
    let endurance = opt_u32(p.eeprom_write_endurance);
    let serial_formats = match &p.serial_formats {
        None => quote!(None),
        Some(f) => {
            let (by, source) = (f.selected_by, f.source);
            let formats = f.formats.iter().map(|x| {
                let code = proc_macro2::Literal::u16_unsuffixed(x.code);
                let data = proc_macro2::Literal::u8_unsuffixed(x.data_bits);
                let stop = proc_macro2::Literal::u8_unsuffixed(x.stop_bits);
                let parity = match x.parity {
                    Parity::None => quote!(None),
                    Parity::Even => quote!(Even),
                    Parity::Odd => quote!(Odd),
                };
                quote!(#rt::profile::SerialFormat { code: #code, data_bits: #data, parity: #rt::profile::Parity::#parity, stop_bits: #stop })
            });
            quote!(Some(#rt::profile::SerialFormats { selected_by: #by, formats: &[#(#formats),*], source: #source }))
        }
    };
    let not_printed = p.not_printed.iter().map(|n| {
        // The variant's name is its `Debug` text (a unit variant).
        let fact = proc_macro2::Ident::new(&format!("{:?}", n.fact), proc_macro2::Span::call_site());
        let why = n.why;
        let source = match n.source {
            Some(s) => quote!(Some(#s)),
            None => quote!(None),
        };
        quote!(#rt::stated::NotPrinted { fact: #rt::stated::ProtocolFact::#fact, why: #why, source: #source })
    });
    quote! {
        /// The protocol profile: what the drive accepts on the wire, per its manual.
        pub static PROFILE: #rt::profile::Profile = #rt::profile::Profile {
            drive_id: #id,
            function_codes: &[#(#fcs),*],
            max_read: #max_read,
            max_write: #max_write,
            max_read_bits: #max_read_bits,
            max_write_bits: #max_write_bits,
            slave_min: #slave_min,
            slave_max: #slave_max,
            broadcast: #broadcast,
            exceptions: &[#(#exceptions),*],
            commands: &[#(#commands),*],
            address_offsets: #rt::profile::AddressOffsets { rtu: #rtu_off, tcp: #tcp_off },
            timing: #rt::profile::Timing {
                frame_gap_chars: #gap,
                frame_gap_us: #gap_min_us,
                inter_char_timeout_us: #ict_us,
                inter_char_timeout_bits: #ict_bits,
                response_delay_us: #resp,
                response_delay_bits: #resp_bits,
                response_delay_param: #resp_param,
                response_delay_param_default_us: #resp_param_default,
                request_gap_bits: #gap_bits,
                request_gap_us: #gap_us,
                char_bits: #char_bits,
            },
            serial_formats: #serial_formats,
            eeprom_write_endurance: #endurance,
            writes: &WRITES,
            not_printed: &[#(#not_printed),*],
        };

        /// The write rule of every writable register, derived from the plan in order.
        static WRITES: [#rt::rule::WriteRule; #rt::plan::writable_count(plan::REGISTERS)] =
            #rt::plan::write_rules(plan::REGISTERS);
    }
}

/// `0x03`-style literal for function and exception codes.
fn hex2(v: u8) -> TokenStream {
    let lit: proc_macro2::Literal = format!("0x{v:02X}")
        .parse()
        .unwrap_or_else(|_| proc_macro2::Literal::u8_unsuffixed(v));
    quote!(#lit)
}

fn opt_u32(v: Option<u32>) -> TokenStream {
    match v {
        Some(v) => {
            let v = proc_macro2::Literal::u32_unsuffixed(v);
            quote!(Some(#v))
        }
        None => quote!(None),
    }
}
