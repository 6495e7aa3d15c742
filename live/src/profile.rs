//! The runtime [`Profile`] of a map loaded at run time.
//!
//! The client takes `&'static Profile` (generated code has statics). A tool that loads a map
//! makes one profile per drive for the life of the process, so leaking it is the honest
//! lifetime: [`leak_profile`] is called once per loaded map.

use drivemap_codegen::ir::{BroadcastUse, Drive};
use drivemap_codegen::model::{Access, CommandKind};
use drivemap_runtime::profile::{
    AddressOffsets, BroadcastInfo, CommandInfo, CommandKind as RtCommandKind, ExceptionInfo,
    Profile, Timing,
};
use drivemap_runtime::scale::RawRange;
use drivemap_runtime::{Access as RtAccess, Broadcast, Transports, WriteRule};

use crate::intern::intern as leak_str;

fn leak_slice<T>(v: Vec<T>) -> &'static [T] {
    Box::leak(v.into_boxed_slice())
}

/// Builds the runtime profile of `drive` with `'static` lifetime (see the module docs).
pub fn leak_profile(drive: &Drive) -> &'static Profile {
    let p = &drive.protocol;
    let broadcast = p.broadcast.as_ref().map(|b| BroadcastInfo {
        functions: leak_slice(b.functions.clone()),
        addresses: leak_slice(drive.broadcast_addresses()),
    });
    let exceptions = p
        .exceptions
        .iter()
        .map(|e| ExceptionInfo {
            code: e.code,
            name: leak_str(&e.name),
            description: leak_str(&e.description),
        })
        .collect();
    let commands = p
        .commands
        .iter()
        .map(|c| CommandInfo {
            id: leak_str(&c.id),
            name: leak_str(&c.name),
            kind: match c.kind {
                CommandKind::Accept => RtCommandKind::Accept,
                CommandKind::Persist => RtCommandKind::Persist,
            },
            writes: leak_slice(c.writes.iter().map(|w| (w.address, w.value)).collect()),
            source: leak_str(&c.source),
        })
        .collect();
    let writes = drive
        .registers
        .iter()
        .filter(|r| r.writable())
        .map(|r| {
            let w = drive.write_rule(r);
            WriteRule {
                register: leak_str(r.id()),
                access: match r.access {
                    Access::Read => RtAccess::Read,
                    Access::Write => RtAccess::Write,
                    Access::ReadWrite => RtAccess::ReadWrite,
                },
                broadcast: match w.broadcast {
                    BroadcastUse::No => Broadcast::No,
                    BroadcastUse::Also => Broadcast::Also,
                    BroadcastUse::Only => Broadcast::Only,
                },
                transports: Transports {
                    rtu: w.rtu,
                    tcp: w.tcp,
                },
                address: r.def.address,
                also_at: leak_slice(w.also_at),
                raw: RawRange {
                    min: w.raw.min as i64,
                    max: w.raw.max as i64,
                },
                reserved: w.reserved,
            }
        })
        .collect();
    let t = drive.timing_figures();
    let (rtu, tcp) = drive.address_offsets();
    let profile = Profile {
        drive_id: leak_str(&drive.meta.id),
        function_codes: leak_slice(p.function_codes.clone()),
        max_read: p.max_read,
        max_write: p.max_write,
        slave_min: p.slave_address.min,
        slave_max: p.slave_address.max,
        broadcast,
        exceptions: leak_slice(exceptions),
        commands: leak_slice(commands),
        address_offsets: AddressOffsets { rtu, tcp },
        timing: Timing {
            frame_gap_chars: t.frame_gap_chars,
            inter_char_timeout_us: t.inter_char_timeout_us,
            inter_char_timeout_bits: t.inter_char_timeout_bits,
            response_delay_us: t.response_delay_us,
            response_delay_bits: t.response_delay_bits,
            response_delay_param: t.response_delay_param.as_deref().map(leak_str),
            response_delay_param_default_us: t.response_delay_param_default_us,
            request_gap_bits: t.request_gap_bits,
            request_gap_us: t.request_gap_us,
            char_bits: t.char_bits,
        },
        eeprom_write_endurance: p.eeprom.as_ref().map(|e| e.endurance),
        writes: leak_slice(writes),
    };
    Box::leak(Box::new(profile))
}
