//! Prometheus' names of a point: its metric family and the base unit its number is given in.

use super::{Meaning, Point, slug};

/// A unit as Prometheus' naming conventions want it: the base unit's name for the metric's
/// suffix and the factor from the map's unit to it (`ms` → seconds × 0.001, `%` → ratio × 0.01).
#[derive(Debug, Clone, PartialEq)]
pub struct MetricUnit {
    /// The suffix (`hertz`), empty for a number without a unit.
    pub suffix: String,
    /// Map value × factor = metric value.
    pub factor: f64,
}

/// The Prometheus unit of a map's unit (`""` for none).
pub fn metric_unit(unit: &str) -> MetricUnit {
    let (suffix, factor) = match unit.trim() {
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
                suffix: slug(other),
                factor: 1.0,
            };
        }
    };
    MetricUnit {
        suffix: suffix.to_owned(),
        factor,
    }
}

impl Point<'_> {
    /// The Prometheus unit of a number point (`None` for codes and fields).
    pub fn metric_unit(&self) -> Option<MetricUnit> {
        self.is_number().then(|| metric_unit(self.unit()))
    }

    /// The Prometheus metric family (without the unit suffix, which [`MetricUnit`] adds): the
    /// role's (`drivemap_output_frequency`), else one per kind of value (`drivemap_register`,
    /// `drivemap_code_info`, `drivemap_bit`, `drivemap_field_info`, `drivemap_coil`,
    /// `drivemap_discrete_input`).
    pub fn metric(&self) -> String {
        let role = self.role;
        match (&self.meaning, role) {
            (Meaning::Number(_) | Meaning::Word, Some(role)) => format!("drivemap_{}", role.id()),
            (Meaning::Number(_) | Meaning::Word, None) => "drivemap_register".to_owned(),
            (Meaning::Code(_) | Meaning::Bits(_), Some(role)) => {
                format!("drivemap_{}_info", role.id())
            }
            (Meaning::Code(_) | Meaning::Bits(_), None) => "drivemap_code_info".to_owned(),
            (Meaning::Field { field, .. }, Some(role)) if field.width == 1 => {
                format!("drivemap_{}", role.id())
            }
            (Meaning::Field { field, .. }, None) if field.width == 1 => "drivemap_bit".to_owned(),
            (Meaning::Field { .. }, _) => "drivemap_field_info".to_owned(),
            (Meaning::Bit, Some(role)) => format!("drivemap_{}", role.id()),
            (Meaning::Bit, None) => format!("drivemap_{}", self.table().key()),
            // Not bridged: `points::polled` leaves strings out.
            (Meaning::Text(_), _) => "drivemap_text_info".to_owned(),
        }
    }

    /// The suffix of the point's metric family (empty for codes and fields).
    pub fn metric_suffix(&self) -> String {
        self.metric_unit().map(|u| u.suffix).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_follow_prometheus_base_units() {
        assert_eq!(metric_unit("Hz").suffix, "hertz");
        let ms = metric_unit("ms");
        assert_eq!((ms.suffix.as_str(), ms.factor), ("seconds", 0.001));
        let pct = metric_unit("%");
        assert_eq!((pct.suffix.as_str(), pct.factor), ("ratio", 0.01));
        assert_eq!(metric_unit("").suffix, "");
        assert_eq!(metric_unit("Ω").suffix, "ohms");
    }
}
