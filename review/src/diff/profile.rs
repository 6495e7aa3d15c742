//! Differences of the protocol profile, on the protocol facts of both sides
//! ([`drivemap_map::Map::protocol_facts`]): the rows are compared key by key, as [`STEPS`] lists
//! them, each by the [`Rule`] its key has ([`rule`]): which [`ChangeKind`] a change of the key
//! is (its direction deciding between the narrowing and the widening kind, whose safety
//! wording is [`super::classify`]'s), and what else of the row is reported (a changed
//! not-printed reason, a changed citation).

use std::collections::BTreeSet;

use drivemap_map::facts::{
    CommandFacts, ExceptionFacts, Figure, ProtocolFacts, ProtocolKey as K, ProtocolRow,
};

use super::{ChangeKind, Collector, HEAD, Side};
use drivemap_map::Map;
use drivemap_map::describe;

/// How a change of a key is reported.
#[derive(Debug, Clone, Copy)]
enum Rule {
    /// Each item gone or new on its own: (gone, new).
    Members(ChangeKind, ChangeKind),
    /// The items gone, then the new ones, each once with both lists; then the reason the list
    /// is not printed, or its citation: (gone, new).
    Set(ChangeKind, ChangeKind),
    /// The working number: (lowered, raised); with its reason, or its citation when the number
    /// stays.
    Count(ChangeKind, ChangeKind),
    /// The working range: (narrowed, widened); else its default or parameter, else its citation.
    Range(ChangeKind, ChangeKind),
    /// Functions or registers lost, else gained, else only the citation: (lost, gained).
    Broadcast(ChangeKind, ChangeKind),
    /// The offsets; else the description.
    Offsets(ChangeKind),
    /// Any change of the map's entry, once, with the entry on each side.
    Entry(ChangeKind),
    /// Any change of the map's entry, once, with the row's value on each side.
    Value(ChangeKind),
    /// Compared with another row: the entry of the whole it is part of, or its own parts.
    Elsewhere,
}

/// The rule of each key (a new key fails to compile here until it has one).
fn rule(key: K) -> Rule {
    use ChangeKind as C;
    match key {
        K::Transports => Rule::Members(C::TransportRemoved, C::TransportAdded),
        K::FunctionCodes => Rule::Set(C::FunctionCodeRemoved, C::FunctionCodeAdded),
        K::MaxRead | K::MaxWrite | K::MaxReadBits | K::MaxWriteBits => {
            Rule::Count(C::MaxRequestLowered, C::MaxRequestRaised)
        }
        K::SlaveAddress => Rule::Range(C::SlaveRangeNarrowed, C::SlaveRangeWidened),
        K::Broadcast => Rule::Broadcast(C::BroadcastRestricted, C::BroadcastExtended),
        K::Addressing => Rule::Offsets(C::AddressingChanged),
        K::Timing => Rule::Entry(C::TimingChanged),
        K::Serial => Rule::Entry(C::LineSettingsChanged),
        K::Eeprom => Rule::Value(C::LineSettingsChanged),
        // The whole of the two limits; the timing's figures are in its entry; the exception
        // list is compared code by code and its reason with the other reasons.
        K::RegistersPerRequest
        | K::BitsPerRequest
        | K::FrameGap
        | K::InterCharTimeout
        | K::ResponseTime
        | K::ResponseDelay
        | K::RequestGap
        | K::Exceptions => Rule::Elsewhere,
    }
}

/// One step of the comparison, in the order the changes are listed.
enum Step {
    /// A row by its rule, named in the change as given.
    Row(K, &'static str),
    /// Every fact that became not printed, printed again, or whose reason changed.
    NotPrinted,
    Exceptions,
    Commands,
    /// The protocol's notes and why its citation is indirect.
    Notes,
    /// The protocol's own citation.
    Source,
}

/// The comparison, step by step.
const STEPS: [Step; 17] = [
    Step::Row(K::Transports, "transports"),
    Step::Row(K::FunctionCodes, "function codes"),
    Step::Row(K::MaxRead, "max_read"),
    Step::Row(K::MaxWrite, "max_write"),
    Step::Row(K::MaxReadBits, "max_read_bits"),
    Step::Row(K::MaxWriteBits, "max_write_bits"),
    Step::Row(K::SlaveAddress, "slave address"),
    Step::NotPrinted,
    Step::Row(K::Broadcast, "broadcast"),
    Step::Exceptions,
    Step::Commands,
    Step::Row(K::Addressing, "address offsets"),
    Step::Row(K::Timing, "timing"),
    Step::Row(K::Serial, "serial line"),
    Step::Row(K::Eeprom, "EEPROM endurance"),
    Step::Notes,
    Step::Source,
];

/// The facts whose reason for not being printed is compared (function codes, limits and
/// broadcast report theirs where their figures are compared).
const REASONS: [K; 8] = [
    K::SlaveAddress,
    K::Exceptions,
    K::Serial,
    K::Timing,
    K::FrameGap,
    K::InterCharTimeout,
    K::ResponseTime,
    K::RequestGap,
];

/// Both sides' protocol facts.
struct Pair {
    a: ProtocolFacts,
    b: ProtocolFacts,
}

impl Pair {
    fn rows(&self, key: K) -> (Option<&ProtocolRow>, Option<&ProtocolRow>) {
        (self.a.get(key), self.b.get(key))
    }

    /// The protocol's own citations.
    fn src(&self) -> (Option<String>, Option<String>) {
        (self.a.source.clone(), self.b.source.clone())
    }
}

fn push(c: &mut Collector, kind: ChangeKind, what: &str, old: Side, new: Side) {
    c.push(kind, "protocol", what, old, new, HEAD);
}

pub(super) fn protocol(c: &mut Collector, old: &Map, new: &Map) {
    let p = Pair {
        a: old.protocol_facts(),
        b: new.protocol_facts(),
    };
    for step in STEPS {
        match step {
            Step::Row(key, what) => row(c, &p, key, what),
            Step::NotPrinted => not_printed(c, &p),
            Step::Exceptions => exceptions(c, &p.a.exceptions, &p.b.exceptions),
            Step::Commands => commands(c, &p.a.commands, &p.b.commands),
            Step::Notes => {
                let (a, b) = (&p.a, &p.b);
                if a.notes != b.notes || a.indirect != b.indirect {
                    let (sa, sb) = p.src();
                    let notes = |f: &ProtocolFacts| Some(format!("{} note(s)", f.notes.len()));
                    let what = "notes or indirect citation";
                    push(
                        c,
                        ChangeKind::DocumentationChanged,
                        what,
                        (notes(a), sa),
                        (notes(b), sb),
                    );
                }
            }
            Step::Source => {
                let (sa, sb) = p.src();
                if sa != sb {
                    push(c, ChangeKind::CitationChanged, "", (None, sa), (None, sb));
                }
            }
        }
    }
}

fn row(c: &mut Collector, p: &Pair, key: K, what: &str) {
    let (a, b) = p.rows(key);
    match rule(key) {
        Rule::Members(gone, new) => members(c, (a, b), (gone, new), what),
        Rule::Set(gone, new) => set(c, p, (a, b), (gone, new), what),
        Rule::Count(lower, higher) => count(c, p, (a, b), (lower, higher), what),
        Rule::Range(narrower, wider) => range(c, (a, b), (narrower, wider), what),
        Rule::Broadcast(lost, gained) => broadcast(c, (a, b), (lost, gained), what),
        Rule::Offsets(kind) => offsets(c, (a, b), kind, what),
        Rule::Entry(kind) => entry(c, (a, b), kind, what, |r| r.entry.to_string()),
        Rule::Value(kind) => entry(c, (a, b), kind, what, |r| r.value.clone()),
        Rule::Elsewhere => {}
    }
}

type Rows<'a> = (Option<&'a ProtocolRow>, Option<&'a ProtocolRow>);

fn citation(r: Option<&ProtocolRow>) -> Option<String> {
    r.and_then(|r| r.citation.clone())
}

/// Why the row is not printed, as the map gives it.
fn why(r: Option<&ProtocolRow>) -> Option<String> {
    r.and_then(|r| r.not_printed.as_ref())
        .map(|n| n.why.clone())
}

fn names(r: Option<&ProtocolRow>) -> BTreeSet<String> {
    match r.map(|r| &r.figure) {
        Some(Figure::Names(n)) => n.iter().cloned().collect(),
        _ => BTreeSet::new(),
    }
}

fn codes(r: Option<&ProtocolRow>) -> Vec<u8> {
    match r.map(|r| &r.figure) {
        Some(Figure::Codes(c)) => c.clone(),
        _ => Vec::new(),
    }
}

fn members(c: &mut Collector, (a, b): Rows, (gone, new): (ChangeKind, ChangeKind), what: &str) {
    let (na, nb) = (names(a), names(b));
    let (sa, sb) = (citation(a), citation(b));
    for t in na.difference(&nb) {
        push(
            c,
            gone,
            what,
            (Some(t.clone()), sa.clone()),
            (None, sb.clone()),
        );
    }
    for t in nb.difference(&na) {
        push(
            c,
            new,
            what,
            (None, sa.clone()),
            (Some(t.clone()), sb.clone()),
        );
    }
}

fn set(
    c: &mut Collector,
    p: &Pair,
    (a, b): Rows,
    (gone, new): (ChangeKind, ChangeKind),
    what: &str,
) {
    let (ca, cb) = (codes(a), codes(b));
    let (fa, fb): (BTreeSet<u8>, BTreeSet<u8>) =
        (ca.iter().copied().collect(), cb.iter().copied().collect());
    let (sa, sb) = p.src();
    let sides = (
        (Some(describe::functions(&ca)), sa),
        (Some(describe::functions(&cb)), sb),
    );
    for (kind, list) in [(gone, fa.difference(&fb)), (new, fb.difference(&fa))] {
        let list: Vec<u8> = list.copied().collect();
        if !list.is_empty() {
            let what = format!("{what}: {}", describe::functions(&list));
            push(c, kind, &what, sides.0.clone(), sides.1.clone());
        }
    }
    reason_or_citation(c, (a, b), what);
}

/// A changed reason for not printing the fact, else a changed citation.
fn reason_or_citation(c: &mut Collector, (a, b): Rows, what: &str) {
    let (sa, sb) = (citation(a), citation(b));
    if why(a) != why(b) {
        let what = format!("{what}: not printed");
        push(
            c,
            ChangeKind::DocumentationChanged,
            &what,
            (why(a), sa),
            (why(b), sb),
        );
    } else if sa != sb {
        push(c, ChangeKind::CitationChanged, what, (None, sa), (None, sb));
    }
}

fn count(
    c: &mut Collector,
    p: &Pair,
    (a, b): Rows,
    (lower, higher): (ChangeKind, ChangeKind),
    what: &str,
) {
    let number = |r: Option<&ProtocolRow>| match r.map(|r| &r.figure) {
        Some(Figure::Count(n)) => *n,
        _ => 0,
    };
    let (x, y) = (number(a), number(b));
    if x == y {
        return reason_or_citation(c, (a, b), what);
    }
    if why(a) != why(b) {
        let (sa, sb) = (citation(a), citation(b));
        let what = format!("{what}: not printed");
        push(
            c,
            ChangeKind::DocumentationChanged,
            &what,
            (why(a), sa),
            (why(b), sb),
        );
    }
    let (pa, pb) = p.src();
    let kind = if y < x { lower } else { higher };
    let (sa, sb) = (citation(a).or(pa), citation(b).or(pb));
    push(
        c,
        kind,
        what,
        (Some(x.to_string()), sa),
        (Some(y.to_string()), sb),
    );
}

fn range(c: &mut Collector, (a, b): Rows, (narrower, wider): (ChangeKind, ChangeKind), what: &str) {
    let bounds = |r: Option<&ProtocolRow>| match r.map(|r| &r.figure) {
        Some(Figure::Range { min, max }) => (*min, *max),
        _ => (0, 0),
    };
    let ((a_min, a_max), (b_min, b_max)) = (bounds(a), bounds(b));
    let (sa, sb) = (citation(a), citation(b));
    let entry = |r: Option<&ProtocolRow>, k: &str| r.and_then(|r| r.entry.get(k).cloned());
    let text = |r: Option<&ProtocolRow>| r.map(|r| r.entry.to_string());
    if (a_min, a_max) != (b_min, b_max) {
        let kind = if b_min > a_min || b_max < a_max {
            narrower
        } else {
            wider
        };
        let (x, y) = (
            format!("{a_min} ..= {a_max}"),
            format!("{b_min} ..= {b_max}"),
        );
        push(c, kind, what, (Some(x), sa), (Some(y), sb));
    } else if entry(a, "default") != entry(b, "default") || entry(a, "param") != entry(b, "param") {
        let what = format!("{what} default or parameter");
        push(
            c,
            ChangeKind::DocumentationChanged,
            &what,
            (text(a), sa),
            (text(b), sb),
        );
    } else if sa != sb {
        push(c, ChangeKind::CitationChanged, what, (None, sa), (None, sb));
    }
}

/// The map's entry of a row (`null` without the row), as the diff compares it.
fn same_entry((a, b): Rows) -> bool {
    let entry = |r: Option<&ProtocolRow>| r.map(|r| r.entry.clone()).unwrap_or_default();
    entry(a) == entry(b)
}

/// What a broadcast may carry: its functions and registers (none: any writable register).
fn carries(r: Option<&ProtocolRow>) -> (BTreeSet<u8>, BTreeSet<String>) {
    match r.map(|r| &r.figure) {
        Some(Figure::Broadcast {
            functions,
            registers,
        }) => (
            functions.iter().copied().collect(),
            registers.iter().cloned().collect(),
        ),
        _ => (BTreeSet::new(), BTreeSet::new()),
    }
}

/// A broadcast in the diff's words: `06h, 10h to run_command`, or why its rules are not printed.
fn broadcast_text(r: Option<&ProtocolRow>) -> Option<String> {
    let r = r?;
    if let Some(n) = &r.not_printed {
        return Some(describe::broadcast_not_printed(&n.why));
    }
    let Figure::Broadcast {
        functions,
        registers,
    } = &r.figure
    else {
        return None;
    };
    let mut t = describe::functions(functions);
    if !registers.is_empty() {
        t += &format!(" to {}", registers.join(", "));
    }
    Some(t)
}

fn broadcast(
    c: &mut Collector,
    (a, b): Rows,
    (lost, gained): (ChangeKind, ChangeKind),
    what: &str,
) {
    if same_entry((a, b)) {
        return;
    }
    let ((fa, ra), (fb, rb)) = (carries(a), carries(b));
    // An empty register list means "any writable register".
    let registers_lost = match (ra.is_empty(), rb.is_empty()) {
        (true, true) | (false, true) => false,
        (true, false) => a.is_some(),
        (false, false) => !ra.is_subset(&rb),
    };
    let is_lost = (a.is_some() && b.is_none()) || !fa.is_subset(&fb) || registers_lost;
    let is_gained = (a.is_none() && b.is_some())
        || !fb.is_subset(&fa)
        || (!ra.is_empty() && (rb.is_empty() || !rb.is_subset(&ra)));
    let kind = match (is_lost, is_gained) {
        (true, _) => lost,
        (false, true) => gained,
        (false, false) => ChangeKind::CitationChanged,
    };
    let (x, y) = (broadcast_text(a), broadcast_text(b));
    push(c, kind, what, (x, citation(a)), (y, citation(b)));
}

fn offsets(c: &mut Collector, (a, b): Rows, kind: ChangeKind, what: &str) {
    let figure = |r: Option<&ProtocolRow>| match r.map(|r| &r.figure) {
        Some(Figure::Offsets { rtu, tcp }) => (*rtu, *tcp),
        _ => (0, 0),
    };
    let text = |(r, t): (i32, i32)| Some(format!("RTU {r:+}, TCP {t:+}"));
    let (sa, sb) = (citation(a), citation(b));
    if figure(a) != figure(b) {
        push(c, kind, what, (text(figure(a)), sa), (text(figure(b)), sb));
    } else if !same_entry((a, b)) {
        let what = "addressing description";
        push(
            c,
            ChangeKind::DocumentationChanged,
            what,
            (None, sa),
            (None, sb),
        );
    }
}

/// Any change of the map's entry, once, each side as `text` gives it.
fn entry(
    c: &mut Collector,
    (a, b): Rows,
    kind: ChangeKind,
    what: &str,
    text: fn(&ProtocolRow) -> String,
) {
    if same_entry((a, b)) {
        return;
    }
    // A serial line without a citation was compared with an empty one.
    let source = |r: Option<&ProtocolRow>| match r {
        Some(r) if r.key == K::Serial => Some(r.citation.clone().unwrap_or_default()),
        r => citation(r),
    };
    push(
        c,
        kind,
        what,
        (a.map(text), source(a)),
        (b.map(text), source(b)),
    );
}

/// A protocol fact that became not printed (`unknown:`), printed again, or whose reason
/// changed: `slave_address: not printed`, the reasons as the old and new values. A change of
/// the working figure it brings (a slave range 1 ..= 32 becoming the Modbus 1 ..= 247) is
/// reported on its own.
fn not_printed(c: &mut Collector, p: &Pair) {
    for key in REASONS {
        let Some(fact) = key.fact() else { continue };
        let (a, b) = p.rows(key);
        let trimmed = |r: Option<&ProtocolRow>| why(r).map(|w| w.trim().to_owned());
        let what = format!("{}: not printed", fact.key());
        let side = |r: Option<&ProtocolRow>| match trimmed(r) {
            Some(w) => (Some(w), citation(r)),
            None => (Some("printed".to_owned()), None),
        };
        if trimmed(a) != trimmed(b) {
            push(c, ChangeKind::DocumentationChanged, &what, side(a), side(b));
        } else if key == K::Exceptions
            && trimmed(a).is_some()
            && trimmed(b).is_some()
            && citation(a) != citation(b)
        {
            // The other facts' citations are compared with their figures.
            push(
                c,
                ChangeKind::CitationChanged,
                &what,
                (None, citation(a)),
                (None, citation(b)),
            );
        }
    }
}

fn exceptions(c: &mut Collector, a: &[ExceptionFacts], b: &[ExceptionFacts]) {
    let cite = |x: &ExceptionFacts| Some(x.citation.clone());
    let name = |x: &ExceptionFacts| (Some(x.name.clone()), cite(x));
    for x in a {
        let what = format!("exception {}", x.code);
        match b.iter().find(|y| y.code == x.code) {
            None => push(
                c,
                ChangeKind::ExceptionRemoved,
                &what,
                name(x),
                (None, None),
            ),
            Some(y) if x.name != y.name || x.description != y.description => {
                push(c, ChangeKind::ExceptionReworded, &what, name(x), name(y));
            }
            Some(y) if x.citation != y.citation => {
                push(
                    c,
                    ChangeKind::CitationChanged,
                    &what,
                    (None, cite(x)),
                    (None, cite(y)),
                );
            }
            Some(_) => {}
        }
    }
    for y in b.iter().filter(|y| !a.iter().any(|x| x.code == y.code)) {
        let what = format!("exception {}", y.code);
        push(c, ChangeKind::ExceptionAdded, &what, (None, None), name(y));
    }
}

fn commands(c: &mut Collector, a: &[CommandFacts], b: &[CommandFacts]) {
    let cite = |x: &CommandFacts| Some(x.citation.clone());
    let text = |x: &CommandFacts| {
        let writes: Vec<String> = (x.words.iter())
            .map(|(address, value)| format!("{} ← {value:04X}h", describe::address(*address)))
            .collect();
        (
            Some(format!("{} ({:?})", writes.join(", "), x.kind).to_lowercase()),
            cite(x),
        )
    };
    let name = |x: &CommandFacts| (Some(x.name.clone()), cite(x));
    for x in a {
        let what = format!("command {}", x.id);
        match b.iter().find(|y| y.id == x.id) {
            None => push(c, ChangeKind::CommandRemoved, &what, text(x), (None, None)),
            Some(y) if x.words != y.words || x.kind != y.kind => {
                push(c, ChangeKind::CommandChanged, &what, text(x), text(y));
            }
            Some(y) if x.name != y.name => {
                push(c, ChangeKind::CommandReworded, &what, name(x), name(y));
            }
            Some(y) if x.citation != y.citation => {
                push(
                    c,
                    ChangeKind::CitationChanged,
                    &what,
                    (None, cite(x)),
                    (None, cite(y)),
                );
            }
            Some(_) => {}
        }
    }
    for y in b.iter().filter(|y| !a.iter().any(|x| x.id == y.id)) {
        let what = format!("command {}", y.id);
        push(c, ChangeKind::CommandAdded, &what, (None, None), text(y));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stepped(key: K) -> usize {
        (STEPS.iter())
            .filter(|s| matches!(s, Step::Row(k, _) if *k == key))
            .count()
    }

    #[test]
    fn every_key_with_a_rule_is_compared_once_and_every_part_with_its_whole() {
        for key in K::ALL {
            match rule(key) {
                Rule::Elsewhere => {
                    assert_eq!(stepped(key), 0, "{key:?} is compared elsewhere");
                    // A part is compared with its whole (or, a whole, by its parts).
                    let whole = key.part_of();
                    let compared = |k: K| !matches!(rule(k), Rule::Elsewhere) && stepped(k) == 1;
                    let parts = K::ALL.iter().filter(|p| p.part_of() == Some(key));
                    assert!(
                        whole.is_some_and(compared)
                            || parts.clone().all(|p| compared(*p)) && parts.count() > 0
                            || key == K::Exceptions,
                        "{key:?}: neither its whole nor its parts are compared"
                    );
                }
                _ => assert_eq!(stepped(key), 1, "{key:?} is not compared exactly once"),
            }
        }
    }

    #[test]
    fn every_fact_a_map_can_mark_not_printed_has_its_reason_compared() {
        for key in K::ALL.into_iter().filter(|k| k.fact().is_some()) {
            // Function codes, limits and broadcast report theirs with their figures.
            let with_figure = matches!(
                rule(key),
                Rule::Set(..) | Rule::Count(..) | Rule::Broadcast(..)
            );
            assert!(
                with_figure || REASONS.contains(&key),
                "{key:?}: a changed reason would not be reported"
            );
        }
    }
}
