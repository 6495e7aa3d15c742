//! Counting writes to the drives' non-volatile memory.
//!
//! The manuals warn that the parameter EEPROM fails after about 100,000 writes (V7
//! `000_032dced3a1e91a75.txt:1506`, GPD 515 `001_ef66da56d29a05af.txt:437-442`, MEMOBUS
//! `003_8bcf5d50afb8e230.txt:728`). A program that saves in a loop destroys a drive within days,
//! so saving is an explicit call that a [`PersistBudget`] allows a limited number of times per
//! rolling hour.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::error::Refusal;

/// The rolling window of the budget.
pub const WINDOW: Duration = Duration::from_secs(3600);

/// A budget of EEPROM writes per rolling hour, and the count of all writes made.
#[derive(Debug, Clone)]
pub struct PersistBudget {
    per_hour: u32,
    recent: VecDeque<Instant>,
    total: u64,
}

impl PersistBudget {
    /// A budget of `per_hour` writes in any hour. Storage is allocated here, once.
    pub fn new(per_hour: u32) -> PersistBudget {
        PersistBudget {
            per_hour,
            recent: VecDeque::with_capacity(per_hour.min(4096) as usize),
            total: 0,
        }
    }

    /// Writes allowed per hour.
    pub fn per_hour(&self) -> u32 {
        self.per_hour
    }

    /// Writes made through this budget since it was created.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Writes made in the hour before `now`.
    pub fn used(&mut self, now: Instant) -> u32 {
        self.expire(now);
        self.recent.len() as u32
    }

    fn expire(&mut self, now: Instant) {
        while let Some(&t) = self.recent.front() {
            if now.saturating_duration_since(t) >= WINDOW {
                self.recent.pop_front();
            } else {
                break;
            }
        }
    }

    /// Takes one write from the budget at `now`, or refuses with when the next is allowed.
    pub fn take(&mut self, now: Instant) -> Result<(), Refusal> {
        self.expire(now);
        if self.recent.len() as u64 >= u64::from(self.per_hour) {
            let next_in = self
                .recent
                .front()
                .map(|&t| WINDOW.saturating_sub(now.saturating_duration_since(t)))
                .unwrap_or(WINDOW);
            return Err(Refusal::EepromBudget {
                used: self.recent.len() as u32,
                budget: self.per_hour,
                next_in,
            });
        }
        self.recent.push_back(now);
        self.total += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_refuses_within_the_hour_and_allows_after() {
        let t0 = Instant::now();
        let mut b = PersistBudget::new(3);
        for i in 0..3 {
            b.take(t0 + Duration::from_secs(i * 60)).unwrap();
        }
        let refused = b.take(t0 + Duration::from_secs(600)).unwrap_err();
        assert_eq!(
            refused,
            Refusal::EepromBudget {
                used: 3,
                budget: 3,
                next_in: Duration::from_secs(3000)
            }
        );
        assert_eq!(b.total(), 3);
        // One hour after the first write, one write is free again, not two.
        b.take(t0 + WINDOW).unwrap();
        assert!(b.take(t0 + WINDOW + Duration::from_secs(1)).is_err());
        assert_eq!(b.used(t0 + WINDOW + Duration::from_secs(60)), 2);
        assert_eq!(b.total(), 4);
    }

    #[test]
    fn zero_budget_refuses_everything() {
        let mut b = PersistBudget::new(0);
        assert!(b.take(Instant::now()).is_err());
        assert_eq!(b.total(), 0);
    }
}
