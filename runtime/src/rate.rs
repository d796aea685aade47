//! What makes a node step: a fixed rate or a message arrival.

use crate::Error;
use std::time::Duration;

/// When a node's step function runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Trigger {
    /// Periodically, with this period.
    Every(Duration),
    /// Whenever a message arrives on this topic.
    OnMessage(String),
    /// At the times the node asks for with [`crate::Step::wake_at`]: first at once (time 0
    /// in lockstep), then only when asked. A player of recorded messages steps this way.
    Scheduled,
}

impl Trigger {
    /// Periodic trigger at `hz` steps per second.
    pub fn every_hz(hz: f64) -> Self {
        Trigger::Every(Duration::from_secs_f64(1.0 / hz))
    }

    pub fn on(topic: &str) -> Self {
        Trigger::OnMessage(topic.to_string())
    }

    pub fn period(&self) -> Option<Duration> {
        match self {
            Trigger::Every(p) => Some(*p),
            Trigger::OnMessage(_) | Trigger::Scheduled => None,
        }
    }
}

/// The longest duration Caravan accepts anywhere (ten years): nothing in a group runs longer,
/// and simulated time (u64 nanoseconds, 584 years) and deadlines never overflow below it.
pub const MAX_DURATION: Duration = Duration::from_secs(10 * 365 * 24 * 3600);

/// The shortest period a rate may have (1 µs, 1 MHz): a node cannot usefully step faster.
/// The launcher also keeps lockstep periods at or above the group's tick.
pub const MIN_PERIOD: Duration = Duration::from_micros(1);

/// Parses a rate: a frequency (`"50Hz"`, `"2.5 kHz"`) or a period (`"20ms"`, `"1s"`), with a
/// period between [`MIN_PERIOD`] and [`MAX_DURATION`].
pub fn parse_rate(text: &str) -> Result<Duration, Error> {
    let t = text.trim();
    let lower = t.to_ascii_lowercase();
    let hz = if let Some(n) = lower.strip_suffix("khz") {
        Some((n, 1e3))
    } else {
        lower.strip_suffix("hz").map(|n| (n, 1.0))
    };
    let period = match hz {
        Some((number, scale)) => {
            let f: f64 = number.trim().parse().map_err(|_| bad_rate(text))?;
            if !(f.is_finite() && f > 0.0) {
                return Err(bad_rate(text));
            }
            let secs = 1.0 / (f * scale);
            match Duration::try_from_secs_f64(secs) {
                Ok(period) if period <= MAX_DURATION => period,
                _ => return Err(rate_out_of_range(text)),
            }
        }
        None => parse_duration(t).map_err(|_| bad_rate(text))?,
    };
    if period.is_zero() {
        return Err(bad_rate(text));
    }
    if period < MIN_PERIOD {
        return Err(rate_out_of_range(text));
    }
    Ok(period)
}

fn rate_out_of_range(text: &str) -> Error {
    Error::Config(format!(
        "rate '{text}' is out of range: its period must be between 1 µs (1 MHz) and ten years"
    ))
}

fn bad_rate(text: &str) -> Error {
    Error::Config(format!(
        "'{text}' is not a rate; write a frequency like \"50Hz\" or a period like \"20ms\""
    ))
}

/// Parses a duration such as `"180s"`, `"2min"`, `"20ms"` or `"1.5s"`.
pub fn parse_duration(text: &str) -> Result<Duration, Error> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number.parse().map_err(|_| bad_duration(text))?;
    let scale = match unit.trim() {
        "ns" => 1e-9,
        "us" | "µs" => 1e-6,
        "ms" => 1e-3,
        "s" => 1.0,
        "min" | "m" => 60.0,
        "h" => 3600.0,
        _ => return Err(bad_duration(text)),
    };
    let secs = value * scale;
    if !secs.is_finite() || secs < 0.0 {
        return Err(bad_duration(text));
    }
    match Duration::try_from_secs_f64(secs) {
        Ok(d) if d <= MAX_DURATION => Ok(d),
        _ => Err(Error::Config(format!(
            "duration '{text}' is too long; Caravan accepts at most ten years"
        ))),
    }
}

/// Checks a number of seconds given on a command line (`--seconds 2.5`): finite, not negative,
/// at most [`MAX_DURATION`].
pub fn seconds(value: f64) -> Result<Duration, String> {
    if !value.is_finite() || value < 0.0 {
        return Err(format!("{value} is not a number of seconds (0 or more)"));
    }
    match Duration::try_from_secs_f64(value) {
        Ok(d) if d <= MAX_DURATION => Ok(d),
        _ => Err(format!("{value} s is too long; at most ten years")),
    }
}

fn bad_duration(text: &str) -> Error {
    Error::Config(format!(
        "'{text}' is not a duration; write a number and a unit: ns, us, ms, s, min or h (\"20ms\", \"180s\")"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_and_periods() {
        assert_eq!(parse_rate("50Hz").unwrap(), Duration::from_millis(20));
        assert_eq!(parse_rate("20ms").unwrap(), Duration::from_millis(20));
        assert_eq!(parse_rate("1kHz").unwrap(), Duration::from_millis(1));
        assert_eq!(parse_duration("2min").unwrap(), Duration::from_secs(120));
        assert_eq!(parse_duration("1.5s").unwrap(), Duration::from_millis(1500));
    }

    #[test]
    fn bad_rates_are_rejected() {
        for bad in ["", "fast", "0Hz", "-5Hz", "10 parsecs", "0s", "Hz"] {
            assert!(parse_rate(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn huge_and_tiny_values_are_errors_not_panics() {
        for bad in ["1e-30Hz", "1e9Hz", "1e300Hz", "1ns", "2777777777777778h"] {
            assert!(parse_rate(bad).is_err(), "{bad}");
        }
        for bad in [
            "2777777777777778h",
            "99999999999999999999999s",
            "1e400s",
            "11000000000000000000000000000000ns",
        ] {
            assert!(parse_duration(bad).is_err(), "{bad}");
        }
        assert!(parse_duration("87600h").is_ok());
        for bad in [f64::NAN, f64::INFINITY, -1.0, 1e300] {
            assert!(seconds(bad).is_err(), "{bad}");
        }
        assert_eq!(seconds(1.5), Ok(Duration::from_millis(1500)));
    }
}
