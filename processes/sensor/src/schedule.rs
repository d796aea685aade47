//! Decimation: the node steps at one rate (100 Hz) and each sensor fires on every n-th step.
//!
//! One node per robot, as one process per Raspberry Pi, keeps the sensors of a robot in step
//! with each other; decimating by whole numbers keeps each sensor's period exact in lockstep.

use crate::params::ParamError;
use std::time::Duration;

/// How many node steps of `step_period` make one period of a sensor at `rate_hz`; the rate must
/// divide the node's rate, or the error names `key`.
pub fn every_nth(
    step_period: Duration,
    rate_hz: f64,
    key: &'static str,
) -> Result<u64, ParamError> {
    let step_hz = 1.0 / step_period.as_secs_f64();
    let ratio = step_hz / rate_hz;
    let n = ratio.round();
    if n >= 1.0 && (ratio - n).abs() <= 1e-6 * n {
        Ok(n as u64)
    } else {
        Err(ParamError {
            key,
            message: format!(
                "{rate_hz} Hz is not the node's rate ({step_hz} Hz) divided by a whole number; \
                 pick a rate that divides it, or change the node's `rate`"
            ),
        })
    }
}

/// Whether step `index` (0 for the first) is one of every `n`-th steps.
pub fn due(index: u64, n: u64) -> bool {
    index.is_multiple_of(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn divides_the_node_rate() {
        let p = Duration::from_secs_f64(1.0 / 100.0);
        assert_eq!(every_nth(p, 10.0, "laser_rate_hz").unwrap(), 10);
        assert_eq!(every_nth(p, 50.0, "encoder_rate_hz").unwrap(), 2);
        assert_eq!(every_nth(p, 100.0, "x").unwrap(), 1);
        let e = every_nth(p, 30.0, "laser_rate_hz").unwrap_err().to_string();
        assert!(e.contains("'laser_rate_hz'") && e.contains("100 Hz"), "{e}");
        assert!(every_nth(p, 200.0, "x").is_err());
        let steps: Vec<u64> = (0..25).filter(|&i| due(i, 10)).collect();
        assert_eq!(steps, [0, 10, 20]);
    }
}
