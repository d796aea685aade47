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
            Trigger::OnMessage(_) => None,
        }
    }
}

/// Parses a rate: a frequency (`"50Hz"`, `"2.5 kHz"`) or a period (`"20ms"`, `"1s"`).
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
            Duration::from_secs_f64(1.0 / (f * scale))
        }
        None => parse_duration(t).map_err(|_| bad_rate(text))?,
    };
    if period.is_zero() {
        return Err(bad_rate(text));
    }
    Ok(period)
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
    Ok(Duration::from_secs_f64(secs))
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
}
