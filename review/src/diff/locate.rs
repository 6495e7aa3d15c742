//! Where a change is in the new map: the line of the key that changed (the register's `scale`,
//! `protocol.function_codes`), else of the register or section, for annotations on the map.

use drivemap_map::{Loc, Map};

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

/// The key path ([`Map::locate`]) of the map section a change of this kind concerns, when it is
/// not a register's.
fn section(kind: ChangeKind, what: &str) -> String {
    use ChangeKind::*;
    let protocol = |key: &str| format!("protocol.{key}");
    match kind {
        DriveAdded | DriveRemoved | DriveMetaChanged => "drive".into(),
        VariantAxisAdded | VariantAxisRemoved | VariantOptionAdded | VariantOptionRemoved
        | VariantBaseChanged => "variants".into(),
        TransportAdded | TransportRemoved => protocol("transports"),
        FunctionCodeAdded | FunctionCodeRemoved => protocol("function_codes"),
        MaxRequestRaised | MaxRequestLowered => protocol(if what.contains("write") {
            "max_write"
        } else {
            "max_read"
        }),
        SlaveRangeWidened | SlaveRangeNarrowed => protocol("slave_address"),
        BroadcastExtended | BroadcastRestricted => protocol("broadcast"),
        ExceptionAdded | ExceptionRemoved | ExceptionReworded => protocol("exceptions"),
        CommandAdded | CommandRemoved | CommandChanged | CommandReworded => protocol("commands"),
        AddressingChanged => protocol("addressing"),
        TimingChanged => protocol("timing"),
        LineSettingsChanged => protocol("serial"),
        RoleAdded | RoleRemoved | RoleRepointed | RoleCodesChanged => role(what),
        DocumentationChanged if what.starts_with("conflict ") => "conflicts".into(),
        DocumentationChanged if what.starts_with("gap ") => "gaps".into(),
        DocumentationChanged if what.starts_with("removed register ") => "removed".into(),
        DocumentationChanged if what == "groups" => "groups".into(),
        // `slave_address: not printed`, `timing.frame_gap: not printed`.
        DocumentationChanged
            if what.ends_with(": not printed")
                && drivemap_core::stated::ProtocolFact::from_key(
                    what.trim_end_matches(": not printed"),
                )
                .is_some() =>
        {
            protocol(what.trim_end_matches(": not printed"))
        }
        _ => String::new(),
    }
}

/// The path of a role named at the start of a change's `what` (`run`, `run place 2`).
fn role(what: &str) -> String {
    let id = what.split([' ', ':']).next().unwrap_or_default();
    format!("roles.{id}")
}

/// Where `change` is in the new map, if the new map has it.
pub(crate) fn at(change: &Change, old: &Map, new: &Map) -> Option<Loc> {
    if change.subject == "roles" {
        return Some(new.locate(&role(&change.what)));
    }
    let id = change.subject.split(' ').next().unwrap_or_default();
    if let Some(r) = new.register_by_id(id) {
        let key = match change.kind {
            ChangeKind::WidthChanged if change.what == "text layout" => Some("string"),
            kind => register_key(kind),
        };
        return Some(match key {
            Some(key) => r.key_location(key),
            None => r.location(),
        });
    }
    if let Some(r) = old.register_by_id(id) {
        // Gone from the new map: the group that held it, if the new map still has it.
        let group = &r.group().id;
        return new
            .groups()
            .iter()
            .position(|g| &g.id == group)
            .map(|i| new.locate(&format!("groups[{i}]")));
    }
    Some(new.locate(&section(change.kind, &change.what)))
}
