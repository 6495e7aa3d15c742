//! Which exception code the simulated drive answers for each rule it enforces, read from the
//! map's own exception list.
//!
//! The drives number their codes differently: a value out of range is 21h "Data Limits Exceeded"
//! on the V7 (`000_032dced3a1e91a75.txt:592`), 21h "Data setting error" on the J7 and GPD 515, but
//! 03h "Data Value Error" on the TDS-V8, whose 21h means "Device Busy"
//! (`002_661580cce154f322.txt:634-636`), and 03h "ILLEGAL DATA VALUE" on the ACN. So each rule
//! looks for the code whose printed name or description says it, and falls back to the Modbus
//! standard code when the map names none:
//!
//! | rule | code whose name/description mentions | fallback |
//! |---|---|---|
//! | unknown function | (01h on every drive) | 01h |
//! | unknown or write-only register | (02h on every drive) | 02h |
//! | bad quantity, malformed request | (03h on every drive) | 03h |
//! | value out of range | limit, range, data setting, data value, invalid data | 03h |
//! | write to a read-only register | write protect, write-in mode/error, write failure, write mode, disabled, read-only (not the range code) | 02h |
//! | write refused in this state (running, DRV mode) | the same | 03h |
//!
//! The fallbacks are choices where a manual is silent: a read-only register written is "not a
//! register that takes data" (02h, which the TDS-V8 describes as an invalid address "during
//! Retrieval / Writing"); a write refused because of the drive's state is a value the drive cannot
//! take now (03h). `sim/README.md` lists the resulting codes per drive.

use drivemap_runtime::core::profile::ExceptionInfo;

/// The exception code for each rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExceptionPlan {
    /// Function not implemented (or loop-back sub-function other than 0000h).
    pub illegal_function: u8,
    /// No readable/writable register at the address.
    pub illegal_address: u8,
    /// Quantity 0, above the drive's maximum, or a malformed request.
    pub illegal_quantity: u8,
    /// A value the register's range or code list refuses.
    pub out_of_range: u8,
    /// A write to a read-only register.
    pub read_only: u8,
    /// A write the drive refuses in its present state (running; TDS-V8 DRV mode).
    pub refused_now: u8,
}

const RANGE_WORDS: &[&str] = &[
    "limit",
    "range",
    "data setting",
    "data value",
    "invalid data",
];
const WRITE_WORDS: &[&str] = &[
    "write protect",
    "write-in mode",
    "write-in error",
    "write failure",
    "write mode",
    "write-mode",
    "disabled",
    "read-only",
];

fn find(exceptions: &[ExceptionInfo], words: &[&str], except: Option<u8>) -> Option<u8> {
    exceptions
        .iter()
        .filter(|e| Some(e.code) != except)
        .find(|e| {
            let text = format!("{} {}", e.name, e.description).to_ascii_lowercase();
            words.iter().any(|w| text.contains(w))
        })
        .map(|e| e.code)
}

impl ExceptionPlan {
    /// The plan for a drive's exception list (its profile's `exceptions`).
    pub fn from_exceptions(exceptions: &[ExceptionInfo]) -> ExceptionPlan {
        let range = find(exceptions, RANGE_WORDS, None);
        let write = find(exceptions, WRITE_WORDS, range);
        ExceptionPlan {
            illegal_function: 0x01,
            illegal_address: 0x02,
            illegal_quantity: 0x03,
            out_of_range: range.unwrap_or(0x03),
            read_only: write.unwrap_or(0x02),
            refused_now: write.unwrap_or(0x03),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(code: u8, name: &'static str, description: &'static str) -> ExceptionInfo {
        ExceptionInfo {
            code,
            name,
            description,
        }
    }

    #[test]
    fn yaskawa_style_codes_are_found_by_meaning() {
        let plan = ExceptionPlan::from_exceptions(&[
            code(
                0x01,
                "Function Error",
                "Invalid or unsupported function code",
            ),
            code(0x02, "Invalid Register", "Invalid register address"),
            code(
                0x03,
                "Invalid Number of Registers",
                "Invalid command message quantity",
            ),
            code(
                0x21,
                "Data Limits Exceeded",
                "out range for the requested register",
            ),
            code(
                0x22,
                "Write Failure",
                "The register to be written is write protected",
            ),
        ]);
        assert_eq!(
            (plan.out_of_range, plan.read_only, plan.refused_now),
            (0x21, 0x22, 0x22)
        );
    }

    #[test]
    fn a_busy_21h_is_not_mistaken_for_a_range_error() {
        let plan = ExceptionPlan::from_exceptions(&[
            code(
                0x03,
                "Data Value Error",
                "Invalid data during Read / Write of command",
            ),
            code(
                0x21,
                "Device Busy",
                "Handling task of the previous command, such as parameter change",
            ),
            code(0x22, "Device Fail", "EEPROM fail while writing data"),
        ]);
        assert_eq!(
            (plan.out_of_range, plan.read_only, plan.refused_now),
            (0x03, 0x02, 0x03)
        );
    }
}
