//! The one mapping of a drive's registers to the tools a plant already runs: what each chosen
//! register is to a tool that reads it, decided once from the drive's plan, for the bridge
//! (Prometheus metrics, MQTT state topics and Home Assistant discovery) and for the static
//! exports of `drivemap export` (Home Assistant's `modbus:` YAML, a Node-RED flow, a Telegraf
//! configuration).
//!
//! A [`Point`] is one value a tool reads: a register, or one field of a bit-field register
//! (the bridge publishes each field on its own). Its [`Meaning`] comes from the register's
//! planned conversion; the names the tools give it are here too: [`slug`] for identifiers and
//! topics, [`prometheus`] for metric families and units, [`home_assistant`] for units and device
//! classes (a number's bounds and step are the map's: `RegisterRef::input_bounds`). [`export`] places the points of a drive on a link
//! (table, PDU address, the planner's reads) for the exports, which [`home_assistant`],
//! [`node_red`] and [`telegraf`] print.

use drivemap_live::lookup::{self, NotFound};
use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::core::plan::{Field, Label, RegisterPlan, ValueShape};
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::core::register::Table;
pub(crate) use drivemap_runtime::core::roles::Role;
use drivemap_runtime::core::roles::{RoleKind, Target};
use drivemap_runtime::core::width::{Width, WordOrder};

pub mod export;
pub mod home_assistant;
pub mod node_red;
pub mod prometheus;
pub mod telegraf;

/// What a point's value means, as far as a tool can show it: from the register's planned
/// conversion.
#[derive(Debug, Clone, PartialEq)]
pub enum Meaning {
    /// An engineering value in the point's unit. `Some` when the tool applies the scale itself
    /// (an export: the map's own scale, or the one the `--set` settings select); `None` when
    /// the bridge's runtime converts each value read with the settings it reads from the drive.
    Number(Option<Fixed>),
    /// A plain integer.
    Word,
    /// A code; the meanings listed for what is read.
    Code(&'static [Label]),
    /// A bit-field register read as its word; its fields.
    Bits(&'static [Field]),
    /// A coil or discrete input: on (1) or off (0).
    Bit,
    /// Text over the point's registers (`string:`), two characters each, in this byte order:
    /// exported where the target describes text (Home Assistant's `data_type: string`).
    Text(drivemap_runtime::core::text::ByteOrder),
    /// One field of a bit-field register, the `index`th of its fields.
    Field {
        /// Its position among the register's fields.
        index: usize,
        /// The field.
        field: &'static Field,
    },
}

/// A scale a tool applies itself: raw × `factor`, shown with `precision` decimals.
#[derive(Debug, Clone, PartialEq)]
pub struct Fixed {
    /// Engineering value of one count.
    pub factor: f64,
    /// Digits after the decimal point worth showing.
    pub precision: usize,
    /// Which `--set` fixed a scale the drive could change (empty when the scale is the map's
    /// own).
    pub given: String,
}

/// One value a tool reads of a drive: a register, or one field of a bit-field register.
#[derive(Debug, Clone)]
pub struct Point<'d> {
    /// The register.
    pub register: RegisterRef<'d>,
    /// The register's plan.
    pub plan: &'static RegisterPlan,
    /// The register's position among the registers chosen (the bridge polls them in order).
    pub slot: usize,
    /// The role it plays on the link's transport, if the map gives one.
    pub role: Option<Role>,
    /// What its value means.
    pub meaning: Meaning,
    /// Where a tool reads it on the link, for the points of an [`export::Export`]; `None` for
    /// the bridge's, whose link reads them with the runtime's planner at the addresses the
    /// drive's settings give.
    pub at: Option<At>,
}

/// Where an export's tool reads a point on its link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct At {
    /// The PDU address on the link (the manual's address moved by the settings and the
    /// transport's offset).
    pub pdu: u16,
    /// The planned read it belongs to (index into [`export::Export::reads`]).
    pub read: usize,
}

impl<'d> Point<'d> {
    /// The map's id of the register.
    pub fn id(&self) -> &'d str {
        self.register.id()
    }

    /// The manual's parameter number, empty when it gives none.
    pub fn param(&self) -> &'d str {
        self.register.param().unwrap_or_default()
    }

    /// The field's id, for the point of a field.
    pub fn field(&self) -> Option<&'static str> {
        match self.meaning {
            Meaning::Field { field, .. } => Some(field.id),
            _ => None,
        }
    }

    /// The human name: the manual's name of the register, and of the field after a colon for
    /// the point of a field.
    pub fn name(&self) -> String {
        match self.meaning {
            Meaning::Field { field, .. } => format!("{}: {}", self.register.name(), field.name),
            _ => self.register.name().to_owned(),
        }
    }

    /// The printed name of the register, with the parameter number when the manual gives one
    /// and the name does not hold it.
    pub fn label(&self) -> String {
        let name = self.register.name();
        match self.register.param() {
            Some(p) if !name.contains(p) => format!("{name} ({p})"),
            _ => name.to_owned(),
        }
    }

    /// The map's unit (`""` for none).
    pub fn unit(&self) -> &'static str {
        self.plan.unit
    }

    /// Holding or input registers, coils or discrete inputs.
    pub fn table(&self) -> Table {
        self.plan.info.table
    }

    /// One register or a 32-bit pair.
    pub fn width(&self) -> Width {
        self.plan.info.width
    }

    /// Whether the raw value is signed.
    pub fn signed(&self) -> bool {
        self.plan.signed()
    }

    /// Whether the second word of a pair comes first on the wire.
    pub fn low_first(&self) -> bool {
        self.width() == Width::Pair(WordOrder::LowFirst)
    }

    /// The PDU address a tool reads it at ([`Point::at`]; 0 for a point not placed on a link).
    pub fn pdu(&self) -> u16 {
        self.at.map_or(0, |a| a.pdu)
    }

    /// The planned read it belongs to ([`Point::at`]; 0 for a point not placed on a link).
    pub fn read(&self) -> usize {
        self.at.map_or(0, |a| a.read)
    }

    /// Whether the value is a number (an engineering value or a plain word).
    pub fn is_number(&self) -> bool {
        matches!(self.meaning, Meaning::Number(_) | Meaning::Word)
    }

    /// The MQTT object id under the drive (`output_frequency`, `status_word_running`).
    pub fn object(&self) -> String {
        match self.field() {
            Some(f) => format!("{}_{}", slug(self.id()), slug(f)),
            None => slug(self.id()),
        }
    }
}

/// `text` as an identifier every tool takes (a Prometheus name part, an MQTT topic level, a Home
/// Assistant unique id): lowercase letters, digits and `_`; `x` when nothing is left.
pub fn slug(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    let out = out.trim_matches('_').to_owned();
    if out.is_empty() { "x".into() } else { out }
}

/// The register `name` means on `map`: an id, parameter number, printed name or address, as
/// `drivemap read` and `write` take it (drivemap-live's lookup).
pub fn find<'m>(map: &'m Map, name: &str) -> Result<RegisterRef<'m>, NotFound> {
    lookup::find(map, name)
}

/// The role a whole register plays (monitors and setpoints), if any, on `kind`.
pub fn register_role(map: &Map, r: RegisterRef<'_>, kind: TransportKind) -> Option<Role> {
    map.plan().roles.places.iter().find_map(|p| {
        let Target::Register(row) = p.target else {
            return None;
        };
        (p.transports.contains(kind) && usize::from(row) == r.row()).then_some(p.role)
    })
}

/// The status role of a one-bit field of `r` at bit `lsb`, if any, on `kind`.
pub fn field_role(map: &Map, r: RegisterRef<'_>, lsb: u8, kind: TransportKind) -> Option<Role> {
    map.plan().roles.places.iter().find_map(|p| {
        let Target::Field(f) = p.target else {
            return None;
        };
        (p.role.kind() == RoleKind::Status
            && p.transports.contains(kind)
            && f.lsb == lsb
            && usize::from(f.row) == r.row())
        .then_some(p.role)
    })
}

/// The role a coil or discrete input plays (a command or a status, on its one bit), if any, on
/// `kind`.
pub fn bit_role(map: &Map, r: RegisterRef<'_>, kind: TransportKind) -> Option<Role> {
    map.plan().roles.places.iter().find_map(|p| {
        let Target::Field(f) = p.target else {
            return None;
        };
        (p.transports.contains(kind) && f.width == 1 && usize::from(f.row) == r.row())
            .then_some(p.role)
    })
}

/// The registers a drive's roles read or write on `kind` (fields' registers included).
pub fn role_registers(map: &Map, kind: TransportKind) -> Vec<RegisterRef<'_>> {
    let mut out: Vec<RegisterRef<'_>> = Vec::new();
    for p in map.plan().roles.places {
        if !p.transports.contains(kind) {
            continue;
        }
        if let Some(r) = p
            .target
            .row()
            .and_then(|row| map.register_of_row(usize::from(row)))
            && !out.contains(&r)
        {
            out.push(r);
        }
    }
    out
}

/// The points the bridge publishes of the polled registers `regs` of `drive` on `kind`: one per
/// register, one per field of a bit-field register. Numbers are converted by the runtime with
/// the settings read from the drive ([`Meaning::Number`] without a fixed scale).
pub fn polled<'d>(map: &'d Map, regs: &[RegisterRef<'d>], kind: TransportKind) -> Vec<Point<'d>> {
    let mut out = Vec::new();
    for (slot, &r) in regs.iter().enumerate() {
        let plan = r.plan();
        let point = |role, meaning| Point {
            register: r,
            plan,
            slot,
            role,
            meaning,
            at: None,
        };
        if plan.info.table.is_bits() {
            out.push(point(bit_role(map, r, kind), Meaning::Bit));
            continue;
        }
        match plan.conversion.shape() {
            ValueShape::Bits { fields, .. } => {
                for (index, field) in fields.iter().enumerate() {
                    let role = if field.width == 1 {
                        field_role(map, r, field.lsb, kind)
                    } else {
                        None
                    };
                    out.push(point(role, Meaning::Field { index, field }));
                }
            }
            ValueShape::Codes(values) => {
                out.push(point(register_role(map, r, kind), Meaning::Code(values)));
            }
            ValueShape::Word { .. } => {
                out.push(point(register_role(map, r, kind), Meaning::Word));
            }
            ValueShape::Number => {
                out.push(point(register_role(map, r, kind), Meaning::Number(None)));
            }
            // The bridge publishes numbers, codes and bits; a string is not bridged (yet).
            ValueShape::Text { .. } => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_are_lowercase_words() {
        assert_eq!(slug("U1-02 (Hz)"), "u1_02_hz");
        assert_eq!(slug("--"), "x");
    }
}
