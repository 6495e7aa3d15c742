//! Commands as intents with deadlines: what MQTT asked of each drive, kept as the latest wish
//! per drive and register (never a queue of stale presses), handed to the drive's link between
//! any two requests.
//!
//! - A **stop** is never refused for a rate or a full queue: it replaces a pending run and
//!   drops every pending reference, set and fault reset of its drive (each reported as
//!   superseded), goes to the line before the link's next request, and is offered again after
//!   a failed delivery (link down, no answer) until it is delivered or a later run replaces it.
//! - A **run**, **reference**, **set** or **fault reset** carries a deadline: one still pending
//!   past it is dropped and reported as expired, never carried out late. A newer one of the same
//!   kind (the same register for a set) replaces an older one, which is reported as superseded.
//! - The board holds at most one stop or run, one reference, one fault reset and one set per
//!   register of each drive, whatever arrives: its size is bounded by the maps, not by a flood.
//!
//! The MQTT side offers ([`Board::offer`]); the link takes what is due ([`Board::next`]) and
//! gives back an undelivered stop ([`Board::retry_stop`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crate::link::{Action, Command};

/// How long a run, reference, set or fault reset may wait for its link by default.
pub const DEFAULT_DEADLINE: Duration = Duration::from_secs(3);

/// Time between two deliveries of a stop that failed.
pub const STOP_RETRY: Duration = Duration::from_millis(200);

/// A command received, with when it came and until when it may be carried out.
#[derive(Debug, Clone)]
pub struct Intent {
    /// The command.
    pub command: Command,
    /// When it was received.
    pub received: Instant,
    /// Past this it is dropped (a stop has none).
    pub deadline: Option<Instant>,
    /// A stop that failed is not offered again before this.
    retry_at: Instant,
    /// Deliveries of a stop that failed so far.
    pub attempts: u32,
}

impl Intent {
    /// A command received at `now`, with `deadline` for all but a stop.
    pub fn new(command: Command, now: Instant, deadline: Duration) -> Intent {
        let stop = command.action == Action::Stop;
        Intent {
            command,
            received: now,
            deadline: (!stop).then(|| now + deadline),
            retry_at: now,
            attempts: 0,
        }
    }
}

/// What the link is to do next.
#[derive(Debug)]
pub enum Next {
    /// Carry it out now.
    Due(Intent),
    /// Past its deadline: report it, write nothing.
    Expired(Intent),
}

/// What became of the pending commands of a drive when one was offered.
#[derive(Debug)]
pub struct Superseded(pub Vec<Intent>);

/// The pending commands of one drive.
#[derive(Debug, Default)]
struct Pending {
    /// The latest of stop and run.
    motion: Option<Intent>,
    reference: Option<Intent>,
    fault_reset: Option<Intent>,
    /// The latest per register (by the register's id).
    sets: Vec<(String, Intent)>,
}

impl Pending {
    fn is_empty(&self) -> bool {
        self.motion.is_none()
            && self.reference.is_none()
            && self.fault_reset.is_none()
            && self.sets.is_empty()
    }

    fn stop_due(&self, now: Instant) -> bool {
        self.motion
            .as_ref()
            .is_some_and(|m| m.command.action == Action::Stop && m.retry_at <= now)
    }

    /// The first expired intent, taken out.
    fn take_expired(&mut self, now: Instant) -> Option<Intent> {
        let expired = |i: &Intent| i.deadline.is_some_and(|d| d <= now);
        for slot in [&mut self.motion, &mut self.reference, &mut self.fault_reset] {
            if slot.as_ref().is_some_and(expired) {
                return slot.take();
            }
        }
        let at = self.sets.iter().position(|(_, i)| expired(i))?;
        Some(self.sets.remove(at).1)
    }

    /// The earliest received intent other than a stop, taken out.
    fn take_earliest(&mut self) -> Option<Intent> {
        let mut best: Option<(Instant, usize)> = None;
        let mut consider = |at: Instant, which: usize| {
            if best.is_none_or(|(b, _)| at < b) {
                best = Some((at, which));
            }
        };
        if let Some(m) = &self.motion
            && m.command.action != Action::Stop
        {
            consider(m.received, 0);
        }
        if let Some(r) = &self.reference {
            consider(r.received, 1);
        }
        if let Some(f) = &self.fault_reset {
            consider(f.received, 2);
        }
        for (k, (_, s)) in self.sets.iter().enumerate() {
            consider(s.received, 3 + k);
        }
        match best?.1 {
            0 => self.motion.take(),
            1 => self.reference.take(),
            2 => self.fault_reset.take(),
            k => Some(self.sets.remove(k - 3).1),
        }
    }
}

/// The pending commands of every drive of the bridge, shared by the MQTT side and the links.
pub struct Board {
    drives: Mutex<Vec<Pending>>,
    /// Rung when something is offered, so a waiting link wakes at once.
    bell: Condvar,
    /// Per drive: the drive answered its link's last poll (commands other than a stop are
    /// refused at once while it does not).
    answering: Vec<AtomicBool>,
    deadline: Duration,
    /// Rung since the last wait.
    rung: Mutex<bool>,
}

impl Board {
    /// A board for `drives` drives, each command but a stop valid for `deadline`.
    pub fn new(drives: usize, deadline: Duration) -> Board {
        Board {
            drives: Mutex::new((0..drives).map(|_| Pending::default()).collect()),
            bell: Condvar::new(),
            answering: (0..drives).map(|_| AtomicBool::new(false)).collect(),
            deadline,
            rung: Mutex::new(false),
        }
    }

    /// How long a command may wait.
    pub fn deadline(&self) -> Duration {
        self.deadline
    }

    fn lock(&self) -> MutexGuard<'_, Vec<Pending>> {
        // A panic while holding the lock leaves plain data: go on with it.
        self.drives.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records whether drive `drive` answered its last poll.
    pub fn set_answering(&self, drive: usize, answering: bool) {
        if let Some(a) = self.answering.get(drive) {
            a.store(answering, Ordering::Relaxed);
        }
    }

    /// Whether drive `drive` answered its last poll.
    pub fn answering(&self, drive: usize) -> bool {
        self.answering
            .get(drive)
            .is_some_and(|a| a.load(Ordering::Relaxed))
    }

    /// Takes `command` (received now) as the latest wish for its drive, keyed by `key` (the
    /// register's id for a set); returns the pending commands it replaced.
    pub fn offer(&self, command: Command, key: &str, now: Instant) -> Superseded {
        let intent = Intent::new(command, now, self.deadline);
        let mut drives = self.lock();
        let Some(p) = drives.get_mut(intent.command.drive) else {
            return Superseded(Vec::new());
        };
        let mut gone = Vec::new();
        match &intent.command.action {
            Action::Stop => {
                gone.extend(p.motion.take());
                gone.extend(p.reference.take());
                gone.extend(p.fault_reset.take());
                gone.extend(p.sets.drain(..).map(|(_, i)| i));
                p.motion = Some(intent);
            }
            Action::Run => {
                gone.extend(p.motion.replace(intent));
            }
            Action::Reference => gone.extend(p.reference.replace(intent)),
            Action::FaultReset => gone.extend(p.fault_reset.replace(intent)),
            Action::Set { .. } => match p.sets.iter_mut().find(|(k, _)| k == key) {
                Some((_, old)) => gone.push(std::mem::replace(old, intent)),
                None => p.sets.push((key.to_owned(), intent)),
            },
        }
        drop(drives);
        self.bell.notify_all();
        Superseded(gone)
    }

    /// What the link of drives `first..first + count` is to do next at `now`: a due stop of any
    /// of them first, then an expired command to report, then the earliest received command.
    pub fn next(&self, first: usize, count: usize, now: Instant) -> Option<Next> {
        let mut drives = self.lock();
        let end = (first + count).min(drives.len());
        let mine = drives.get_mut(first..end)?;
        for p in mine.iter_mut() {
            if p.stop_due(now) {
                return p.motion.take().map(Next::Due);
            }
        }
        for p in mine.iter_mut() {
            if let Some(e) = p.take_expired(now) {
                return Some(Next::Expired(e));
            }
        }
        let (earliest, _) = mine
            .iter()
            .enumerate()
            .filter_map(|(k, p)| {
                let at = [
                    p.motion
                        .as_ref()
                        .filter(|m| m.command.action != Action::Stop),
                    p.reference.as_ref(),
                    p.fault_reset.as_ref(),
                ]
                .into_iter()
                .flatten()
                .chain(p.sets.iter().map(|(_, i)| i))
                .map(|i| i.received)
                .min()?;
                Some((k, at))
            })
            .min_by_key(|&(_, at)| at)?;
        mine[earliest].take_earliest().map(Next::Due)
    }

    /// Takes out every command of drives `first..first + count` past its deadline at `now`.
    pub fn expired(&self, first: usize, count: usize, now: Instant) -> Vec<Intent> {
        let mut drives = self.lock();
        let end = (first + count).min(drives.len());
        let mut out = Vec::new();
        if let Some(mine) = drives.get_mut(first..end) {
            for p in mine {
                while let Some(e) = p.take_expired(now) {
                    out.push(e);
                }
            }
        }
        out
    }

    /// Gives back a stop whose delivery failed: offered again after [`STOP_RETRY`], unless a
    /// run or another stop came meanwhile (then that one stands). Returns whether it was kept.
    pub fn retry_stop(&self, mut stop: Intent, now: Instant) -> bool {
        let mut drives = self.lock();
        let Some(p) = drives.get_mut(stop.command.drive) else {
            return false;
        };
        if p.motion.is_some() {
            return false;
        }
        stop.attempts += 1;
        stop.retry_at = now + STOP_RETRY;
        p.motion = Some(stop);
        true
    }

    /// Whether drives `first..first + count` have nothing pending.
    pub fn idle(&self, first: usize, count: usize) -> bool {
        let drives = self.lock();
        let end = (first + count).min(drives.len());
        drives
            .get(first..end)
            .is_none_or(|d| d.iter().all(Pending::is_empty))
    }

    /// Waits until something is offered (or [`Board::ring`] is called) or `timeout` passes.
    pub fn wait(&self, timeout: Duration) {
        let drives = self.lock();
        if std::mem::take(&mut *self.rung.lock().unwrap_or_else(|e| e.into_inner())) {
            return;
        }
        let _ = self.bell.wait_timeout(drives, timeout);
    }

    /// Wakes the links waiting on the board (a proxied request came); a link that is not
    /// waiting does not wait at its next [`Board::wait`].
    pub fn ring(&self) {
        let _drives = self.lock();
        *self.rung.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.bell.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivemap_test_support::rng::SplitMix;

    fn command(drive: usize, action: Action, n: usize) -> Command {
        Command {
            drive,
            action,
            topic: format!("t/{n}"),
            payload: format!("{n}"),
        }
    }

    fn action(r: u64) -> Action {
        match r % 5 {
            0 => Action::Run,
            1 => Action::Stop,
            2 => Action::Reference,
            3 => Action::FaultReset,
            _ => Action::Set {
                register: format!("r{}", r % 3),
            },
        }
    }

    /// Random offers, takes, failed stops and clock steps against a model of what must hold:
    /// a stop is handed out before anything else of its link and is only ever dropped by a
    /// later run; nothing is handed out past its deadline; a run handed out was received after
    /// every stop received for its drive (a run never overtakes a later stop); the board never
    /// holds more than one motion, reference, fault reset and set per register of a drive; every
    /// command offered comes out exactly once (handed out, expired or superseded).
    #[test]
    fn intents_keep_the_contract_under_random_interleavings() {
        for seed in 0..2_000u64 {
            let mut rng = SplitMix(seed);
            let deadline = Duration::from_millis(50 + rng.next_u64() % 200);
            let drives = 1 + (rng.next_u64() % 3) as usize;
            let board = Board::new(drives, deadline);
            let t0 = Instant::now();
            let mut now = t0;
            let mut offered = 0usize;
            let mut out = 0usize;
            let mut last_stop: Vec<Option<Instant>> = vec![None; drives];
            for step in 0..60 {
                match rng.next_u64() % 4 {
                    0 | 1 => {
                        let d = (rng.next_u64() % drives as u64) as usize;
                        let a = action(rng.next_u64());
                        let key = match &a {
                            Action::Set { register } => register.clone(),
                            _ => String::new(),
                        };
                        if a == Action::Stop {
                            last_stop[d] = Some(now);
                        }
                        offered += 1;
                        let gone = board.offer(command(d, a, step), &key, now);
                        for g in &gone.0 {
                            // Only a stop supersedes a stop, or a run.
                            if g.command.action == Action::Stop {
                                assert!(board.lock()[d].motion.is_some(), "seed {seed}");
                            }
                        }
                        out += gone.0.len();
                    }
                    2 => {
                        let stop_pending: Vec<bool> =
                            board.lock().iter().map(|p| p.stop_due(now)).collect();
                        match board.next(0, drives, now) {
                            Some(Next::Due(i)) => {
                                if stop_pending.iter().any(|&s| s) {
                                    assert_eq!(i.command.action, Action::Stop, "seed {seed}");
                                }
                                if let Some(d) = i.deadline {
                                    assert!(now < d, "seed {seed}: handed out late");
                                }
                                if i.command.action == Action::Run
                                    && let Some(s) = last_stop[i.command.drive]
                                {
                                    assert!(i.received >= s, "seed {seed}: a run overtook a stop");
                                }
                                if i.command.action == Action::Stop && rng.chance(50) {
                                    // Delivery failed: given back, or dropped for a later run.
                                    if !board.retry_stop(i, now) {
                                        out += 1;
                                    }
                                } else {
                                    out += 1;
                                }
                            }
                            Some(Next::Expired(i)) => {
                                assert!(i.deadline.is_some_and(|d| d <= now), "seed {seed}");
                                assert_ne!(i.command.action, Action::Stop, "seed {seed}");
                                out += 1;
                            }
                            None => assert!(
                                board.lock().iter().all(|p| {
                                    p.motion.as_ref().is_none_or(|m| {
                                        m.command.action == Action::Stop && m.retry_at > now
                                    }) && p.reference.is_none()
                                        && p.fault_reset.is_none()
                                        && p.sets.is_empty()
                                }),
                                "seed {seed}: something due was not handed out"
                            ),
                        }
                    }
                    _ => now += Duration::from_millis(rng.next_u64() % 120),
                }
                for p in board.lock().iter() {
                    assert!(p.sets.len() <= 3, "seed {seed}");
                }
            }
            // Drain: everything offered comes out once.
            now += Duration::from_secs(3600);
            while let Some(n) = board.next(0, drives, now) {
                match n {
                    Next::Due(i) => assert_eq!(i.command.action, Action::Stop, "seed {seed}"),
                    Next::Expired(_) => {}
                }
                out += 1;
            }
            assert_eq!(offered, out, "seed {seed}");
        }
    }

    #[test]
    fn a_stop_drops_the_runs_references_and_sets_pending_before_it() {
        let board = Board::new(1, DEFAULT_DEADLINE);
        let now = Instant::now();
        board.offer(command(0, Action::Reference, 1), "", now);
        board.offer(command(0, Action::Run, 2), "", now);
        board.offer(
            command(
                0,
                Action::Set {
                    register: "x".into(),
                },
                3,
            ),
            "x",
            now,
        );
        let gone = board.offer(command(0, Action::Stop, 4), "", now);
        assert_eq!(gone.0.len(), 3);
        match board.next(0, 1, now) {
            Some(Next::Due(i)) => assert_eq!(i.command.action, Action::Stop),
            other => panic!("{other:?}"),
        }
        assert!(board.next(0, 1, now).is_none());
    }

    #[test]
    fn a_run_is_dropped_past_its_deadline_and_a_stop_is_not() {
        let board = Board::new(1, Duration::from_millis(100));
        let now = Instant::now();
        board.offer(command(0, Action::Run, 1), "", now);
        let later = now + Duration::from_millis(100);
        assert!(matches!(board.next(0, 1, later), Some(Next::Expired(_))));
        board.offer(command(0, Action::Stop, 2), "", now);
        let much_later = now + Duration::from_secs(3600);
        assert!(matches!(board.next(0, 1, much_later), Some(Next::Due(_))));
    }
}
