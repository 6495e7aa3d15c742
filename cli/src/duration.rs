//! Durations as users type them: `500ms`, `2s`, `1.5s`, `250us`; a bare number is milliseconds.

use std::time::Duration;

/// Parses a duration for a command-line option.
pub fn parse(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let (number, unit) = match t.find(|c: char| !(c.is_ascii_digit() || c == '.')) {
        Some(i) => t.split_at(i),
        None => (t, "ms"),
    };
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a duration (try 500ms or 2s)"))?;
    let seconds = match unit.trim() {
        "ms" => value / 1000.0,
        "s" => value,
        "us" | "µs" => value / 1_000_000.0,
        "m" | "min" => value * 60.0,
        other => {
            return Err(format!(
                "`{other}` is not a unit of time in `{text}` (use us, ms, s or min)"
            ));
        }
    };
    Duration::try_from_secs_f64(seconds).map_err(|_| format!("`{text}` is out of range"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units() {
        assert_eq!(parse("500ms").unwrap(), Duration::from_millis(500));
        assert_eq!(parse("2s").unwrap(), Duration::from_secs(2));
        assert_eq!(parse("1.5s").unwrap(), Duration::from_millis(1500));
        assert_eq!(parse("250").unwrap(), Duration::from_millis(250));
        assert_eq!(parse("100us").unwrap(), Duration::from_micros(100));
        assert!(parse("fast").is_err());
        assert!(parse("5 parsecs").is_err());
        assert!(parse("").is_err());
    }
}
