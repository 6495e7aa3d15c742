//! Several consecutive registers in one request: tuples of register types.
//!
//! `(FrequencyReference, OutputFrequency, OutputCurrent)` reads three typed values with one 03h
//! request when the three registers are consecutive and in one table for the settings and
//! transport in use (registers can move with a setting, so this is checked at run time, before
//! anything is sent). Tuples of 1 to 8 registers sharing one `Settings` type are supported.

use crate::error::Refusal;
use drivemap_core::profile::TransportKind;
use drivemap_core::register::{Readable, Register, Table, Writable};
use drivemap_core::scale::ValueError;
use drivemap_core::width::Width;

/// Consecutive registers handled in one request.
pub trait RegisterSet {
    /// The drive's settings type, common to all members.
    type Settings;
    /// The typed values, one per member, in address order.
    type Values;
    /// Number of words: one per register, two per 32-bit pair.
    const LEN: usize;

    /// Address of the first register and the table, after checking that the members are
    /// consecutive and in one table for these settings and this transport.
    fn layout(settings: &Self::Settings, kind: TransportKind) -> Result<(u16, Table), Refusal>;
}

/// A set whose members can all be read.
pub trait ReadSet: RegisterSet {
    /// Decodes `raw` (exactly [`RegisterSet::LEN`] words) into typed values; a pair's words are
    /// joined in the map's order.
    fn decode(raw: &[u16], settings: &Self::Settings) -> Result<Self::Values, ValueError>;
}

/// A set whose members can all be written.
pub trait WriteSet: RegisterSet {
    /// Encodes the values into `out` (exactly [`RegisterSet::LEN`] words), checking each range;
    /// a pair's value becomes its two words in the map's order.
    fn encode(
        values: &Self::Values,
        settings: &Self::Settings,
        out: &mut [u16],
    ) -> Result<(), ValueError>;
}

fn check_next<R: Register>(
    first: &'static str,
    start: u16,
    table: Table,
    index: u16,
    settings: &R::Settings,
    kind: TransportKind,
) -> Result<(), Refusal> {
    if !R::on_transport(kind) {
        return Err(Refusal::NotOnTransport {
            register: R::ID,
            transport: kind,
        });
    }
    let expected = start.wrapping_add(index);
    let got = R::address(settings, kind)?;
    if got != expected || R::TABLE != table {
        return Err(Refusal::NotContiguous {
            first,
            register: R::ID,
            expected,
            got,
        });
    }
    Ok(())
}

/// The words of the next member of a set from the front of `rest`, taking them off.
fn take<'a>(rest: &mut &'a [u16], width: Width) -> &'a [u16] {
    let n = usize::from(width.count()).min(rest.len());
    let (these, after) = rest.split_at(n);
    *rest = after;
    these
}

/// Puts the raw value of the next member of a set into the next words of `slots`, in the map's
/// order.
fn put<'a>(slots: &mut impl Iterator<Item = &'a mut u16>, width: Width, raw: u32) {
    // A string is never written (the gate refuses it): at most a pair's two words here.
    for word in width.split(raw).iter().take(usize::from(width.count())) {
        if let Some(slot) = slots.next() {
            *slot = *word;
        }
    }
}

/// The three traits for the tuple of the registers named (`A a, B b`: each type with a name
/// for its value).
macro_rules! register_set {
    ($first:ident $fv:ident $(, $rest:ident $rv:ident)*) => {
        impl<$first: Register, $($rest: Register<Settings = $first::Settings>),*> RegisterSet
            for ($first, $($rest,)*)
        {
            type Settings = $first::Settings;
            type Values = ($first::Value, $($rest::Value,)*);
            const LEN: usize = $first::WIDTH.count() as usize $(+ $rest::WIDTH.count() as usize)*;

            // `index` is the next register's offset: the one-register set never reads it and every
            // set's last `+=` is never read (the macro writes one loop body per register).
            #[allow(unused_assignments, unused_mut, unused_variables)]
            fn layout(settings: &Self::Settings, kind: TransportKind) -> Result<(u16, Table), Refusal> {
                if !$first::on_transport(kind) {
                    return Err(Refusal::NotOnTransport { register: $first::ID, transport: kind });
                }
                let start = $first::address(settings, kind)?;
                let mut index = $first::WIDTH.count();
                $(
                    check_next::<$rest>($first::ID, start, $first::TABLE, index, settings, kind)?;
                    index += $rest::WIDTH.count();
                )*
                Ok((start, $first::TABLE))
            }
        }

        impl<$first: Readable, $($rest: Readable<Settings = $first::Settings>),*> ReadSet
            for ($first, $($rest,)*)
        {
            fn decode(raw: &[u16], settings: &Self::Settings) -> Result<Self::Values, ValueError> {
                let mut rest = raw;
                Ok((
                    $first::decode_words(take(&mut rest, $first::WIDTH), settings)?,
                    $($rest::decode_words(take(&mut rest, $rest::WIDTH), settings)?,)*
                ))
            }
        }

        impl<
            $first: Writable<Input = <$first as Register>::Value>,
            $($rest: Writable<Settings = $first::Settings, Input = <$rest as Register>::Value>),*
        > WriteSet
            for ($first, $($rest,)*)
        {
            fn encode(
                values: &Self::Values,
                settings: &Self::Settings,
                out: &mut [u16],
            ) -> Result<(), ValueError> {
                let ($fv, $($rv,)*) = values;
                let mut slots = out.iter_mut();
                put(&mut slots, $first::WIDTH, $first::encode($fv, settings)?);
                $(put(&mut slots, $rest::WIDTH, $rest::encode($rv, settings)?);)*
                Ok(())
            }
        }
    };
}

register_set!(A a);
register_set!(A a, B b);
register_set!(A a, B b, C c);
register_set!(A a, B b, C c, D d);
register_set!(A a, B b, C c, D d, E e);
register_set!(A a, B b, C c, D d, E e, F f);
register_set!(A a, B b, C c, D d, E e, F f, G g);
register_set!(A a, B b, C c, D d, E e, F f, G g, H h);
