//! A Node-RED flow for node-red-contrib-modbus: a tab, a `modbus-client` configuration node for
//! the link, per planned read a `modbus-read` node and a `function` node that decodes its words
//! (scale, sign, 32-bit pairs in the map's word order, codes' meanings, bit fields) into one
//! message per register (`topic` the register id, `payload` the value) and keeps the latest
//! values in the flow context; a `comment` node says what was left out and why.

use drivemap_runtime::core::register::Table;
use serde_json::{Value, json};

use super::export::{Endpoint, Export};
use super::{Fixed, Meaning, Point, slug};

/// A stable node id: 16 hex digits (as the editor makes them) from `key`.
fn node_id(key: &str) -> String {
    // FNV-1a, 64 bits.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in key.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

fn js(text: &str) -> String {
    serde_json::Value::from(text).to_string()
}

/// The JavaScript expression of point `p`'s value from the read's words `w`, `p` at offset `o`.
fn decode(p: &Point, o: usize) -> String {
    if matches!(p.meaning, Meaning::Bit) {
        // node-red-contrib-modbus gives coils and inputs as booleans.
        return format!("(w[{o}] ? 1 : 0)");
    }
    if let Meaning::Text(order) = p.meaning {
        // Two characters per register in the map's byte order, trailing NUL and space padding
        // dropped (as `drivemap read`; the payload is the text as read, not escaped).
        let (first, second) = match order {
            drivemap_runtime::core::text::ByteOrder::HighFirst => ("x >> 8", "x & 255"),
            drivemap_runtime::core::text::ByteOrder::LowFirst => ("x & 255", "x >> 8"),
        };
        let n = usize::from(p.width().count());
        return format!(
            "w.slice({o}, {}).map(x => String.fromCharCode({first}, {second})).join('').replace(/[\\0 ]+$/, '')",
            o + n
        );
    }
    let raw = match (p.width().count(), p.signed(), p.low_first()) {
        (1, false, _) => format!("w[{o}]"),
        (1, true, _) => format!("((w[{o}] << 16) >> 16)"),
        (_, signed, low_first) => {
            let (hi, lo) = if low_first { (o + 1, o) } else { (o, o + 1) };
            if signed {
                format!("((w[{hi}] << 16) | w[{lo}])")
            } else {
                format!("(((w[{hi}] << 16) | w[{lo}]) >>> 0)")
            }
        }
    };
    match &p.meaning {
        Meaning::Number(Some(Fixed {
            factor, precision, ..
        })) => format!("Number(({raw} * {factor:?}).toFixed({precision}))"),
        _ => raw,
    }
}

fn function_body(points: &Export, i: usize) -> String {
    let read = points.reads[i];
    let mut f = String::new();
    f.push_str(&format!(
        "// drivemap: {} slave {}, {} PDU {} x{}\n",
        points.drive.id(),
        points.slave,
        read.table.key(),
        read.pdu,
        read.quantity
    ));
    f.push_str("const w = msg.payload;\nconst out = [];\n");
    f.push_str("function put(id, value, extra) {\n  flow.set(id, value);\n  out.push(Object.assign({topic: id, payload: value}, extra));\n}\n");
    for p in points.in_read(i) {
        let o = usize::from(p.pdu() - read.pdu);
        let value = decode(p, o);
        let mut extra = vec![
            format!("drive: {}", js(points.drive.id())),
            format!("slave: {}", points.slave),
            format!("name: {}", js(&p.label())),
        ];
        if !p.unit().is_empty() {
            extra.push(format!("unit: {}", js(p.unit())));
        }
        match &p.meaning {
            Meaning::Code(labels) if !labels.is_empty() => {
                let map: Vec<String> = labels
                    .iter()
                    .map(|l| format!("{}: {}", l.code, js(l.name)))
                    .collect();
                extra.push(format!(
                    "text: ({{{}}})[{value}] || (\"unlisted code \" + {value})",
                    map.join(", ")
                ));
            }
            Meaning::Bits(fields) => {
                let fs: Vec<String> = fields
                    .iter()
                    .map(|fl| {
                        format!(
                            "{}: ({value} >> {}) & {}",
                            js(fl.id),
                            fl.lsb,
                            (1u32 << fl.width) - 1
                        )
                    })
                    .collect();
                extra.push(format!("fields: {{{}}}", fs.join(", ")));
            }
            _ => {}
        }
        f.push_str(&format!(
            "put({}, {value}, {{{}}});\n",
            js(p.id()),
            extra.join(", ")
        ));
    }
    f.push_str("return [out];\n");
    f
}

/// The flow of `points`: a JSON array of nodes to import or to start `node-red` with.
pub fn render(points: &Export) -> Value {
    let base = format!("drivemap {} {}", points.name, points.slave);
    let tab = node_id(&format!("{base} tab"));
    let client = node_id(&format!("{base} client"));
    let debug = node_id(&format!("{base} debug"));
    let mut nodes = Vec::new();
    nodes.push(json!({
        "id": tab,
        "type": "tab",
        "label": format!("drivemap {} slave {}", points.name, points.slave),
        "disabled": false,
        "info": points.summary(),
    }));
    let mut notes: Vec<String> = Vec::new();
    for p in &points.points {
        if let Meaning::Number(Some(Fixed { given, .. })) = &p.meaning
            && !given.is_empty()
        {
            notes.push(format!(
                "{}: its scale holds for {given}; export again if the drive's setting changes.",
                p.id()
            ));
        }
    }
    notes.extend(points.left_out_lines());
    nodes.push(json!({
        "id": node_id(&format!("{base} comment")),
        "type": "comment",
        "z": tab,
        "name": format!(
            "drivemap: {} register(s) in {} read(s); {} left out",
            points.points.len(),
            points.reads.len(),
            points.left_out.len()
        ),
        "info": if notes.is_empty() {
            "Every register asked for is read.".to_owned()
        } else {
            notes.join("\n")
        },
        "x": 200,
        "y": 40,
        "wires": [],
    }));
    let mut config = json!({
        "id": client,
        "type": "modbus-client",
        "name": format!("{} slave {}", points.name, points.slave),
        "bufferCommands": true,
        "stateLogEnabled": false,
        "queueLogEnabled": false,
        "failureLogEnabled": true,
        "tcpHost": "127.0.0.1",
        "tcpPort": 502,
        "tcpType": "DEFAULT",
        "serialPort": "/dev/ttyUSB",
        "serialType": "RTU-BUFFERD",
        "serialBaudrate": 9600,
        "serialDatabits": 8,
        "serialStopbits": 1,
        "serialParity": "none",
        "serialConnectionDelay": 100,
        "serialAsciiResponseStartDelimiter": "0x3A",
        "unit_id": points.slave,
        "commandDelay": points.gap_ms.max(1),
        "clientTimeout": points.timeout_ms,
        "reconnectOnTimeout": true,
        "reconnectTimeout": 2000,
        "parallelUnitIdsAllowed": true,
    });
    match &points.endpoint {
        Endpoint::Tcp {
            host,
            port,
            rtu_frames,
        } => {
            config["clienttype"] = json!("tcp");
            config["tcpHost"] = json!(host);
            config["tcpPort"] = json!(port);
            config["tcpType"] = json!(if *rtu_frames {
                "TCP-RTU-BUFFERED"
            } else {
                "DEFAULT"
            });
        }
        Endpoint::Serial {
            path,
            baud,
            parity,
            stop_bits,
        } => {
            config["clienttype"] = json!("simpleser");
            config["serialPort"] = json!(path);
            config["serialBaudrate"] = json!(baud);
            config["serialStopbits"] = json!(stop_bits);
            config["serialParity"] = json!(parity.name());
        }
    }
    nodes.push(config);
    for (i, read) in points.reads.iter().enumerate() {
        let y = 100 + 60 * i as i64;
        let reader = node_id(&format!("{base} read {i}"));
        let decoder = node_id(&format!("{base} decode {i}"));
        let ids: Vec<&str> = points.in_read(i).map(|p| p.id()).collect();
        nodes.push(json!({
            "id": reader,
            "type": "modbus-read",
            "z": tab,
            "name": format!(
                "{} {}..{}",
                read.table.key(),
                read.pdu,
                u32::from(read.pdu) + u32::from(read.quantity) - 1
            ),
            "topic": slug(&format!("{} {}", points.name, ids.join(" "))),
            "showStatusActivities": false,
            "logIOActivities": false,
            "showErrors": true,
            "unitid": points.slave.to_string(),
            "dataType": match read.table {
                Table::Holding => "HoldingRegister",
                Table::Input => "InputRegister",
                Table::Coil => "Coil",
                Table::DiscreteInput => "Input",
            },
            "adr": read.pdu.to_string(),
            "quantity": read.quantity.to_string(),
            "rate": points.period_ms.to_string(),
            "rateUnit": "ms",
            "delayOnStart": false,
            "startDelayTime": "",
            "server": client,
            "useIOFile": false,
            "ioFile": "",
            "useIOForPayload": false,
            "emptyMsgOnFail": false,
            "x": 200,
            "y": y,
            "wires": [[decoder], []],
        }));
        nodes.push(json!({
            "id": decoder,
            "type": "function",
            "z": tab,
            "name": format!("decode {}", ids.join(", ")),
            "func": function_body(points, i),
            "outputs": 1,
            "noerr": 0,
            "initialize": "",
            "finalize": "",
            "libs": [],
            "x": 480,
            "y": y,
            "wires": [[debug]],
        }));
    }
    nodes.push(json!({
        "id": debug,
        "type": "debug",
        "z": tab,
        "name": format!("{} values", points.name),
        "active": false,
        "tosidebar": true,
        "console": false,
        "tostatus": false,
        "complete": "true",
        "targetType": "full",
        "x": 760,
        "y": 100,
        "wires": [],
    }));
    Value::Array(nodes)
}
