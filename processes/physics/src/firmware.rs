//! The motor-controller firmware of the reference robot (an Arduino Uno): a wheel-speed PID in
//! incremental form, run at 50 Hz for each driven wheel.
//!
//! ```text
//! e(n) = set-point − measured speed
//! u(n) = u(n−1) + Kp·(e(n) − e(n−1)) + Ki·e(n) + Kd·(e(n) − 2e(n−1) + e(n−2))
//! Kp = kp, Ki = ki·Δt, Kd = kd/Δt
//! ```
//!
//! `u` is the motor voltage. The firmware stores the clamped value, as a PWM register would,
//! so the integrator cannot wind up beyond the supply. The measured speed is the wheel's angle
//! change over the last control period divided by that period, what an encoder-based speed
//! estimate sees (without tick quantisation, which the sensor process adds on its own topic).

use serde::Deserialize;

/// PID gains and rate (the `dc_motor` actuator's `pid` keys). Defaults: the convoy robot's
/// firmware, fitted as [`crate::step_response`] documents.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FirmwareParams {
    /// Proportional gain kp, V per rad/s.
    pub kp: f64,
    /// Integral gain ki, V per rad (Ki = ki·Δt per sample).
    pub ki: f64,
    /// Derivative gain kd, V·s² per rad (Kd = kd/Δt per sample).
    pub kd: f64,
    /// Control rate, Hz (the reference's Δt = 0.02 s).
    pub rate_hz: f64,
}

impl Default for FirmwareParams {
    fn default() -> Self {
        Self {
            kp: 0.22,
            ki: 2.3,
            kd: 0.0,
            rate_hz: 50.0,
        }
    }
}

impl FirmwareParams {
    /// Control period Δt in whole nanoseconds, so that ticks fall on exact simulated times.
    pub fn period_ns(&self) -> u64 {
        (1e9 / self.rate_hz).round() as u64
    }

    pub fn validate(&self) -> Result<(), String> {
        for (key, v) in [("kp", self.kp), ("ki", self.ki), ("kd", self.kd)] {
            if !v.is_finite() || v.abs() > 1e6 {
                return Err(format!(
                    "pid.{key} must be a finite number within ±1e6, got {v}"
                ));
            }
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 10_000.0) {
            return Err(format!(
                "pid.rate_hz must be in (0, 10000], got {}",
                self.rate_hz
            ));
        }
        Ok(())
    }
}

/// One wheel's speed controller.
#[derive(Debug, Clone)]
pub struct SpeedPid {
    kp: f64,
    ki: f64,
    kd: f64,
    limit: f64,
    u: f64,
    e1: f64,
    e2: f64,
}

impl SpeedPid {
    /// A controller with output limited to ±`limit` volts.
    pub fn new(p: &FirmwareParams, limit: f64) -> Self {
        let dt = 1.0 / p.rate_hz;
        Self {
            kp: p.kp,
            ki: p.ki * dt,
            kd: p.kd / dt,
            limit,
            u: 0.0,
            e1: 0.0,
            e2: 0.0,
        }
    }

    /// One control period: the new motor voltage for `setpoint` and `measured` speed (rad/s).
    pub fn update(&mut self, setpoint: f64, measured: f64) -> f64 {
        let e = setpoint - measured;
        let du = self.kp * (e - self.e1) + self.ki * e + self.kd * (e - 2.0 * self.e1 + self.e2);
        self.u = (self.u + du).clamp(-self.limit, self.limit);
        self.e2 = self.e1;
        self.e1 = e;
        self.u
    }

    /// The voltage currently commanded.
    pub fn output(&self) -> f64 {
        self.u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incremental_form_matches_positional_pid() {
        let p = FirmwareParams {
            kp: 0.7,
            ki: 3.0,
            kd: 0.01,
            rate_hz: 50.0,
        };
        let mut pid = SpeedPid::new(&p, 1e9);
        let dt = 0.02;
        let errors = [1.0, 0.8, 0.5, 0.1, -0.2, 0.05];
        let (mut sum, mut prev) = (0.0, 0.0);
        for &e in &errors {
            let u = pid.update(e, 0.0);
            sum += e;
            let positional = p.kp * e + p.ki * dt * sum + p.kd / dt * (e - prev);
            prev = e;
            assert!((u - positional).abs() < 1e-12, "{u} vs {positional}");
        }
    }

    #[test]
    fn output_is_clamped_without_windup() {
        let mut pid = SpeedPid::new(&FirmwareParams::default(), 6.0);
        for _ in 0..1000 {
            pid.update(100.0, 0.0);
        }
        assert_eq!(pid.output(), 6.0);
        // Once the error reverses, the output leaves the limit at once.
        assert!(pid.update(-1.0, 0.0) < 6.0);
    }
}
