//! Home Assistant's view of a point, for both ways the tools reach it: the unit and device
//! class of a sensor or number, used by the bridge's MQTT discovery ([`crate::mqtt`], whose
//! number entities take their bounds and step from the map: `RegisterRef::input_bounds`); and
//! [`render`], the `modbus:` integration's YAML
//! of an [`Export`]: one hub for the link, a sensor per register with `data_type`, `swap`,
//! `scale`, `offset` and `precision`; what the integration cannot show (codes' meanings, bit
//! fields, scales another parameter selects) as comments.

use std::fmt::Write;

use drivemap_runtime::core::register::Table;

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
    let data_type = match p.meaning {
        // Text: Home Assistant reads `count` registers, high byte first unless `swap: byte`.
        Meaning::Text(_) => "string".to_owned(),
        _ => format!("{}int{bits}", if p.signed() { "" } else { "u" }),
    };
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
            Table::Coil => "coil",
            Table::DiscreteInput => "discrete_input",
        }
    );
    let _ = writeln!(out, "        data_type: {data_type}");
    if let Meaning::Text(order) = p.meaning {
        let _ = writeln!(out, "        count: {}", p.width().count());
        if order == drivemap_runtime::core::text::ByteOrder::LowFirst {
            // The first character in the low byte: Home Assistant swaps each register's bytes.
            let _ = writeln!(out, "        swap: byte");
        }
    }
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
        Meaning::Number(None)
        | Meaning::Text(_)
        | Meaning::Code(_)
        | Meaning::Bits(_)
        | Meaning::Field { .. }
        | Meaning::Bit => {}
    }
    let _ = writeln!(
        out,
        "        scan_interval: {}",
        points.period_ms.div_ceil(1000).max(1)
    );
}

/// A coil or discrete input as a `binary_sensors:` entry (read only: a coil is written through
/// drivemap, whose drive trait keeps the run contract, not from a switch beside it).
fn binary_sensor(out: &mut String, points: &Export, p: &Point, name: &str) {
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
        if p.table() == Table::Coil {
            "coil"
        } else {
            "discrete_input"
        }
    );
    match p.role {
        Some(super::Role::Fault | super::Role::Alarm) => {
            let _ = writeln!(out, "        device_class: problem");
        }
        Some(super::Role::Running) => {
            let _ = writeln!(out, "        device_class: running");
        }
        _ => {}
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
    let (bits, sensors): (Vec<_>, Vec<_>) = sensors
        .into_iter()
        .partition(|(p, _)| matches!(p.meaning, Meaning::Bit));
    if sensors.is_empty() {
        let _ = writeln!(out, "    sensors: []");
    } else {
        let _ = writeln!(out, "    sensors:");
        for (p, name) in &sensors {
            sensor(&mut out, points, p, name);
        }
    }
    if !bits.is_empty() {
        let _ = writeln!(out, "    binary_sensors:");
        for (p, name) in &bits {
            binary_sensor(&mut out, points, p, name);
        }
    }
    out
}
