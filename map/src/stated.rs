//! The protocol facts a map marks not printed (`unknown:`), read once for every tool: the
//! lowering (the profile's `not_printed`), `export`, `doc`, `diff` and the CLI's warnings.

use crate::model::{Interval, Protocol};
use drivemap_core::stated::ProtocolFact;

/// One fact the manual does not print, as the map says it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unprinted {
    /// The fact.
    pub fact: ProtocolFact,
    /// Why, as the map's `unknown:` gives it (trimmed).
    pub why: String,
    /// Where the manual says it prints none, when the map cites it.
    pub source: Option<String>,
}

fn one(fact: ProtocolFact, why: &Option<String>, source: &Option<String>) -> Option<Unprinted> {
    why.as_ref().map(|w| Unprinted {
        fact,
        why: w.trim().to_string(),
        source: source.clone(),
    })
}

fn interval(fact: ProtocolFact, i: &Option<Interval>) -> Option<Unprinted> {
    i.as_ref().and_then(|i| one(fact, &i.unknown, &i.source))
}

/// Every fact of `p` marked `unknown:`, in [`ProtocolFact::ALL`] order.
pub(crate) fn unprinted(p: &Protocol) -> Vec<Unprinted> {
    let mut out = Vec::new();
    let fc = &p.function_codes;
    out.extend(one(ProtocolFact::FunctionCodes, &fc.unknown, &fc.source));
    out.extend(one(
        ProtocolFact::MaxRead,
        &p.max_read.unknown,
        &p.max_read.source,
    ));
    out.extend(one(
        ProtocolFact::MaxWrite,
        &p.max_write.unknown,
        &p.max_write.source,
    ));
    for (fact, l) in [
        (ProtocolFact::MaxReadBits, &p.max_read_bits),
        (ProtocolFact::MaxWriteBits, &p.max_write_bits),
    ] {
        if let Some(l) = l {
            out.extend(one(fact, &l.unknown, &l.source));
        }
    }
    let s = &p.slave_address;
    out.extend(one(ProtocolFact::SlaveAddress, &s.unknown, &s.source));
    if let Some(b) = &p.broadcast {
        out.extend(one(
            ProtocolFact::Broadcast,
            &b.unknown,
            &Some(b.source.clone()),
        ));
    }
    let e = &p.exceptions;
    out.extend(one(ProtocolFact::Exceptions, &e.unknown, &e.source));
    if let Some(s) = &p.serial {
        let source = (!s.source.is_empty()).then(|| s.source.clone());
        out.extend(one(ProtocolFact::Serial, &s.unknown, &source));
    }
    if let Some(t) = &p.timing {
        out.extend(one(ProtocolFact::Timing, &t.unknown, &t.source));
        out.extend(interval(ProtocolFact::FrameGap, &t.frame_gap));
        out.extend(interval(
            ProtocolFact::InterCharTimeout,
            &t.inter_char_timeout,
        ));
        out.extend(interval(ProtocolFact::ResponseTime, &t.response_time));
        out.extend(interval(ProtocolFact::RequestGap, &t.request_gap));
    }
    out
}

/// Why `fact` is not printed, if the map says so.
pub(crate) fn why(p: &Protocol, fact: ProtocolFact) -> Option<Unprinted> {
    unprinted(p).into_iter().find(|u| u.fact == fact)
}
