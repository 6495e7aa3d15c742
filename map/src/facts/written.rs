//! A map and its registers as the map writes them, every key named ([`WrittenMap`],
//! [`WrittenRegister`]): what a comparison of two maps reads (`drivemap diff`, in
//! `drivemap-review`), so that it misses no key.
//!
//! Both are built here by naming every field of the expanded map and of the schema's register,
//! with no `..`: a key added to the schema does not compile until it has its place in these
//! views (or a comment here says why it has none), and a reader that names every field of the
//! views in turn (the diff does) does not compile until it reads it. The values are the map's
//! own (the schema's types, re-exported by [`crate::facts`]) after expansion: a block's
//! instance with its placeholders filled in, and the keys a register takes from its group
//! (access, table, write restriction, transports, repeat rule, function codes) as they apply
//! to it.

use std::collections::BTreeMap;

use serde::Serialize;

use drivemap_core::register::{Access, Table, WriteRestriction};

use super::{
    AddressAlternative, AddressFormat, BitField, Conflict, DefaultValue, DisplayStep, Draft,
    DriveMeta, EnumValue, Example, Gap, Group, Indexed, Pair, ProfileSpec, Protocol,
    RegisterFunctions, RelativeLimit, Removed, RepeatNeedsChange, RolePlace, Scale, StringText,
    TransportName, Unknown, VariantAxis, VariantOverride,
};
use crate::ir::{Drive, Register};
use crate::map::Map;
use crate::model;

/// Every part of a map as it writes it ([`Map::written`]), the registers as
/// [`WrittenRegister`]s in map order: what a comparison of two maps reads (`drivemap diff`),
/// so that it misses no key.
///
/// Both views are built by naming every field of the expanded map and of the schema's
/// register, with no `..`: a key added to the schema does not compile until it has its place
/// in them (or a comment there says why it has none), and a reader that names every field of
/// the views in turn (the diff does) does not compile until it reads it. The values are the
/// map's own (the schema's types) after expansion: a block's instance with its placeholders
/// filled in, and the keys a register takes from its group (access, table, write restriction,
/// transports, repeat rule, function codes) as they apply to it.
#[derive(Debug, Clone, Serialize)]
pub struct WrittenMap<'m> {
    /// Who the drive is: id, vendor, models, manuals, base map, description.
    pub meta: &'m DriveMeta,
    /// How the manual numbers registers.
    pub address_format: AddressFormat,
    /// The variant axes, each option 0 the base.
    pub variants: &'m [VariantAxis],
    /// The protocol as written.
    pub protocol: &'m Protocol,
    /// The groups of registers, with their own keys (their defaults are in each register's).
    pub groups: &'m [Group],
    /// Every register, blocks expanded, in map order.
    pub registers: Vec<WrittenRegister<'m>>,
    /// Conflicts between readings of the manual outside the registers.
    pub conflicts: &'m [Conflict],
    /// Address ranges the manual leaves out.
    pub gaps: &'m [Gap],
    /// Registers of the base map a variant map removes.
    pub removed: &'m [Removed],
    /// The roles, by role id.
    pub roles: &'m BTreeMap<String, Vec<RolePlace>>,
    /// The command profile (`profile:`), if any.
    pub profile: Option<&'m ProfileSpec>,
    /// The `draft:` mark, if any.
    pub draft: Option<&'m Draft>,
    /// The example frames the manual prints.
    pub examples: &'m [Example],
}

impl<'m> WrittenMap<'m> {
    pub(crate) fn of(map: &'m Map) -> WrittenMap<'m> {
        let drive = map.drive();
        let Drive {
            meta,
            address_format,
            module: _, // the drive id as a Rust name, not written
            variants,
            protocol,
            groups,
            registers,
            conflicts,
            gaps,
            removed,
            roles,
            profile,
            file: _,     // where the map was read, not what it says
            tree: _,     // the same map as text (`Map::tree`)
            plan: _,     // decided from the parts here (`Map::plan`)
            warnings: _, // how an earlier schema version was read, not what the map says
            draft,
            examples,
        } = drive;
        WrittenMap {
            meta,
            address_format: *address_format,
            variants,
            protocol,
            groups,
            registers: registers
                .iter()
                .map(|r| WrittenRegister::of(drive, r))
                .collect(),
            conflicts,
            gaps,
            removed,
            roles,
            profile: profile.as_ref(),
            draft: draft.as_ref(),
            examples,
        }
    }
}

/// Every key of one register as the map writes it ([`RegisterRef::written`]), with what the
/// register takes from its group: see [`WrittenMap`].
///
/// [`RegisterRef::written`]: crate::RegisterRef::written
#[derive(Debug, Clone, Serialize)]
pub struct WrittenRegister<'m> {
    /// The register id (snake_case).
    pub id: &'m str,
    /// The parameter number exactly as printed (with `read_param`, the one a write sets).
    pub param: Option<&'m str>,
    /// The parameter a read returns, when it is not `param` (`read_param:`).
    pub read_param: Option<&'m str>,
    /// The name as printed.
    pub name: &'m str,
    /// The communication address as the manual prints it.
    pub address: u16,
    /// The Modicon reference the manual prints beside it (`reference:`), as printed.
    pub reference: Option<&'m str>,
    /// Its access: its own, else its group's, else read-only.
    pub access: Access,
    /// Its Modbus table: its own, else its group's, else holding registers.
    pub table: Table,
    /// The unit as the manual prints it.
    pub unit: Option<&'m str>,
    /// The scale as written (`scale:`); a range chosen by a setting (`limits: {selected_by}`)
    /// is the selected scale it is expanded into, each case the register's own factor.
    pub scale: Option<&'m Scale>,
    /// A signed word or pair.
    pub signed: bool,
    /// A 32-bit pair's word order and its citation (`pair:`).
    pub pair: Option<&'m Pair>,
    /// Text over consecutive registers: their number, byte order, example and citation
    /// (`string:`).
    pub string: Option<&'m StringText>,
    /// The base variant's lower limit in engineering units.
    pub min: Option<f64>,
    /// The base variant's upper limit in engineering units.
    pub max: Option<f64>,
    /// The base variant's default.
    pub default: Option<&'m DefaultValue>,
    /// What each variant option overrides, by option id.
    pub by_variant: &'m BTreeMap<String, VariantOverride>,
    /// An upper limit through another register or quantity (`max_relative:`).
    pub max_relative: Option<&'m RelativeLimit>,
    /// Addresses it moves to under a condition.
    pub address_alternatives: &'m [AddressAlternative],
    /// Enumeration codes, with their citations.
    pub values: &'m [EnumValue],
    /// Bit fields, with their codes and citations.
    pub fields: &'m [BitField],
    /// What a read means when it differs from a write.
    pub read_values: &'m [EnumValue],
    /// The repeat rule: its own, else its group's.
    pub repeat_needs_change: Option<&'m RepeatNeedsChange>,
    /// Indexed access (`indexed:`).
    pub indexed: Option<&'m Indexed>,
    /// The functions it accepts: its own restriction, else its group's.
    pub function_codes: Option<&'m RegisterFunctions>,
    /// When the drive accepts a write: its own, else its group's, else any time.
    pub write_restriction: WriteRestriction,
    /// The transports it exists on: its own list, else its group's; `None` for every transport
    /// of the drive.
    pub transports: Option<&'m [TransportName]>,
    /// How the keypad shows finer values.
    pub display_steps: &'m [DisplayStep],
    /// The register's own citation.
    pub source: Option<&'m str>,
    /// Why its citation is indirect, when it is.
    pub indirect: Option<&'m str>,
    /// Its notes.
    pub notes: &'m [String],
    /// Conflicts between readings of the manual about it.
    pub conflicts: &'m [Conflict],
    /// What the manual leaves unknown about it.
    pub unknown: &'m [Unknown],
    /// Member of a broadcast group: written to slave 0 only.
    pub broadcast: bool,
    /// The id of its group.
    pub group: &'m str,
}

impl<'m> WrittenRegister<'m> {
    pub(crate) fn of(drive: &'m Drive, r: &'m Register) -> WrittenRegister<'m> {
        let Register {
            def,
            access,
            table,
            write_restriction,
            transports,
            broadcast,
            group,
            path: _, // where it is written (`RegisterRef::location`), not what it says
            repeat_needs_change,
            function_codes,
            limits_form: _, // where its cases are written, not what they say
            index: _,       // its place in the map's list, not a property
        } = r;
        let model::Register {
            id,
            param,
            read_param,
            name,
            address,
            reference,
            access: _,       // in `access`, with its group's
            modbus_table: _, // in `table`, with its group's
            unit,
            scale,
            signed,
            pair,
            string,
            min,
            max,
            max_relative,
            limits: _, // expanded into `scale` (`ir::selected_limits`)
            default,
            by_variant,
            address_alternatives,
            values,
            fields,
            read_values,
            repeat_needs_change: _, // in `repeat_needs_change`, with its group's
            indexed,
            function_codes: _,    // in `function_codes`, with its group's
            write_restriction: _, // in `write_restriction`, with its group's
            transports: _,        // in `transports`, with its group's
            display_steps,
            repeat: _, // expanded: one register per instance, its placeholders filled in
            source,
            indirect,
            notes,
            conflicts,
            unknown,
        } = def;
        WrittenRegister {
            id,
            param: param.as_deref(),
            read_param: read_param.as_deref(),
            name,
            address: *address,
            reference: reference.as_deref(),
            access: *access,
            table: *table,
            unit: unit.as_deref(),
            scale: scale.as_ref(),
            signed: *signed,
            pair: pair.as_ref(),
            string: string.as_ref(),
            min: *min,
            max: *max,
            default: default.as_ref(),
            by_variant,
            max_relative: max_relative.as_ref(),
            address_alternatives,
            values,
            fields,
            read_values,
            repeat_needs_change: repeat_needs_change.as_ref().map(|(rule, _)| rule),
            indexed: indexed.as_ref(),
            function_codes: function_codes.as_ref().map(|(f, _)| f),
            write_restriction: *write_restriction,
            transports: transports.as_deref(),
            display_steps,
            source: source.as_deref(),
            indirect: indirect.as_deref(),
            notes,
            conflicts,
            unknown,
            broadcast: *broadcast,
            group: &drive.groups[*group].id,
        }
    }
}
