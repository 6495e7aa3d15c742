//! Modbus RTU or Modbus ASCII ([`SerialOptions::ascii`]) on a serial line, through the
//! `serialport` crate.
//!
//! What the transport adds to moving bytes:
//! - the silence of 3.5 characters between frames (characters of the line's format: 10 bits
//!   for 8N1, 11 for 8E1, 8O1 and 8N2, or the map's fixed length; 1.75 ms above 19 200 baud),
//!   measured from the last byte sent or received;
//! - stale bytes (a late reply, noise) discarded before each request, and the request held back
//!   until the line has been silent for the whole gap;
//! - the inter-character timeout, which the client uses to discard frames broken off mid-way;
//! - RS-485 direction control: the Linux kernel's own (`TIOCSRS485`), or RTS toggled by the
//!   transport around each frame where the kernel offers nothing.

use std::io::{self, Read, Write};
use std::thread;
use std::time::{Duration, Instant};

use serialport::{ClearBuffer, DataBits, FlowControl, SerialPort};

use super::Transport;
use crate::bus_time::SerialConfig;
use crate::error::Refusal;
use drivemap_core::profile::{Profile, SerialFormats, TransportKind};

pub use serialport::{Parity, StopBits};

/// Bits in one RTU character for timing purposes: start, 8 data, parity or second stop, stop.
pub const BITS_PER_CHAR: u32 = 11;

/// How the RS-485 transceiver's driver is switched between sending and receiving.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Rs485 {
    /// No direction control: RS-232, RS-422 / 4-wire RS-485, or an adapter that switches by
    /// itself (most USB RS-485 adapters).
    #[default]
    None,
    /// The Linux kernel drives RTS (`TIOCSRS485`). Opening fails where the driver does not
    /// support it, rather than silently sending with the transmitter off.
    Kernel {
        /// RTS level while sending (true: high).
        rts_on_send: bool,
        /// Delay between raising RTS and the first bit, in milliseconds.
        delay_before_send_ms: u32,
        /// Delay between the last bit and dropping RTS, in milliseconds.
        delay_after_send_ms: u32,
    },
    /// The transport sets RTS before writing a frame and clears it once the UART has sent the
    /// last bit (`tcdrain`). Portable, but timing depends on the OS scheduler.
    SoftwareRts {
        /// RTS level while sending (true: asserted).
        rts_on_send: bool,
    },
}

/// Settings of a serial line.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialOptions {
    /// Device path (`/dev/ttyUSB0`, `COM3`).
    pub path: String,
    /// Bits per second.
    pub baud: u32,
    /// Parity (the drives offer none, even and odd).
    pub parity: Parity,
    /// Stop bits.
    pub stop_bits: StopBits,
    /// Silence between frames in character times (3.5 per the Modbus specification and every
    /// manual here).
    pub frame_gap_chars: f64,
    /// Least silence between frames whatever the baud rate, when the manual states the gap in
    /// time (`timing.frame_gap_us`, "at least 10 ms"); zero when it does not. The gap kept is
    /// the larger of this and `frame_gap_chars` characters.
    pub frame_gap_min: Duration,
    /// Longest gap allowed between two bytes of a reply; a reply broken off by a longer gap is
    /// discarded. [`SerialOptions::new`] sets 1.5 characters plus [`USB_LATENCY`].
    pub inter_char_timeout: Duration,
    /// Direction control.
    pub rs485: Rs485,
    /// The only character formats the drive offers, when its map lists them (set by
    /// [`SerialOptions::with_profile`]): [`SerialTransport::open`] refuses any other parity
    /// and stop bits. `None`: any.
    pub formats: Option<SerialFormats>,
    /// The drive the formats are those of, for the refusal.
    pub drive_id: &'static str,
    /// Bits per character when the drive's map fixes it whatever the parity (TDS-V8: 11, the
    /// map's `serial.char_bits`; set by [`SerialOptions::with_profile`]).
    pub char_bits: Option<u8>,
    /// Data bits per character: 8 (RTU needs them), or 7 (Modbus ASCII's usual format).
    pub data_bits: u8,
    /// Frames are Modbus ASCII (`:` ... LRC CR LF, [`crate::ascii`]) rather than RTU: the
    /// transport's kind is [`TransportKind::Ascii`] and a reply ends with its CR LF, not with
    /// a silence (no inter-character timeout).
    pub ascii: bool,
}

/// Allowance added to the inter-character timeout for adapters that deliver received bytes
/// in batches (a USB serial adapter's latency timer is 16 ms by default).
pub const USB_LATENCY: Duration = Duration::from_millis(16);

impl SerialOptions {
    /// 8 data bits, no parity, 1 stop bit at `baud`; 3.5-character frame gap.
    pub fn new(path: impl Into<String>, baud: u32) -> SerialOptions {
        SerialOptions {
            path: path.into(),
            baud,
            parity: Parity::None,
            stop_bits: StopBits::One,
            frame_gap_chars: 3.5,
            frame_gap_min: Duration::ZERO,
            inter_char_timeout: char_times(1.5, baud) + USB_LATENCY,
            rs485: Rs485::None,
            formats: None,
            drive_id: "",
            char_bits: None,
            data_bits: 8,
            ascii: false,
        }
    }

    /// Modbus ASCII with `data_bits` data bits per character (7 as Delta's factory setting,
    /// or 8); refused unless 7 or 8.
    pub fn ascii(mut self, data_bits: u8) -> io::Result<SerialOptions> {
        if !matches!(data_bits, 7 | 8) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{data_bits} data bits: a Modbus ASCII line has 7 or 8"),
            ));
        }
        self.ascii = true;
        self.data_bits = data_bits;
        Ok(self)
    }

    /// Takes the frame gap the drive's manual prescribes (in characters, and its least time
    /// when stated in milliseconds), and the character formats its map lists, if any, which
    /// [`SerialTransport::open`] then holds the line to.
    pub fn with_profile(mut self, profile: &Profile) -> SerialOptions {
        self.frame_gap_chars = profile.timing.frame_gap_chars;
        self.frame_gap_min =
            Duration::from_micros(u64::from(profile.timing.frame_gap_us.unwrap_or(0)));
        self.formats = profile.serial_formats;
        self.drive_id = profile.drive_id;
        self.char_bits = profile.timing.char_bits;
        self
    }

    /// The line to a drive with `profile`: [`with_profile`](SerialOptions::with_profile),
    /// `parity`, and `stop_bits` as given, else the stop bits of the map's formats for that
    /// parity when they have only one (ACN: 1 with even or odd parity), else 1 (2 without
    /// parity where the map fixes 11-bit characters). Refused when the map lists its formats
    /// and this is not one of them.
    pub fn line(
        self,
        profile: &Profile,
        parity: Parity,
        stop_bits: Option<StopBits>,
    ) -> Result<SerialOptions, Refusal> {
        let config = SerialConfig::for_profile(
            profile,
            self.baud,
            bus_parity(parity),
            stop_bits.map(stop_count),
        )?;
        let stop_bits = if config.stop_bits == 2 {
            StopBits::Two
        } else {
            StopBits::One
        };
        Ok(self
            .with_profile(profile)
            .parity(parity)
            .stop_bits(stop_bits))
    }

    /// Refuses a parity and stop bits that are not one of the formats of
    /// [`formats`](SerialOptions::formats) (with the line's data bits).
    pub fn check_format(&self) -> Result<(), Refusal> {
        match self.formats {
            Some(f) => f
                .check(
                    self.drive_id,
                    self.data_bits,
                    bus_parity(self.parity),
                    stop_count(self.stop_bits),
                )
                .map(|_| ())
                .map_err(Refusal::SerialFormat),
            None => Ok(()),
        }
    }

    /// Sets the parity.
    pub fn parity(mut self, parity: Parity) -> SerialOptions {
        self.parity = parity;
        self
    }

    /// Sets the stop bits.
    pub fn stop_bits(mut self, stop_bits: StopBits) -> SerialOptions {
        self.stop_bits = stop_bits;
        self
    }

    /// Sets RS-485 direction control.
    pub fn rs485(mut self, rs485: Rs485) -> SerialOptions {
        self.rs485 = rs485;
        self
    }

    /// The line as the bus-time model counts it: baud rate, data bits, parity, stop bits and
    /// the map's fixed character length.
    pub fn serial_config(&self) -> SerialConfig {
        SerialConfig {
            baud: self.baud,
            data_bits: self.data_bits,
            parity: bus_parity(self.parity),
            stop_bits: stop_count(self.stop_bits),
            char_bits: self.char_bits,
        }
    }

    /// The silence kept between frames: the larger of the gap in characters of the line's
    /// format (10 bits for 8N1, 11 for 8E1, 8O1, 8N2; 1.75 ms above 19 200 baud) and
    /// [`frame_gap_min`](SerialOptions::frame_gap_min). The bus-time model counts the same
    /// (`BusModel::frame_gap_ns`): an 8N1 line is not held silent for 11-bit characters.
    pub fn frame_gap(&self) -> Duration {
        let chars = if self.baud > 19_200 {
            Duration::from_micros(1750)
        } else {
            Duration::from_nanos(
                (self.frame_gap_chars * self.serial_config().char_ns()).ceil() as u64,
            )
        };
        chars.max(self.frame_gap_min)
    }
}

/// The vocabulary crate's parity for the `serialport` crate's.
pub(crate) fn bus_parity(parity: Parity) -> drivemap_core::profile::Parity {
    match parity {
        Parity::None => drivemap_core::profile::Parity::None,
        Parity::Even => drivemap_core::profile::Parity::Even,
        Parity::Odd => drivemap_core::profile::Parity::Odd,
    }
}

fn stop_count(stop_bits: StopBits) -> u8 {
    match stop_bits {
        StopBits::One => 1,
        StopBits::Two => 2,
    }
}

/// Duration of `chars` characters of 11 bits at `baud` (the longest RTU character: the
/// transport's frame gap counts the line's own, [`SerialOptions::frame_gap`]).
pub fn char_times(chars: f64, baud: u32) -> Duration {
    let baud = f64::from(baud.max(1));
    Duration::from_secs_f64(chars * f64::from(BITS_PER_CHAR) / baud)
}

/// The inter-frame silence: `chars` characters, but a fixed 1.75 ms above 19 200 baud (Modbus
/// over serial line specification, 2.5.1.1), where the character time is too short to time.
pub fn frame_gap(chars: f64, baud: u32) -> Duration {
    if baud > 19_200 {
        Duration::from_micros(1750)
    } else {
        char_times(chars, baud)
    }
}

/// A serial port speaking Modbus RTU, or Modbus ASCII ([`SerialOptions::ascii`]).
pub struct SerialTransport {
    port: Box<dyn SerialPort>,
    options: SerialOptions,
    gap: Duration,
    last_activity: Instant,
}

impl SerialTransport {
    /// Opens and configures the port.
    pub fn open(options: SerialOptions) -> io::Result<SerialTransport> {
        // A format the drive's map does not list is refused before the port is touched.
        options
            .check_format()
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e.to_string()))?;
        let data_bits = if options.data_bits == 7 {
            DataBits::Seven
        } else {
            DataBits::Eight
        };
        let builder = serialport::new(&options.path, options.baud)
            .data_bits(data_bits)
            .parity(options.parity)
            .stop_bits(options.stop_bits)
            .flow_control(FlowControl::None)
            .timeout(Duration::from_millis(10));
        #[cfg(unix)]
        let port: Box<dyn SerialPort> = {
            let port = builder.open_native().map_err(io::Error::from)?;
            if let Rs485::Kernel {
                rts_on_send,
                delay_before_send_ms,
                delay_after_send_ms,
            } = options.rs485
            {
                kernel_rs485(
                    &port,
                    rts_on_send,
                    delay_before_send_ms,
                    delay_after_send_ms,
                )?;
            }
            Box::new(port)
        };
        #[cfg(not(unix))]
        let port: Box<dyn SerialPort> = {
            if matches!(options.rs485, Rs485::Kernel { .. }) {
                return Err(io::Error::new(
                    io::ErrorKind::Unsupported,
                    "kernel RS-485 direction control needs Linux; use Rs485::SoftwareRts",
                ));
            }
            builder.open().map_err(io::Error::from)?
        };
        Self::from_port(port, options)
    }

    /// Uses an already opened port (its line settings are left as they are).
    pub fn from_port(mut port: Box<dyn SerialPort>, options: SerialOptions) -> io::Result<Self> {
        if let Rs485::SoftwareRts { rts_on_send } = options.rs485 {
            port.write_request_to_send(!rts_on_send)
                .map_err(io::Error::from)?;
        }
        let gap = options.frame_gap();
        Ok(SerialTransport {
            port,
            options,
            gap,
            last_activity: Instant::now(),
        })
    }

    /// The options in force.
    pub fn options(&self) -> &SerialOptions {
        &self.options
    }

    /// Waits until the line has been silent for the frame gap, discarding whatever arrives in
    /// the meantime. Gives up waiting for silence after 64 gaps of continuous noise.
    fn wait_for_silence(&mut self) -> io::Result<()> {
        for _ in 0..64 {
            let quiet_at = self.last_activity + self.gap;
            let now = Instant::now();
            if quiet_at > now {
                thread::sleep(quiet_at - now);
            }
            if self.port.bytes_to_read().map_err(io::Error::from)? == 0 {
                return Ok(());
            }
            self.port
                .clear(ClearBuffer::Input)
                .map_err(io::Error::from)?;
            self.last_activity = Instant::now();
        }
        Ok(())
    }
}

impl Transport for SerialTransport {
    fn kind(&self) -> TransportKind {
        if self.options.ascii {
            TransportKind::Ascii
        } else {
            TransportKind::Rtu
        }
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.wait_for_silence()?;
        let rts = match self.options.rs485 {
            Rs485::SoftwareRts { rts_on_send } => Some(rts_on_send),
            _ => None,
        };
        if let Some(level) = rts {
            self.port
                .write_request_to_send(level)
                .map_err(io::Error::from)?;
        }
        // One write for the whole frame, so no gap opens between its characters.
        let written = self.port.write_all(frame).and_then(|_| self.port.flush());
        if let Some(level) = rts {
            self.port
                .write_request_to_send(!level)
                .map_err(io::Error::from)?;
        }
        self.last_activity = Instant::now();
        written
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let Some(wait) = super::remaining(deadline) else {
            return Ok(0);
        };
        self.port.set_timeout(wait).map_err(io::Error::from)?;
        match self.port.read(buf) {
            Ok(n) => {
                if n > 0 {
                    self.last_activity = Instant::now();
                }
                Ok(n)
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
                ) =>
            {
                Ok(0)
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn discard_input(&mut self) -> io::Result<()> {
        self.port.clear(ClearBuffer::Input).map_err(io::Error::from)
    }

    fn inter_char_timeout(&self) -> Option<Duration> {
        if self.options.ascii {
            return None;
        }
        Some(self.options.inter_char_timeout)
    }
}

/// Switches the Linux kernel's RS-485 mode on for `port` (`TIOCSRS485`, see the kernel's
/// Documentation/driver-api/serial/serial-rs485.rst).
#[cfg(target_os = "linux")]
// The workspace denies `unsafe`; this ioctl has no safe wrapper among the dependencies
// (serialport has no RS-485 call, rustix's `ioctl` is itself unsafe).
#[allow(unsafe_code)]
fn kernel_rs485(
    port: &serialport::TTYPort,
    rts_on_send: bool,
    delay_before_send_ms: u32,
    delay_after_send_ms: u32,
) -> io::Result<()> {
    use std::os::fd::AsRawFd;

    /// `struct serial_rs485` of `<linux/serial.h>`.
    #[repr(C)]
    struct SerialRs485 {
        flags: u32,
        delay_rts_before_send: u32,
        delay_rts_after_send: u32,
        padding: [u32; 5],
    }
    const SER_RS485_ENABLED: u32 = 1 << 0;
    const SER_RS485_RTS_ON_SEND: u32 = 1 << 1;
    const SER_RS485_RTS_AFTER_SEND: u32 = 1 << 2;

    let flags = SER_RS485_ENABLED
        | if rts_on_send {
            SER_RS485_RTS_ON_SEND
        } else {
            SER_RS485_RTS_AFTER_SEND
        };
    let config = SerialRs485 {
        flags,
        delay_rts_before_send: delay_before_send_ms,
        delay_rts_after_send: delay_after_send_ms,
        padding: [0; 5],
    };
    // SAFETY: the only `unsafe` in the project. `fd` is the open descriptor owned by `port`,
    // which outlives the call; TIOCSRS485 reads exactly one `struct serial_rs485`, which
    // `config` is (same layout, `repr(C)`), and the kernel does not keep the pointer.
    let rc = unsafe {
        libc::ioctl(
            port.as_raw_fd(),
            libc::TIOCSRS485 as _,
            &config as *const SerialRs485,
        )
    };
    if rc < 0 {
        let e = io::Error::last_os_error();
        return Err(io::Error::new(
            e.kind(),
            format!("the serial driver refuses kernel RS-485 mode (TIOCSRS485): {e}"),
        ));
    }
    Ok(())
}

#[cfg(all(unix, not(target_os = "linux")))]
fn kernel_rs485(_: &serialport::TTYPort, _: bool, _: u32, _: u32) -> io::Result<()> {
    Err(io::Error::new(
        io::ErrorKind::Unsupported,
        "kernel RS-485 direction control needs Linux; use Rs485::SoftwareRts",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_gap_follows_the_specification() {
        // 9600 baud: 3.5 × 11 / 9600 s = 4.0104 ms.
        let g = frame_gap(3.5, 9600);
        assert!(
            g > Duration::from_micros(4010) && g < Duration::from_micros(4011),
            "{g:?}"
        );
        assert_eq!(frame_gap(3.5, 38_400), Duration::from_micros(1750));
        assert_eq!(frame_gap(3.5, 115_200), Duration::from_micros(1750));
        // 19 200 is not above 19 200: 2.005 ms.
        assert!(frame_gap(3.5, 19_200) > Duration::from_micros(2000));
        // A gap the manual states in ms is kept where it is the longer.
        let mut p = drivemap_core::profile::Profile::GENERIC;
        p.timing.frame_gap_us = Some(10_000);
        let o = SerialOptions::new("/dev/null", 115_200).with_profile(&p);
        assert_eq!(o.frame_gap(), Duration::from_millis(10));
        let o = SerialOptions::new("/dev/null", 1200).with_profile(&p);
        assert_eq!(o.frame_gap(), Duration::from_nanos(29_166_667));
    }

    /// The gap is 3.5 characters of the line's own format, as the bus-time model counts it:
    /// an 8N1 line was held silent for 11-bit characters (4.01 ms at 9600 instead of 3.65 ms),
    /// each turnaround 0.36 ms longer than the rules need.
    #[test]
    fn frame_gap_counts_the_lines_own_character() {
        use crate::bus_time::BusModel;
        let o = SerialOptions::new("/dev/null", 9600);
        assert_eq!(o.frame_gap(), Duration::from_nanos(3_645_834));
        let even = SerialOptions::new("/dev/null", 9600).parity(Parity::Even);
        assert_eq!(even.frame_gap(), Duration::from_nanos(4_010_417));
        let two = SerialOptions::new("/dev/null", 19_200).stop_bits(StopBits::Two);
        assert_eq!(two.frame_gap(), Duration::from_nanos(2_005_209));
        // The map's fixed 11-bit character (TDS-V8) counts whatever the parity.
        let mut p = drivemap_core::profile::Profile::GENERIC;
        p.timing.char_bits = Some(11);
        let tds = SerialOptions::new("/dev/null", 9600).with_profile(&p);
        assert_eq!(tds.frame_gap(), Duration::from_nanos(4_010_417));
        // The same as the model's frame gap, for every format.
        for o in [o, even, two, tds] {
            let model = BusModel::new(&drivemap_core::profile::Profile::GENERIC, o.serial_config());
            assert_eq!(
                o.frame_gap().as_nanos() as f64,
                model.frame_gap_ns().ceil(),
                "{o:?}"
            );
        }
    }

    /// A drive whose map lists the formats a parameter selects (the ACN's CM.04: 8N1, 8N2,
    /// 8E1, 8O1), and one whose only format without parity has 2 stop bits.
    fn acn() -> Profile {
        use drivemap_core::profile::{Parity as P, SerialFormat, SerialFormats};
        const fn f(code: u16, parity: P, stop_bits: u8) -> SerialFormat {
            SerialFormat {
                code,
                data_bits: 8,
                parity,
                stop_bits,
            }
        }
        static FORMATS: [SerialFormat; 4] = [
            f(0, P::None, 1),
            f(1, P::None, 2),
            f(2, P::Even, 1),
            f(3, P::Odd, 1),
        ];
        Profile {
            drive_id: "automationdirect-acn",
            serial_formats: Some(SerialFormats {
                selected_by: "CM.04",
                formats: &FORMATS,
                source: "004_c5cbf92472673495.txt:262",
            }),
            ..Profile::GENERIC
        }
    }

    #[test]
    fn a_format_the_map_does_not_list_is_refused() {
        let p = acn();
        let e = SerialOptions::new("/dev/null", 9600)
            .line(&p, Parity::Even, Some(StopBits::Two))
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "automationdirect-acn's serial line offers only the formats its map lists (CM.04: 0 = 8N1, 1 = 8N2, 2 = 8E1, 3 = 8O1); 8E2 is not one of them (`004_c5cbf92472673495.txt:262`)"
        );
        // Set by hand past `line`: `open` refuses it before touching the port.
        let o = SerialOptions::new("/nonexistent/tty", 9600)
            .with_profile(&p)
            .parity(Parity::Odd)
            .stop_bits(StopBits::Two);
        let e = SerialTransport::open(o).err().expect("refused");
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("8O2 is not one of them"), "{e}");
        // Listed formats pass; even parity takes its only stop bits, none keeps 1 or 2.
        let o = SerialOptions::new("/dev/null", 9600)
            .line(&p, Parity::Even, None)
            .unwrap();
        assert_eq!((o.parity, o.stop_bits), (Parity::Even, StopBits::One));
        assert!(o.check_format().is_ok());
        for stop in [StopBits::One, StopBits::Two] {
            let o = SerialOptions::new("/dev/null", 9600)
                .line(&p, Parity::None, Some(stop))
                .unwrap();
            assert_eq!(o.stop_bits, stop);
        }
        // A profile without formats takes any line.
        let o = SerialOptions::new("/dev/null", 9600)
            .line(&Profile::GENERIC, Parity::Even, Some(StopBits::Two))
            .unwrap();
        assert!(o.check_format().is_ok());
    }

    #[test]
    fn the_stop_bits_of_a_parity_with_one_format_are_the_maps() {
        use drivemap_core::profile::{Parity as P, SerialFormat, SerialFormats};
        // 8N2 is the only format without parity (as on a drive with 11-bit characters).
        static FORMATS: [SerialFormat; 2] = [
            SerialFormat {
                code: 0,
                data_bits: 8,
                parity: P::None,
                stop_bits: 2,
            },
            SerialFormat {
                code: 1,
                data_bits: 8,
                parity: P::Even,
                stop_bits: 1,
            },
        ];
        let p = Profile {
            serial_formats: Some(SerialFormats {
                selected_by: "P-10",
                formats: &FORMATS,
                source: "manual.txt:1",
            }),
            ..Profile::GENERIC
        };
        let o = SerialOptions::new("/dev/null", 9600)
            .line(&p, Parity::None, None)
            .unwrap();
        assert_eq!(o.stop_bits, StopBits::Two);
        let c = SerialConfig::for_profile(&p, 9600, drivemap_core::profile::Parity::None, None)
            .unwrap();
        assert_eq!((c.stop_bits, c.bits_per_char()), (2, 11));
        assert!(matches!(
            SerialConfig::for_profile(&p, 9600, drivemap_core::profile::Parity::Odd, None),
            Err(Refusal::SerialFormat(_))
        ));
    }
}
