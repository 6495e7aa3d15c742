//! A binary that includes the V7's generated module (not the `drivemap-drives` library) inside
//! a private module, as applications do, and uses one register of it: with `unused` denied
//! (below), it builds only if the generated code gives no dead-code or unused warning
//! for the registers, types and tables it does not use (290 of them before).
#![doc = include_str!("../README.md")]
// Every `unused` lint (dead code, unused imports, ...) an error: the generated module must not
// make a binary that uses one of its registers warn.
#![deny(unused)]

mod generated {
    include!(concat!(env!("OUT_DIR"), "/drivemap.rs"));
}

use drivemap_runtime::core::register::Register;
use generated::yaskawa_v7 as v7;

fn main() {
    // The output current: 0.1 A per unit, whatever the settings.
    match v7::OutputCurrent::decode(123, &v7::Settings::default()) {
        Ok(amps) => println!("{amps} A"),
        Err(e) => println!("{e}"),
    }
}
