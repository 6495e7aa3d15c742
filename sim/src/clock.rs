//! Time for the drive model, injectable so tests are deterministic.
//!
//! The model asks its [`Clock`] how much time has passed since the simulator started and ramps
//! the output frequency by that much. [`SystemClock`] follows the wall clock, optionally faster
//! (`time_scale` 10 makes a 10 s ramp take 1 s); [`ManualClock`] moves only when a test says so.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// A monotonic source of simulated time.
pub trait Clock: Send + Sync + fmt::Debug {
    /// Simulated time elapsed since the clock's origin. Never decreases.
    fn now(&self) -> Duration;
}

/// Real time, optionally sped up.
#[derive(Debug, Clone, Copy)]
pub struct SystemClock {
    origin: Instant,
    scale: f64,
}

impl SystemClock {
    /// Real time from now on.
    pub fn new() -> SystemClock {
        SystemClock::scaled(1.0)
    }

    /// Real time multiplied by `scale` (a non-finite or non-positive scale counts as 1).
    pub fn scaled(scale: f64) -> SystemClock {
        let scale = if scale.is_finite() && scale > 0.0 {
            scale
        } else {
            1.0
        };
        SystemClock {
            origin: Instant::now(),
            scale,
        }
    }

    /// The speed-up factor.
    pub fn scale(&self) -> f64 {
        self.scale
    }
}

impl Default for SystemClock {
    fn default() -> Self {
        SystemClock::new()
    }
}

impl Clock for SystemClock {
    fn now(&self) -> Duration {
        let real = self.origin.elapsed();
        if self.scale == 1.0 {
            real
        } else {
            Duration::try_from_secs_f64(real.as_secs_f64() * self.scale).unwrap_or(Duration::MAX)
        }
    }
}

/// A clock that moves only when told to; clones share the same time.
#[derive(Debug, Clone, Default)]
pub struct ManualClock {
    nanos: Arc<AtomicU64>,
}

impl ManualClock {
    /// A clock at time zero.
    pub fn new() -> ManualClock {
        ManualClock::default()
    }

    /// Moves the clock forward by `by`.
    pub fn advance(&self, by: Duration) {
        let by = u64::try_from(by.as_nanos()).unwrap_or(u64::MAX);
        let _ = self
            .nanos
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                Some(n.saturating_add(by))
            });
    }
}

impl Clock for ManualClock {
    fn now(&self) -> Duration {
        Duration::from_nanos(self.nanos.load(Ordering::SeqCst))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manual_clock_moves_only_when_told_and_clones_share_time() {
        let c = ManualClock::new();
        let d = c.clone();
        assert_eq!(c.now(), Duration::ZERO);
        c.advance(Duration::from_millis(1500));
        assert_eq!(d.now(), Duration::from_millis(1500));
    }

    #[test]
    fn scaled_clock_runs_faster() {
        let c = SystemClock::scaled(1000.0);
        std::thread::sleep(Duration::from_millis(5));
        assert!(c.now() >= Duration::from_secs(5), "{:?}", c.now());
        assert_eq!(SystemClock::scaled(f64::NAN).scale(), 1.0);
        assert_eq!(SystemClock::scaled(-2.0).scale(), 1.0);
    }
}
