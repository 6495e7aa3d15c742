//! How long a Modbus RTU transaction occupies a serial line, from the drive's [`Profile`] and
//! the line's serial settings.
//!
//! A read planner needs a cost per request, and on a 9600-baud RS-485 line the cost is bus time,
//! not CPU time. One transaction is modelled as four terms, in this order on the wire:
//!
//! | term | what | source |
//! |---|---|---|
//! | request | request bytes × character time | byte counts per function code below |
//! | latency | from the last request byte to the first reply byte: the larger of the frame gap and the drive's own response time | V7/J7: 24 bits + n156/n73 (`003_8bcf5d50afb8e230.txt:282`); ACN: CM.05 (`004_c5cbf92472673495.txt:231`, `:266-278`); TDS-V8: "after 5ms" (`002_661580cce154f322.txt:158`) |
//! | response | reply bytes × character time (none for a broadcast) | byte counts below |
//! | turnaround | from the last reply byte to the next request: the larger of the frame gap and the master's wait the manual prescribes | V7/J7: 24 bits + 10 ms (`003_8bcf5d50afb8e230.txt:284`) |
//!
//! The frame gap is [`Timing::frame_gap_chars`](drivemap_core::profile::Timing::frame_gap_chars)
//! characters (3.5 on every map; the manuals defer to the Modbus RTU rule), or a fixed 1.75 ms
//! above 19 200 baud (Modbus over Serial Line V1.02, 2.5.1.1), as the serial transport keeps it.
//!
//! **Character length.** A character is 1 start bit, 8 data bits, the parity bit if any, and the
//! stop bits: 10 bits for 8N1, 11 for 8E1, 8O1 and 8N2. Where a map fixes the character length
//! whatever the parity (TDS-V8: always 11 bits, a second stop bit taking the parity slot,
//! `002_661580cce154f322.txt:81`, `:91`; the map's `serial.char_bits`), [`BusModel::new`] takes
//! it from the profile unless [`SerialConfig::fixed_char_bits`] says otherwise. The serial transport times its silences with the same
//! characters (`SerialOptions::frame_gap`), so the model is the physical lower bound that the
//! planner optimises for and the client keeps.
//!
//! **Byte counts** (RTU: slave address, function, data, CRC-16; `000_032dced3a1e91a75.txt:296-302`
//! Table 2.1, `003_8bcf5d50afb8e230.txt:290-300` Table 7.1, `002_661580cce154f322.txt:163-170`):
//!
//! | function | request | normal reply |
//! |---|---|---|
//! | 03h / 04h read `n` registers | 8 | 5 + 2`n` |
//! | 06h write one register | 8 | 8 |
//! | 08h loop-back | 8 | 8 |
//! | 10h write `n` registers | 9 + 2`n` | 8 |
//! | any, exception reply | — | 5 |
//!
//! **Response time.** Where the profile names a response-delay parameter (V7 n156, J7 n73, ACN
//! CM.05) the delay is the value configured in the drive: give it with
//! [`BusModel::with_delay_param`]; otherwise the parameter's default from the map
//! ([`Timing::response_delay_param_default_us`](drivemap_core::profile::Timing::response_delay_param_default_us))
//! is assumed, or none where the map prints no default. Where the profile states a fixed response time
//! ([`Timing::response_delay_us`](drivemap_core::profile::Timing::response_delay_us), TDS-V8 5 ms) it is
//! used. The V7/J7 "24 bits" before the delay and the master's "24 bits + 10 ms" after a reply
//! come from the map's `timing.response_time` and `timing.request_gap`. A drive
//! whose manual prints nothing (GPD 515: it defers to PI-MBUS-300, `001_ef66da56d29a05af.txt:1-3`)
//! is modelled with the frame gap alone, a lower bound.

use std::time::Duration;

use crate::error::Refusal;
use crate::pdu::function;
use drivemap_core::profile::{Parity, Profile};

/// The settings of a serial line that decide the length of a character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SerialConfig {
    /// Bits per second.
    pub baud: u32,
    /// Data bits per character (8 for Modbus RTU).
    pub data_bits: u8,
    /// Parity.
    pub parity: Parity,
    /// Stop bits (1 or 2).
    pub stop_bits: u8,
    /// Bits per character when the drive fixes it whatever the parity (TDS-V8: 11).
    pub char_bits: Option<u8>,
}

impl SerialConfig {
    /// 8 data bits, no parity, 1 stop bit at `baud`.
    pub const fn new(baud: u32) -> SerialConfig {
        SerialConfig {
            baud,
            data_bits: 8,
            parity: Parity::None,
            stop_bits: 1,
            char_bits: None,
        }
    }

    /// Sets the parity.
    pub const fn parity(mut self, parity: Parity) -> SerialConfig {
        self.parity = parity;
        self
    }

    /// Sets the number of stop bits.
    pub const fn stop_bits(mut self, stop_bits: u8) -> SerialConfig {
        self.stop_bits = stop_bits;
        self
    }

    /// Fixes the character length whatever the parity, as a map's `serial.char_bits` does.
    pub const fn fixed_char_bits(mut self, bits: u8) -> SerialConfig {
        self.char_bits = Some(bits);
        self
    }

    /// The line to a drive with `profile` at `baud` and `parity`: `stop_bits` as given, else
    /// the stop bits of the map's formats for that parity when they have only one (the map's
    /// `serial.formats`), else 1 (2 without parity where the map fixes 11-bit characters);
    /// refused when the map lists its formats and this is not one of them.
    pub fn for_profile(
        profile: &Profile,
        baud: u32,
        parity: Parity,
        stop_bits: Option<u8>,
    ) -> Result<SerialConfig, Refusal> {
        let stop_bits = stop_bits
            .or_else(|| profile.serial_formats.and_then(|f| f.stop_bits_for(parity)))
            .unwrap_or(
                if profile.timing.char_bits == Some(11) && parity == Parity::None {
                    2
                } else {
                    1
                },
            );
        let config = SerialConfig {
            char_bits: profile.timing.char_bits,
            ..SerialConfig::new(baud).parity(parity).stop_bits(stop_bits)
        };
        config.check_format(profile)?;
        Ok(config)
    }

    /// Refuses a line whose data bits, parity and stop bits are not one of the formats the
    /// map lists for the drive (`Profile::serial_formats`); any line passes when it lists none.
    pub fn check_format(&self, profile: &Profile) -> Result<(), Refusal> {
        match profile.serial_formats {
            Some(f) => f
                .check(
                    profile.drive_id,
                    self.data_bits,
                    self.parity,
                    self.stop_bits,
                )
                .map(|_| ())
                .map_err(Refusal::SerialFormat),
            None => Ok(()),
        }
    }

    /// Bits per character on the wire: start, data, parity, stop; or the fixed length.
    pub const fn bits_per_char(&self) -> u32 {
        if let Some(bits) = self.char_bits {
            return bits as u32;
        }
        let parity = match self.parity {
            Parity::None => 0,
            Parity::Even | Parity::Odd => 1,
        };
        1 + self.data_bits as u32 + parity + self.stop_bits as u32
    }

    /// The duration of `bits` bit times, in nanoseconds.
    pub fn bits_ns(&self, bits: f64) -> f64 {
        bits * 1e9 / f64::from(self.baud.max(1))
    }

    /// The duration of one character, in nanoseconds.
    pub fn char_ns(&self) -> f64 {
        self.bits_ns(f64::from(self.bits_per_char()))
    }
}

impl Default for SerialConfig {
    /// 9600 baud 8N1.
    fn default() -> Self {
        SerialConfig::new(9600)
    }
}

/// Bytes of an RTU request with `function` carrying `quantity` registers, or `None` for a
/// function the model does not know.
pub const fn request_bytes(function: u8, quantity: u16) -> Option<u32> {
    match function {
        function::READ_HOLDING
        | function::READ_INPUT
        | function::WRITE_SINGLE
        | function::LOOP_BACK => Some(8),
        function::WRITE_MULTIPLE => Some(9 + 2 * quantity as u32),
        function::READ_COILS | function::READ_DISCRETE_INPUTS | function::WRITE_COIL => Some(8),
        function::WRITE_COILS => Some(9 + (quantity as u32).div_ceil(8)),
        _ => None,
    }
}

/// Bytes of the normal RTU reply to `function` with `quantity` registers.
pub const fn response_bytes(function: u8, quantity: u16) -> Option<u32> {
    match function {
        function::READ_HOLDING | function::READ_INPUT => Some(5 + 2 * quantity as u32),
        function::READ_COILS | function::READ_DISCRETE_INPUTS => {
            Some(5 + (quantity as u32).div_ceil(8))
        }
        function::WRITE_SINGLE
        | function::LOOP_BACK
        | function::WRITE_MULTIPLE
        | function::WRITE_COIL
        | function::WRITE_COILS => Some(8),
        _ => None,
    }
}

/// Bytes of an RTU exception reply: slave, function | 80h, code, CRC.
pub const EXCEPTION_BYTES: u32 = 5;

/// One transaction's bus time, term by term, in nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct Breakdown {
    /// The request on the wire.
    pub request_ns: u64,
    /// From the end of the request to the first reply byte.
    pub latency_ns: u64,
    /// The reply on the wire (0 for a broadcast).
    pub response_ns: u64,
    /// From the end of the reply to the earliest next request.
    pub turnaround_ns: u64,
}

impl Breakdown {
    /// The whole transaction, in nanoseconds.
    pub const fn total_ns(&self) -> u64 {
        self.request_ns + self.latency_ns + self.response_ns + self.turnaround_ns
    }

    /// The whole transaction.
    pub const fn total(&self) -> Duration {
        Duration::from_nanos(self.total_ns())
    }
}

/// The bus-time model of one drive on one serial line. See the module documentation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusModel {
    /// The serial line.
    pub serial: SerialConfig,
    /// Silence between frames, in characters.
    pub frame_gap_chars: f64,
    /// Least silence between frames in microseconds, when the manual states it in time (0 when
    /// it does not): the gap is the larger of this and `frame_gap_chars` characters.
    pub frame_gap_us: u32,
    /// Bit times the drive takes before its response delay.
    pub response_bits: u32,
    /// The drive's response delay, in microseconds (fixed, or the delay parameter's value).
    pub response_delay_us: u32,
    /// Bit times the master waits after a reply (beyond the frame gap when larger).
    pub request_gap_bits: u32,
    /// Microseconds the master waits after a reply, on top of `request_gap_bits`.
    pub request_gap_us: u32,
}

impl BusModel {
    /// The model for a drive with `profile` on a line with `serial`, with the manual's default
    /// for any delay parameter.
    pub fn new(profile: &Profile, serial: SerialConfig) -> BusModel {
        let timing = &profile.timing;
        let mut serial = serial;
        if serial.char_bits.is_none() {
            serial.char_bits = timing.char_bits;
        }
        BusModel {
            serial,
            frame_gap_chars: timing.frame_gap_chars,
            frame_gap_us: timing.frame_gap_us.unwrap_or(0),
            response_bits: timing.response_delay_bits.unwrap_or(0),
            response_delay_us: timing
                .response_delay_us
                .unwrap_or(0)
                .max(timing.response_delay_param_default_us.unwrap_or(0)),
            request_gap_bits: timing.request_gap_bits.unwrap_or(0),
            request_gap_us: timing.request_gap_us.unwrap_or(0),
        }
    }

    /// Sets the value configured in the drive's response-delay parameter (V7 n156, J7 n73,
    /// ACN CM.05) in place of the manual's default.
    pub fn with_delay_param(mut self, delay: Duration) -> BusModel {
        self.response_delay_us = u32::try_from(delay.as_micros()).unwrap_or(u32::MAX);
        self
    }

    /// The silence between frames, in nanoseconds: `frame_gap_chars` characters, 1.75 ms above
    /// 19 200 baud, or `frame_gap_us` where the manual states a longer gap in time.
    pub fn frame_gap_ns(&self) -> f64 {
        let chars = if self.serial.baud > 19_200 {
            1_750_000.0
        } else {
            self.frame_gap_chars * self.serial.char_ns()
        };
        chars.max(f64::from(self.frame_gap_us) * 1e3)
    }

    /// From the end of a request to the first byte of the reply, in nanoseconds.
    pub fn latency_ns(&self) -> f64 {
        let drive = self.serial.bits_ns(f64::from(self.response_bits))
            + f64::from(self.response_delay_us) * 1e3;
        drive.max(self.frame_gap_ns())
    }

    /// From the end of a reply to the earliest next request, in nanoseconds.
    pub fn turnaround_ns(&self) -> f64 {
        let master = self.serial.bits_ns(f64::from(self.request_gap_bits))
            + f64::from(self.request_gap_us) * 1e3;
        master.max(self.frame_gap_ns())
    }

    /// The least time between a reply and the next request that the manual asks of the master,
    /// beyond the frame gap: what to give [`ClientOptions::request_gap`](crate::client::ClientOptions).
    pub fn master_request_gap(&self) -> Duration {
        let master = self.serial.bits_ns(f64::from(self.request_gap_bits))
            + f64::from(self.request_gap_us) * 1e3;
        Duration::from_nanos(master.ceil() as u64)
    }

    /// A transaction of `request` bytes answered by `response` bytes (`None`: no reply, as for
    /// a broadcast, which is followed by the frame gap only).
    pub fn transaction(&self, request: u32, response: Option<u32>) -> Breakdown {
        let char_ns = self.serial.char_ns();
        let round = |ns: f64| ns.round() as u64;
        match response {
            Some(bytes) => Breakdown {
                request_ns: round(f64::from(request) * char_ns),
                latency_ns: round(self.latency_ns()),
                response_ns: round(f64::from(bytes) * char_ns),
                turnaround_ns: round(self.turnaround_ns()),
            },
            None => Breakdown {
                request_ns: round(f64::from(request) * char_ns),
                latency_ns: 0,
                response_ns: 0,
                turnaround_ns: round(self.frame_gap_ns()),
            },
        }
    }

    /// A normal transaction with `function` and `quantity` registers, or `None` for a function
    /// the model does not know.
    pub fn exchange(&self, function: u8, quantity: u16) -> Option<Breakdown> {
        Some(self.transaction(
            request_bytes(function, quantity)?,
            Some(response_bytes(function, quantity)?),
        ))
    }

    /// A request answered with an exception.
    pub fn exception(&self, function: u8, quantity: u16) -> Option<Breakdown> {
        Some(self.transaction(request_bytes(function, quantity)?, Some(EXCEPTION_BYTES)))
    }

    /// A read (03h/04h) of `quantity` registers, in nanoseconds: the cost the planner uses.
    pub fn read_ns(&self, quantity: u16) -> u64 {
        self.transaction(8, Some(5 + 2 * u32::from(quantity)))
            .total_ns()
    }

    /// A read of `quantity` registers.
    pub fn read(&self, quantity: u16) -> Duration {
        Duration::from_nanos(self.read_ns(quantity))
    }

    /// A read of `quantity` coils or discrete inputs (01h/02h), in nanoseconds: eight states a
    /// byte in the reply.
    pub fn read_bits_ns(&self, quantity: u16) -> u64 {
        self.transaction(8, Some(5 + u32::from(quantity).div_ceil(8)))
            .total_ns()
    }

    /// A read of `quantity` items of `table`, in nanoseconds: [`BusModel::read_ns`] for
    /// registers, [`BusModel::read_bits_ns`] for coils and discrete inputs.
    pub fn read_ns_of(&self, table: drivemap_core::register::Table, quantity: u16) -> u64 {
        if table.is_bits() {
            self.read_bits_ns(quantity)
        } else {
            self.read_ns(quantity)
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn profile(drive_id: &'static str, response_delay_us: Option<u32>) -> Profile {
        let mut p = Profile {
            drive_id,
            ..Profile::GENERIC
        };
        p.timing.response_delay_us = response_delay_us;
        p
    }

    #[test]
    fn character_length_follows_parity_stop_bits_and_fixed_length() {
        assert_eq!(SerialConfig::new(9600).bits_per_char(), 10);
        assert_eq!(
            SerialConfig::new(9600).parity(Parity::Even).bits_per_char(),
            11
        );
        assert_eq!(
            SerialConfig::new(9600).parity(Parity::Odd).bits_per_char(),
            11
        );
        assert_eq!(SerialConfig::new(9600).stop_bits(2).bits_per_char(), 11);
        // TDS-V8: 11 bits whatever the parity.
        assert_eq!(
            SerialConfig::new(9600).fixed_char_bits(11).bits_per_char(),
            11
        );
    }

    #[test]
    fn byte_counts_match_the_manual_tables() {
        // 000_032dced3a1e91a75.txt:296-302 (V7, max 8 registers read, 16 written).
        assert_eq!(request_bytes(0x03, 8), Some(8));
        assert_eq!(response_bytes(0x03, 1), Some(7));
        assert_eq!(response_bytes(0x03, 8), Some(21));
        assert_eq!(request_bytes(0x06, 1), Some(8));
        assert_eq!(response_bytes(0x06, 1), Some(8));
        assert_eq!(request_bytes(0x08, 1), Some(8));
        assert_eq!(response_bytes(0x08, 1), Some(8));
        assert_eq!(request_bytes(0x10, 1), Some(11));
        assert_eq!(request_bytes(0x10, 16), Some(41));
        assert_eq!(response_bytes(0x10, 16), Some(8));
        // 003 Table 7.1 and TDS-V8: a 16-register read answers with 37 bytes.
        assert_eq!(response_bytes(0x03, 16), Some(37));
        assert_eq!(response_bytes(0x04, 16), Some(37));
        assert_eq!(request_bytes(0x2B, 1), None);
    }

    /// The V7's timing as its map states it: 24 bits + n156 (default 10 ms) before the reply,
    /// 24 bits + 10 ms after it (`003_8bcf5d50afb8e230.txt:282-284`). Shared with the client's
    /// tests.
    pub(crate) fn v7() -> Profile {
        let mut p = profile("yaskawa-v7", None);
        p.timing.response_delay_bits = Some(24);
        p.timing.response_delay_param = Some("n156");
        p.timing.response_delay_param_default_us = Some(10_000);
        p.timing.request_gap_bits = Some(24);
        p.timing.request_gap_us = Some(10_000);
        p
    }

    #[test]
    fn v7_read_at_9600_8n1_follows_the_24_bit_and_10_ms_rules() {
        let model = BusModel::new(&v7(), SerialConfig::new(9600));
        let b = model.exchange(0x03, 8).unwrap();
        // 8 bytes of 10 bits at 9600 baud.
        assert_eq!(b.request_ns, 8_333_333);
        // 24 bits + n156 default 10 ms.
        assert_eq!(b.latency_ns, 2_500_000 + 10_000_000);
        assert_eq!(b.response_ns, 21_875_000);
        // 24 bits + 10 ms before the next request.
        assert_eq!(b.turnaround_ns, 12_500_000);
        assert_eq!(model.read_ns(8), b.total_ns());
        assert_eq!(model.master_request_gap(), Duration::from_micros(12_500));
        // A configured n156 of 20 ms lengthens the latency only.
        let slow = model.with_delay_param(Duration::from_millis(20));
        assert_eq!(slow.exchange(0x03, 8).unwrap().latency_ns, 22_500_000);
        assert_eq!(slow.exchange(0x03, 8).unwrap().turnaround_ns, 12_500_000);
    }

    #[test]
    fn fixed_response_time_and_frame_gap() {
        // TDS-V8: 5 ms response, 11-bit characters (taken from the profile); the gap after the
        // reply is 3.5 characters.
        let mut tds_profile = profile("ptlk-tds-v8", Some(5000));
        tds_profile.timing.char_bits = Some(11);
        let tds = BusModel::new(&tds_profile, SerialConfig::new(9600));
        assert_eq!(tds.serial.bits_per_char(), 11);
        let b = tds.exchange(0x03, 16).unwrap();
        assert_eq!(b.latency_ns, 5_000_000);
        assert_eq!(
            b.response_ns,
            (37.0 * 11.0 * 1e9 / 9600.0_f64).round() as u64
        );
        assert_eq!(
            b.turnaround_ns,
            (3.5 * 11.0 * 1e9 / 9600.0_f64).round() as u64
        );
        // A drive with no printed timing: the frame gap on both sides.
        let generic = BusModel::new(&Profile::GENERIC, SerialConfig::new(9600));
        let g = generic.exchange(0x06, 1).unwrap();
        assert_eq!(g.latency_ns, 3_645_833);
        assert_eq!(g.turnaround_ns, 3_645_833);
        // Above 19 200 baud the gap is 1.75 ms.
        let fast = BusModel::new(&Profile::GENERIC, SerialConfig::new(115_200));
        assert_eq!(fast.exchange(0x03, 1).unwrap().turnaround_ns, 1_750_000);
    }

    #[test]
    fn a_frame_gap_stated_in_ms_is_kept_when_longer_than_the_characters() {
        // "Silence of at least 10 ms": longer than 3.5 characters at 9600 (3.65 ms) and the
        // 1.75 ms above 19 200 baud, so it rules at both.
        let mut p = Profile::GENERIC;
        p.timing.frame_gap_us = Some(10_000);
        let slow = BusModel::new(&p, SerialConfig::new(9600));
        assert_eq!(slow.frame_gap_ns(), 10_000_000.0);
        assert_eq!(slow.exchange(0x03, 1).unwrap().turnaround_ns, 10_000_000);
        let fast = BusModel::new(&p, SerialConfig::new(115_200));
        assert_eq!(fast.exchange(0x03, 1).unwrap().latency_ns, 10_000_000);
        // At 1200 baud 3.5 characters (32 ms) are longer than the 10 ms: the characters rule.
        let crawl = BusModel::new(&p, SerialConfig::new(1200));
        assert_eq!(crawl.frame_gap_ns().round(), 29_166_667.0);
    }

    #[test]
    fn acn_delay_parameter_without_a_printed_default() {
        // The ACN map names CM.05 but prints no default: the frame gap is the lower bound.
        let mut p = profile("automationdirect-acn", None);
        p.timing.response_delay_param = Some("CM.05");
        let acn = BusModel::new(&p, SerialConfig::new(9600));
        assert_eq!(acn.exchange(0x04, 1).unwrap().latency_ns, 3_645_833);
        // CM.05 configured to 5 ms lengthens the latency.
        let set = acn.with_delay_param(Duration::from_millis(5));
        assert_eq!(set.exchange(0x04, 1).unwrap().latency_ns, 5_000_000);
    }

    #[test]
    fn exceptions_broadcasts_and_monotone_reads() {
        let model = BusModel::new(&Profile::GENERIC, SerialConfig::new(9600));
        let e = model.exception(0x03, 16).unwrap();
        assert_eq!(e.response_ns, 5_208_333);
        let broadcast = model.transaction(11, None);
        assert_eq!(broadcast.response_ns, 0);
        assert_eq!(broadcast.latency_ns, 0);
        assert_eq!(broadcast.turnaround_ns, 3_645_833);
        for q in 1..125 {
            assert!(model.read_ns(q) < model.read_ns(q + 1));
        }
        assert_eq!(model.exchange(0x2B, 1), None);
    }
}
