//! Home Assistant's view of a point, for both ways the tools reach it: the unit and device
//! class of a sensor or number, and a number's step and bounds for its input box, used by the
//! bridge's MQTT discovery ([`crate::mqtt`]); and [`render`], the `modbus:` integration's YAML
//! of an [`Export`]: one hub for the link, a sensor per register with `data_type`, `swap`,
//! `scale`, `offset` and `precision`; what the integration cannot show (codes' meanings, bit
//! fields, scales another parameter selects) as comments.

use std::fmt::Write;

use drivemap_map::Drive;
use drivemap_runtime::Table;
use drivemap_runtime::plan::{CaseScale, Conversion, RegisterPlan, Relative, Scale, SettingsView};
use drivemap_runtime::scale::RawRange;

use super::export::{Endpoint, Export, write_point_caveats};
use super::{Meaning, Point, slug};

fn q(text: &str) -> String {
    // A JSON string is a YAML double-quoted scalar.
    serde_json::Value::from(text).to_string()
}

/// Home Assistant's spelling of a map's unit (`degC` → `°C`, `ohm` → `Ω`, `day` → `d`).
pub fn unit(unit: &str) -> &str {
    match unit.trim() {
        "degC" => "°C",
        "ohm" => "Ω",
        "day" => "d",
        u => u,
    }
}

/// Home Assistant's device class of a sensor or number in the map's unit, where the unit, as
/// Home Assistant spells it ([`unit()`]), is one the class accepts.
pub fn device_class(map_unit: &str) -> Option<&'static str> {
    Some(match unit(map_unit) {
        "Hz" | "kHz" => "frequency",
        "A" => "current",
        "V" => "voltage",
        "W" | "kW" => "power",
        "kWh" => "energy",
        "°C" => "temperature",
        "d" | "h" | "min" | "s" | "ms" => "duration",
        _ => return None,
    })
}

/// The step of a number register's input box, from its planned conversion: one count of a
/// decimal or ratio scale (a ratio's as the nearest `f64`: 1/60 Hz for 3600 = 60.0 Hz), the
/// finest of a selected scale's cases; for a scale relative to another quantity, whose count
/// is not known before that quantity is read, the resolution the runtime shows such a value
/// with ([`Scale::decimals`]: 0.01); else 1.
pub fn step(plan: &RegisterPlan) -> f64 {
    fn relative(r: &Relative) -> f64 {
        let shown = Scale::Relative {
            full_scale: r.full_scale,
            reference: f64::NAN,
            label: r.reference.label,
        };
        1.0 / 10f64.powi(shown.decimals() as i32)
    }
    let step = match &plan.conversion {
        Conversion::Decimal { scale, .. } => scale.decode(1),
        Conversion::Ratio { ratio, .. } => ratio.decode(1),
        Conversion::Relative { relative: r, .. } => relative(r),
        Conversion::Selected { cases, .. } => cases
            .iter()
            .map(|c| match &c.scale {
                CaseScale::Decimal { scale, .. } => scale.decode(1),
                CaseScale::Relative(r) => relative(r),
            })
            .fold(f64::INFINITY, f64::min),
        Conversion::Word { .. } | Conversion::Enum { .. } | Conversion::Bits { .. } => 1.0,
    };
    if step.is_finite() && step > 0.0 {
        step
    } else {
        1.0
    }
}

/// The quantities a relative limit is taken at for [`bounds`]: each register at the largest
/// value its range allows.
struct AtMost<'d>(&'d Drive);

impl SettingsView for AtMost<'_> {
    fn code(&self, _: u8) -> Option<u16> {
        None
    }
    fn quantity(&self, slot: u8) -> Option<f64> {
        let all = self.0.plan();
        let drivemap_map::lower::Quantity::Register(row) =
            all.settings.quantities.get(usize::from(slot))?
        else {
            return None;
        };
        let plan = all.registers.get(*row)?;
        let (_, max) = printed_range(plan)?;
        Some(max)
    }
    fn variant(&self, _: u8) -> u8 {
        0
    }
}

/// The range the manual prints for a register, widest over a selected scale's cases, decoded
/// (`None` when it prints none: the plan's range is then the word's own).
fn printed_range(plan: &RegisterPlan) -> Option<(f64, f64)> {
    let full = plan.full_range();
    let printed = |r: &RawRange| (*r != full).then_some(*r);
    let widest = |a: Option<(f64, f64)>, b: (f64, f64)| match a {
        Some((lo, hi)) => Some((lo.min(b.0), hi.max(b.1))),
        None => Some(b),
    };
    match &plan.conversion {
        Conversion::Decimal { scale, range, .. } => {
            printed(&range.base).map(|r| (scale.decode(r.min), scale.decode(r.max)))
        }
        Conversion::Ratio { ratio, range, .. } => {
            printed(&range.base).map(|r| (ratio.decode(r.min), ratio.decode(r.max)))
        }
        Conversion::Word { range, .. } => {
            printed(&range.base).map(|r| (r.min as f64, r.max as f64))
        }
        Conversion::Selected { cases, .. } => cases.iter().fold(None, |acc, c| match &c.scale {
            CaseScale::Decimal { scale, range } => match printed(range) {
                Some(r) => widest(acc, (scale.decode(r.min), scale.decode(r.max))),
                None => acc,
            },
            CaseScale::Relative(_) => acc,
        }),
        Conversion::Relative { .. } | Conversion::Enum { .. } | Conversion::Bits { .. } => None,
    }
}

/// The widest bounds the map gives a number register, for Home Assistant's input box (the
/// bridge checks the bounds in force when a value comes), from its plan: its range (the widest
/// of a selected scale's cases), else its limit through another register at that register's
/// largest value, else what the raw word holds (decoded by its scale where fixed, else counted
/// in [`step`]s).
pub fn bounds(drive: &Drive, plan: &RegisterPlan) -> (f64, f64) {
    if let Some(range) = printed_range(plan) {
        return range;
    }
    let full = plan.full_range();
    let (lo, hi) = match &plan.conversion {
        Conversion::Decimal { scale, .. } => (scale.decode(full.min), scale.decode(full.max)),
        Conversion::Ratio { ratio, .. } => (ratio.decode(full.min), ratio.decode(full.max)),
        _ => {
            let step = step(plan);
            (full.min as f64 * step, full.max as f64 * step)
        }
    };
    let limit = plan.relative_max(&AtMost(drive)).ok().flatten();
    (lo, limit.unwrap_or(hi))
}

fn number(v: f64) -> String {
    let s = format!("{v}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

fn sensor(out: &mut String, points: &Export, p: &Point, name: &str) {
    let bits = p.width().count() * 16;
    let data_type = format!("{}int{bits}", if p.signed() { "" } else { "u" });
    let _ = writeln!(out, "      - name: {}", q(name));
    let _ = writeln!(
        out,
        "        unique_id: {}",
        q(&slug(&format!(
            "{} {} {}",
            points.name,
            points.slave,
            p.id()
        )))
    );
    let _ = writeln!(out, "        slave: {}", points.slave);
    let _ = writeln!(out, "        address: {}", p.pdu());
    let _ = writeln!(
        out,
        "        input_type: {}",
        match p.table() {
            Table::Holding => "holding",
            Table::Input => "input",
        }
    );
    let _ = writeln!(out, "        data_type: {data_type}");
    if p.low_first() {
        // The low word at the lower address: Home Assistant swaps the words.
        let _ = writeln!(out, "        swap: word");
    }
    match &p.meaning {
        Meaning::Number(Some(fixed)) => {
            let (scale, precision) = (fixed.factor, fixed.precision);
            let _ = writeln!(out, "        scale: {}", number(scale));
            let _ = writeln!(out, "        offset: 0");
            let _ = writeln!(out, "        precision: {precision}");
            if !p.unit().is_empty() {
                let _ = writeln!(out, "        unit_of_measurement: {}", q(unit(p.unit())));
                if let Some(class) = device_class(p.unit()) {
                    let _ = writeln!(out, "        device_class: {class}");
                }
            }
            let _ = writeln!(out, "        state_class: measurement");
        }
        Meaning::Word => {
            if !p.unit().is_empty() {
                let _ = writeln!(out, "        unit_of_measurement: {}", q(unit(p.unit())));
            }
        }
        Meaning::Number(None) | Meaning::Code(_) | Meaning::Bits(_) | Meaning::Field { .. } => {}
    }
    let _ = writeln!(
        out,
        "        scan_interval: {}",
        points.period_ms.div_ceil(1000).max(1)
    );
}

/// The `modbus:` configuration of `points`.
pub fn render(points: &Export) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Home Assistant `modbus:` configuration written by `drivemap export --format home-assistant`"
    );
    let _ = writeln!(out, "# {}", points.summary());
    let _ = writeln!(
        out,
        "# Home Assistant reads each sensor with a request of its own: {} request(s) per scan where drivemap's planner needs {}.",
        points.points.len(),
        points.reads.len()
    );
    let _ = writeln!(
        out,
        "# Addresses are the PDU addresses on this link (the manual's address, moved for the transport)."
    );
    write_point_caveats(
        &mut out,
        points,
        "Home Assistant's modbus sensors cannot split bit fields: the sensor shows the word",
        "Home Assistant's modbus sensors show the code, not its meaning",
    );
    // Home Assistant loads one entity per name and one per address (the second is dropped with
    // a warning): a printed name the manual gives twice takes the register id, a second
    // register at an address is left out here.
    let mut sensors: Vec<(&Point, String)> = Vec::new();
    for p in &points.points {
        if let Some((first, _)) = sensors
            .iter()
            .find(|(s, _)| s.pdu() == p.pdu() && s.table() == p.table())
        {
            let _ = writeln!(
                out,
                "# left out {}: it shares PDU address {} with {}, and Home Assistant loads one entity per address",
                p.id(),
                p.pdu(),
                first.id()
            );
            continue;
        }
        let mut name = format!("{} {}", points.name, p.label());
        if points
            .points
            .iter()
            .filter(|o| o.label() == p.label())
            .count()
            > 1
        {
            name = format!("{name} [{}]", p.id());
        }
        sensors.push((p, name));
    }
    for line in points.left_out_lines() {
        let _ = writeln!(out, "# {line}");
    }
    let _ = writeln!(out, "modbus:");
    let _ = writeln!(out, "  - name: {}", q(&slug(&points.name)));
    match &points.endpoint {
        Endpoint::Tcp {
            host,
            port,
            rtu_frames,
        } => {
            let _ = writeln!(
                out,
                "    type: {}",
                if *rtu_frames { "rtuovertcp" } else { "tcp" }
            );
            let _ = writeln!(out, "    host: {}", q(host));
            let _ = writeln!(out, "    port: {port}");
        }
        Endpoint::Serial {
            path,
            baud,
            parity,
            stop_bits,
        } => {
            let _ = writeln!(out, "    type: serial");
            let _ = writeln!(out, "    method: rtu");
            let _ = writeln!(out, "    port: {}", q(path));
            let _ = writeln!(out, "    baudrate: {baud}");
            let _ = writeln!(out, "    bytesize: 8");
            let _ = writeln!(out, "    parity: {}", parity.letter());
            let _ = writeln!(out, "    stopbits: {stop_bits}");
        }
    }
    let _ = writeln!(
        out,
        "    timeout: {}",
        points.timeout_ms.div_ceil(1000).max(1)
    );
    if points.gap_ms > 0 {
        let _ = writeln!(out, "    message_wait_milliseconds: {}", points.gap_ms);
    }
    if sensors.is_empty() {
        let _ = writeln!(out, "    sensors: []");
    } else {
        let _ = writeln!(out, "    sensors:");
        for (p, name) in &sensors {
            sensor(&mut out, points, p, name);
        }
    }
    out
}
