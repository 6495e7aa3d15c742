//! The drive model: run/direction commands, a frequency reference, and an output frequency that
//! ramps towards it at the accel/decel rate.
//!
//! The output is kept signed (negative = reverse). The rates are `max_frequency / accel_time`
//! and `max_frequency / decel_time`, as every manual here defines accel time (time from 0 to the
//! maximum output frequency). A change of direction ramps down to 0 at the decel rate, then up at
//! the accel rate, as the TDS-V8 example describes ("decelerate to Stop from 50% speed and
//! reverse and accelerate", `002_661580cce154f322.txt:794`). A time of 0 jumps.

use crate::roles::{Condition, Mode};

/// What the drive is doing, for tests and displays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveState {
    /// Output frequency in Hz, negative in reverse.
    pub output_hz: f64,
    /// The output the drive is heading for: ±reference while run is commanded, 0 otherwise.
    pub target_hz: f64,
    /// Frequency reference in force (Hz, never negative).
    pub reference_hz: f64,
    /// Run commanded.
    pub run_command: bool,
    /// Reverse commanded.
    pub reverse_command: bool,
    /// Run commanded or the output not yet 0.
    pub running: bool,
    /// TDS-V8 operating mode, where the drive has one.
    pub mode: Option<Mode>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Model {
    pub run: bool,
    pub reverse: bool,
    pub output: f64,
    pub target: f64,
    pub reference: f64,
    pub mode: Option<Mode>,
    /// Register index of the frequency reference last written.
    pub reference_register: Option<usize>,
    /// The fault code the drive tripped with, until reset.
    pub fault: Option<u16>,
    /// The command profile's state (index), for a drive with one.
    pub machine: Option<u8>,
    /// An interlock holds (a safe torque off input open, the DC bus not charged): a drive with a
    /// command profile refuses the transitions towards running, still taking stops.
    pub interlock: bool,
}

fn rate(max_frequency: f64, seconds: f64) -> f64 {
    if seconds > 0.0 && seconds.is_finite() {
        max_frequency / seconds
    } else {
        f64::INFINITY
    }
}

impl Model {
    /// Sets the target from the commands and a reference (Hz, clamped to `0..=max`).
    pub(crate) fn aim(&mut self, reference: f64, max_frequency: f64) {
        let reference = if reference.is_finite() {
            reference.abs().min(max_frequency)
        } else {
            0.0
        };
        self.reference = reference;
        self.target = match (self.run, self.reverse) {
            (false, _) => 0.0,
            (true, false) => reference,
            (true, true) => -reference,
        };
    }

    /// Moves the output towards the target for `dt` seconds.
    pub(crate) fn advance(&mut self, dt: f64, max_frequency: f64, accel_s: f64, decel_s: f64) {
        let up = rate(max_frequency, accel_s);
        let down = rate(max_frequency, decel_s);
        let mut left = if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
        let target = self.target;
        let mut out = self.output;
        // At most: down to 0, then up to the target.
        for _ in 0..3 {
            if out == target {
                break;
            }
            let same_side = out == 0.0 || (target != 0.0 && target.signum() == out.signum());
            if same_side && target.abs() > out.abs() {
                let need = (target - out).abs() / up;
                if need <= left {
                    out = target;
                } else {
                    out += target.signum() * up * left;
                }
                break;
            }
            // Towards 0: to the target if it lies on this side, else to 0 first.
            let stop_at = if same_side { target } else { 0.0 };
            let need = (out - stop_at).abs() / down;
            if need <= left {
                left -= need;
                out = stop_at;
            } else {
                out -= out.signum() * down * left;
                break;
            }
        }
        self.output = out;
    }

    pub(crate) fn running(&self) -> bool {
        self.run || self.output != 0.0
    }

    fn reverse_now(&self) -> bool {
        if self.output != 0.0 {
            self.output < 0.0
        } else {
            (self.running() && self.target < 0.0)
                || (self.run && self.reverse && self.target == 0.0)
        }
    }

    fn at_reference(&self) -> bool {
        self.run && (self.output - self.target).abs() < 1e-9
    }

    /// Whether a status condition holds.
    pub(crate) fn holds(&self, c: Condition) -> bool {
        let moving = (self.output - self.target).abs() >= 1e-9;
        let accelerating = self.run
            && moving
            && self.target.abs() > self.output.abs()
            && (self.output == 0.0 || self.output.signum() == self.target.signum());
        match c {
            Condition::Never => false,
            Condition::Fault => self.fault.is_some(),
            Condition::Ready => self.mode != Some(Mode::Prg) && self.fault.is_none(),
            Condition::Running => self.running(),
            Condition::Reverse => self.running() && self.reverse_now(),
            Condition::ZeroSpeed => self.output == 0.0,
            Condition::SpeedAgree => self.at_reference(),
            Condition::Accelerating => accelerating,
            Condition::Decelerating => self.run && moving && !accelerating,
            Condition::Stopping => !self.run && self.output != 0.0,
            Condition::DrvMode => self.mode == Some(Mode::Drv),
        }
    }

    pub(crate) fn state(&self) -> DriveState {
        DriveState {
            output_hz: self.output,
            target_hz: self.target,
            reference_hz: self.reference,
            run_command: self.run,
            reverse_command: self.reverse,
            running: self.running(),
            mode: self.mode,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(run: bool, reverse: bool, reference: f64) -> Model {
        let mut m = Model {
            run,
            reverse,
            ..Model::default()
        };
        m.aim(reference, 60.0);
        m
    }

    #[test]
    fn ramps_up_at_the_accel_rate_and_stops_at_the_reference() {
        let mut m = model(true, false, 48.0);
        m.advance(2.0, 60.0, 10.0, 10.0); // 6 Hz/s
        assert!((m.output - 12.0).abs() < 1e-9, "{}", m.output);
        assert!(m.holds(Condition::Accelerating) && !m.holds(Condition::SpeedAgree));
        m.advance(100.0, 60.0, 10.0, 10.0);
        assert_eq!(m.output, 48.0);
        assert!(m.holds(Condition::SpeedAgree));
    }

    #[test]
    fn reversing_ramps_through_zero() {
        let mut m = model(true, false, 30.0);
        m.advance(100.0, 60.0, 10.0, 5.0);
        m.reverse = true;
        m.aim(30.0, 60.0);
        // 12 Hz/s down: 2.5 s to 0, then 6 Hz/s up for 0.5 s.
        m.advance(3.0, 60.0, 10.0, 5.0);
        assert!((m.output + 3.0).abs() < 1e-9, "{}", m.output);
        assert!(m.holds(Condition::Reverse));
    }

    #[test]
    fn stop_ramps_down_and_running_holds_until_zero() {
        let mut m = model(true, false, 60.0);
        m.advance(100.0, 60.0, 0.0, 0.0);
        assert_eq!(m.output, 60.0, "time 0 jumps");
        m.run = false;
        m.aim(60.0, 60.0);
        m.advance(1.0, 60.0, 10.0, 20.0); // 3 Hz/s down
        assert!((m.output - 57.0).abs() < 1e-9);
        assert!(m.holds(Condition::Running) && m.holds(Condition::Stopping));
        m.advance(100.0, 60.0, 10.0, 20.0);
        assert_eq!(m.output, 0.0);
        assert!(!m.holds(Condition::Running) && m.holds(Condition::ZeroSpeed));
    }

    #[test]
    fn references_beyond_max_are_clamped_and_nan_is_zero() {
        let mut m = model(true, true, 500.0);
        assert_eq!(m.target, -60.0);
        m.aim(f64::NAN, 60.0);
        assert_eq!(m.target, 0.0);
    }
}
