//! Shared test fixtures: a V7-like profile transcribed from the manual, and client helpers.
// Each test binary compiles this module and uses only the helpers it needs.
#![allow(dead_code)]

use std::time::Duration;

use drivemap_runtime::client::ClientOptions;
use drivemap_runtime::core::profile::{
    AddressOffsets, BroadcastInfo, CommandInfo, CommandKind, ExceptionInfo, Profile, Timing,
};

/// The V7 as `000_032dced3a1e91a75.txt` describes it: functions 03/06/08/10h (:290), 8 registers
/// per read (:327), 16 per write (:529), slaves 1-32 (:321), broadcast writes of 0001h/0002h
/// (Table 4.2, :882-892), error codes (Table 2-14, :587-593), ENTER/ACCEPT (Table 4.6,
/// :1508-1511).
pub static V7: Profile = Profile {
    drive_id: "yaskawa-v7",
    function_codes: &[0x03, 0x06, 0x08, 0x10],
    max_read: 8,
    max_write: 16,
    max_read_bits: drivemap_runtime::core::stated::MODBUS_MAX_READ_BITS,
    max_write_bits: drivemap_runtime::core::stated::MODBUS_MAX_WRITE_BITS,
    slave_min: 1,
    slave_max: 32,
    broadcast: Some(BroadcastInfo::new(&[0x06, 0x10], &[0x0001, 0x0002])),
    exceptions: &[
        ExceptionInfo {
            code: 0x01,
            name: "Function Error",
            description: "Invalid or unsupported function code in command message",
        },
        ExceptionInfo {
            code: 0x21,
            name: "Data Limits Exceeded",
            description: "The write command message data is out range for the requested register",
        },
        ExceptionInfo {
            code: 0x22,
            name: "Write Failure",
            description: "The register to be written is write protected",
        },
    ],
    commands: &[
        CommandInfo {
            id: "accept",
            name: "ACCEPT",
            kind: CommandKind::Accept,
            writes: &[(0x0910, 0)],
            source: "000_032dced3a1e91a75.txt:1510",
        },
        CommandInfo {
            id: "enter",
            name: "ENTER",
            kind: CommandKind::Persist,
            writes: &[(0x0900, 0)],
            source: "000_032dced3a1e91a75.txt:1511",
        },
    ],
    address_offsets: AddressOffsets { rtu: 0, tcp: 0 },
    timing: Timing {
        frame_gap_chars: 3.5,
        inter_char_timeout_us: Some(3500),
        inter_char_timeout_bits: None,
        response_delay_us: None,
        response_delay_param: Some("n156"),
        ..Timing::MODBUS
    },
    serial_formats: None,
    eeprom_write_endurance: Some(100_000),
    writes: &[],
    not_printed: &[],
};

/// The ACN's addressing: RTU PDU address = communication address - 1 (its example writes
/// 0x1102 to reach 0x1103, `004_c5cbf92472673495.txt:607-628`); functions 03/04/06/10h
/// (`:473-560`); exception 06h busy (`:580`); save by writing 0 then 1 to 0x03E0 (`:1030`).
pub static ACN: Profile = Profile {
    drive_id: "automationdirect-acn",
    function_codes: &[0x03, 0x04, 0x06, 0x10],
    max_read: 8,
    max_write: 8,
    max_read_bits: drivemap_runtime::core::stated::MODBUS_MAX_READ_BITS,
    max_write_bits: drivemap_runtime::core::stated::MODBUS_MAX_WRITE_BITS,
    slave_min: 1,
    slave_max: 250,
    broadcast: None,
    exceptions: &[ExceptionInfo {
        code: 0x06,
        name: "SLAVE DEVICE BUSY",
        description: "",
    }],
    commands: &[CommandInfo {
        id: "save_parameters",
        name: "Save parameters",
        kind: CommandKind::Persist,
        writes: &[(0x03E0, 0), (0x03E0, 1)],
        source: "004_c5cbf92472673495.txt:1030",
    }],
    address_offsets: AddressOffsets { rtu: -1, tcp: 0 },
    timing: Timing {
        frame_gap_chars: 3.5,
        inter_char_timeout_us: None,
        inter_char_timeout_bits: None,
        response_delay_us: None,
        response_delay_param: Some("CM.05"),
        ..Timing::MODBUS
    },
    serial_formats: None,
    eeprom_write_endurance: None,
    writes: &[],
    not_printed: &[],
};

/// The VS mini J7: no 06h (`003_8bcf5d50afb8e230.txt:226-231`).
pub static J7: Profile = Profile {
    drive_id: "yaskawa-j7",
    function_codes: &[0x03, 0x08, 0x10],
    ..V7
};

/// Short timeout, no retries: each fault shows as its own error.
pub fn strict() -> ClientOptions {
    ClientOptions {
        timeout: Duration::from_millis(100),
        retries: 0,
        ..ClientOptions::default()
    }
}
