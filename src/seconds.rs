//! Durations that users give in seconds: the time budgets of `solve`,
//! `sweep` and `support` (and of their Python functions), the translation
//! budget and the interval between progress lines. One parser and one
//! conversion serve all of them, so that no number a user may type panics.
//!
//! A budget is a finite, non-negative number of seconds (0: no limit, where
//! the option allows it). A budget larger than the clock can hold (beyond
//! about 5.8e11 years for a [`Duration`], less for an [`Instant`] after
//! now), such as `1e20` or `1e308`, also means no limit: no run would ever
//! reach it. NaN, infinities and negative numbers are refused by name.

use std::time::{Duration, Instant};

/// Parses a time budget from the command line: a finite, non-negative
/// number of seconds ([`check`]).
pub fn parse(text: &str) -> Result<f64, String> {
    let seconds = number(text)?;
    check(seconds)?;
    Ok(seconds)
}

/// Parses a positive number of seconds from the command line ([`check_positive`]).
pub fn parse_positive(text: &str) -> Result<f64, String> {
    let seconds = number(text)?;
    check_positive(seconds)?;
    Ok(seconds)
}

/// `text` as a number, or an error naming it.
fn number(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .map_err(|_| format!("'{text}' is not a number of seconds"))
}

/// Checks a budget: finite and non-negative (any size; beyond the clock it
/// means no limit). The error reads "must be a finite, non-negative number
/// of seconds, got VALUE".
pub fn check(seconds: f64) -> Result<(), String> {
    if seconds.is_finite() && seconds >= 0.0 {
        Ok(())
    } else {
        Err(format!(
            "must be a finite, non-negative number of seconds, got {seconds}"
        ))
    }
}

/// Checks an interval: finite and positive (any size; beyond the clock it
/// means never).
pub fn check_positive(seconds: f64) -> Result<(), String> {
    if seconds.is_finite() && seconds > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "must be a finite, positive number of seconds, got {seconds}"
        ))
    }
}

/// `seconds` as a [`Duration`]; `None` when no `Duration` holds it (too
/// large, or not a checked number of seconds): no limit.
pub fn duration(seconds: f64) -> Option<Duration> {
    Duration::try_from_secs_f64(seconds).ok()
}

/// The instant `seconds` after `start`; `None` when the clock cannot hold
/// it (no limit).
pub fn after(start: Instant, seconds: f64) -> Option<Instant> {
    duration(seconds).and_then(|span| start.checked_add(span))
}

/// The deadline of a budget of `seconds` begun at `start`: `None` for 0
/// (no budget) or a budget beyond the clock (no limit either).
pub fn deadline(start: Instant, seconds: f64) -> Option<Instant> {
    (seconds > 0.0).then(|| after(start, seconds)).flatten()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_beyond_the_clock_mean_no_limit_and_never_panic() {
        let now = Instant::now();
        for seconds in [1e20, 1e308, f64::MAX, 1.8e19, 9.3e18] {
            assert_eq!(parse(&seconds.to_string()), Ok(seconds));
            assert_eq!(deadline(now, seconds), None, "{seconds}");
        }
        assert_eq!(duration(1e20), None);
        assert_eq!(deadline(now, 0.0), None);
        assert_eq!(deadline(now, 2.0), Some(now + Duration::from_secs(2)));
    }

    #[test]
    fn nan_infinity_negative_and_words_are_refused_by_name() {
        for text in ["NaN", "inf", "-inf", "-1"] {
            let message = parse(text).unwrap_err();
            assert!(
                message.contains("finite, non-negative"),
                "{text}: {message}"
            );
        }
        assert!(parse("soon").unwrap_err().contains("'soon'"));
        assert!(parse_positive("0").unwrap_err().contains("positive"));
        assert_eq!(parse_positive("1e300"), Ok(1e300));
    }
}
