//! The Modbus functions one register accepts, where the manual restricts them below the drive's
//! list (`function_codes:` on a register or its group in the map): a drive that accepts 10h
//! (write multiple) only on its first registers, a register writable only with 06h, a monitor
//! area answering only 04h.
//!
//! Decided once by the map's lowering pass and carried by the register's plan
//! (the `functions` of [`RegisterPlan`](crate::plan::RegisterPlan)) and its write rule (the
//! `functions` of [`WriteRule`](crate::rule::WriteRule)): the write gate refuses a
//! function the register does not accept, a single word goes out with 06h or 10h as the register
//! allows, the read planner never bridges a read over a register that refuses the read function,
//! and the simulator answers such a request with [`Functions::refused_with`].

/// Read coils.
pub const READ_COILS: u8 = 0x01;
/// Read discrete inputs.
pub const READ_DISCRETE_INPUTS: u8 = 0x02;
/// Write single coil (FF00h on, 0000h off).
pub const WRITE_COIL: u8 = 0x05;
/// Write multiple coils.
pub const WRITE_COILS: u8 = 0x0F;
/// Read holding registers.
pub const READ_HOLDING: u8 = 0x03;
/// Read input registers.
pub const READ_INPUT: u8 = 0x04;
/// Write single register.
pub const WRITE_SINGLE: u8 = 0x06;
/// Write multiple registers.
pub const WRITE_MULTIPLE: u8 = 0x10;

/// The functions a register accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Functions {
    /// The function codes the register accepts, a subset of the drive's list; empty: every
    /// function the drive implements ([`Functions::ANY`]).
    pub codes: &'static [u8],
    /// The exception code the drive answers another function on this register with: 01h
    /// (illegal function, the default) or 02h (illegal data address).
    pub refused_with: u8,
    /// `file:line` of the manual's statement (`""` for [`Functions::ANY`]).
    pub source: &'static str,
}

impl Functions {
    /// No restriction: the register accepts every function the drive implements.
    pub const ANY: Functions = Functions {
        codes: &[],
        refused_with: 0x01,
        source: "",
    };

    /// A register accepting only `codes`.
    pub const fn only(codes: &'static [u8], refused_with: u8, source: &'static str) -> Functions {
        Functions {
            codes,
            refused_with,
            source,
        }
    }

    /// Whether the map restricts the register's functions at all.
    pub const fn restricted(&self) -> bool {
        !self.codes.is_empty()
    }

    /// Whether the register accepts `function` (always, without a restriction; the drive's own
    /// list is checked apart).
    pub fn allows(&self, function: u8) -> bool {
        self.codes.is_empty() || self.codes.contains(&function)
    }
}

impl Default for Functions {
    fn default() -> Functions {
        Functions::ANY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_allows_every_function_and_a_restriction_only_its_codes() {
        assert!(Functions::ANY.allows(WRITE_MULTIPLE));
        assert!(!Functions::ANY.restricted());
        let f = Functions::only(&[READ_HOLDING, WRITE_SINGLE], 0x02, "m.txt:3");
        assert!(f.restricted());
        assert!(f.allows(WRITE_SINGLE));
        assert!(!f.allows(WRITE_MULTIPLE));
        assert!(!f.allows(READ_INPUT));
    }
}
