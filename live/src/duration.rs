//! Durations as users type them: `500ms`, `2s`, `1.5s`, `250us`; a bare number is milliseconds.
//! Every duration and number option of the `drivemap` command is range-checked here, when clap
//! parses it, so no command meets an infinite, negative or absurd value
//! (`Duration::from_secs_f64` and `Instant + d` panic on those; a zero time scale loops for ever).

use std::time::Duration;

/// The longest duration an option takes: one hour (timeouts, poll intervals, request gaps).
pub const MAX: Duration = Duration::from_secs(3600);

/// Why a text is not a duration or number an option takes; each names the text.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParseError {
    /// Not a number followed by a unit.
    #[error("`{0}` is not a duration (try 500ms or 2s)")]
    NotADuration(String),
    /// A number with a unit that is not one of time.
    #[error("`{unit}` is not a unit of time in `{text}` (use us, ms, s or min)")]
    NotAUnit {
        /// The unit as typed.
        unit: String,
        /// The whole text.
        text: String,
    },
    /// Longer than [`MAX`].
    #[error("`{0}` is longer than the 1 hour an option allows")]
    TooLong(String),
    /// Not representable as a [`Duration`].
    #[error("`{0}` is out of range")]
    OutOfRange(String),
    /// Zero where a timeout is wanted.
    #[error(
        "`{0}` is zero: a timeout of 0 expires before anything can arrive; give a duration longer than 0 (e.g. 500ms or 2s)"
    )]
    Zero(String),
    /// Not a number.
    #[error("`{0}` is not a number")]
    NotANumber(String),
    /// A number outside the option's range (or not finite).
    #[error("`{text}` is outside {min}..={max}")]
    Outside {
        /// The text.
        text: String,
        /// The least value taken.
        min: f64,
        /// The greatest value taken.
        max: f64,
    },
}

/// Parses a duration for a command-line option: at most [`MAX`].
pub fn parse(text: &str) -> Result<Duration, ParseError> {
    let d = parse_any(text)?;
    if d > MAX {
        return Err(ParseError::TooLong(text.to_owned()));
    }
    Ok(d)
}

/// Parses a duration that must be longer than zero: a timeout of 0 would give up before any
/// reply could arrive (or close every connection at once), so it is refused with what it means.
pub fn positive(text: &str) -> Result<Duration, ParseError> {
    let d = parse(text)?;
    if d.is_zero() {
        return Err(ParseError::Zero(text.to_owned()));
    }
    Ok(d)
}

/// A value parser for a number option in `min..=max` (finite; `inf`, `nan` refused).
pub fn number(
    min: f64,
    max: f64,
) -> impl Fn(&str) -> Result<f64, ParseError> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let v: f64 = text
            .trim()
            .parse()
            .map_err(|_| ParseError::NotANumber(text.to_owned()))?;
        if v.is_finite() && (min..=max).contains(&v) {
            Ok(v)
        } else {
            Err(ParseError::Outside {
                text: text.to_owned(),
                min,
                max,
            })
        }
    }
}

fn parse_any(text: &str) -> Result<Duration, ParseError> {
    let t = text.trim();
    let (number, unit) = match t.find(|c: char| !(c.is_ascii_digit() || c == '.')) {
        Some(i) => t.split_at(i),
        None => (t, "ms"),
    };
    let value: f64 = number
        .parse()
        .map_err(|_| ParseError::NotADuration(text.to_owned()))?;
    let seconds = match unit.trim() {
        "ms" => value / 1000.0,
        "s" => value,
        "us" | "µs" => value / 1_000_000.0,
        "m" | "min" => value * 60.0,
        other => {
            return Err(ParseError::NotAUnit {
                unit: other.to_owned(),
                text: text.to_owned(),
            });
        }
    };
    if seconds > MAX.as_secs_f64() {
        return Err(ParseError::TooLong(text.to_owned()));
    }
    Duration::try_from_secs_f64(seconds).map_err(|_| ParseError::OutOfRange(text.to_owned()))
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
        assert_eq!(
            parse("1h").unwrap_err().to_string(),
            "`h` is not a unit of time in `1h` (use us, ms, s or min)"
        );
        assert_eq!(parse("60min").unwrap(), MAX);
        assert!(
            parse("61min")
                .unwrap_err()
                .to_string()
                .contains("longer than the 1 hour")
        );
        assert!(parse("1e300s").is_err());
        assert!(
            parse(&"9".repeat(400))
                .unwrap_err()
                .to_string()
                .contains("longer than")
        );
    }

    #[test]
    fn zero_is_not_a_timeout() {
        assert!(positive("0s").unwrap_err().to_string().contains("is zero"));
        assert!(positive("0").unwrap_err().to_string().contains("is zero"));
        assert!(
            positive("0.0ms")
                .unwrap_err()
                .to_string()
                .contains("is zero")
        );
        assert_eq!(positive("1ms").unwrap(), Duration::from_millis(1));
        assert!(
            positive("61min")
                .unwrap_err()
                .to_string()
                .contains("longer than")
        );
    }

    #[test]
    fn numbers_are_finite_and_in_range() {
        let p = number(0.01, 1000.0);
        assert_eq!(p("4"), Ok(4.0));
        assert_eq!(
            p("1e-300").unwrap_err().to_string(),
            "`1e-300` is outside 0.01..=1000"
        );
        assert!(p("1e308").is_err());
        assert!(p("inf").is_err());
        assert!(p("NaN").is_err());
        assert!(p("-1").is_err());
        assert!(p("fast").is_err());
    }
}
