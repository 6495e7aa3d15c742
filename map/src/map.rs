//! A validated map ([`Map`]) and its registers ([`RegisterRef`]): what every consumer reads,
//! the plan for what a register means on the wire, the facts view for what the map says
//! about it (with citations), locations for what a tool reports.

use std::path::Path;

use drivemap_core::kind::ConversionKind;
use drivemap_core::plan::RegisterPlan;
use drivemap_core::width::Width;

use crate::diagnostic::{Diagnostic, Diagnostics, Loc};
use crate::facts::{self, DriveFacts, ProtocolFacts, RegisterFacts};
use crate::ir::{self, Drive};
use crate::lower::MapPlan;

/// A map read and validated by a [`Loader`](crate::Loader): one drive's registers, its
/// plan and its facts.
#[derive(Debug, Clone)]
pub struct Map {
    drive: Drive,
}

impl Map {
    /// A map when validation found nothing and the drive lowers (the last pass), else the
    /// findings.
    pub(crate) fn checked(drive: Drive, errors: Vec<Diagnostic>) -> Result<Map, Diagnostics> {
        if !errors.is_empty() {
            return Err(errors.into());
        }
        drive.try_plan()?;
        Ok(Map { drive })
    }

    /// The expanded map, for this crate's own views.
    pub(crate) fn drive(&self) -> &Drive {
        &self.drive
    }

    // ---- who the drive is -------------------------------------------------------------

    /// The drive id (`yaskawa-v7`).
    pub fn id(&self) -> &str {
        &self.drive.meta.id
    }

    /// The Rust module name of the generated drive (`yaskawa_v7`).
    pub fn module(&self) -> &str {
        &self.drive.module
    }

    /// The file the map was read from.
    pub fn file(&self) -> &Path {
        &self.drive.file
    }

    /// Vendor, models, manuals, base map and description, as the map writes them.
    pub fn meta(&self) -> &facts::DriveMeta {
        &self.drive.meta
    }

    /// How the manual numbers registers (hex unless the map says decimal).
    pub fn address_format(&self) -> facts::AddressFormat {
        self.drive.address_format
    }

    /// An address as the manual prints it (`0200h`, or decimal).
    pub fn manual_address(&self, address: u16) -> String {
        facts::manual_address(&self.drive, address)
    }

    /// The map's `draft:` mark: it loads and checks (with a warning), the generator refuses it.
    pub fn draft(&self) -> Option<&facts::Draft> {
        self.drive.draft.as_ref()
    }

    /// The warning that a draft map prints, when it is one.
    pub fn draft_warning(&self) -> Option<String> {
        self.drive.draft.as_ref().map(ir::draft_warning)
    }

    /// What reading a file of the map in an earlier schema version changed: printed by
    /// `check`, `diff` and the build, never an error.
    pub fn warnings(&self) -> &[Diagnostic] {
        &self.drive.warnings
    }

    // ---- the plan ---------------------------------------------------------------------

    /// What every register means, decided once (lowered on first use).
    ///
    /// The plan's tables are `'static`, as generated code's are: lowering leaks them, and they
    /// stay in memory until the process ends, whether the `Map` is kept or dropped (measured:
    /// 0.2 MB per load of `yaskawa-v7`, 206 registers; 0.5 MB of `automationdirect-acn`, 762).
    /// Lower each map once and keep it: a program that loads maps again and again (a service
    /// taking maps from its users) grows with every load.
    pub fn plan(&self) -> &MapPlan {
        self.drive.plan()
    }

    // ---- registers --------------------------------------------------------------------

    /// Every register in the map's order (group by group, blocks expanded).
    pub fn registers(&self) -> impl ExactSizeIterator<Item = RegisterRef<'_>> + '_ {
        self.drive
            .registers
            .iter()
            .map(|r| RegisterRef { map: self, reg: r })
    }

    /// A register by id, or else by parameter number as printed.
    pub fn register(&self, name: &str) -> Option<RegisterRef<'_>> {
        self.drive
            .find(name)
            .map(|r| RegisterRef { map: self, reg: r })
    }

    /// A register by id only.
    pub fn register_by_id(&self, id: &str) -> Option<RegisterRef<'_>> {
        self.drive
            .registers
            .iter()
            .find(|r| r.def.id == id)
            .map(|r| RegisterRef { map: self, reg: r })
    }

    /// The register of `row` of the plan (`plan().registers[row]`).
    pub fn register_of_row(&self, row: usize) -> Option<RegisterRef<'_>> {
        self.drive
            .register_of_row(row)
            .map(|r| RegisterRef { map: self, reg: r })
    }

    /// The register at place `index` of [`Map::registers`] (map order).
    pub fn register_at(&self, index: usize) -> Option<RegisterRef<'_>> {
        self.drive
            .registers
            .get(index)
            .map(|r| RegisterRef { map: self, reg: r })
    }

    /// The registers whose values (or a field of whose values) select scales or addresses, in
    /// first-use order, each once (what a client reads before converting).
    pub fn selectors(&self) -> Vec<RegisterRef<'_>> {
        self.wrap(self.drive.selectors())
    }

    /// The registers other registers are scaled or limited relative to, in first-use order.
    pub fn references(&self) -> Vec<RegisterRef<'_>> {
        self.wrap(self.drive.references())
    }

    /// The external quantities (not registers) relative scales and limits refer to.
    pub fn externals(&self) -> Vec<&facts::ExternalQuantity> {
        self.drive.externals()
    }

    fn wrap<'m>(&'m self, list: Vec<&'m ir::Register>) -> Vec<RegisterRef<'m>> {
        list.into_iter()
            .map(|reg| RegisterRef { map: self, reg })
            .collect()
    }

    /// The serial line's defaults when a link gives none: baud, parity and character format.
    pub fn serial_defaults(&self) -> facts::SerialDefaults {
        self.drive.serial_defaults()
    }

    /// Communication addresses a broadcast may write, sorted.
    pub fn broadcast_addresses(&self) -> Vec<u16> {
        self.drive.broadcast_addresses()
    }

    // ---- the facts view ---------------------------------------------------------------

    /// The facts of every register and of the protocol.
    pub fn facts(&self) -> DriveFacts {
        facts::facts(&self.drive)
    }

    /// The protocol's facts.
    pub fn protocol_facts(&self) -> ProtocolFacts {
        facts::protocol(&self.drive)
    }

    /// The protocol as the map writes it.
    pub fn protocol(&self) -> &facts::Protocol {
        &self.drive.protocol
    }

    /// Every protocol fact the map marks not printed (`unknown:`), in `ProtocolFact::ALL`
    /// order, with why.
    pub fn not_printed(&self) -> Vec<facts::Unprinted> {
        crate::stated::unprinted(&self.drive.protocol)
    }

    /// Why `fact` is not printed, if the map says so.
    pub fn not_printed_why(
        &self,
        fact: drivemap_core::stated::ProtocolFact,
    ) -> Option<facts::Unprinted> {
        crate::stated::why(&self.drive.protocol, fact)
    }

    /// The warnings `drivemap check` prints for protocol facts the map neither states nor
    /// marks not printed.
    pub fn protocol_warnings(&self) -> Vec<Diagnostic> {
        crate::validate::protocol_stated::warnings(&self.drive)
    }

    /// The groups of registers as the manual groups them, in the map's order.
    pub fn groups(&self) -> &[facts::Group] {
        &self.drive.groups
    }

    /// The access a group states for its registers (`access:` of the group), if it does.
    pub fn group_access(&self, group: &facts::Group) -> Option<drivemap_core::register::Access> {
        let node = self.drive.tree.at(&group.path.key("access"))?;
        serde_yaml::from_value(node.to_value()).ok()
    }

    /// The variant axes (voltage class, capacity), each option 0 the base.
    pub fn variants(&self) -> &[facts::VariantAxis] {
        &self.drive.variants
    }

    /// The variant axis and option for an option id.
    pub fn variant_option(
        &self,
        option: &str,
    ) -> Option<(&facts::VariantAxis, &facts::VariantOption)> {
        self.drive.variant_option(option)
    }

    /// The map's conflicts between readings of the manual (outside registers).
    pub fn conflicts(&self) -> &[facts::Conflict] {
        &self.drive.conflicts
    }

    /// Address ranges the manual leaves out, with why.
    pub fn gaps(&self) -> &[facts::Gap] {
        &self.drive.gaps
    }

    /// Registers of the base map a variant map removes.
    pub fn removed(&self) -> &[facts::Removed] {
        &self.drive.removed
    }

    /// The example frames the manual prints.
    pub fn examples(&self) -> &[facts::Example] {
        &self.drive.examples
    }

    /// The map's roles as written, by role id (the lowered ones are [`MapPlan::roles`]).
    pub fn roles(&self) -> &std::collections::BTreeMap<String, Vec<facts::RolePlace>> {
        &self.drive.roles
    }

    /// The command profile as written (`profile:`), if any; [`facts::ProfileSpec::resolved`]
    /// merges it under the standard it names.
    pub fn profile(&self) -> Option<&facts::ProfileSpec> {
        self.drive.profile.as_ref()
    }

    /// PDU address offsets (RTU, TCP).
    pub fn address_offsets(&self) -> (i32, i32) {
        self.drive.address_offsets()
    }

    // ---- printing -----------------------------------------------------------------------

    /// The map as `drivemap export --format json` writes it.
    pub fn export(&self) -> serde_json::Value {
        crate::export::export(&self.drive)
    }

    /// A setting named in the map (a selector, a reference) as a user names it.
    pub fn describe_setting(&self, name: &str) -> String {
        crate::describe::setting(&self.drive, name)
    }

    /// Every part of the map as it writes it, each register's keys with them
    /// ([`facts::WrittenMap`]): what a comparison of two maps reads to miss none.
    pub fn written(&self) -> facts::WrittenMap<'_> {
        facts::WrittenMap::of(self)
    }

    // ---- locations ----------------------------------------------------------------------

    /// The YAML tree the map was read from, every node located (a variant map merged onto its
    /// base).
    pub fn tree(&self) -> &crate::Tree {
        &self.drive.tree
    }

    /// Where a key path of the map (`protocol.timing`, `groups[0].registers[1].scale`,
    /// written with `.` between keys and `[i]` for items) is written; the map's own file
    /// start when no node is there.
    pub fn locate(&self, path: &str) -> Loc {
        self.drive.locate(&parse_path(path))
    }

    /// Where the value at a key path of the map (see [`Map::locate`]) starts, as opposed to its
    /// key: the first character of a string, for a finding at a byte inside it; where its key
    /// or the nearest written ancestor is when no value is there.
    pub fn locate_value(&self, path: &str) -> Loc {
        let path = parse_path(path);
        self.drive
            .tree
            .at(&path)
            .map_or_else(|| self.drive.locate(&path), |n| n.loc.clone())
    }

    /// Where a path of the map's tree ([`crate::TreePath`], as a citation place or another
    /// citation carries it) is written.
    pub fn locate_tree_path(&self, path: &crate::TreePath) -> Loc {
        self.drive.locate(path)
    }

    // ---- citations ----------------------------------------------------------------------

    /// Every place of the map that cites a manual (registers, values, fields, protocol items,
    /// roles, conflicts, gaps), in map order: the one list the citation checks read.
    pub fn citation_places(&self) -> Vec<facts::CitationPlace<'_>> {
        crate::citations::citation_places(&self.drive)
    }

    /// The citations outside the registers' rows, each with what its line is expected to show.
    pub fn other_citations(&self) -> Vec<facts::OtherCitation> {
        crate::others::other_citations(&self.drive)
    }

    /// What the line of an other citation is expected to show, for messages.
    pub fn expected(&self, rule: &facts::CitationRule) -> String {
        rule.expected(&self.drive)
    }

    /// A diagnostic at a key path of the map (see [`Map::locate`]), naming `register`.
    pub fn error_at(
        &self,
        path: &str,
        register: Option<&str>,
        message: impl Into<String>,
    ) -> Diagnostic {
        Diagnostic::new(self.locate(path), register, message)
    }
}

/// `a.b[2].c` → a tree path.
fn parse_path(text: &str) -> crate::source::Path {
    let mut p = crate::source::Path::root();
    for part in text.split('.').filter(|s| !s.is_empty()) {
        let (key, rest) = part.split_once('[').unwrap_or((part, ""));
        if !key.is_empty() {
            p = p.key(key);
        }
        for index in rest.split('[') {
            if let Ok(i) = index.trim_end_matches(']').parse::<usize>() {
                p = p.index(i);
            }
        }
    }
    p
}

/// One register of a [`Map`]: its names, its plan, its facts and where it is written.
#[derive(Debug, Clone, Copy)]
pub struct RegisterRef<'m> {
    map: &'m Map,
    reg: &'m ir::Register,
}

impl PartialEq for RegisterRef<'_> {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.map, other.map) && self.reg.index == other.reg.index
    }
}

impl<'m> RegisterRef<'m> {
    /// The map it belongs to.
    pub fn map(&self) -> &'m Map {
        self.map
    }

    /// The register id (snake_case).
    pub fn id(&self) -> &'m str {
        &self.reg.def.id
    }

    /// The parameter number exactly as printed (`Bn-01`, `n019`).
    pub fn param(&self) -> Option<&'m str> {
        self.reg.def.param.as_deref()
    }

    /// The parameter a read returns when it is not [`RegisterRef::param`], which is then the
    /// one a write sets (Siemens BICO: read r0055.8, write P2200).
    pub fn read_param(&self) -> Option<&'m str> {
        self.reg.def.read_param.as_deref()
    }

    /// The name as printed.
    pub fn name(&self) -> &'m str {
        &self.reg.def.name
    }

    /// The register as a user names it: id, and the parameter number when printed
    /// (`frequency_reference (n024)`).
    pub fn label(&self) -> String {
        crate::describe::register(self.reg)
    }

    /// The parameter number when printed, else the id.
    pub fn shown(&self) -> &'m str {
        self.param().unwrap_or(self.id())
    }

    /// The communication address as the manual prints it (the plan's `info.address`).
    pub fn address(&self) -> u16 {
        self.reg.def.address
    }

    /// The Modicon reference the manual prints beside the register (`reference:`), as printed
    /// (`40024`, a coil's `00001`).
    pub fn reference(&self) -> Option<&'m str> {
        self.reg.def.reference.as_deref()
    }

    /// The Modicon reference the map records for the register, read
    /// ([`crate::modicon::Modicon::parse`]); `None` when it records none (or `check` refuses it).
    pub fn modicon(&self) -> Option<crate::modicon::Modicon> {
        self.reference().and_then(crate::modicon::Modicon::parse)
    }

    /// The unit as the manual prints it.
    pub fn unit(&self) -> Option<&'m str> {
        self.reg.def.unit.as_deref()
    }

    /// The register's own citation (`file:line`).
    pub fn source(&self) -> Option<&'m str> {
        self.reg.def.source.as_deref()
    }

    /// Why the citation is indirect, when it is.
    pub fn indirect(&self) -> Option<&'m str> {
        self.reg.def.indirect.as_deref()
    }

    /// The register's notes.
    pub fn notes(&self) -> &'m [String] {
        &self.reg.def.notes
    }

    /// Its place in [`Map::registers`] (map order).
    pub fn index(&self) -> usize {
        self.reg.index()
    }

    /// Its row in the plan (`plan().registers[row]`).
    pub fn row(&self) -> usize {
        self.map.drive.plan().order[self.reg.index()]
    }

    /// What it means on the wire, decided once.
    pub fn plan(&self) -> &'static RegisterPlan {
        self.map.drive.register_plan(self.reg)
    }

    /// The kind of conversion the plan decided.
    pub fn kind(&self) -> ConversionKind {
        ConversionKind::of(&self.plan().conversion)
    }

    /// Everything the printers say about it (rows with citations, and the typed values).
    pub fn facts(&self) -> RegisterFacts {
        facts::register(&self.map.drive, self.reg)
    }

    /// The same facts as typed values.
    pub fn data(&self) -> facts::RegisterData {
        facts::RegisterData::of(&self.map.drive, self.reg)
    }

    /// Every key of the register as the map writes it, with what it takes from its group
    /// ([`facts::WrittenRegister`]): what a comparison of two registers reads to miss none.
    pub fn written(&self) -> facts::WrittenRegister<'m> {
        facts::WrittenRegister::of(&self.map.drive, self.reg)
    }

    /// One register, or a 32-bit pair in the map's word order.
    pub fn width(&self) -> Width {
        self.reg.width()
    }

    /// A signed word or pair.
    pub fn signed(&self) -> bool {
        self.reg.def.signed
    }

    /// Readable (access `r` or `rw`).
    pub fn readable(&self) -> bool {
        self.reg.readable()
    }

    /// Writable (access `w` or `rw`).
    pub fn writable(&self) -> bool {
        self.reg.writable()
    }

    /// The access the register's own row states; `None` where it takes its group's (or the
    /// default, read-only).
    pub fn access_written(&self) -> Option<drivemap_core::register::Access> {
        self.reg.def.access
    }

    /// The access its group states for its registers (`access:` of the group), if it does.
    pub fn group_access(&self) -> Option<drivemap_core::register::Access> {
        self.map.group_access(self.map.drive.group_of(self.reg))
    }

    /// Member of a broadcast group: written to slave 0 only.
    pub fn broadcast_only(&self) -> bool {
        self.reg.broadcast
    }

    /// The group it belongs to.
    pub fn group(&self) -> &'m facts::Group {
        self.map.drive.group_of(self.reg)
    }

    /// The base variant's limits in engineering units.
    pub fn limits(&self) -> (Option<f64>, Option<f64>) {
        self.reg.limits()
    }

    /// The limits for a variant option: its override where given, else the base.
    pub fn limits_for(&self, option: &str) -> (Option<f64>, Option<f64>) {
        self.reg.limits_for(option)
    }

    /// The variant options that override its limits or default, in the map's order (by id).
    pub fn variant_options(&self) -> impl Iterator<Item = &'m str> + 'm {
        self.reg.def.by_variant.keys().map(String::as_str)
    }

    /// The base variant's default as a number, if the manual prints one.
    pub fn default_value(&self) -> Option<f64> {
        self.reg.default_value()
    }

    /// The printed numeric default for the first variant option `chosen` accepts that
    /// overrides it, else the base default.
    pub fn default_for(&self, chosen: impl Fn(&str) -> bool) -> Option<f64> {
        self.reg.default_for(chosen)
    }

    /// The base variant's default as written (a value, or what it depends on).
    pub fn default(&self) -> Option<&'m facts::DefaultValue> {
        self.reg.def.default.as_ref()
    }

    /// Addresses the register moves to under a condition, cited.
    pub fn address_alternatives(&self) -> &'m [facts::AddressAlternative] {
        &self.reg.def.address_alternatives
    }

    /// Conflicts between readings of the manual about this register.
    pub fn conflicts(&self) -> &'m [facts::Conflict] {
        &self.reg.def.conflicts
    }

    /// What the manual leaves unknown about it.
    pub fn unknown(&self) -> &'m [facts::Unknown] {
        &self.reg.def.unknown
    }

    /// Indexed access: the entries an index register selects, when it has them.
    pub fn indexed(&self) -> Option<&'m facts::Indexed> {
        self.reg.def.indexed.as_ref()
    }

    /// The scale as the map writes it (`scale:`), `None` where it writes none (the plan's
    /// conversion takes a unit without a scale as factor 1).
    pub fn scale(&self) -> Option<facts::data::ScaleData> {
        (self.reg.def.scale.as_ref()).map(|s| facts::data::scale_of(&self.map.drive, s))
    }

    /// The scale the map writes in one line, as [`describe`](crate::describe) words it (a
    /// selected scale with its cases: `selected by n152: 0 → 0.1 Hz; 1 → 0.01 Hz`); `None` where
    /// it writes none.
    pub fn scale_text(&self) -> Option<String> {
        let unit = self.reg.def.unit.as_deref().unwrap_or("");
        (self.reg.def.scale.as_ref()).map(|s| crate::describe::scale(&self.map.drive, s, unit))
    }

    /// Enumeration codes as written, with their citations (the plan's are
    /// `Conversion::Enum { values }`).
    pub fn values(&self) -> &'m [facts::EnumValue] {
        &self.reg.def.values
    }

    /// What a read means when it differs from a write, as written with citations (the plan's
    /// are `RegisterPlan::read_values`).
    pub fn read_values(&self) -> &'m [facts::EnumValue] {
        &self.reg.def.read_values
    }

    /// Bit fields as written, with names, notes and citations (the plan's, with their bit
    /// spans decided, are `Conversion::Bits { fields }`).
    pub fn fields(&self) -> &'m [facts::BitField] {
        &self.reg.def.fields
    }

    /// The Rust type of the register in generated code: `accel_time_1` → `AccelTime1`.
    pub fn type_name(&self) -> String {
        crate::names::register_type(self.reg)
    }

    /// The generated enumeration of its codes: `RunSourceValue`.
    pub fn value_enum_name(&self) -> String {
        crate::names::value_enum(self.reg)
    }

    /// The generated enumeration of what a read means (`read_values`): `…Read`.
    pub fn read_enum_name(&self) -> String {
        crate::names::read_enum(self.reg)
    }

    /// The generated bit-field struct: `InverterStatusBits`.
    pub fn bits_type_name(&self) -> String {
        crate::names::bits_type(self.reg)
    }

    /// The generated enumeration of a multi-bit field's codes: `InverterStatusSettingError`.
    pub fn field_enum_name(&self, field: &facts::BitField) -> String {
        crate::names::field_enum(self.reg, field)
    }

    /// The widest bounds and finest step of a number input for the register (Home Assistant's
    /// `number`): see [`facts::InputBounds`].
    pub fn input_bounds(&self) -> facts::InputBounds {
        facts::InputBounds::of(&self.map.drive, self.reg)
    }

    /// Where the register (or its block template) is written.
    pub fn location(&self) -> Loc {
        self.map.drive.locate(&self.reg.path)
    }

    /// Where key `key` of the register is written (the register's own place when it has no
    /// such key).
    pub fn key_location(&self, key: &str) -> Loc {
        self.map.drive.locate(&self.reg.key_path(key))
    }

    /// A diagnostic at key `key` of this register.
    pub fn error_at(&self, key: &str, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(self.key_location(key), Some(self.id()), message)
    }
}
