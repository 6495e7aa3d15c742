//! Telegraf's `inputs.modbus` plugin in its request style: one `[[inputs.modbus.request]]` per
//! read of drivemap's planner, the addresses it bridges as `omit` fields, so Telegraf sends
//! exactly the planned requests (optimization `none` keeps a request's fields as given).

use std::fmt::Write;

use drivemap_runtime::core::register::Table;

use super::Meaning;
use super::export::{Endpoint, Export, write_point_caveats};

fn q(text: &str) -> String {
    // A JSON string without control characters is a TOML basic string.
    serde_json::Value::from(text).to_string()
}

/// The `[[inputs.modbus]]` configuration of `points`.
pub fn render(points: &Export) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Telegraf inputs.modbus configuration written by `drivemap export --format telegraf`"
    );
    let _ = writeln!(out, "# {}", points.summary());
    let _ = writeln!(
        out,
        "# One [[inputs.modbus.request]] per planned read; `omit` fields are addresses a read bridges."
    );
    write_point_caveats(
        &mut out,
        points,
        "the request style reads whole registers: the field is the word",
        "the field is the code",
    );
    // A request's byte order is one for all its fields: a pair of the other word order cannot
    // share a read with a pair of this order.
    let mut mixed = Vec::new();
    for (i, _) in points.reads.iter().enumerate() {
        let pairs: Vec<_> = points
            .in_read(i)
            .filter(|p| p.width().count() == 2)
            .collect();
        if let Some(first) = pairs.first() {
            for p in &pairs {
                if p.low_first() != first.low_first() {
                    mixed.push(p.id().to_owned());
                    let _ = writeln!(
                        out,
                        "# left out {}: its word order differs from {}'s in the same read, and a Telegraf request has one byte_order",
                        p.id(),
                        first.id()
                    );
                }
            }
        }
    }
    for line in points.left_out_lines() {
        let _ = writeln!(out, "# {line}");
    }
    let _ = writeln!(out, "[[inputs.modbus]]");
    let _ = writeln!(out, "  name = {}", q(&points.name));
    let _ = writeln!(out, "  interval = \"{}ms\"", points.period_ms);
    let _ = writeln!(out, "  timeout = \"{}ms\"", points.timeout_ms);
    match &points.endpoint {
        Endpoint::Tcp {
            host,
            port,
            rtu_frames,
        } => {
            let host = if host.contains(':') {
                format!("[{host}]")
            } else {
                host.clone()
            };
            let _ = writeln!(out, "  controller = {}", q(&format!("tcp://{host}:{port}")));
            let _ = writeln!(
                out,
                "  transmission_mode = \"{}\"",
                if *rtu_frames { "RTUoverTCP" } else { "TCP" }
            );
        }
        Endpoint::Serial {
            path,
            baud,
            parity,
            stop_bits,
        } => {
            let _ = writeln!(out, "  controller = {}", q(&format!("file://{path}")));
            let _ = writeln!(out, "  baud_rate = {baud}");
            let _ = writeln!(out, "  data_bits = 8");
            let _ = writeln!(out, "  parity = \"{}\"", parity.letter());
            let _ = writeln!(out, "  stop_bits = {stop_bits}");
            let _ = writeln!(out, "  transmission_mode = \"RTU\"");
        }
    }
    let _ = writeln!(out, "  configuration_type = \"request\"");
    for (i, read) in points.reads.iter().enumerate() {
        let members: Vec<_> = points
            .in_read(i)
            .filter(|p| !mixed.iter().any(|m| m == p.id()))
            .collect();
        let low_first = members
            .iter()
            .find(|p| p.width().count() == 2)
            .is_some_and(|p| p.low_first());
        let _ = writeln!(out);
        let _ = writeln!(
            out,
            "  # planned read {}: {} PDU {}..{} ({} {})",
            i + 1,
            match read.table {
                Table::Holding => "holding (03h)",
                Table::Input => "input (04h)",
                Table::Coil => "coil (01h)",
                Table::DiscreteInput => "discrete input (02h)",
            },
            read.pdu,
            u32::from(read.pdu) + u32::from(read.quantity) - 1,
            read.quantity,
            if read.table.is_bits() {
                "bit(s)"
            } else {
                "register(s)"
            }
        );
        let bits = read.table.is_bits();
        let _ = writeln!(out, "  [[inputs.modbus.request]]");
        let _ = writeln!(out, "    slave_id = {}", points.slave);
        if !bits {
            // Coils and discrete inputs have no byte order.
            let _ = writeln!(
                out,
                "    byte_order = \"{}\"",
                if low_first { "CDAB" } else { "ABCD" }
            );
        }
        let _ = writeln!(
            out,
            "    register = \"{}\"",
            match read.table {
                Table::Holding => "holding",
                Table::Input => "input",
                Table::Coil => "coil",
                Table::DiscreteInput => "discrete",
            }
        );
        let _ = writeln!(out, "    measurement = \"drivemap\"");
        let _ = writeln!(out, "    optimization = \"none\"");
        let _ = writeln!(out, "    fields = [");
        let end = u32::from(read.pdu) + u32::from(read.quantity);
        let mut address = u32::from(read.pdu);
        while address < end {
            match members.iter().find(|p| u32::from(p.pdu()) == address) {
                Some(p) if bits => {
                    // A coil or discrete input: Telegraf gives 1 or 0 (no type, no scale).
                    let _ = writeln!(
                        out,
                        "      {{ address = {address}, name = {} }},  # {}",
                        q(p.id()),
                        p.label()
                    );
                    address += 1;
                }
                None if bits => {
                    let _ = writeln!(
                        out,
                        "      {{ address = {address}, name = \"unread_{address}\", omit = true }},"
                    );
                    address += 1;
                }
                Some(p) if matches!(p.meaning, Meaning::Text(_)) => {
                    // Text: the request style's fields are numbers; the string's registers are
                    // read with the request (one planned read) and omitted.
                    for k in 0..u32::from(p.width().count()) {
                        let _ = writeln!(
                            out,
                            "      {{ address = {}, name = \"unread_{}\", type = \"UINT16\", omit = true }},{}",
                            address + k,
                            address + k,
                            if k == 0 {
                                format!("  # {}: text, left out of Telegraf's fields", p.label())
                            } else {
                                String::new()
                            }
                        );
                    }
                    address += u32::from(p.width().count());
                }
                Some(p) => {
                    let bits = p.width().count() * 16;
                    let ty = format!("{}INT{bits}", if p.signed() { "" } else { "U" });
                    let scale = match &p.meaning {
                        Meaning::Number(Some(f)) => format!(", scale = {:?}", f.factor),
                        _ => String::new(),
                    };
                    let unit = if p.unit().is_empty() {
                        String::new()
                    } else {
                        format!(" {}", p.unit())
                    };
                    let _ = writeln!(
                        out,
                        "      {{ address = {address}, name = {}, type = \"{ty}\"{scale} }},  # {}{unit}",
                        q(p.id()),
                        p.label()
                    );
                    address += u32::from(p.width().count());
                }
                None => {
                    let _ = writeln!(
                        out,
                        "      {{ address = {address}, name = \"unread_{address}\", type = \"UINT16\", omit = true }},"
                    );
                    address += 1;
                }
            }
        }
        let _ = writeln!(out, "    ]");
        let _ = writeln!(out, "    [inputs.modbus.request.tags]");
        let _ = writeln!(out, "      drive = {}", q(points.drive.id()));
        let _ = writeln!(out, "      slave = \"{}\"", points.slave);
    }
    let _ = writeln!(out);
    let _ = writeln!(out, "  [inputs.modbus.workarounds]");
    let _ = writeln!(out, "    pause_between_requests = \"{}ms\"", points.gap_ms);
    let _ = writeln!(
        out,
        "    max_word_registers_per_request = {}",
        points.drive.plan().profile.max_read.min(125)
    );
    out
}
