//! Exception responses: the drive's own code, named from its profile.
//!
//! The drives reuse codes that the Modbus specification leaves free or defines otherwise: 21h is
//! "data setting error" on the Yaskawa drives (`000_032dced3a1e91a75.txt:592`) but "device busy"
//! on the TDS-V8 (`002_661580cce154f322.txt:636`), and the TDS-V8 answers 04h for a CRC error
//! (`002_661580cce154f322.txt:635`). The code is always kept as received; its name comes from the
//! drive's [`Profile`] when the manual defines it, and from the Modbus specification otherwise.

use ::core::fmt;

use drivemap_core::profile::Profile;

/// The Modbus specification's name and meaning of a standard exception code.
pub fn standard(code: u8) -> Option<(&'static str, &'static str)> {
    Some(match code {
        0x01 => (
            "Illegal function",
            "the function code is not supported by the device",
        ),
        0x02 => (
            "Illegal data address",
            "the register address is not valid in the device",
        ),
        0x03 => (
            "Illegal data value",
            "a value in the request is not acceptable (often the quantity)",
        ),
        0x04 => (
            "Server device failure",
            "an unrecoverable error occurred while performing the request",
        ),
        0x05 => (
            "Acknowledge",
            "the request was accepted but needs a long time to complete",
        ),
        0x06 => (
            "Server device busy",
            "the device is processing a long command; retry later",
        ),
        0x08 => (
            "Memory parity error",
            "the device detected a parity error in its memory",
        ),
        0x0A => (
            "Gateway path unavailable",
            "the gateway could not allocate a path to the target",
        ),
        0x0B => (
            "Gateway target device failed to respond",
            "no response was obtained from the target device",
        ),
        _ => return None,
    })
}

/// An exception response as received, with the meaning the drive's manual gives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Exception {
    /// The function code of the request (without the 80h bit).
    pub function: u8,
    /// The exception code exactly as received.
    pub code: u8,
    /// Name of the code: from the drive's profile, or the Modbus standard name.
    pub name: &'static str,
    /// What the code means.
    pub description: &'static str,
    /// Whether the name comes from the drive's manual rather than the Modbus specification.
    pub from_profile: bool,
}

impl Exception {
    /// Names `code` from `profile`, falling back to the Modbus standard names.
    pub fn new(profile: &Profile, function: u8, code: u8) -> Exception {
        if let Some(info) = profile.exception(code) {
            return Exception {
                function,
                code,
                name: info.name,
                description: info.description,
                from_profile: true,
            };
        }
        let (name, description) = standard(code).unwrap_or((
            "Unknown exception",
            "neither the drive's manual nor the Modbus specification defines this code",
        ));
        Exception {
            function,
            code,
            name,
            description,
            from_profile: false,
        }
    }

    /// Whether the drive says it is busy and the request may succeed if repeated later
    /// (standard 06h, or a code the drive's manual names "busy", such as the TDS-V8's 21h).
    pub fn is_busy(&self) -> bool {
        if self.from_profile {
            // "busy", "Busy", "BUSY" anywhere in the name, without allocating.
            self.name
                .as_bytes()
                .windows(4)
                .any(|w| w.eq_ignore_ascii_case(b"busy"))
        } else {
            self.code == 0x06
        }
    }
}

impl fmt::Display for Exception {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "exception {:02X}h ({}", self.code, self.name)?;
        if !self.description.is_empty() {
            write!(f, ": {}", self.description)?;
        }
        if !self.from_profile {
            write!(f, "; Modbus standard meaning")?;
        }
        write!(f, ")")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivemap_core::profile::ExceptionInfo;

    static TDS: Profile = Profile {
        drive_id: "tds",
        exceptions: &[
            ExceptionInfo {
                code: 0x04,
                name: "CRC_16 Error",
                description: "CRC reception differs from calculated CRC",
            },
            ExceptionInfo {
                code: 0x21,
                name: "Device Busy",
                description: "Handling task of the previous command",
            },
        ],
        ..Profile::GENERIC
    };

    #[test]
    fn drive_codes_are_kept_and_named_from_the_profile() {
        let e = Exception::new(&TDS, 0x06, 0x21);
        assert_eq!(
            (e.code, e.name, e.from_profile),
            (0x21, "Device Busy", true)
        );
        assert!(e.is_busy());
        let e = Exception::new(&TDS, 0x03, 0x04);
        assert_eq!(e.name, "CRC_16 Error");
        assert!(!e.is_busy());
    }

    #[test]
    fn standard_names_are_the_fallback() {
        let e = Exception::new(&Profile::GENERIC, 0x03, 0x02);
        assert_eq!(e.name, "Illegal data address");
        assert!(!e.from_profile);
        let e = Exception::new(&Profile::GENERIC, 0x06, 0x21);
        assert_eq!((e.code, e.name), (0x21, "Unknown exception"));
        assert!(Exception::new(&Profile::GENERIC, 0x03, 0x06).is_busy());
        assert!(e.to_string().contains("21h"));
    }
}
