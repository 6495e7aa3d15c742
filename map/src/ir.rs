//! The intermediate representation: the model with group defaults applied, blocks expanded and
//! every register located, plus the lookups that validation, emission and tools share.
//!
//! `expand` builds it from a loaded map; `validate` checks it; once it is valid, the
//! accessors here (value kind, raw ranges, references) cannot fail on well-formed input and the
//! generator, the exporter and the simulator all read the same answers.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use crate::diagnostic::{Diagnostic, Loc};
use crate::load::LoadedMap;
use crate::lower::MapPlan;
use crate::model::{
    self, Access, Conflict, DefaultValue, EnumValue, Field, Gap, ModbusTable, Parity, Reference,
    Removed, Scale, TransportName, VariantAxis, WriteRestriction,
};
use crate::source::{Node, Path};
use drivemap_core::scale::{Decimal, RawRange, raw_of};
use drivemap_core::width::Width;

/// A drive map, expanded and located.
#[derive(Debug, Clone)]
pub(crate) struct Drive {
    pub meta: model::DriveMeta,
    /// How the manual numbers registers (`address_format`; hex unless the map says decimal).
    pub address_format: model::AddressFormat,
    /// Rust module name (`ptlk_tds_v8`).
    pub module: String,
    pub variants: Vec<VariantAxis>,
    pub protocol: model::Protocol,
    pub groups: Vec<Group>,
    /// All registers in document order (group by group).
    pub registers: Vec<Register>,
    pub conflicts: Vec<Conflict>,
    pub gaps: Vec<Gap>,
    pub removed: Vec<Removed>,
    /// Roles by id, as written (checked by `validate::roles_valid`, lowered in `lower`).
    pub roles: std::collections::BTreeMap<String, Vec<model::RolePlace>>,
    /// The command profile, as written (`profile:`; checked and lowered by
    /// [`crate::command_profile`]).
    pub profile: Option<crate::command_profile::ProfileSpec>,
    /// The file the map was read from.
    pub file: PathBuf,
    /// The merged YAML tree, for locating findings.
    pub tree: Node,
    /// The drive plan, lowered on first use ([`Drive::plan`]).
    pub plan: OnceLock<Arc<MapPlan>>,
    /// What reading a file of the map in an earlier schema version changed
    /// (`schema`): printed by `check`, `diff` and the build, never an error.
    pub warnings: Vec<Diagnostic>,
    /// The map's `draft:` mark: it loads and checks (with a warning), the generator refuses it.
    pub draft: Option<model::Draft>,
    /// The example frames the manual prints (`examples:`), as written.
    pub examples: Vec<crate::examples::Example>,
}

/// A group of registers as the manual groups them.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Group {
    /// The group id.
    pub id: String,
    /// Its name as the map gives it.
    pub name: String,
    /// The manual's table name.
    pub table: Option<String>,
    /// Its citation.
    pub source: Option<String>,
    /// Broadcast registers: written to slave 0 only.
    pub broadcast: bool,
    /// The group's notes.
    pub notes: Vec<String>,
    /// Where the group is written.
    #[serde(skip)]
    pub path: Path,
}

/// One register (blocks already expanded), with group defaults applied.
#[derive(Debug, Clone)]
pub(crate) struct Register {
    /// The register as written, with `repeat` placeholders substituted and `repeat` removed.
    pub def: model::Register,
    pub access: Access,
    pub table: ModbusTable,
    pub write_restriction: WriteRestriction,
    pub transports: Option<Vec<TransportName>>,
    /// Member of a broadcast group: written to slave 0 only, in its own address space.
    pub broadcast: bool,
    /// Index into [`Drive::groups`].
    pub group: usize,
    /// Where the register (or its block template) is written.
    pub path: Path,
    /// The register's `repeat_needs_change`, else its group's, with where it is written.
    pub repeat_needs_change: Option<(model::RepeatNeedsChange, Path)>,
    /// The register's `function_codes`, else its group's, with where it is written.
    pub function_codes: Option<(model::RegisterFunctions, Path)>,
    /// Its selected scale was written as `limits: {selected_by, cases}` (its cases are located
    /// there: [`Register::cases_path`]).
    pub limits_form: bool,
    /// Its place in [`Drive::registers`], given by `expand` (only this crate can make a
    /// [`RegisterIndex`]): the handle the plan lookups ([`Drive::register_plan`], lowering)
    /// index by.
    pub index: RegisterIndex,
}

/// A register's place in [`Drive::registers`] (map order). Made only when a map is expanded,
/// so a lookup by it needs no search and has no row to fall back to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct RegisterIndex(usize);

/// What a register's word means.
#[derive(Debug, Clone, Copy)]
pub(crate) enum ValueKind<'a> {
    /// A plain `u16` / `i16`.
    Word,
    /// An engineering value: `f64` in `unit`.
    Quantity(&'a Scale),
    /// A quantity with a unit but no scale: factor 1.
    UnitQuantity,
    Enum(&'a [EnumValue]),
    Bits(&'a [Field]),
    /// Text over [`Register::width`] registers.
    Text(&'a crate::model::StringText),
}

impl Register {
    pub(crate) fn id(&self) -> &str {
        &self.def.id
    }

    /// Its place in [`Drive::registers`] (map order), given when the map was expanded.
    pub(crate) fn index(&self) -> usize {
        self.index.0
    }

    /// One register, or a 32-bit pair in the map's word order.
    pub(crate) fn width(&self) -> Width {
        match (&self.def.pair, &self.def.string) {
            (_, Some(t)) => Width::Text(t.registers),
            (None, None) => Width::Word,
            (Some(p), None) => Width::Pair(p.order),
        }
    }

    /// The whole range of the register's word or pair, signed or not; 0 ..= 1 for a coil or a
    /// discrete input (one bit).
    pub(crate) fn full_limits(&self) -> RawRange {
        if self.table.is_bits() {
            return RawRange { min: 0, max: 1 };
        }
        self.width().range(self.def.signed)
    }

    pub(crate) fn kind(&self) -> ValueKind<'_> {
        if let Some(text) = &self.def.string {
            ValueKind::Text(text)
        } else if !self.def.fields.is_empty() {
            ValueKind::Bits(&self.def.fields)
        } else if !self.def.values.is_empty() {
            ValueKind::Enum(&self.def.values)
        } else if let Some(scale) = &self.def.scale {
            ValueKind::Quantity(scale)
        } else if self.def.unit.is_some() {
            ValueKind::UnitQuantity
        } else {
            ValueKind::Word
        }
    }

    pub(crate) fn readable(&self) -> bool {
        matches!(self.access, Access::Read | Access::ReadWrite)
    }

    pub(crate) fn writable(&self) -> bool {
        matches!(self.access, Access::Write | Access::ReadWrite)
    }

    /// The decimal factor of a fixed-scale register (scale 1 for unit quantities and words).
    pub(crate) fn factor(&self) -> Option<Decimal> {
        match self.kind() {
            ValueKind::Quantity(Scale::Factor(f)) => Decimal::from_f64(*f),
            ValueKind::Quantity(_) => None,
            _ => Some(Decimal::ONE),
        }
    }

    /// Raw limits for given engineering limits at a fixed decimal factor; missing limits are
    /// the word's own. `None` when a limit is not a whole number of increments (or beyond
    /// `i64`, far outside any word: validation reports both).
    pub(crate) fn raw_limits(
        &self,
        factor: Decimal,
        min: Option<f64>,
        max: Option<f64>,
    ) -> Option<RawRange> {
        let word = self.full_limits();
        let raw = |m: f64| raw_of(m, factor).and_then(|r| i64::try_from(r).ok());
        let min = match min {
            Some(m) => raw(m)?,
            None => word.min,
        };
        let max = match max {
            Some(m) => raw(m)?,
            None => word.max,
        };
        Some(RawRange { min, max })
    }

    /// Limits of the base variant in engineering units.
    pub(crate) fn limits(&self) -> (Option<f64>, Option<f64>) {
        (self.def.min, self.def.max)
    }

    /// Limits for a variant option: its override where given, else the base.
    pub(crate) fn limits_for(&self, option: &str) -> (Option<f64>, Option<f64>) {
        match self.def.by_variant.get(option) {
            Some(o) => (o.min.or(self.def.min), o.max.or(self.def.max)),
            None => (self.def.min, self.def.max),
        }
    }

    /// The base variant's default as a number, if the manual prints one.
    pub(crate) fn default_value(&self) -> Option<f64> {
        match &self.def.default {
            Some(DefaultValue::Value(v)) => Some(*v),
            _ => None,
        }
    }

    /// The printed numeric default for the first variant option `chosen` accepts that overrides
    /// it (`by_variant.<option>.default`), else the base default; `None` where the default is
    /// not a number (it depends on another setting) or not printed.
    pub(crate) fn default_for(&self, chosen: impl Fn(&str) -> bool) -> Option<f64> {
        let by_variant = self
            .def
            .by_variant
            .iter()
            .find(|(option, _)| chosen(option))
            .and_then(|(_, o)| o.default.as_ref());
        match by_variant.or(self.def.default.as_ref()) {
            Some(DefaultValue::Value(v)) => Some(*v),
            _ => None,
        }
    }

    /// Location of a key of this register.
    pub(crate) fn key_path(&self, key: &str) -> Path {
        self.path.key(key)
    }

    /// Where the cases of its selected scale are written: `scale.cases`, or `limits.cases`
    /// for a range chosen by a setting ([`Register::limits_form`]).
    pub(crate) fn cases_path(&self) -> Path {
        if self.limits_form {
            self.path.key("limits").key("cases")
        } else {
            self.path.key("scale").key("cases")
        }
    }

    /// Where its selected scale is written: `scale`, or `limits` ([`Register::cases_path`]).
    pub(crate) fn selection_path(&self) -> Path {
        self.path
            .key(if self.limits_form { "limits" } else { "scale" })
    }
}

impl Drive {
    /// What every register means, decided once ([`crate::lower`]): lowered on first use and
    /// kept for the life of this value. Call it on a validated drive.
    ///
    /// # Panics
    /// When the drive does not lower: a [`crate::Map`] is lowered when it is loaded, so only
    /// the crate's own passes ask a drive that may not, through [`Drive::try_plan`].
    pub(crate) fn plan(&self) -> &MapPlan {
        match self.try_plan() {
            Ok(plan) => plan,
            Err(errors) => panic!("{} does not lower: {errors:?}", self.meta.id),
        }
    }

    /// The plan, lowered on first use, or why the drive does not lower.
    pub(crate) fn try_plan(&self) -> Result<&MapPlan, Vec<Diagnostic>> {
        if let Some(plan) = self.plan.get() {
            return Ok(plan);
        }
        let plan = crate::lower::lower(self)?;
        Ok(self.plan.get_or_init(|| Arc::new(plan)))
    }

    /// The register of row `row` of the plan (`plan().registers[row]`).
    pub(crate) fn register_of_row(&self, row: usize) -> Option<&Register> {
        let m = self.plan().order.iter().position(|&r| r == row)?;
        self.registers.get(m)
    }

    /// The plan of register `r` of this drive, by the place `expand` gave it (constant time:
    /// the simulator asks for every word it serves).
    ///
    /// # Panics
    /// When `r` is not a register of this drive (a register of another map, or of this map
    /// expanded separately, with another id at its place): a caller's mistake, never the data's —
    /// [`crate::Map::register_by_id`] finds another map's register by id. There is no fallback
    /// row.
    pub(crate) fn register_plan(&self, r: &Register) -> &'static drivemap_core::plan::RegisterPlan {
        let plan = self.plan();
        let index = r.index();
        match self.registers.get(index) {
            // The same row (a `RegisterRef` of this map) without comparing ids; an equal row of
            // a clone of this map by its id.
            Some(own) if std::ptr::eq(own, r) || own.def.id == r.def.id => {
                &plan.registers[plan.order[index]]
            }
            _ => panic!(
                "register {} (#{index}) is not a register of {}: look another map's register up by id (Map::register_by_id)",
                r.def.id, self.meta.id
            ),
        }
    }

    /// Locates a path in the merged tree.
    pub(crate) fn locate(&self, path: &Path) -> Loc {
        self.tree.locate(path)
    }

    /// A diagnostic at `path`, naming `register`.
    pub(crate) fn error(
        &self,
        path: &Path,
        register: Option<&str>,
        message: impl Into<String>,
    ) -> Diagnostic {
        Diagnostic::new(self.locate(path), register, message)
    }

    /// A register by id, or else by parameter number as printed (the one a write sets, then
    /// the one a read returns where they differ: `read_param`), or else by the Modicon
    /// reference it records (`reference: 40024`, named `40024` or `400024`).
    pub(crate) fn find(&self, name: &str) -> Option<&Register> {
        self.registers
            .iter()
            .find(|r| r.def.id == name)
            .or_else(|| {
                self.registers
                    .iter()
                    .find(|r| r.def.param.as_deref() == Some(name))
            })
            .or_else(|| {
                self.registers
                    .iter()
                    .find(|r| r.def.read_param.as_deref() == Some(name))
            })
            .or_else(|| {
                let m = crate::modicon::Modicon::parse(name)?;
                self.registers.iter().find(|r| {
                    r.def
                        .reference
                        .as_deref()
                        .and_then(crate::modicon::Modicon::parse)
                        == Some(m)
                })
            })
    }

    /// What a `selected_by` (or a `setting` condition) names: a register by id or parameter
    /// number, or `<register>.<field>`, a field of a bit-field register. A whole name that is a
    /// register wins (parameter numbers such as `UF.11` contain dots); otherwise the name is
    /// split at its last dot.
    pub(crate) fn selector(&self, name: &str) -> Option<SelectorRef<'_>> {
        if let Some(register) = self.find(name) {
            return Some(SelectorRef {
                register,
                field: None,
            });
        }
        let (register, field) = name.rsplit_once('.')?;
        let register = self.find(register)?;
        let field = register.def.fields.iter().find(|f| f.id == field)?;
        Some(SelectorRef {
            register,
            field: Some(field),
        })
    }

    /// The code slots of the drive's settings: every distinct selector (a register, or a field
    /// of one) that a scale or an address condition names, in first-use order. Names that do not
    /// resolve are left out (validation reports them).
    pub(crate) fn selector_slots(&self) -> Vec<SelectorRef<'_>> {
        let mut out: Vec<SelectorRef<'_>> = Vec::new();
        for name in self.selector_names() {
            if let Some(s) = self.selector(name)
                && !out.iter().any(|o| o.same(&s))
            {
                out.push(s);
            }
        }
        out
    }

    fn selector_names(&self) -> Vec<&str> {
        let mut names = Vec::new();
        for r in &self.registers {
            if let Some(Scale::Selected(s)) = &r.def.scale {
                names.push(s.selected_by.as_str());
            }
            for alt in &r.def.address_alternatives {
                if let Some(s) = &alt.when.setting {
                    names.push(s.as_str());
                }
            }
        }
        names
    }

    /// The registers whose values (or a field of whose values) select scales or addresses, in
    /// first-use order, each once.
    pub(crate) fn selectors(&self) -> Vec<&Register> {
        let mut out: Vec<&Register> = Vec::new();
        for s in self.selector_slots() {
            if !out.iter().any(|r| r.def.id == s.register.def.id) {
                out.push(s.register);
            }
        }
        out
    }

    /// The registers other registers are scaled relative to, in first-use order.
    pub(crate) fn references(&self) -> Vec<&Register> {
        let mut names = Vec::new();
        for r in &self.registers {
            for scale in scales_of(r) {
                if let Scale::Relative(rel) = scale
                    && let Reference::Register(name) = &rel.relative_to
                {
                    names.push(name.as_str());
                }
            }
            if let Some(Reference::Register(name)) =
                r.def.max_relative.as_ref().map(|l| &l.relative_to)
            {
                names.push(name.as_str());
            }
        }
        self.unique_registers(names)
    }

    /// External quantities (not registers) that relative scales refer to, by name.
    pub(crate) fn externals(&self) -> Vec<&model::ExternalQuantity> {
        let mut seen = BTreeSet::new();
        let mut out = Vec::new();
        for r in &self.registers {
            for scale in scales_of(r) {
                if let Scale::Relative(rel) = scale
                    && let Reference::External(q) = &rel.relative_to
                    && seen.insert(q.external.clone())
                {
                    out.push(q);
                }
            }
            if let Some(Reference::External(q)) =
                r.def.max_relative.as_ref().map(|l| &l.relative_to)
                && seen.insert(q.external.clone())
            {
                out.push(q);
            }
        }
        out
    }

    fn unique_registers<'a>(&'a self, names: Vec<&str>) -> Vec<&'a Register> {
        let mut seen = BTreeSet::new();
        let mut out = Vec::new();
        for name in names {
            if let Some(r) = self.find(name)
                && seen.insert(r.def.id.clone())
            {
                out.push(r);
            }
        }
        out
    }

    /// Communication addresses a broadcast may write: the protocol's broadcast registers and
    /// every register of a broadcast group, sorted.
    pub(crate) fn broadcast_addresses(&self) -> Vec<u16> {
        let named = self
            .protocol
            .broadcast
            .iter()
            .flat_map(|b| b.registers.iter())
            .filter_map(|name| self.find(name).map(|r| r.def.address));
        let grouped = self
            .registers
            .iter()
            .filter(|r| r.broadcast)
            .map(|r| r.def.address);
        let mut addresses: Vec<u16> = named.chain(grouped).collect();
        addresses.sort_unstable();
        addresses.dedup();
        addresses
    }

    /// PDU address offsets (RTU, TCP).
    pub(crate) fn address_offsets(&self) -> (i32, i32) {
        self.protocol
            .addressing
            .as_ref()
            .map(|a| (a.rtu_offset, a.tcp_offset))
            .unwrap_or((0, 0))
    }

    /// The variant axis and option for an option id.
    pub(crate) fn variant_option(
        &self,
        option: &str,
    ) -> Option<(&VariantAxis, &model::VariantOption)> {
        self.variants
            .iter()
            .find_map(|a| a.options.iter().find(|o| o.id == option).map(|o| (a, o)))
    }

    /// The group of a register.
    pub(crate) fn group_of(&self, r: &Register) -> &Group {
        &self.groups[r.group]
    }
}

/// The scales of a register: its own, and those of each selected case.
pub(crate) fn scales_of(r: &Register) -> Vec<&Scale> {
    match &r.def.scale {
        Some(Scale::Selected(sel)) => sel.cases.iter().map(|c| &c.scale).collect(),
        Some(s) => vec![s],
        None => Vec::new(),
    }
}

/// A selector resolved: a register, or one field of a bit-field register.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SelectorRef<'a> {
    pub register: &'a Register,
    /// The field whose code selects, when the selector names one (`status.decimals`).
    pub field: Option<&'a Field>,
}

impl SelectorRef<'_> {
    /// Whether both name the same register and field.
    pub(crate) fn same(&self, other: &SelectorRef<'_>) -> bool {
        self.register.def.id == other.register.def.id
            && self.field.map(|f| &f.id) == other.field.map(|f| &f.id)
    }

    /// The name the plan's code slot gives it (errors, exports): the register's parameter number
    /// (else its id), with `.<field>` for a field.
    pub(crate) fn label(&self) -> String {
        let r = &self.register.def;
        let name = r.param.clone().unwrap_or_else(|| r.id.clone());
        match self.field {
            Some(f) => format!("{name}.{}", f.id),
            None => name,
        }
    }

    /// How documentation names it, after "scale selected by": `n152`, or
    /// `field current_decimals (bits 8-15) of status_word`.
    pub(crate) fn prose(&self) -> String {
        let r = &self.register.def;
        let name = r.param.clone().unwrap_or_else(|| r.id.clone());
        match (self.field, self.field.and_then(crate::names::field_span)) {
            (Some(f), Some((lsb, 1))) => format!("field {} (bit {lsb}) of {name}", f.id),
            (Some(f), Some((lsb, width))) => {
                format!("field {} (bits {lsb}-{}) of {name}", f.id, lsb + width - 1)
            }
            (Some(f), None) => format!("field {} of {name}", f.id),
            (None, _) => name,
        }
    }

    /// The largest code the selector can hold: the field's all-ones value, or `u16::MAX`.
    pub(crate) fn max_code(&self) -> u16 {
        match self.field.and_then(crate::names::field_span) {
            Some((_, width)) if width < 16 => (1u16 << width) - 1,
            _ => u16::MAX,
        }
    }

    /// The codes the selector lists, if it lists any: an enumeration's values or a multi-bit
    /// field's values.
    pub(crate) fn listed(&self) -> Option<&[EnumValue]> {
        let values = match self.field {
            Some(f) => f.values.as_slice(),
            None => match self.register.kind() {
                ValueKind::Enum(values) => values,
                _ => return None,
            },
        };
        (!values.is_empty()).then_some(values)
    }
}

/// The Rust module name of a drive id.
pub(crate) fn module_name(id: &str) -> String {
    id.replace(['-', '.'], "_")
}

/// Why a register's `limits: {selected_by}` cannot be expanded: the key to point at and what to
/// write instead.
struct LimitsError {
    key: &'static str,
    message: String,
}

/// Expands `limits: {selected_by, cases}` into the selected scale it means: each case the
/// register's own decimal `scale` (1 without one) and the case's `min`/`max`, so the plan, the
/// write gate, the simulator, parameter-set ordering and every report treat a range chosen by a
/// setting exactly as a scale chosen by one (there is one mechanism). `limits` is taken off the
/// definition once expanded. Refused: beside a `scale` that is not a decimal factor, beside
/// codes or bit fields, or beside limits of its own (`min`/`max`, or a variant's) that would
/// say a second range.
fn selected_limits(def: &mut model::Register) -> Result<(), LimitsError> {
    let Some(limits) = def.limits.take() else {
        return Ok(());
    };
    let fail = |key, message: String| Err(LimitsError { key, message });
    let factor = match &def.scale {
        None if def.unit.is_none() => {
            return fail(
                "limits",
                "`limits: {selected_by: ..}` is the range of a quantity: give the register its `unit` (and its `scale` when not 1)".to_owned(),
            );
        }
        None => 1.0,
        Some(Scale::Factor(f)) => *f,
        Some(_) => {
            return fail(
                "limits",
                "`limits: {selected_by: ..}` needs a fixed decimal `scale`; a scale chosen by a setting carries its limits in its cases (`scale: {selected_by: .., cases: [{when: .., scale: .., min: .., max: ..}]}`)".to_owned(),
            );
        }
    };
    if !def.values.is_empty() || !def.fields.is_empty() {
        return fail(
            "limits",
            "`limits: {selected_by: ..}` is the range of a quantity, not of codes or bit fields"
                .to_owned(),
        );
    }
    if def.min.is_some() || def.max.is_some() {
        return fail(
            if def.min.is_some() { "min" } else { "max" },
            "`min`/`max` beside `limits: {selected_by: ..}`: which range applies? give each case its `min` and `max` instead".to_owned(),
        );
    }
    if let Some((v, _)) = def
        .by_variant
        .iter()
        .find(|(_, o)| o.min.is_some() || o.max.is_some())
    {
        return fail(
            "by_variant",
            format!(
                "`by_variant.{v}` gives limits beside `limits: {{selected_by: ..}}`: ranges chosen both by a variant and by a setting are not expressible; give each case its range"
            ),
        );
    }
    def.scale = Some(Scale::Selected(model::SelectedScale {
        selected_by: limits.selected_by,
        cases: limits
            .cases
            .into_iter()
            .map(|c| model::ScaleCase {
                when: c.when,
                scale: Scale::Factor(factor),
                min: c.min,
                max: c.max,
                source: c.source,
            })
            .collect(),
    }));
    Ok(())
}

/// Builds the IR from a loaded map. Errors are those of block expansion and of a
/// `limits: {selected_by}` that cannot be expanded ([`selected_limits`]); everything else is
/// left to `validate`.
/// Takes the loaded map by value: its model's parts and its tree move into the drive.
pub(crate) fn expand(map: LoadedMap) -> Result<Drive, Vec<Diagnostic>> {
    let LoadedMap {
        path: file,
        mut model,
        tree,
        warnings: read_warnings,
    } = map;
    let draft = model.draft.is_some();
    let mut errors = Vec::new();
    let mut groups = Vec::new();
    let mut registers = Vec::new();
    for (gi, g) in model.groups.iter_mut().enumerate() {
        let gpath = Path::root().key("groups").index(gi);
        groups.push(Group {
            id: g.id.clone(),
            name: g.name.clone(),
            table: g.table.clone(),
            source: g.source.clone(),
            broadcast: g.broadcast,
            notes: g.notes.clone(),
            path: gpath.clone(),
        });
        for (ri, r) in std::mem::take(&mut g.registers).into_iter().enumerate() {
            let path = gpath.key("registers").index(ri);
            // The id as written (a block's template), for the block's errors.
            let written_id = r.id.clone();
            let instances = match r.repeat.as_ref().map(|rep| expand_block(&r, rep)) {
                None => vec![r],
                Some(Ok(list)) => list,
                Some(Err(e)) => {
                    errors.push(Diagnostic::new(
                        tree.locate(&path.key("repeat")),
                        Some(&r.id),
                        e.to_string(),
                    ));
                    continue;
                }
            };
            for mut def in instances {
                let limits_form = def.limits.is_some();
                if let Err(e) = selected_limits(&mut def) {
                    errors.push(Diagnostic::new(
                        tree.locate(&path.key(e.key)),
                        Some(&written_id),
                        e.message,
                    ));
                    continue;
                }
                let table = def
                    .modbus_table
                    .or(g.modbus_table)
                    .unwrap_or(ModbusTable::Holding);
                registers.push(Register {
                    // A draft's rows were not read against the manual: an access nobody
                    // wrote is read-only there, read-write only in a reviewed map. A coil or
                    // discrete input without an access is read-only in every map: writing a
                    // coil runs, reverses or trips a drive, so it is written only where the
                    // map says so.
                    // A string (text) is read-only unless the register itself says otherwise
                    // (refused by `strings_valid`): its group's access is that of its numbers.
                    access: def
                        .access
                        .or(g.access.filter(|_| def.string.is_none()))
                        .unwrap_or(if draft || table.is_bits() || def.string.is_some() {
                            Access::Read
                        } else {
                            Access::ReadWrite
                        }),
                    table,
                    write_restriction: def
                        .write_restriction
                        .or(g.write_restriction)
                        .unwrap_or(WriteRestriction::None),
                    transports: def.transports.clone().or_else(|| g.transports.clone()),
                    broadcast: g.broadcast,
                    group: gi,
                    repeat_needs_change: match (&def.repeat_needs_change, &g.repeat_needs_change) {
                        (Some(x), _) => Some((x.clone(), path.key("repeat_needs_change"))),
                        (None, Some(x)) => Some((x.clone(), gpath.key("repeat_needs_change"))),
                        (None, None) => None,
                    },
                    function_codes: match (&def.function_codes, &g.function_codes) {
                        (Some(x), _) => Some((x.clone(), path.key("function_codes"))),
                        (None, Some(x)) => Some((x.clone(), gpath.key("function_codes"))),
                        (None, None) => None,
                    },
                    path: path.clone(),
                    limits_form,
                    def,
                    index: RegisterIndex(registers.len()),
                });
            }
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let warnings = {
        let mut w = read_warnings;
        if let Some(d) = &model.draft {
            w.push(Diagnostic::new(
                tree.locate(&crate::source::Path::root().key("draft")),
                None,
                draft_warning(d),
            ));
        }
        w
    };
    Ok(Drive {
        module: module_name(&model.drive.id),
        meta: model.drive,
        address_format: model.address_format.unwrap_or(model::AddressFormat::Hex),
        variants: model.variants,
        protocol: model.protocol,
        groups,
        registers,
        conflicts: model.conflicts,
        gaps: model.gaps,
        removed: model.removed,
        roles: model.roles,
        profile: model.profile,
        file,
        tree,
        plan: OnceLock::new(),
        warnings,
        draft: model.draft,
        examples: model.examples,
    })
}

/// What `check` says of a draft: what made it, how many items to confirm, each of them, and that
/// the generator refuses it.
pub(crate) fn draft_warning(d: &model::Draft) -> String {
    let mut s = format!(
        "a draft (made by {}), not yet reviewed: the generator refuses it until `draft:` is removed",
        d.by
    );
    if !d.to_confirm.is_empty() {
        s.push_str(&format!("; {} item(s) to confirm:", d.to_confirm.len()));
        for c in &d.to_confirm {
            s.push_str("\n    - ");
            s.push_str(c);
        }
    }
    s
}

fn expand_block(
    r: &model::Register,
    rep: &model::Repeat,
) -> Result<Vec<model::Register>, BlockError> {
    if rep.count == 0 {
        return Err(BlockError::NoCount);
    }
    if !r.id.contains("{n}")
        && !r.id.contains("{p}")
        && !r.id.contains("{n:")
        && !r.id.contains("{p:")
    {
        return Err(BlockError::SameId);
    }
    let mut out = Vec::new();
    for k in 0..rep.count {
        let n = rep.start as u32 + k as u32;
        let p = rep.param_start.map(|s| s as u32 + k as u32);
        let mut def = r.clone();
        def.repeat = None;
        def.id = substitute(&r.id, n, p)?;
        def.name = substitute(&r.name, n, p)?;
        def.param = r
            .param
            .as_deref()
            .map(|s| substitute(s, n, p))
            .transpose()?;
        let address = r.address as u32 + k as u32 * rep.address_step as u32;
        def.address = u16::try_from(address).map_err(|_| BlockError::PastFfff { n })?;
        def.source = r
            .source
            .as_deref()
            .map(|s| shift_line(s, k as usize * rep.line_step as usize))
            .transpose()?;
        out.push(def);
    }
    Ok(out)
}

/// Replaces `{n}`, `{p}`, `{n:02}`, `{p:03}` in a block template.
fn substitute(template: &str, n: u32, p: Option<u32>) -> Result<String, BlockError> {
    let t = || template.to_owned();
    let mut out = String::new();
    let mut rest = template;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| BlockError::Unclosed { template: t() })?
            + open;
        let spec = &rest[open + 1..close];
        let (name, width) = match spec.split_once(':') {
            Some((name, w)) => (
                name,
                w.parse::<usize>().map_err(|_| BlockError::BadWidth {
                    width: w.to_owned(),
                    template: t(),
                })?,
            ),
            None => (spec, 0),
        };
        let value = match name {
            "n" => n,
            "p" => p.ok_or_else(|| BlockError::NoParamStart { template: t() })?,
            other => {
                return Err(BlockError::UnknownPlaceholder {
                    name: other.to_owned(),
                    template: t(),
                });
            }
        };
        out.push_str(&format!("{value:0width$}"));
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

fn shift_line(source: &str, by: usize) -> Result<String, BlockError> {
    let not_file_line = || BlockError::NotFileLine {
        citation: source.to_owned(),
    };
    let (file, line) = source.rsplit_once(':').ok_or_else(not_file_line)?;
    let line: usize = line.parse().map_err(|_| not_file_line())?;
    let shifted = line
        .checked_add(by)
        .ok_or_else(|| BlockError::LineOverflow {
            citation: source.to_owned(),
            by,
        })?;
    Ok(format!("{file}:{shifted}"))
}

/// Why a `repeat:` block cannot be expanded into its registers (reported at `repeat`, naming
/// the block's register).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum BlockError {
    /// `repeat.count: 0`.
    #[error("`repeat.count` must be at least 1")]
    NoCount,
    /// The id template has no placeholder, so every instance would have the same id.
    #[error("a block's `id` must contain `{{n}}` or `{{p}}` so each register gets its own id")]
    SameId,
    /// Instance `n` would sit beyond address FFFFh.
    #[error("block runs past address FFFFh at instance {n}")]
    PastFfff {
        /// The instance number.
        n: u32,
    },
    /// A `{` without its `}`.
    #[error("unclosed placeholder in `{template}`")]
    Unclosed {
        /// The template.
        template: String,
    },
    /// `{n:WIDTH}` whose width is not a number.
    #[error("bad width `{width}` in `{template}`")]
    BadWidth {
        /// The width as written.
        width: String,
        /// The template.
        template: String,
    },
    /// `{p}` without `repeat.param_start`.
    #[error("`{{p}}` in `{template}` needs `repeat.param_start`")]
    NoParamStart {
        /// The template.
        template: String,
    },
    /// A placeholder other than `n` and `p`.
    #[error("unknown placeholder `{{{name}}}` in `{template}`")]
    UnknownPlaceholder {
        /// Its name.
        name: String,
        /// The template.
        template: String,
    },
    /// The block's `source` is not `file:line`, so it cannot be shifted per instance.
    #[error("citation `{citation}` is not `file:line`")]
    NotFileLine {
        /// The citation.
        citation: String,
    },
    /// The shifted line number overflows.
    #[error("citation `{citation}` shifted by {by} lines overflows")]
    LineOverflow {
        /// The citation.
        citation: String,
        /// The shift.
        by: usize,
    },
}

/// A drive's serial line as its map gives the defaults (`protocol.serial`), with the fallbacks
/// of a map that gives none: 9600 baud, no parity. The one reading of the map's serial
/// defaults, for a client's link and for a simulated drive's port.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SerialDefaults {
    /// The default baud rate.
    pub baud: u32,
    /// The default parity.
    pub parity: Parity,
    /// Bits per character on the wire when the manual fixes it regardless of parity (TDS-V8:
    /// always 11 — without parity the parity slot is sent as a second stop bit).
    pub char_bits: Option<u8>,
    /// When the map lists the formats a parameter selects (`serial.formats`): the stop bits of
    /// the formats with no, even and odd parity, where they all agree (ACN: none for no
    /// parity, which has 8N1 and 8N2; 1 for even and odd).
    pub format_stop_bits: [Option<u8>; 3],
}

impl SerialDefaults {
    /// Stop bits for `parity`: the map's formats', when only one stop-bit count goes with that
    /// parity, else [`SerialDefaults::stop_bits`].
    pub fn stop_bits_for(&self, parity: Parity) -> u8 {
        let i = match parity {
            Parity::None => 0,
            Parity::Even => 1,
            Parity::Odd => 2,
        };
        self.format_stop_bits[i].unwrap_or_else(|| self.stop_bits(parity != Parity::None))
    }

    /// Stop bits: 2 without parity (`with_parity` false) where the map fixes 11-bit
    /// characters, else 1.
    pub fn stop_bits(&self, with_parity: bool) -> u8 {
        if self.char_bits == Some(11) && !with_parity {
            2
        } else {
            1
        }
    }
}

impl Drive {
    /// The character formats of `serial.formats`, in the runtime's words (a case without
    /// `data_bits` has the line's); empty when the map lists none.
    pub(crate) fn serial_format_list(&self) -> Vec<drivemap_core::profile::SerialFormat> {
        use drivemap_core::profile::SerialFormat;
        let Some(serial) = self.protocol.serial.as_ref() else {
            return Vec::new();
        };
        let Some(formats) = serial.formats.as_ref() else {
            return Vec::new();
        };
        formats
            .cases
            .iter()
            .map(|c| SerialFormat {
                code: c.when,
                data_bits: c.data_bits.unwrap_or(serial.data_bits),
                parity: c.parity,
                stop_bits: c.stop_bits,
            })
            .collect()
    }

    /// The serial line's defaults (see [`SerialDefaults`]).
    pub(crate) fn serial_defaults(&self) -> SerialDefaults {
        let serial = self.protocol.serial.as_ref();
        SerialDefaults {
            baud: serial.and_then(|s| s.default_baud).unwrap_or(9600),
            parity: serial
                .and_then(|s| s.default_parity)
                .unwrap_or(Parity::None),
            char_bits: serial.and_then(|s| s.char_bits),
            format_stop_bits: {
                use drivemap_core::profile::only_stop_bits;
                let list = self.serial_format_list();
                Parity::ALL.map(|p| only_stop_bits(&list, p))
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders() {
        assert_eq!(substitute("An-{n:02}", 3, None).unwrap(), "An-03");
        assert_eq!(
            substitute("step_{n}_time", 12, None).unwrap(),
            "step_12_time"
        );
        assert_eq!(substitute("Bn-{p}", 1, Some(22)).unwrap(), "Bn-22");
        assert!(substitute("x{q}", 1, None).is_err());
        assert!(substitute("x{p}", 1, None).is_err());
        assert_eq!(shift_line("a.txt:10", 3).unwrap(), "a.txt:13");
    }

    /// Every map of `maps/` and a variant map, loaded.
    fn maps() -> Vec<crate::Map> {
        use drivemap_test_support::paths as at;
        let mut paths = crate::find_maps(&at::maps()).expect("maps/");
        paths.push(at::fixture("crafted/maps/variants/child-drive.yaml"));
        assert!(paths.len() > 5, "{paths:?}");
        (paths.iter())
            .map(|p| {
                crate::Loader::new()
                    .load(p)
                    .unwrap_or_else(|d| panic!("{d}"))
            })
            .collect()
    }

    /// A register names its plan row by the place expansion gave it (`Register::index`): every
    /// register of every map finds its own row, also when copied.
    #[test]
    fn every_register_finds_its_own_row() {
        for map in maps() {
            let drive = map.drive();
            let plan = drive.plan();
            for (i, r) in drive.registers.iter().enumerate() {
                assert_eq!(r.index(), i, "{}: {}", drive.meta.id, r.id());
                let row = drive.register_plan(r);
                assert_eq!(row.info.id, r.id(), "{}", drive.meta.id);
                assert!(std::ptr::eq(row, &plan.registers[plan.order[i]]));
                // A copy of the register is still this drive's register.
                assert!(std::ptr::eq(drive.register_plan(&r.clone()), row));
            }
        }
    }

    /// The old lookup fell back to row 0 for a register it could not place; now a register of
    /// another map is refused by name.
    #[test]
    fn another_maps_register_has_no_row_here() {
        let maps = maps();
        let (a, b) = (maps[0].drive(), maps[1].drive());
        let foreign = (b.registers.iter())
            .find(|r| !a.registers.iter().any(|x| x.id() == r.id()))
            .expect("a register of the second map that the first lacks");
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            a.register_plan(foreign).info.id
        }));
        let message = match caught {
            Ok(id) => panic!("{} answered row {id} for {}", a.meta.id, foreign.id()),
            Err(e) => e.downcast_ref::<String>().cloned().unwrap_or_default(),
        };
        assert!(
            message.contains(foreign.id()) && message.contains(&a.meta.id),
            "{message}"
        );
    }
}
