//! Static exports for pollers a plant already runs (`drivemap export --format home-assistant |
//! node-red | telegraf`): the [`Point`]s of a drive placed on one link.
//!
//! [`Export::build`] decides, once for every format, what each chosen register is on the wire
//! (table, PDU address on the link, 16 or 32 bits, word order, signedness) and what its value
//! means (a fixed scale, a code, bit fields), and which reads the runtime's planner makes of
//! them. A register none of these tools can read as the map means it (a scale that another
//! parameter selects and no `--set` fixed, an address that moves with a setting) is kept in
//! [`Export::left_out`] with the reason, which every format prints: nothing is dropped silently.

use drivemap_live::link::Link;
use drivemap_live::session::{on_transport, rows_on_link, value_error};
use drivemap_live::{LiveSettings, leak_profile};
use drivemap_map::{Map, RegisterRef};
use drivemap_runtime::bus_time::BusModel;
use drivemap_runtime::core::plan::{RegisterPlan, SettingsView, ValueShape};
use drivemap_runtime::core::profile::{Parity, TransportKind};
use drivemap_runtime::core::register::Table;
use drivemap_runtime::planner::Poller;

use super::{At, Fixed, Meaning, Point};
use crate::error::ExportError;

/// One read request of the plan, in PDU addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlannedRead {
    /// Holding or input.
    pub table: Table,
    /// The first PDU address read.
    pub pdu: u16,
    /// How many registers it reads.
    pub quantity: u16,
}

/// Where the drive is, as the tools configure a connection.
#[derive(Debug, Clone, PartialEq)]
pub enum Endpoint {
    /// `host`, `port` over TCP: Modbus TCP frames (`--tcp`, `--gateway`) or RTU frames
    /// (`--rtu-tcp`).
    Tcp {
        /// Host name or IP address (an IPv6 address without brackets).
        host: String,
        /// TCP port.
        port: u16,
        /// RTU frames over TCP (a transparent serial gateway) rather than Modbus TCP.
        rtu_frames: bool,
    },
    /// A serial port speaking RTU.
    Serial {
        /// The port's path.
        path: String,
        /// Baud rate.
        baud: u32,
        /// Parity.
        parity: Parity,
        /// Stop bits.
        stop_bits: u8,
    },
}

/// The chosen registers of a drive on one link, ready for a tool.
#[derive(Debug)]
pub struct Export<'d> {
    /// The drive.
    pub drive: &'d Map,
    /// The link's transport.
    pub kind: TransportKind,
    /// Where the tool connects.
    pub endpoint: Endpoint,
    /// The drive's slave address.
    pub slave: u8,
    /// Reply timeout in milliseconds (the client's default for the map and line).
    pub timeout_ms: u64,
    /// Least pause between requests in milliseconds (the map's request gap on RTU links).
    pub gap_ms: u64,
    /// Poll period in milliseconds.
    pub period_ms: u64,
    /// A name for the hub, entities and measurements (`--name`, default the drive id).
    pub name: String,
    /// The registers a tool reads, each placed on the link ([`Point::at`]).
    pub points: Vec<Point<'d>>,
    /// Registers asked for that no tool can read as the map means them, with the reason.
    pub left_out: Vec<(RegisterRef<'d>, String)>,
    /// The planner's requests, ascending per table.
    pub reads: Vec<PlannedRead>,
    /// Modelled bus time of one cycle of `reads`, in microseconds.
    pub cycle_us: u64,
}

fn split_host(addr: &str) -> Result<(String, u16), ExportError> {
    let (host, port) = addr
        .rsplit_once(':')
        .ok_or_else(|| ExportError::NotHostPort {
            addr: addr.to_owned(),
        })?;
    let port = port.parse::<u16>().map_err(|_| ExportError::NotPort {
        addr: addr.to_owned(),
        port: port.to_owned(),
    })?;
    let host = host.trim_start_matches('[').trim_end_matches(']');
    if host.is_empty() {
        return Err(ExportError::NoHost {
            addr: addr.to_owned(),
        });
    }
    Ok((host.to_owned(), port))
}

/// The registers exported when none are named: those the map's roles name and every
/// read-only register (monitors and status words).
pub fn default_registers(map: &Map) -> Vec<RegisterRef<'_>> {
    let mut named: Vec<&str> = Vec::new();
    for places in map.roles().values() {
        for p in places {
            if let Some(r) = &p.register {
                named.push(r.as_str());
            }
        }
    }
    map.registers()
        .filter(|r| r.readable())
        .filter(|r| !r.writable() || named.iter().any(|n| r.id() == *n || r.param() == Some(n)))
        .collect()
}

impl<'d> Export<'d> {
    /// Decides every register of `regs` on `link` under `settings` and plans their reads.
    pub fn build(
        drive: &'d Map,
        regs: &[RegisterRef<'d>],
        link: &Link,
        settings: &LiveSettings,
        period_ms: u64,
        name: Option<&str>,
    ) -> Result<Export<'d>, ExportError> {
        link.check_transport(drive)?;
        let kind = link.kind();
        let endpoint = if let Some(a) = link.tcp.as_ref().or(link.gateway.as_ref()) {
            let (host, port) = split_host(a)?;
            Endpoint::Tcp {
                host,
                port,
                rtu_frames: false,
            }
        } else if let Some(a) = &link.rtu_tcp {
            let (host, port) = split_host(a)?;
            Endpoint::Tcp {
                host,
                port,
                rtu_frames: true,
            }
        } else if let Some(path) = &link.serial {
            let (baud, parity, stop_bits) = link.line(drive);
            Endpoint::Serial {
                path: path.clone(),
                baud,
                parity,
                stop_bits,
            }
        } else {
            return Err(ExportError::NoLink);
        };
        let profile = leak_profile(drive);
        let options = link.client_options(drive, profile);
        let view = settings.view(drive);
        let offsets = profile.address_offsets;

        let mut points = Vec::new();
        let mut left_out = Vec::new();
        let mut wanted = Vec::new();
        for &r in regs {
            let plan = r.plan();
            let why = if r.broadcast_only() {
                Some("broadcast-only: written to slave 0, never read".to_owned())
            } else if !r.readable() {
                Some("write-only: the drive does not let it be read".to_owned())
            } else if !on_transport(drive, r, kind) {
                Some(format!("does not exist on this link ({})", kind.name()))
            } else {
                None
            };
            if let Some(why) = why {
                left_out.push((r, why));
                continue;
            }
            let address = match plan.locate(&view, kind) {
                Ok(a) => a,
                Err(e) => {
                    left_out.push((
                        r,
                        format!(
                            "its address moves with {}, which a tool does not read first; give the drive's value with --set {}=<value>",
                            e.setting, e.setting
                        ),
                    ));
                    continue;
                }
            };
            let Some(pdu) = offsets.pdu_address(address, kind) else {
                left_out.push((r, "its address is outside 0..=FFFFh on this link".into()));
                continue;
            };
            let meaning = match plan.scale(&view) {
                _ if plan.info.table.is_bits() => Meaning::Bit,
                Some(Err(e)) => {
                    left_out.push((
                        r,
                        format!(
                            "its scale depends on another parameter, which a tool does not read first ({})",
                            value_error(drive, &e)
                        ),
                    ));
                    continue;
                }
                Some(Ok(scale)) => Meaning::Number(Some(Fixed {
                    // One count as the nearest `f64` (1/60 Hz for a ratio of 3600 = 60.0 Hz);
                    // the target shows `decimals` of it (six when not a decimal).
                    factor: scale.step(),
                    precision: scale.decimals(),
                    given: given(plan, &view),
                })),
                None => match plan.conversion.shape() {
                    ValueShape::Codes(values) => Meaning::Code(if plan.read_values.is_empty() {
                        values
                    } else {
                        plan.read_values
                    }),
                    ValueShape::Bits { fields, .. } => Meaning::Bits(fields),
                    ValueShape::Text { order } => Meaning::Text(order),
                    // A number always has a scale (`RegisterPlan::scale`).
                    ValueShape::Word { .. } | ValueShape::Number => Meaning::Word,
                },
            };
            wanted.push((plan.info.table, address));
            points.push((
                Point {
                    register: r,
                    plan,
                    slot: points.len(),
                    role: if plan.info.table.is_bits() {
                        super::bit_role(drive, r, kind)
                    } else {
                        super::register_role(drive, r, kind)
                    },
                    meaning,
                    at: Some(At { pdu, read: 0 }),
                },
                address,
            ));
        }

        // The planner's reads over the registers this link can read at the addresses these
        // settings put them (a register whose address is not known is not bridged over).
        // Plans, not bare infos: the planner respects each register's `function_codes`.
        let infos = rows_on_link(drive, kind, |r| r.plan().locate(&view, kind).ok());
        let model = BusModel::new(profile, link.bus_line(drive));
        let poller = Poller::new(profile, &infos, wanted)
            .map_err(ExportError::Plan)?
            .with_model(model);
        let mut reads = Vec::new();
        for (table, read) in poller.plan() {
            let pdu = offsets
                .pdu_address(read.address, kind)
                .ok_or(ExportError::ReadOutside {
                    address: read.address,
                })?;
            reads.push(PlannedRead {
                table,
                pdu,
                quantity: read.quantity,
            });
        }
        let cycle_us = poller.plan_ns() / 1000;
        let mut placed = Vec::with_capacity(points.len());
        for (mut p, address) in points {
            let pdu = p.pdu();
            let read = reads
                .iter()
                .position(|q| {
                    q.table == p.table()
                        && pdu >= q.pdu
                        && u32::from(pdu) + u32::from(p.width().count())
                            <= u32::from(q.pdu) + u32::from(q.quantity)
                })
                .ok_or_else(|| ExportError::NotCovered {
                    register: p.id().to_owned(),
                    address,
                })?;
            p.at = Some(At { pdu, read });
            placed.push(p);
        }
        Ok(Export {
            drive,
            kind,
            endpoint,
            slave: link.slave(drive),
            timeout_ms: options.timeout.as_millis() as u64,
            gap_ms: options.request_gap.as_micros().div_ceil(1000) as u64,
            period_ms,
            name: name.unwrap_or(drive.id()).to_owned(),
            points: placed,
            left_out,
            reads,
            cycle_us,
        })
    }

    /// The points of read `i`, in address order.
    pub fn in_read(&self, i: usize) -> impl Iterator<Item = &Point<'d>> {
        self.points.iter().filter(move |p| p.read() == i)
    }

    /// One line per register left out, for a tool's comments.
    pub fn left_out_lines(&self) -> Vec<String> {
        self.left_out
            .iter()
            .map(|(r, why)| format!("left out {}: {why}", r.label()))
            .collect()
    }

    /// A sentence on what the export covers, for headers.
    pub fn summary(&self) -> String {
        format!(
            "{} ({} {}) slave {} over {}: {} register(s) in {} planned read(s), {:.1} ms of bus time per cycle (drivemap's bus-time model); {} left out",
            self.drive.id(),
            self.drive.meta().vendor,
            self.drive.meta().models.join(" / "),
            self.slave,
            self.kind.name(),
            self.points.len(),
            self.reads.len(),
            self.cycle_us as f64 / 1000.0,
            self.left_out.len()
        )
    }
}

/// The comments every export writes per point: a scale that holds only for the settings given
/// (`--set`), and what the tool shows of a bit-field register (`bits`) or a code register
/// (`codes`) instead of its meanings.
pub fn write_point_caveats(out: &mut String, points: &Export, bits: &str, codes: &str) {
    use std::fmt::Write as _;
    for p in &points.points {
        if let Meaning::Number(Some(Fixed { given, .. })) = &p.meaning
            && !given.is_empty()
        {
            let _ = writeln!(
                out,
                "# {}: its scale holds for {given}; export again if the drive's setting changes.",
                p.id()
            );
        }
        if let Some(m) = meanings_text(p) {
            let what = match p.meaning {
                Meaning::Bits(_) => bits,
                _ => codes,
            };
            let _ = writeln!(out, "# {}: {what}; {m}", p.id());
        }
    }
}

/// What a tool cannot show of a code or bit-field register, for comments.
pub fn meanings_text(p: &Point) -> Option<String> {
    match &p.meaning {
        Meaning::Code(labels) if !labels.is_empty() => Some(format!(
            "codes {}",
            labels
                .iter()
                .map(|l| format!("{} = {}", l.code, l.name))
                .collect::<Vec<_>>()
                .join(", ")
        )),
        Meaning::Bits(fields) => Some(format!(
            "fields {}",
            fields
                .iter()
                .map(|f| {
                    if f.width == 1 {
                        format!("bit {} {}", f.lsb, f.id)
                    } else {
                        format!("bits {}-{} {}", f.lsb, f.lsb + f.width - 1, f.id)
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        )),
        _ => None,
    }
}

/// The settings a fixed scale was fixed with, as the formats note them: `n152 as given with
/// --set`, `, and n011` for the quantity the selected case refers to; empty where the scale
/// reads no setting.
fn given(plan: &RegisterPlan, settings: &impl SettingsView) -> String {
    let mut labels: Vec<&str> = Vec::new();
    plan.conversion.depends_on(settings, |d| {
        let label = d.setting().label;
        if !labels.contains(&label) {
            labels.push(label);
        }
    });
    let Some((first, rest)) = labels.split_first() else {
        return String::new();
    };
    let mut given = format!("{first} as given with --set");
    for label in rest {
        given = format!("{given}, and {label}");
    }
    given
}

#[cfg(test)]
mod tests {
    use drivemap_runtime::core::plan::{Case, CaseScale, Conversion, Ranges, Relative, Setting};
    use drivemap_runtime::core::register::RegisterInfo;
    use drivemap_runtime::core::scale::{Decimal, RawRange};

    use super::*;

    const SELECTOR: Setting = Setting {
        slot: 0,
        label: "n152",
    };

    fn plan(conversion: Conversion) -> RegisterPlan {
        let info = RegisterInfo {
            id: "current",
            name: "Current",
            ..RegisterInfo::DEFAULT
        };
        RegisterPlan::new(info, "A", conversion, RawRange::word(false))
    }

    struct Code(u16);

    impl SettingsView for Code {
        fn code(&self, _: u8) -> Option<u16> {
            Some(self.0)
        }
        fn quantity(&self, _: u8) -> Option<f64> {
            Some(50.0)
        }
        fn variant(&self, _: u8) -> u8 {
            0
        }
    }

    /// The settings a fixed scale names: the selector, then the quantity of the case in force
    /// when it is another setting; the reference of a relative scale; none for a decimal.
    #[test]
    fn a_fixed_scale_names_the_settings_given() {
        let relative = |label| {
            CaseScale::Relative(Relative {
                full_scale: 30000.0,
                reference: Setting { slot: 1, label },
            })
        };
        let cases: &'static [Case] = Box::leak(Box::new([
            Case {
                codes: &[0],
                scale: CaseScale::Decimal {
                    scale: Decimal::new(1, 1),
                    range: RawRange::word(false),
                },
            },
            Case {
                codes: &[1],
                scale: relative("n011"),
            },
            Case {
                codes: &[2],
                scale: relative("n152"),
            },
        ]));
        let selected = plan(Conversion::Selected {
            signed: false,
            selector: SELECTOR,
            cases,
        });
        assert_eq!(given(&selected, &Code(0)), "n152 as given with --set");
        assert_eq!(
            given(&selected, &Code(1)),
            "n152 as given with --set, and n011"
        );
        assert_eq!(given(&selected, &Code(2)), "n152 as given with --set");
        let relative = plan(Conversion::Relative {
            signed: false,
            relative: Relative {
                full_scale: 30000.0,
                reference: Setting {
                    slot: 1,
                    label: "Cn-02",
                },
            },
        });
        assert_eq!(given(&relative, &Code(0)), "Cn-02 as given with --set");
        let decimal = plan(Conversion::Decimal {
            signed: false,
            scale: Decimal::new(1, 2),
            range: Ranges::fixed(RawRange::word(false)),
        });
        assert_eq!(given(&decimal, &Code(0)), "");
    }
}
