//! The drive's side of a serial line in time: the drive answers after its response time (the
//! map's `timing.response_time` bits plus its fixed delay or the value of its response-delay
//! parameter, V7 n156, as the simulated drive holds it now), and, on a line whose characters
//! the link delivers at once (a pseudo-terminal), hands over each reply when its last character
//! would have left the wire at the line's speed (`drivemap simulate --serial PATH
//! --line-speed BAUD`).

use std::io;
use std::thread;
use std::time::{Duration, Instant};

use drivemap_live::codec::Value;
use drivemap_runtime::bus_time::SerialConfig;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;

use crate::Line;
use crate::Simulator;
use crate::server::lock;

/// How the simulated drive keeps time on its serial line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriveLine {
    /// The line's speed and character format.
    pub serial: SerialConfig,
    /// Whether the link delivers characters at once (a pseudo-terminal): the drive then counts
    /// a request as ending one character time per byte after its first byte arrived, and holds
    /// its reply until its last character would have ended. `false` where the link itself
    /// takes each character's time (a real port, or an emulated line).
    pub pace: bool,
}

impl Simulator {
    /// From the end of a request to the first character of the reply, as this drive answers on
    /// `serial`: the map's response bits (V7/J7: 24) plus the larger of its fixed response
    /// time (TDS-V8: 5 ms) and the value its response-delay parameter (V7 n156, J7 n73, ACN
    /// CM.05) holds now, in ms or s as the map gives its unit. The frame gap is kept by the
    /// serial transport.
    pub fn response_time(&self, serial: SerialConfig) -> Duration {
        let timing = &self.profile().timing;
        let bits = serial.bits_ns(f64::from(timing.response_delay_bits.unwrap_or(0)));
        let param_us = timing
            .response_delay_param
            .and_then(|p| self.value(p).ok())
            .and_then(|v| match v {
                Value::Quantity { value, unit, .. } => match unit.as_str() {
                    "ms" => Some(value * 1e3),
                    "s" => Some(value * 1e6),
                    _ => None,
                },
                _ => None,
            })
            .unwrap_or(0.0);
        let fixed_us = f64::from(timing.response_delay_us.unwrap_or(0));
        Duration::from_nanos((bits + fixed_us.max(param_us) * 1e3).round() as u64)
    }
}

/// A link that holds each reply of a simulated drive to that drive's timing on `line`.
pub struct TimedLink<T> {
    inner: T,
    sim: Line,
    line: DriveLine,
    /// When the first byte of the request being received arrived, and how many arrived.
    first_byte: Option<Instant>,
    bytes: usize,
    last_byte: Instant,
}

impl<T: Transport> TimedLink<T> {
    /// `inner` with the timing of the drives of `sim` on `line` (each reply that of the drive
    /// whose address it carries).
    pub fn new(inner: T, sim: Line, line: DriveLine) -> TimedLink<T> {
        TimedLink {
            inner,
            sim,
            line,
            first_byte: None,
            bytes: 0,
            last_byte: Instant::now(),
        }
    }

    fn chars(&self, n: usize) -> Duration {
        Duration::from_nanos((self.line.serial.char_ns() * n as f64).round() as u64)
    }
}

impl<T: Transport> Transport for TimedLink<T> {
    fn kind(&self) -> TransportKind {
        self.inner.kind()
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        let mut request_end = self.last_byte;
        if self.line.pace
            && let Some(first) = self.first_byte
        {
            // The link delivers bytes as they are written: the first arrived when the master
            // started sending, and the request takes a character time per byte on the wire.
            request_end = request_end.max(first + self.chars(self.bytes));
        }
        self.first_byte = None;
        self.bytes = 0;
        let response = frame
            .first()
            .and_then(|&slave| self.sim.drive(slave))
            .map_or(Duration::ZERO, |d| lock(d).response_time(self.line.serial));
        let mut at = request_end + response;
        if self.line.pace {
            at += self.chars(frame.len());
        }
        let now = Instant::now();
        if at > now {
            thread::sleep(at - now);
        }
        self.inner.send(frame)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        let n = self.inner.recv(buf, deadline)?;
        if n > 0 {
            let now = Instant::now();
            // After a frame gap of silence the bytes start another frame (a request to
            // another slave gets no reply, so no send resets the count).
            if now.saturating_duration_since(self.last_byte) >= self.chars(3) + self.chars(1) / 2 {
                self.first_byte = None;
                self.bytes = 0;
            }
            self.first_byte.get_or_insert(now);
            self.bytes += n;
            self.last_byte = now;
        }
        Ok(n)
    }

    fn discard_input(&mut self) -> io::Result<()> {
        self.inner.discard_input()
    }

    fn inter_char_timeout(&self) -> Option<Duration> {
        self.inner.inter_char_timeout()
    }
}
