//! The manual's example frames in the generated module (`examples:` in the map): one `const`
//! byte slice per example, documented with what it is and where the manual prints it, and
//! `ALL` (id, bytes) for a test that walks them. Emitted only for a map with `examples:`.

use proc_macro2::TokenStream;
use quote::{format_ident, quote};
use syn::LitInt;

use drivemap_map::Map;

pub(super) fn emit(drive: &Map) -> TokenStream {
    if drive.examples().is_empty() {
        return TokenStream::new();
    }
    let mut items = Vec::new();
    let mut all = Vec::new();
    for e in drive.examples() {
        let Ok(bytes) = drivemap_map::facts::parse_bytes(&e.bytes) else {
            continue; // validation refuses the map before generation
        };
        let name = format_ident!("{}", e.id.to_uppercase());
        let values = bytes.iter().map(|b| {
            syn::parse_str::<LitInt>(&format!("0x{:02X}", b.value)).expect("a hex literal")
        });
        let doc = format!(" {} (`{}`).", e.summary(), e.source);
        let id = &e.id;
        items.push(quote! {
            #[doc = #doc]
            pub const #name: &[u8] = &[#(#values),*];
        });
        all.push(quote!((#id, #name)));
    }
    quote! {
        /// The example frames the manual prints, byte for byte as printed (`examples:` in the
        /// map), verified by `drivemap check` against the codec and the map.
        pub mod examples {
            #(#items)*
            /// Every example: its id in the map and its bytes.
            pub const ALL: &[(&str, &[u8])] = &[#(#all),*];
        }
    }
}
