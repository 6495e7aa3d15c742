//! What the bridge publishes of a drive: its polled registers ("points"), each with the
//! Prometheus metric it feeds and the Home Assistant entity it is, named from the map.

use drivemap_map::Map;
use drivemap_map::RegisterRef;
use drivemap_map::ir::ValueKind;
use drivemap_runtime::profile::TransportKind;
use drivemap_runtime::roles::{Role, RoleKind, Target};

/// A unit as Prometheus' naming conventions want it: the base unit's name for the metric's
/// suffix and the factor from the map's unit to it (`ms` → seconds × 0.001, `%` → ratio × 0.01).
#[derive(Debug, Clone, PartialEq)]
pub struct MetricUnit {
    /// The suffix (`hertz`), empty for a number without a unit.
    pub suffix: String,
    /// Map value × factor = metric value.
    pub factor: f64,
}

/// The Prometheus unit of a map's unit.
pub fn metric_unit(unit: Option<&str>) -> MetricUnit {
    let (suffix, factor) = match unit.map(str::trim).unwrap_or("") {
        "" => ("", 1.0),
        "Hz" => ("hertz", 1.0),
        "kHz" => ("hertz", 1000.0),
        "A" => ("amperes", 1.0),
        "V" => ("volts", 1.0),
        "s" => ("seconds", 1.0),
        "ms" => ("seconds", 0.001),
        "min" => ("seconds", 60.0),
        "h" => ("seconds", 3600.0),
        "day" => ("seconds", 86400.0),
        "%" => ("ratio", 0.01),
        "W" => ("watts", 1.0),
        "kW" => ("watts", 1000.0),
        "kWh" => ("joules", 3.6e6),
        "Ω" => ("ohms", 1.0),
        "°C" | "degC" => ("celsius", 1.0),
        "rpm" | "r/min" | "min-1" => ("rpm", 1.0),
        other => {
            return MetricUnit {
                suffix: sanitize(other),
                factor: 1.0,
            };
        }
    };
    MetricUnit {
        suffix: suffix.to_owned(),
        factor,
    }
}

/// `text` as a Prometheus name part / MQTT topic level: lowercase letters, digits and `_`.
pub fn sanitize(text: &str) -> String {
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

/// Home Assistant's `device_class` of a sensor or number in `unit`, where HA has one.
pub fn device_class(unit: Option<&str>) -> Option<&'static str> {
    Some(match unit?.trim() {
        "Hz" | "kHz" => "frequency",
        "A" => "current",
        "V" => "voltage",
        "s" | "ms" | "min" | "h" | "day" => "duration",
        "W" | "kW" => "power",
        "kWh" => "energy",
        "°C" => "temperature",
        _ => return None,
    })
}

/// How a point's value is shown.
#[derive(Debug, Clone)]
pub enum PointKind {
    /// A number (engineering value, word): a gauge.
    Number { unit: MetricUnit },
    /// An enumeration code: an info-style metric labelled with the code and its meaning.
    Code,
    /// One field of a bit-field register: 0/1 gauge (one bit) or info-style (several bits).
    Field { index: usize, width: u8 },
}

/// One polled value.
#[derive(Debug, Clone)]
pub struct Point {
    /// Index of the register among the drive's polled registers.
    pub slot: usize,
    /// The register id (`output_frequency`, `u1_02`).
    pub register: String,
    /// The manual's parameter number, if any.
    pub param: String,
    /// The field id, for a field point.
    pub field: Option<String>,
    /// The role the value plays, if the map gives one (`output_frequency`, `running`).
    pub role: Option<Role>,
    /// Human name (the manual's).
    pub name: String,
    /// The map's unit.
    pub unit: Option<String>,
    pub kind: PointKind,
    /// The Prometheus metric family (without the unit suffix, which [`MetricUnit`] adds).
    pub metric: String,
    /// The MQTT object id under the drive (`output_frequency`, `status_word_running`).
    pub object: String,
}

/// The role a whole register plays (monitors and setpoints), if any, on `kind`.
pub fn register_role(drive: &Map, r: RegisterRef<'_>, kind: TransportKind) -> Option<Role> {
    let plan = drive.plan();
    plan.roles.places.iter().find_map(|p| {
        let row = match p.target {
            Target::Register(row) => row,
            _ => return None,
        };
        (p.transports.contains(kind)
            && drive
                .register_of_row(usize::from(row))
                .is_some_and(|x| x.id() == r.id()))
        .then_some(p.role)
    })
}

/// The status role of a field of `r`, if any, on `kind`.
pub fn field_role(drive: &Map, r: RegisterRef<'_>, lsb: u8, kind: TransportKind) -> Option<Role> {
    let plan = drive.plan();
    plan.roles.places.iter().find_map(|p| {
        let Target::Field(f) = p.target else {
            return None;
        };
        (p.role.kind() == RoleKind::Status
            && p.transports.contains(kind)
            && f.lsb == lsb
            && drive
                .register_of_row(usize::from(f.row))
                .is_some_and(|x| x.id() == r.id()))
        .then_some(p.role)
    })
}

/// The registers a drive's roles read or write on `kind` (fields' registers included).
pub fn role_registers(drive: &Map, kind: TransportKind) -> Vec<RegisterRef<'_>> {
    let plan = drive.plan();
    let mut out: Vec<RegisterRef<'_>> = Vec::new();
    for p in plan.roles.places {
        if !p.transports.contains(kind) {
            continue;
        }
        if let Some(r) = p
            .target
            .row()
            .and_then(|row| drive.register_of_row(usize::from(row)))
            && !out.iter().any(|x| x.id() == r.id())
        {
            out.push(r);
        }
    }
    out
}

/// A field's lowest bit and width.
pub fn field_span(f: &drivemap_map::model::Field) -> (u8, u8) {
    match (f.bit, f.bits) {
        (Some(b), _) => (b, 1),
        (None, Some([a, b])) => (a.min(b), a.abs_diff(b) + 1),
        (None, None) => (0, 16),
    }
}

/// The points of the polled registers `regs` of `drive` on `kind`.
pub fn points(drive: &Map, regs: &[RegisterRef<'_>], kind: TransportKind) -> Vec<Point> {
    let mut out = Vec::new();
    for (slot, r) in regs.iter().enumerate() {
        let param = r.param().map(str::to_owned).unwrap_or_default();
        let role = register_role(drive, *r, kind);
        let base = |field: Option<String>, role: Option<Role>, name: String, kind: PointKind| {
            let object = match &field {
                Some(f) => format!("{}_{}", sanitize(r.id()), sanitize(f)),
                None => sanitize(r.id()),
            };
            let metric = match (&kind, role) {
                (PointKind::Number { .. }, Some(role)) => format!("drivemap_{}", role.id()),
                (PointKind::Number { .. }, None) => "drivemap_register".to_owned(),
                (PointKind::Code, Some(role)) => format!("drivemap_{}_info", role.id()),
                (PointKind::Code, None) => "drivemap_code_info".to_owned(),
                (PointKind::Field { width: 1, .. }, Some(role)) => {
                    format!("drivemap_{}", role.id())
                }
                (PointKind::Field { width: 1, .. }, None) => "drivemap_bit".to_owned(),
                (PointKind::Field { .. }, _) => "drivemap_field_info".to_owned(),
            };
            Point {
                slot,
                register: r.id().to_owned(),
                param: param.clone(),
                field,
                role,
                name,
                unit: r.unit().map(str::to_owned),
                kind,
                metric,
                object,
            }
        };
        match r.ir().kind() {
            ValueKind::Bits(fields) => {
                for (index, f) in fields.iter().enumerate() {
                    let (lsb, width) = field_span(f);
                    let frole = if width == 1 {
                        field_role(drive, *r, lsb, kind)
                    } else {
                        None
                    };
                    out.push(base(
                        Some(f.id.clone()),
                        frole,
                        format!("{}: {}", r.name(), f.name),
                        PointKind::Field { index, width },
                    ));
                }
            }
            ValueKind::Enum(_) => out.push(base(None, role, r.name().to_owned(), PointKind::Code)),
            _ => out.push(base(
                None,
                role,
                r.name().to_owned(),
                PointKind::Number {
                    unit: metric_unit(r.unit()),
                },
            )),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_follow_prometheus_base_units() {
        assert_eq!(metric_unit(Some("Hz")).suffix, "hertz");
        let ms = metric_unit(Some("ms"));
        assert_eq!((ms.suffix.as_str(), ms.factor), ("seconds", 0.001));
        let pct = metric_unit(Some("%"));
        assert_eq!((pct.suffix.as_str(), pct.factor), ("ratio", 0.01));
        assert_eq!(metric_unit(None).suffix, "");
        assert_eq!(metric_unit(Some("Ω")).suffix, "ohms");
        assert_eq!(sanitize("U1-02 (Hz)"), "u1_02_hz");
        assert_eq!(sanitize("--"), "x");
    }
}
