//! Lowering: a validated [`Drive`] → a [`MapPlan`], where everything a register means is
//! decided once — its conversion with the raw range for every variant and selector case, its
//! addresses under each setting, variant and transport, its access, table, transports and
//! broadcast use, the settings it depends on — and the drive's runtime [`Profile`].
//!
//! The plan is made of the vocabulary crate's types ([`drivemap_core::plan`]). The generator
//! prints it as `const` data; the run-time interpreter (`drivemap-live`) uses it as it is.
//! Nothing downstream of this pass reads the serde model again: **a register's scale is decided
//! in `Lowering::conversion` below.**
//!
//! The plan's tables and strings have `'static` lifetime, as generated code's have. Lowering
//! leaks them: a process lowers each map once (a build script, a tool loading its maps), so the
//! memory is bounded by the maps it was given.

use drivemap_core::functions::Functions;
use drivemap_core::plan::{
    Case, CaseScale, Condition, Conversion, Field, Label, Move, Ranges, RegisterPlan, Relative,
    RelativeLimit, RepeatNeedsChange, Setting, VariantOption,
};
use drivemap_core::profile::{
    AddressOffsets, BroadcastInfo, CommandInfo, ExceptionInfo, Profile, SerialFormats, Timing,
};
use drivemap_core::register::RegisterInfo;
use drivemap_core::roles::{Edge, FieldRole, NumberField, Place, Role, RoleKind, Roles, Target};
use drivemap_core::rule::{Broadcast, Transports, WriteRule};
use drivemap_core::scale::{Decimal, RawRange};

use std::cell::RefCell;

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register, ValueKind};
use crate::model::{self, Reference, Scale, TransportName};
use crate::names::field_span;

/// A drive, lowered.
#[derive(Debug, Clone)]
pub struct MapPlan {
    /// Every register's plan, sorted by address with broadcast-only registers last (stable:
    /// registers at one address keep the map's order). Generated code indexes this table.
    pub registers: &'static [RegisterPlan],
    /// For each register of [`Map::registers`](crate::Map::registers) (map order), its index in `registers`.
    pub order: Vec<usize>,
    /// What conversions and addresses depend on.
    pub settings: SettingsPlan,
    /// The drive's protocol profile, with one write rule per writable register.
    pub profile: &'static Profile,
    /// Which registers and fields play the standard parts of a drive.
    pub roles: Roles,
    /// Index/value register pairs and their entries (the map's `indexed:`,
    /// [`RegisterRef::indexed`](crate::RegisterRef::indexed)).
    pub indexed: &'static [drivemap_core::indexed::Indexed],
}

/// The slots of a drive's settings: what a `SettingsView` answers.
#[derive(Debug, Clone, Default)]
pub struct SettingsPlan {
    /// Selecting parameters, by code slot: the register and, for a `<register>.<field>`
    /// selector, the field whose value is the code.
    pub codes: Vec<CodeSlot>,
    /// Reference quantities, by quantity slot.
    pub quantities: Vec<Quantity>,
    /// Variant axes, by axis slot: (id, option ids; option 0 is the base).
    pub axes: Vec<(String, Vec<String>)>,
}

/// One code slot: what a selector's word read from the drive makes of the code.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CodeSlot {
    /// The selecting register's index in `DrivePlan::registers`.
    pub register: usize,
    /// The field of that register whose value is the code; `None`: the whole word is.
    pub field: Option<Field>,
}

impl CodeSlot {
    /// The code this slot holds when its register reads `word`.
    pub const fn code(&self, word: u16) -> u16 {
        match &self.field {
            Some(f) => f.get(word),
            None => word,
        }
    }
}

/// A quantity other values are relative to.
#[derive(Debug, Clone, PartialEq)]
pub enum Quantity {
    /// A register (index in `DrivePlan::registers`), read from the drive and decoded.
    Register(usize),
    /// Not a register: the application supplies it.
    External {
        /// The quantity's name.
        id: String,
        /// What it is.
        description: String,
        /// Its unit.
        unit: String,
    },
}

impl MapPlan {
    /// The plan of the register with map id `id`.
    pub fn register(&self, id: &str) -> Option<&'static RegisterPlan> {
        self.registers.iter().find(|r| r.info.id == id)
    }

    /// Communication addresses of the registers conversions depend on, in slot order (codes,
    /// then register quantities): what a client reads to fill the settings.
    pub fn dependencies(&self) -> Vec<u16> {
        let mut out: Vec<u16> = Vec::new();
        for c in &self.settings.codes {
            let a = self.registers[c.register].info.address;
            if !out.contains(&a) {
                out.push(a);
            }
        }
        for q in &self.settings.quantities {
            if let Quantity::Register(i) = q {
                let a = self.registers[*i].info.address;
                if !out.contains(&a) {
                    out.push(a);
                }
            }
        }
        out
    }
}

fn leak<T>(v: Vec<T>) -> &'static [T] {
    Box::leak(v.into_boxed_slice())
}

fn text(s: &str) -> &'static str {
    Box::leak(s.to_owned().into_boxed_str())
}

/// Lowers a validated drive: the last pass of checking a map. What the earlier passes should
/// have refused and lowering cannot decide (a scale that is no decimal, a selector or a
/// reference without a slot) is a diagnostic at the register's key, never a fallback value.
pub(crate) fn lower(drive: &Drive) -> Result<MapPlan, Vec<Diagnostic>> {
    let mut order: Vec<usize> = (0..drive.registers.len()).collect();
    order.sort_by_key(|&i| {
        let r = &drive.registers[i];
        (r.broadcast, r.def.address)
    });
    // position[i] = index in the sorted table of map register i
    let mut position = vec![0; order.len()];
    for (sorted, &i) in order.iter().enumerate() {
        position[i] = sorted;
    }
    let index_of = |r: &Register| -> usize { position[r.index()] };
    let settings = SettingsPlan {
        codes: drive
            .selector_slots()
            .into_iter()
            .map(|s| CodeSlot {
                register: index_of(s.register),
                field: s.field.and_then(lower_field),
            })
            .collect(),
        quantities: drive
            .references()
            .into_iter()
            .map(|r| Quantity::Register(index_of(r)))
            .chain(drive.externals().into_iter().map(|q| Quantity::External {
                id: q.external.clone(),
                description: q.description.clone(),
                unit: q.unit.clone(),
            }))
            .collect(),
        axes: drive
            .variants
            .iter()
            .map(|a| {
                (
                    a.id.clone(),
                    a.options.iter().map(|o| o.id.clone()).collect(),
                )
            })
            .collect(),
    };
    let lowering = Lowering {
        drive,
        settings: &settings,
        sorted: &order,
        errors: RefCell::new(Vec::new()),
    };
    let registers = leak(
        order
            .iter()
            .map(|&i| lowering.register(&drive.registers[i]))
            .collect(),
    );
    let errors = lowering.errors.into_inner();
    if !errors.is_empty() {
        return Err(errors);
    }
    let profile = Box::leak(Box::new(profile(drive, registers)));
    let roles = roles(drive, &position, &settings);
    let indexed = crate::indexed::lower(drive, registers);
    Ok(MapPlan {
        registers,
        order: position,
        settings,
        profile,
        roles,
        indexed,
    })
}

/// The map's roles as plan rows, bit positions and codes, in the order of [`Role::ALL`]. Places
/// that do not resolve are left out: validation has reported them.
fn roles(drive: &Drive, position: &[usize], settings: &SettingsPlan) -> Roles {
    let mut places = Vec::new();
    for &role in Role::ALL {
        for p in drive.roles.get(role.id()).into_iter().flatten() {
            if let Some(target) = role_target(drive, position, settings, role, p) {
                let transports = match p.transports.as_deref() {
                    None => Transports::ALL,
                    Some(list) => Transports {
                        rtu: list.iter().any(|t| t.is_serial()),
                        tcp: list.contains(&TransportName::Tcp),
                    },
                };
                places.push(Place {
                    role,
                    target,
                    transports,
                    source: text(p.source.as_deref().unwrap_or_default()),
                    shared_with: p.shared_with.as_deref().and_then(Role::from_id),
                });
            }
        }
    }
    // A sharing said on one place holds for the other too.
    for i in 0..places.len() {
        let Some(other) = places[i].shared_with else {
            continue;
        };
        let (role, target) = (places[i].role, places[i].target);
        for p in places.iter_mut() {
            if p.role == other && p.shared_with.is_none() && same_bits(&p.target, &target) {
                p.shared_with = Some(role);
            }
        }
    }
    let row_of = |id: &str| {
        drive
            .find(id)
            .and_then(|r| position.get(r.index()))
            .map(|&row| row as u16)
    };
    Roles {
        places: leak(places),
        profile: crate::command_profile::lower(drive, &row_of).map(|p| &*Box::leak(Box::new(p))),
    }
}

/// Whether two role targets write the same register bits.
fn same_bits(a: &Target, b: &Target) -> bool {
    match (a, b) {
        (Target::Field(x), Target::Field(y)) => x.row == y.row && x.mask() & y.mask() != 0,
        (Target::NumberField(x), Target::NumberField(y)) => {
            x.row == y.row && x.mask() & y.mask() != 0
        }
        _ => a.row().is_some() && a.row() == b.row(),
    }
}

fn role_target(
    drive: &Drive,
    position: &[usize],
    settings: &SettingsPlan,
    role: Role,
    p: &model::RolePlace,
) -> Option<Target> {
    if let Some(name) = &p.external {
        let slot = settings
            .quantities
            .iter()
            .position(|q| matches!(q, Quantity::External { id, .. } if id == name))?;
        return Some(Target::External {
            slot: slot as u8,
            name: text(name),
        });
    }
    let r = drive.find(p.register.as_deref()?)?;
    let row = position[r.index()] as u16;
    if r.table.is_bits()
        && p.field.is_none()
        && matches!(role.kind(), RoleKind::Command | RoleKind::Status)
    {
        // A coil or discrete input is one bit: the place is its bit 0, on at 1 unless the map
        // says `on: 0` (a coil whose 1 means forward, for the reverse role).
        let code = |c: &model::CodeRef| match c {
            model::CodeRef::Number(n) => Some(*n),
            model::CodeRef::Id(_) => None,
        };
        let on: Vec<u16> = match &p.on {
            Some(codes) => codes.list().into_iter().filter_map(code).collect(),
            None => vec![1],
        };
        let off = match &p.off {
            Some(c) => code(c),
            None => Some(if on == [0] { 1 } else { 0 }),
        };
        return Some(Target::Field(FieldRole {
            row,
            lsb: 0,
            width: 1,
            on: leak(on),
            off,
            edge: match &p.edge {
                model::EdgeSpec::Known(false) => Edge::Level,
                model::EdgeSpec::Known(true) => Edge::Edge,
                model::EdgeSpec::Unknown(u) => Edge::NotPrinted(text(&u.unknown)),
            },
        }));
    }
    let Some(field_id) = &p.field else {
        if role.kind() == RoleKind::Status {
            // Codes of the whole register (an inverter status register: 3 run, 2 stop).
            let code = |c: &model::CodeRef| match c {
                model::CodeRef::Number(n) => Some(*n),
                model::CodeRef::Id(id) => {
                    r.def.values.iter().find(|v| v.id == *id).map(|v| v.value)
                }
            };
            let on: Vec<u16> =
                p.on.iter()
                    .flat_map(|c| c.list())
                    .filter_map(code)
                    .collect();
            return Some(Target::Field(FieldRole {
                row,
                lsb: 0,
                width: 16,
                on: leak(on),
                off: p.off.as_ref().and_then(code),
                edge: Edge::Level,
            }));
        }
        if role.kind() == RoleKind::Source {
            // A source parameter: the whole word is the code (its `values`, or a number).
            let code = |c: &model::CodeRef| match c {
                model::CodeRef::Number(n) => Some(*n),
                model::CodeRef::Id(id) => {
                    r.def.values.iter().find(|v| v.id == *id).map(|v| v.value)
                }
            };
            let on: Vec<u16> =
                p.on.iter()
                    .flat_map(|c| c.list())
                    .filter_map(code)
                    .collect();
            return Some(Target::Field(FieldRole {
                row,
                lsb: 0,
                width: 16,
                on: leak(on),
                off: None,
                edge: Edge::Level,
            }));
        }
        return Some(Target::Register(row));
    };
    let f = r.def.fields.iter().find(|f| f.id == *field_id)?;
    let (lsb, width) = field_span(f)?;
    if matches!(role.kind(), RoleKind::Setpoint | RoleKind::Monitor) {
        // A number in part of the word (a fault code in the status word's high byte).
        let scale = match p.scale {
            Some(s) => Decimal::from_f64(s)?,
            None => Decimal::ONE,
        };
        return Some(Target::NumberField(NumberField {
            row,
            lsb,
            width,
            signed: p.signed,
            scale,
        }));
    }
    let code = |c: &model::CodeRef| match c {
        model::CodeRef::Number(n) => Some(*n),
        model::CodeRef::Id(id) => f.values.iter().find(|v| v.id == *id).map(|v| v.value),
    };
    let on: Vec<u16> = match &p.on {
        Some(codes) => codes.list().into_iter().filter_map(code).collect(),
        None => vec![1],
    };
    let off = match &p.off {
        Some(c) => code(c),
        None if width == 1 => Some(if on == [0] { 1 } else { 0 }),
        None => None,
    };
    Some(Target::Field(FieldRole {
        row,
        lsb,
        width,
        on: leak(on),
        off,
        edge: match &p.edge {
            model::EdgeSpec::Known(false) => Edge::Level,
            model::EdgeSpec::Known(true) => Edge::Edge,
            model::EdgeSpec::Unknown(u) => Edge::NotPrinted(text(&u.unknown)),
        },
    }))
}

struct Lowering<'a> {
    drive: &'a Drive,
    settings: &'a SettingsPlan,
    sorted: &'a [usize],
    /// What could not be decided, each at the register's key.
    errors: RefCell<Vec<Diagnostic>>,
}

/// The label a setting has in errors: the parameter number when printed, else the id.
pub(crate) fn setting_label(r: &Register) -> String {
    r.def.param.clone().unwrap_or_else(|| r.def.id.clone())
}

const ONE: Decimal = Decimal::ONE;

impl Lowering<'_> {
    /// Records that `r`'s `key` cannot be lowered. The value lowering goes on with is never
    /// used: a plan with an error is not returned.
    fn fail(&self, r: &Register, key: &str, message: impl std::fmt::Display) {
        self.errors.borrow_mut().push(self.drive.error(
            &r.key_path(key),
            Some(r.id()),
            format!("cannot be lowered: {message}"),
        ));
    }

    fn map_index(&self, sorted_index: usize) -> &Register {
        &self.drive.registers[self.sorted[sorted_index]]
    }

    /// The code slot of a selector named `name` (a register, or `<register>.<field>`).
    fn selector(&self, name: &str) -> Option<Setting> {
        let target = self.drive.selector(name)?;
        let field = target.field.map(|f| f.id.as_str());
        let slot = self.settings.codes.iter().position(|c| {
            self.map_index(c.register).def.id == target.register.def.id
                && c.field.map(|f| f.id) == field
        })?;
        Some(Setting {
            slot: slot as u8,
            label: text(&target.label()),
        })
    }

    /// The quantity slot of a reference of `r`'s `key`.
    fn reference(&self, r: &Register, key: &str, reference: &Reference) -> Setting {
        let (slot, label) = match reference {
            Reference::Register(name) => {
                let target = self.drive.find(name);
                let slot = self.settings.quantities.iter().position(|q| match q {
                    Quantity::Register(i) => {
                        target.is_some_and(|t| self.map_index(*i).def.id == t.def.id)
                    }
                    Quantity::External { .. } => false,
                });
                (slot, target.map_or(name.clone(), setting_label))
            }
            Reference::External(q) => (
                self.settings
                    .quantities
                    .iter()
                    .position(|x| matches!(x, Quantity::External { id, .. } if *id == q.external)),
                q.external.clone(),
            ),
        };
        let slot = match slot.map(u8::try_from) {
            Some(Ok(slot)) => slot,
            _ => {
                self.fail(
                    r,
                    key,
                    format_args!("`{label}` is no quantity slot of the drive"),
                );
                0
            }
        };
        Setting {
            slot,
            label: text(&label),
        }
    }

    fn variant(&self, option: &str) -> Option<VariantOption> {
        self.settings
            .axes
            .iter()
            .enumerate()
            .find_map(|(a, (_, options))| {
                options
                    .iter()
                    .position(|o| o == option)
                    .map(|o| VariantOption {
                        axis: a as u8,
                        option: o as u8,
                    })
            })
    }

    /// Raw ranges per variant at a fixed decimal factor: the map's overrides in map order.
    fn ranges(&self, r: &Register, factor: Decimal) -> Ranges {
        self.ranges_with(r, |min, max| r.raw_limits(factor, min, max))
    }

    /// Raw ranges per variant, each from the engineering limits by `limits`.
    fn ranges_with(
        &self,
        r: &Register,
        limits: impl Fn(Option<f64>, Option<f64>) -> Option<RawRange>,
    ) -> Ranges {
        let word = r.full_limits();
        let raw = |min: Option<f64>, max: Option<f64>, key: &str| {
            limits(min, max).unwrap_or_else(|| {
                self.fail(r, key, "a limit is not a whole number of raw increments");
                word
            })
        };
        let base = raw(r.def.min, r.def.max, "min");
        let mut by_variant = Vec::new();
        for k in r.def.by_variant.keys() {
            let Some(v) = self.variant(k) else {
                self.fail(r, "by_variant", format_args!("`{k}` is no variant option"));
                continue;
            };
            let (min, max) = r.limits_for(k);
            let lim = raw(min, max, "by_variant");
            if lim != base {
                by_variant.push((v, lim));
            }
        }
        Ranges {
            base,
            by_variant: leak(by_variant),
        }
    }

    fn relative(&self, r: &Register, rel: &model::RelativeScale) -> Relative {
        Relative {
            full_scale: rel.full_scale,
            reference: self.reference(r, "scale", &rel.relative_to),
        }
    }

    /// A decimal factor, or a diagnostic at `r`'s scale.
    fn factor(&self, r: &Register, factor: Option<Decimal>, written: f64) -> Decimal {
        factor.unwrap_or_else(|| {
            self.fail(
                r,
                "scale",
                format_args!("{written} is not a decimal factor"),
            );
            ONE
        })
    }

    /// How the register's word converts: decided here and nowhere else.
    fn conversion(&self, r: &Register) -> Conversion {
        let signed = r.def.signed;
        match r.kind() {
            ValueKind::Word => Conversion::Word {
                signed,
                range: self.ranges(r, ONE),
            },
            ValueKind::UnitQuantity => Conversion::Decimal {
                signed,
                scale: ONE,
                range: self.ranges(r, ONE),
            },
            ValueKind::Quantity(Scale::Factor(f)) => {
                let factor = self.factor(r, Decimal::from_f64(*f), *f);
                Conversion::Decimal {
                    signed,
                    scale: factor,
                    range: self.ranges(r, factor),
                }
            }
            ValueKind::Quantity(Scale::Relative(rel)) => Conversion::Relative {
                signed,
                relative: self.relative(r, rel),
            },
            ValueKind::Quantity(Scale::Ratio(s)) => {
                // Validation refuses a ratio that `ratio_of` rejects.
                let ratio = crate::ratio::ratio_of(s).unwrap_or_else(|| {
                    self.fail(
                        r,
                        "scale",
                        format_args!("{} = {} is no exact ratio", s.counts, s.equals),
                    );
                    drivemap_core::ratio::Ratio::new(1, Decimal::ONE)
                });
                Conversion::Ratio {
                    signed,
                    ratio,
                    range: self.ranges_with(r, |min, max| r.ratio_limits(ratio, min, max)),
                }
            }
            ValueKind::Quantity(Scale::Selected(sel)) => {
                let cases = sel
                    .cases
                    .iter()
                    .filter_map(|case| {
                        let scale = match &case.scale {
                            Scale::Factor(f) => {
                                let factor = self.factor(r, Decimal::from_f64(*f), *f);
                                let lim = r
                                    .raw_limits(factor, case.min, case.max)
                                    .unwrap_or(r.full_limits());
                                CaseScale::Decimal {
                                    scale: factor,
                                    range: lim,
                                }
                            }
                            Scale::Relative(rel) => CaseScale::Relative(self.relative(r, rel)),
                            // Refused by validation (`ratio_scales`): not inside a selection.
                            Scale::Selected(_) | Scale::Ratio(_) => {
                                self.fail(
                                    r,
                                    "scale",
                                    "a case of a selected scale is itself selected or a ratio",
                                );
                                return None;
                            }
                        };
                        Some(Case {
                            codes: leak(case.when.clone()),
                            scale,
                        })
                    })
                    .collect();
                let selector = self.selector(&sel.selected_by).unwrap_or_else(|| {
                    self.fail(
                        r,
                        "scale",
                        format_args!("the selector `{}` has no code slot", sel.selected_by),
                    );
                    Setting {
                        slot: 0,
                        label: text(&sel.selected_by),
                    }
                });
                Conversion::Selected {
                    signed,
                    selector,
                    cases: leak(cases),
                }
            }
            ValueKind::Text(text) => Conversion::Text {
                order: text.byte_order,
            },
            ValueKind::Enum(values) => Conversion::Enum {
                values: labels(values),
                unlisted: match (r.def.min, r.def.max) {
                    (None, None) => None,
                    (min, max) => Some(RawRange {
                        min: min.map_or(0, |m| m as i64),
                        max: max.map_or(65535, |m| m as i64),
                    }),
                },
            },
            ValueKind::Bits(fields) => {
                let fields: Vec<Field> = fields.iter().filter_map(lower_field).collect();
                Conversion::Bits {
                    mask: fields.iter().fold(0, |m, f| m | f.mask()),
                    fields: leak(fields),
                }
            }
        }
    }

    fn condition(&self, w: &model::Condition) -> Option<Condition> {
        if let Some(s) = &w.setting
            && let Some(selector) = self.selector(s)
        {
            return Some(Condition::Setting {
                selector,
                codes: leak(w.is.clone()),
            });
        }
        if let Some(v) = &w.variant
            && let Some(v) = self.variant(v)
        {
            return Some(Condition::Variant(v));
        }
        w.transport.map(|t| {
            Condition::Transport(match t {
                TransportName::Rtu | TransportName::Ascii => Transports::RTU,
                TransportName::Tcp => Transports::TCP,
            })
        })
    }

    fn register(&self, r: &Register) -> RegisterPlan {
        let d = &r.def;
        let w = self.write_rule(r);
        let conversion = self.conversion(r);
        let envelope = envelope(&conversion, r.full_limits());
        RegisterPlan {
            info: RegisterInfo {
                id: text(&d.id),
                param: d.param.as_deref().map(text),
                name: text(&d.name),
                address: d.address,
                access: r.access,
                table: r.table,
                width: r.width(),
                broadcast_only: r.broadcast,
                source: text(d.source.as_deref().unwrap_or_default()),
            },
            unit: text(d.unit.as_deref().unwrap_or_default()),
            conversion,
            moves: leak(
                d.address_alternatives
                    .iter()
                    .filter_map(|a| {
                        Some(Move {
                            when: self.condition(&a.when)?,
                            address: a.address,
                        })
                    })
                    .collect(),
            ),
            transports: Transports {
                rtu: w.rtu,
                tcp: w.tcp,
            },
            broadcast: w.broadcast,
            restriction: r.write_restriction,
            envelope,
            also_at: leak(w.also_at),
            repeat_needs_change: r.repeat_needs_change.as_ref().map(|(rule, _)| {
                RepeatNeedsChange {
                    between: between_word(r, rule.between),
                    source: text(&rule.source),
                }
            }),
            read_values: labels(&d.read_values),
            read_param: d.read_param.as_deref().map(text),
            limit: d.max_relative.as_ref().map(|l| RelativeLimit {
                reference: self.reference(r, "max_relative", &l.relative_to),
                percent: l.percent,
                source: text(&l.source),
            }),
            functions: functions(r),
        }
    }
}

/// Where a register exists and may be written: the write gate's data beside the conversion.
struct WriteRuleFigures {
    broadcast: Broadcast,
    /// Exists on RTU framing (serial, RTU over TCP).
    rtu: bool,
    /// Exists on Modbus TCP.
    tcp: bool,
    /// The addresses it moves to (with a setting, variant or transport), without repeats and
    /// without its own.
    also_at: Vec<u16>,
}

impl Lowering<'_> {
    fn write_rule(&self, r: &Register) -> WriteRuleFigures {
        let drive = self.drive;
        let named = drive.protocol.broadcast.iter().any(|b| {
            b.registers
                .iter()
                .any(|n| drive.find(n).is_some_and(|x| x.def.id == r.def.id))
        });
        let broadcast = if r.broadcast {
            Broadcast::Only
        } else if named {
            Broadcast::Also
        } else {
            Broadcast::No
        };
        let (rtu, tcp) = match &r.transports {
            None => (true, true),
            Some(list) => (
                list.iter().any(|t| t.is_serial()),
                list.contains(&TransportName::Tcp),
            ),
        };
        let mut also_at = Vec::new();
        for alt in &r.def.address_alternatives {
            if alt.address != r.def.address && !also_at.contains(&alt.address) {
                also_at.push(alt.address);
            }
        }
        WriteRuleFigures {
            broadcast,
            rtu,
            tcp,
            also_at,
        }
    }
}

/// The union of the raw ranges a conversion admits under any variant and any case of a
/// selected scale, within the word: what the write gate lets through before converting. Read
/// off the decided conversion, so it cannot disagree with it; the word's range where the
/// conversion has none (relative scales, bit fields).
fn envelope(conversion: &Conversion, word: RawRange) -> RawRange {
    let mut ranges: Vec<RawRange> = Vec::new();
    let all = |r: &Ranges, out: &mut Vec<RawRange>| {
        out.push(r.base);
        out.extend(r.by_variant.iter().map(|(_, range)| *range));
    };
    match conversion {
        Conversion::Word { range, .. }
        | Conversion::Decimal { range, .. }
        | Conversion::Ratio { range, .. } => all(range, &mut ranges),
        Conversion::Relative { .. } | Conversion::Bits { .. } | Conversion::Text { .. } => {
            ranges.push(word)
        }
        Conversion::Enum { values, unlisted } => {
            ranges.extend(values.iter().map(|v| RawRange {
                min: i64::from(v.code),
                max: i64::from(v.code),
            }));
            ranges.extend(*unlisted);
        }
        Conversion::Selected { cases, .. } => {
            for case in cases.iter() {
                match case.scale {
                    CaseScale::Decimal { range, .. } => ranges.push(range),
                    CaseScale::Relative(_) => ranges.push(word),
                }
            }
        }
    }
    let min = ranges.iter().map(|l| l.min).min().unwrap_or(word.min);
    let max = ranges.iter().map(|l| l.max).max().unwrap_or(word.max);
    RawRange {
        min: min.max(word.min),
        max: max.min(word.max),
    }
}

/// The functions a register accepts: its (or its group's) validated `function_codes`, else
/// every function of the drive.
fn functions(r: &Register) -> Functions {
    match &r.function_codes {
        None => Functions::ANY,
        Some((f, _)) => Functions::only(leak(f.codes.clone()), f.refusal(), text(&f.source)),
    }
}

/// The word of a `repeat_needs_change.between` value (validated legal): the value in raw
/// increments of a fixed scale, two's complement when signed; 0 where the scale depends on a
/// setting (validation admits only 0 there).
fn between_word(r: &Register, value: f64) -> u32 {
    match r
        .factor()
        .and_then(|f| drivemap_core::scale::raw_of(value, f))
    {
        Some(raw) => r.width().from_int(raw as i64),
        None => 0,
    }
}

/// A field of a bit-field register; `None` if its span is malformed (validation reports it).
fn lower_field(f: &model::Field) -> Option<Field> {
    let (lsb, width) = field_span(f)?;
    Some(Field {
        id: text(&f.id),
        name: text(&f.name),
        lsb,
        width,
        values: labels(&f.values),
        source: text(f.source.as_deref().unwrap_or_default()),
    })
}

fn labels(values: &[model::EnumValue]) -> &'static [Label] {
    leak(
        values
            .iter()
            .map(|v| Label {
                code: v.value,
                id: text(&v.id),
                name: text(&v.name),
            })
            .collect(),
    )
}

/// The protocol's timing in the runtime's units (microseconds, bit times).
fn timing(drive: &Drive) -> Timing {
    let timing = drive.protocol.timing.as_ref();
    let ict = timing.and_then(|t| t.inter_char_timeout.as_ref());
    let us = |ms: f64| (ms * 1000.0).round() as u32;
    // Character counts are converted at 11 bits per character, the RTU character with parity.
    let bits = |i: &crate::model::Interval| match (i.bits, i.chars) {
        (None, None) => None,
        (b, c) => Some(b.unwrap_or(0) + c.map_or(0, |c| (c * 11.0).round() as u32)),
    };
    let response = timing.and_then(|t| t.response_time.as_ref());
    let gap = timing.and_then(|t| t.request_gap.as_ref());
    let param = timing.and_then(|t| t.response_delay_param.clone());
    let param_default_us = param.as_deref().and_then(|p| drive.find(p)).and_then(|r| {
        let per_unit_us = match r.def.unit.as_deref()? {
            "ms" => 1000.0,
            "s" => 1_000_000.0,
            _ => return None,
        };
        r.default_value().map(|v| (v * per_unit_us).round() as u32)
    });
    Timing {
        frame_gap_chars: timing.map(|t| t.frame_gap_chars()).unwrap_or(3.5),
        frame_gap_us: timing
            .and_then(|t| t.frame_gap.as_ref())
            .and_then(|i| i.ms)
            .map(us),
        inter_char_timeout_us: ict.and_then(|i| i.ms).map(us),
        inter_char_timeout_bits: ict.and_then(bits),
        response_delay_us: response.and_then(|i| i.ms).map(us),
        response_delay_bits: response.and_then(bits),
        response_delay_param: param.as_deref().map(text),
        response_delay_param_default_us: param_default_us,
        request_gap_bits: gap.and_then(bits),
        request_gap_us: gap.and_then(|i| i.ms).map(us),
        char_bits: drive.protocol.serial.as_ref().and_then(|s| s.char_bits),
    }
}

/// The drive's runtime profile; `registers` gives the write rules.
fn profile(drive: &Drive, registers: &'static [RegisterPlan]) -> Profile {
    let p = &drive.protocol;
    let (rtu, tcp) = drive.address_offsets();
    let writes: Vec<WriteRule> = registers
        .iter()
        .filter(|r| r.info.access.writable())
        .map(RegisterPlan::write_rule)
        .collect();
    Profile {
        drive_id: text(&drive.meta.id),
        function_codes: leak(p.function_codes.codes.clone()),
        max_read: p.max_read(),
        max_write: p.max_write(),
        max_read_bits: p.max_read_bits(),
        max_write_bits: p.max_write_bits(),
        slave_min: p.slave_address.range().0,
        slave_max: p.slave_address.range().1,
        broadcast: p.broadcast.as_ref().map(|b| match &b.unknown {
            Some(why) => BroadcastInfo::not_printed(text(why.trim())),
            None => {
                BroadcastInfo::new(leak(b.functions.clone()), leak(drive.broadcast_addresses()))
            }
        }),
        exceptions: leak(
            p.exceptions
                .iter()
                .map(|e| ExceptionInfo {
                    code: e.code,
                    name: text(&e.name),
                    description: text(&e.description),
                })
                .collect(),
        ),
        commands: leak(
            p.commands
                .iter()
                .map(|c| CommandInfo {
                    id: text(&c.id),
                    name: text(&c.name),
                    kind: c.kind,
                    writes: leak(c.writes.iter().map(|w| (w.address, w.value)).collect()),
                    source: text(&c.source),
                })
                .collect(),
        ),
        address_offsets: AddressOffsets { rtu, tcp },
        timing: timing(drive),
        serial_formats: p
            .serial
            .as_ref()
            .and_then(|s| s.formats.as_ref())
            .map(|f| SerialFormats {
                selected_by: text(&f.selected_by),
                formats: leak(drive.serial_format_list()),
                source: text(&f.source),
            }),
        eeprom_write_endurance: p.eeprom.as_ref().map(|e| e.endurance),
        writes: leak(writes),
        not_printed: leak(
            crate::stated::unprinted(p)
                .into_iter()
                .map(|u| drivemap_core::stated::NotPrinted {
                    fact: u.fact,
                    why: text(&u.why),
                    source: u.source.as_deref().map(text),
                })
                .collect(),
        ),
    }
}
