//! What the bridge says about untrusted text (topics and payloads from the broker): quoted,
//! escaped and shortened, so a payload cannot forge a log line or fill a disk; and how often it
//! says it (refusals are counted always, logged at a bounded rate).

use std::time::{Duration, Instant};

/// Characters of untrusted text quoted at the most.
pub(crate) const QUOTED_CHARS: usize = 64;

/// `text` in double quotes, control characters, quotes and backslashes escaped, cut after
/// [`QUOTED_CHARS`] characters with the length of the whole said: `"OFF"`,
/// `"line\nforged"`, `"aaaa…" (1048576 bytes)`.
pub(crate) fn quote(text: &str) -> String {
    let mut out = String::from("\"");
    let mut cut = false;
    for (n, c) in text.chars().enumerate() {
        if n == QUOTED_CHARS {
            cut = true;
            break;
        }
        out.extend(c.escape_debug());
    }
    if cut {
        out.push_str(&format!("…\" ({} bytes)", text.len()));
    } else {
        out.push('"');
    }
    out
}

/// `text` cut after `max` characters (with `…`), for JSON values (which escape the rest).
pub(crate) fn shorten(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text.to_owned(),
    }
}

/// Lets at most `burst` lines through per `window`, and counts the rest, so that a flood of
/// refusals costs a bounded log.
#[derive(Debug)]
pub(crate) struct Limiter {
    burst: u32,
    window: Duration,
    start: Instant,
    said: u32,
    held: u64,
}

impl Limiter {
    /// At most `burst` lines per `window`.
    pub(crate) fn new(burst: u32, window: Duration) -> Limiter {
        Limiter {
            burst,
            window,
            start: Instant::now(),
            said: 0,
            held: 0,
        }
    }

    /// Whether a line may be said now; when one may after some were held back, the count of
    /// those is returned too (`Some(n)`: say "n more not logged").
    pub(crate) fn allow(&mut self, now: Instant) -> (bool, Option<u64>) {
        if now.duration_since(self.start) >= self.window {
            self.start = now;
            self.said = 0;
        }
        if self.said < self.burst {
            self.said += 1;
            let held = std::mem::take(&mut self.held);
            (true, (held > 0).then_some(held))
        } else {
            self.held += 1;
            (false, None)
        }
    }
}

impl Default for Limiter {
    /// Ten lines per ten seconds.
    fn default() -> Limiter {
        Limiter::new(10, Duration::from_secs(10))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn untrusted_text_is_escaped_and_shortened() {
        assert_eq!(quote("OFF"), "\"OFF\"");
        assert_eq!(
            quote("x\nbridge: command on a/command/stop (PRESS): stopped"),
            "\"x\\nbridge: command on a/command/stop (PRESS): stopped\""
        );
        let long = "a".repeat(1 << 20);
        let q = quote(&long);
        assert!(q.len() < 100, "{q}");
        assert!(q.ends_with("(1048576 bytes)"), "{q}");
        assert!(!quote("\u{1b}[2J\r").contains('\u{1b}'));
    }

    #[test]
    fn a_flood_is_logged_at_the_bounded_rate_and_counted() {
        let mut l = Limiter::new(3, Duration::from_secs(10));
        let t = Instant::now();
        let said = (0..100).filter(|_| l.allow(t).0).count();
        assert_eq!(said, 3);
        let (ok, held) = l.allow(t + Duration::from_secs(10));
        assert!(ok);
        assert_eq!(held, Some(97));
    }
}
