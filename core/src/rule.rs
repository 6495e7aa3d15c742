//! What the map allows when writing one register: the data of the write gate. The gate itself
//! (`drivemap_runtime::gate`) checks requests against it.

use crate::functions::Functions;
use crate::profile::TransportKind;
use crate::register::{Access, Table};
use crate::scale::RawRange;
use crate::width::{Width, WordOrder};

/// The transports a register exists on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Transports {
    /// The drive's serial (RTU) side: serial lines, RTU over TCP, a Modbus TCP gateway to
    /// the serial line ([`TransportKind::TcpGateway`]), and Modbus ASCII.
    pub rtu: bool,
    /// The drive's own Modbus TCP interface (MBAP).
    pub tcp: bool,
}

impl Transports {
    /// Every transport.
    pub const ALL: Transports = Transports {
        rtu: true,
        tcp: true,
    };

    /// RTU framing only (serial lines, RTU over TCP).
    pub const RTU: Transports = Transports {
        rtu: true,
        tcp: false,
    };

    /// Modbus TCP only (the V7's CM091/CM092 option card registers).
    pub const TCP: Transports = Transports {
        rtu: false,
        tcp: true,
    };

    /// Whether a register with these transports exists on `kind`.
    pub const fn contains(self, kind: TransportKind) -> bool {
        if kind.reaches_rtu_side() {
            self.rtu
        } else {
            self.tcp
        }
    }
}

/// Whether a register may be written to slave 0 (broadcast).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Broadcast {
    /// An ordinary register. Where the drive lists the registers a broadcast may write
    /// ([`BroadcastInfo::addresses`](crate::profile::BroadcastInfo::addresses) not empty), it is
    /// not one of them; where the list is empty, any writable register may be broadcast.
    No,
    /// An ordinary register that the manual also lets a broadcast write (TDS-V8 0001h/0002h).
    Also,
    /// Only reachable as a broadcast, in the drive's broadcast address space with its own
    /// layout (V7 and GPD 515 broadcast registers 0001h/0002h).
    Only,
}

/// What the map allows when writing one register.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WriteRule {
    /// Register id in the map.
    pub register: &'static str,
    /// Access as the manual states it.
    pub access: Access,
    /// Whether the register may be written as a broadcast (slave 0).
    pub broadcast: Broadcast,
    /// Transports the register exists on.
    pub transports: Transports,
    /// The register's communication address as the manual prints it.
    pub address: u16,
    /// The addresses it moves to with a setting, a variant or the transport.
    pub also_at: &'static [u16],
    /// Raw values the map allows under some variant and selector case (a signed register's
    /// words are read as `i16`).
    pub raw: RawRange,
    /// Bits that must be 0 (reserved bits of a bit-field register).
    pub reserved: u16,
    /// One register, or a 32-bit pair that is only written whole, both words in one request.
    pub width: Width,
    /// The Modbus functions the register accepts ([`Functions::ANY`]: every function of the
    /// drive): the gate refuses a write with another, and a single word goes out with 06h or
    /// 10h as the register allows.
    pub functions: Functions,
    /// The table (address space) the register is in: holding registers are written with
    /// 06h/10h, coils with 05h/0Fh, and an address of one space never matches a rule of the
    /// other.
    pub table: Table,
}

impl WriteRule {
    /// A read/write register at `address` on every transport, no broadcast, no reserved bits,
    /// raw values `min ..= max`.
    pub const fn rw(register: &'static str, address: u16, min: i64, max: i64) -> WriteRule {
        WriteRule {
            register,
            access: Access::ReadWrite,
            broadcast: Broadcast::No,
            transports: Transports::ALL,
            address,
            also_at: &[],
            raw: RawRange { min, max },
            reserved: 0,
            width: Width::Word,
            functions: Functions::ANY,
            table: Table::Holding,
        }
    }

    /// [`WriteRule::rw`] for a write-only register.
    pub const fn write_only(register: &'static str, address: u16, min: i64, max: i64) -> WriteRule {
        WriteRule {
            access: Access::Write,
            ..WriteRule::rw(register, address, min, max)
        }
    }

    /// The rule with broadcast use `broadcast`.
    pub const fn broadcast(self, broadcast: Broadcast) -> WriteRule {
        WriteRule { broadcast, ..self }
    }

    /// The rule for a register that exists only on `transports`.
    pub const fn on(self, transports: Transports) -> WriteRule {
        WriteRule { transports, ..self }
    }

    /// The rule for a register that also occupies `addresses`.
    pub const fn also_at(self, also_at: &'static [u16]) -> WriteRule {
        WriteRule { also_at, ..self }
    }

    /// The rule with reserved bits `reserved`, which must be written as 0.
    pub const fn reserved(self, reserved: u16) -> WriteRule {
        WriteRule { reserved, ..self }
    }

    /// The rule for a register that accepts only `functions`.
    pub const fn functions(self, functions: Functions) -> WriteRule {
        WriteRule { functions, ..self }
    }

    /// The rule for a register of `table` (a coil: raw values 0 and 1).
    pub const fn in_table(self, table: Table) -> WriteRule {
        WriteRule { table, ..self }
    }

    /// The rule for a 32-bit pair whose words go in `order`.
    pub const fn pair(self, order: WordOrder) -> WriteRule {
        WriteRule {
            width: Width::Pair(order),
            ..self
        }
    }

    /// Whether the register starts at `address` (under some setting, variant or transport).
    pub fn occupies(&self, address: u16) -> bool {
        self.address == address || self.also_at.contains(&address)
    }
}

impl WriteRule {
    /// Where `address` falls in the register: `Some(0)` for its first (or only) word, `Some(1)`
    /// for the second word of a pair, `Some(i)` for a string's word `i`, `None` outside it.
    pub fn word_index(&self, address: u16) -> Option<u16> {
        if self.occupies(address) {
            return Some(0);
        }
        match self.width {
            Width::Pair(_) if self.occupies(address.wrapping_sub(1)) => Some(1),
            Width::Text(n) => (1..u16::from(n)).find(|&i| self.occupies(address.wrapping_sub(i))),
            _ => None,
        }
    }
}
