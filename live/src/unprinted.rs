//! Warnings for the protocol facts a tool relies on although the drive's manual does not print
//! them (the map's `unknown:`): each names the fact, the map's reason and the figure used in
//! its place, so that an operator knows which settings rest on the Modbus defaults rather than
//! on the manual.

use drivemap_map::Map;
use drivemap_runtime::core::stated::{MODBUS_SLAVE_MAX, MODBUS_SLAVE_MIN, ProtocolFact};

use crate::link::Link;
use drivemap_runtime::core::profile::Parity;

/// The warnings for `facts` that `drive`'s map marks not printed, as the command using `link`
/// relies on them: the serial settings only on a serial line, and only those not given on the
/// command line; a limit only where the Modbus one stands in for it; the slave range when
/// `slaves_scanned` is the Modbus range the scan then tries.
pub fn warnings(
    drive: &Map,
    link: &Link,
    facts: &[ProtocolFact],
    slaves_scanned: Option<&[u8]>,
) -> Vec<String> {
    let p = drive.protocol();
    let id = &drive.id();
    let mut out = Vec::new();
    for &fact in facts {
        let Some(u) = drive.not_printed_why(fact) else {
            continue;
        };
        let used = match fact {
            ProtocolFact::Serial => {
                if link.serial.is_none() {
                    continue;
                }
                let (baud, parity, stop) = link.line(drive);
                let mut defaulted = Vec::new();
                if link.baud.is_none() {
                    defaulted.push(format!("{baud} baud"));
                }
                if link.parity.is_none() {
                    defaulted.push(format!(
                        "parity {}",
                        match parity {
                            Parity::None => "none",
                            Parity::Even => "even",
                            Parity::Odd => "odd",
                        }
                    ));
                }
                if link.stop_bits.is_none() {
                    defaulted.push(format!("{stop} stop bit(s)"));
                }
                if defaulted.is_empty() {
                    continue;
                }
                format!(
                    "using {}, the runtime's defaults (set the line with --baud, --parity, --stop-bits)",
                    defaulted.join(", ")
                )
            }
            ProtocolFact::MaxRead => match p.max_read.value {
                Some(_) => continue,
                None => format!(
                    "reading up to {} registers per request, the Modbus limit",
                    p.max_read()
                ),
            },
            ProtocolFact::MaxWrite => match p.max_write.value {
                Some(_) => continue,
                None => format!(
                    "writing up to {} registers per request, the Modbus limit",
                    p.max_write()
                ),
            },
            ProtocolFact::SlaveAddress => match slaves_scanned {
                Some(s)
                    if s.first() == Some(&MODBUS_SLAVE_MIN)
                        && s.last() == Some(&MODBUS_SLAVE_MAX)
                        && s.len() == usize::from(MODBUS_SLAVE_MAX) =>
                {
                    format!(
                        "scanning {MODBUS_SLAVE_MIN}-{MODBUS_SLAVE_MAX}, the Modbus unicast range"
                    )
                }
                Some(_) => continue,
                None => format!(
                    "accepting {MODBUS_SLAVE_MIN}-{MODBUS_SLAVE_MAX}, the Modbus unicast range"
                ),
            },
            other => format!("using {}", other.fallback()),
        };
        let src = u.source.map(|s| format!(" ({s})")).unwrap_or_default();
        out.push(format!(
            "warning: {id}: {} not printed in the manual: {}{src}; {used}",
            fact.name(),
            u.why
        ));
    }
    out
}
