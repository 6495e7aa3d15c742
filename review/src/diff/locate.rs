//! Where a change is in the new map: the line of the key that changed (the register's `scale`,
//! `protocol.function_codes`), else of the register or section, for annotations on the map.

use drivemap_map::Loc;
use drivemap_map::ir::Drive;
use drivemap_map::source::Path;

use super::{Change, ChangeKind};

/// The key of a register that a change of this kind concerns.
fn register_key(kind: ChangeKind) -> Option<&'static str> {
    use ChangeKind::*;
    Some(match kind {
        RegisterRenamed => "id",
        NameChanged => "name",
        ParamChanged => "param",
        RegisterMoved => "address",
        AddressAlternativesChanged => "address_alternatives",
        TableChanged => "modbus_table",
        ScaleChanged | ScaleCaseAdded => "scale",
        UnitChanged => "unit",
        SignednessChanged => "signed",
        WidthChanged => "pair",
        DefaultChanged => "default",
        AccessNarrowed | AccessWidened => "access",
        WriteRestrictionTightened | WriteRestrictionRelaxed => "write_restriction",
        TransportsNarrowed | TransportsWidened => "transports",
        RepeatNeedsChangeChanged => "repeat_needs_change",
        FunctionCodesChanged => "function_codes",
        RelativeLimitChanged => "max_relative",
        ReadMeaningChanged => "read_values",
        IndexedChanged => "indexed",
        CodeAdded | CodeRemoved | CodeRenamed | CodeReworded => "values",
        FieldAdded | FieldRemoved | FieldMoved | FieldRenamed | FieldReworded => "fields",
        CitationChanged => "source",
        _ => return None,
    })
}

/// The path of the map section a change of this kind concerns, when it is not a register's.
fn section(kind: ChangeKind, what: &str) -> Path {
    use ChangeKind::*;
    let root = Path::root();
    let protocol = root.key("protocol");
    match kind {
        DriveAdded | DriveRemoved | DriveMetaChanged => root.key("drive"),
        VariantAxisAdded | VariantAxisRemoved | VariantOptionAdded | VariantOptionRemoved
        | VariantBaseChanged => root.key("variants"),
        TransportAdded | TransportRemoved => protocol.key("transports"),
        FunctionCodeAdded | FunctionCodeRemoved => protocol.key("function_codes"),
        MaxRequestRaised | MaxRequestLowered => protocol.key(if what.contains("write") {
            "max_write"
        } else {
            "max_read"
        }),
        SlaveRangeWidened | SlaveRangeNarrowed => protocol.key("slave_address"),
        BroadcastExtended | BroadcastRestricted => protocol.key("broadcast"),
        ExceptionAdded | ExceptionRemoved | ExceptionReworded => protocol.key("exceptions"),
        CommandAdded | CommandRemoved | CommandChanged | CommandReworded => {
            protocol.key("commands")
        }
        AddressingChanged => protocol.key("addressing"),
        TimingChanged => protocol.key("timing"),
        LineSettingsChanged => protocol.key("serial"),
        RoleAdded | RoleRemoved | RoleRepointed | RoleCodesChanged => role(what),
        DocumentationChanged if what.starts_with("conflict ") => root.key("conflicts"),
        DocumentationChanged if what.starts_with("gap ") => root.key("gaps"),
        DocumentationChanged if what.starts_with("removed register ") => root.key("removed"),
        DocumentationChanged if what == "groups" => root.key("groups"),
        // `slave_address: not printed`, `timing.frame_gap: not printed`.
        DocumentationChanged
            if what.ends_with(": not printed")
                && drivemap_core::stated::ProtocolFact::from_key(
                    what.trim_end_matches(": not printed"),
                )
                .is_some() =>
        {
            what.trim_end_matches(": not printed")
                .split('.')
                .fold(protocol, |p, k| p.key(k))
        }
        _ => root,
    }
}

/// The path of a role named at the start of a change's `what` (`run`, `run place 2`).
fn role(what: &str) -> Path {
    let id = what.split([' ', ':']).next().unwrap_or_default();
    Path::root().key("roles").key(id)
}

/// Where `change` is in the new map, if the new map has it.
pub(crate) fn at(change: &Change, old: &Drive, new: &Drive) -> Option<Loc> {
    if change.subject == "roles" {
        return Some(new.locate(&role(&change.what)));
    }
    let id = change.subject.split(' ').next().unwrap_or_default();
    if let Some(r) = new.registers.iter().find(|r| r.def.id == id) {
        let path = match register_key(change.kind) {
            Some(key) => r.key_path(key),
            None => r.path.clone(),
        };
        return Some(new.locate(&path));
    }
    if let Some(r) = old.registers.iter().find(|r| r.def.id == id) {
        // Gone from the new map: the group that held it, if the new map still has it.
        let group = &old.group_of(r).id;
        return new
            .groups
            .iter()
            .find(|g| &g.id == group)
            .map(|g| new.locate(&g.path));
    }
    Some(new.locate(&section(change.kind, &change.what)))
}
