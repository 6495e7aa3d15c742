//! Example frames (`examples:`) are well formed: a unique identifier, bytes in hex (the citation,
//! one line or a line range of a declared text manual, is checked with every citation place by
//! `citations_present`), a transport of the drive, a response answering an earlier request of the same transport, and `says` naming
//! registers of the map. What the bytes mean (CRC, function, address, values) is verified
//! against the codec by `drivemap_live::examples`.

use super::is_identifier;
use crate::diagnostic::Diagnostic;
use crate::examples::{Direction, locate_offset, parse_bytes};
use crate::ir::Drive;
use crate::source::Path;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let list = Path::root().key("examples");
    for (i, e) in drive.examples.iter().enumerate() {
        let path = list.index(i);
        if let Err((offset, message)) = parse_bytes(&e.bytes) {
            let at = drive
                .tree
                .at(&path.key("bytes"))
                .map(|n| locate_offset(&n.loc, offset))
                .unwrap_or_else(|| drive.locate(&path.key("bytes")));
            out.push(Diagnostic::new(
                at,
                None,
                format!("example `{}`: bytes: {message}", e.id),
            ));
        }
        let mut error = |key: &str, message: String| {
            out.push(drive.error(
                &path.key(key),
                None,
                format!("example `{}`: {message}", e.id),
            ));
        };
        if !is_identifier(&e.id) {
            error(
                "id",
                "the id must be lowercase letters, digits and `_`, starting with a letter".into(),
            );
        }
        if drive.examples[..i].iter().any(|o| o.id == e.id) {
            error("id", "another example has this id".into());
        }
        if !drive.protocol.transports.contains(&e.transport) {
            error(
                "transport",
                format!(
                    "the drive's `protocol.transports` does not list {}",
                    e.transport
                ),
            );
        }
        match (&e.answers, e.direction) {
            (Some(_), Direction::Request) => error(
                "answers",
                "a request answers nothing (`answers` is for a response)".into(),
            ),
            (Some(a), Direction::Response) => {
                match drive.examples[..i].iter().find(|o| o.id == *a) {
                    None => error(
                        "answers",
                        format!("`{a}` is not an example written before this one"),
                    ),
                    Some(o) if o.direction != Direction::Request => {
                        error("answers", format!("`{a}` is a response, not a request"))
                    }
                    Some(o) if o.transport != e.transport => error(
                        "answers",
                        format!(
                            "`{a}` is framed for {}, this one for {}",
                            o.transport, e.transport
                        ),
                    ),
                    Some(_) => {}
                }
            }
            (None, _) => {}
        }
        for name in e.settings.keys() {
            let external = drive.externals().iter().any(|q| q.external == *name);
            if drive.find(name).is_none() && !external {
                error(
                    "settings",
                    format!(
                        "`{name}` is no register (id or parameter number) or external quantity of the map"
                    ),
                );
            }
        }
        if let Some(topic) = &e.conflict
            && !drive.conflicts.iter().any(|c| c.topic == *topic)
        {
            error(
                "conflict",
                format!("no entry of `conflicts:` has the topic \"{topic}\""),
            );
        }
        let Some(says) = &e.says else { continue };
        let said = usize::from(says.read.is_some())
            + usize::from(says.write.is_some())
            + usize::from(says.exception.is_some());
        if said > 1 {
            error(
                "says",
                "says one of `read`, `write` and `exception`, not several".into(),
            );
        }
        if says.exception.is_some() && e.direction == Direction::Request {
            error(
                "says",
                "a request is not an exception (`exception` is for a response)".into(),
            );
        }
        if !says.values.is_empty() && says.read.is_none() && says.write.is_none() {
            error(
                "says",
                "`values` belong to a `read` or a `write`: say which register they start at".into(),
            );
        }
        if !says.values.is_empty() && says.read.is_some() && e.direction == Direction::Request {
            error(
                "says",
                "a read request carries no values (give them on its response)".into(),
            );
        }
        for (key, id) in [("read", &says.read), ("write", &says.write)] {
            if let Some(id) = id
                && !drive.registers.iter().any(|r| r.def.id == *id)
            {
                out.push(drive.error(
                    &path.key("says").key(key),
                    None,
                    format!("example `{}`: no register `{id}` in the map", e.id),
                ));
            }
        }
    }
}
