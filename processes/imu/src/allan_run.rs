//! The Allan-deviation check of the IMU's error model: a static IMU (the sensor's model fed
//! a body at rest, as the physics gives it in f64: exactly at rest) read for a long time,
//! its Allan deviation per triad, and the noise density and bias instability read off it
//! against the configured ones.
//!
//! `caravan-imu-allan` runs it and writes `allan.json` and `allan.svg`.

use caravan_sensor::allan::{allan_deviation, log_clusters, white_and_flicker};
use caravan_sensor::imu::{BodyState, ImuNoise, Mount, VirtualImu};
use caravan_sensor::imu_errors::{ImuErrors, TriadErrors};
use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;

/// The datasheet of an MPU-6050-class part, Caravan's chosen example: accelerometer
/// 400 µg/√Hz and 40 µg bias instability, gyroscope 0.005 °/s/√Hz and 5 °/h, flicker
/// correlation from 1 s to 1000 s, no random walk.
pub fn example_errors() -> ImuErrors {
    ImuErrors {
        accel: TriadErrors {
            noise_density: 400e-6 * 9.81,
            bias_instability: 40e-6 * 9.81,
            ..TriadErrors::default()
        },
        gyro: TriadErrors {
            noise_density: 0.005f64.to_radians(),
            bias_instability: (5.0f64 / 3600.0).to_radians(),
            ..TriadErrors::default()
        },
        bias_correlation_s: [1.0, 1000.0],
    }
}

/// One triad's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TriadResult {
    pub triad: &'static str,
    pub noise_density: f64,
    pub noise_density_estimated: f64,
    pub noise_density_err_rel: f64,
    pub bias_instability: f64,
    pub bias_instability_estimated: f64,
    pub bias_instability_err_rel: f64,
    /// (τ s, Allan deviation) of the x axis.
    pub adev: Vec<(f64, f64)>,
}

impl TriadResult {
    /// The configured and read-off values with their errors, as table cells:
    /// `[triad, N configured / read off, N error, B configured / read off, B error]`.
    pub fn cells(&self) -> [String; 5] {
        [
            self.triad.to_string(),
            format!(
                "{:.4e} / {:.4e}",
                self.noise_density, self.noise_density_estimated
            ),
            format!("{:+.1} %", 100.0 * self.noise_density_err_rel),
            format!(
                "{:.4e} / {:.4e}",
                self.bias_instability, self.bias_instability_estimated
            ),
            format!("{:+.1} %", 100.0 * self.bias_instability_err_rel),
        ]
    }
}

/// Reads a static IMU with `errors` at `rate_hz` for `seconds`; seeded by `seed`.
pub fn run(errors: &ImuErrors, rate_hz: f64, seconds: f64, seed: u64) -> [TriadResult; 2] {
    let dt_ns = (1e9 / rate_hz).round() as u64;
    let dt = dt_ns as f64 * 1e-9;
    let n = (seconds / dt) as u64;
    let mount = Mount {
        offset: Vector3::zeros(),
    };
    let mut imu = VirtualImu::new(mount, ImuNoise::OFF, seed).with_errors(errors);
    let (mut accel, mut gyro) = (
        Vec::with_capacity(n as usize),
        Vec::with_capacity(n as usize),
    );
    for k in 0..=n {
        let rest = BodyState {
            stamp_ns: k * dt_ns,
            orientation: UnitQuaternion::identity(),
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
        };
        if let Some(r) = imu.update(&rest) {
            accel.push(r.linear_acceleration.x);
            gyro.push(r.angular_velocity.x);
        }
    }
    analyse(errors, dt, &accel, &gyro)
}

/// The Allan deviation of one axis of each triad's static readings, `dt` s apart, and the
/// noise density and bias instability read off it against `errors`.
pub fn analyse(errors: &ImuErrors, dt: f64, accel: &[f64], gyro: &[f64]) -> [TriadResult; 2] {
    let clusters = log_clusters(accel.len().min(gyro.len()) / 4, 8);
    // The flicker bias is flat up to a third of its longest correlation time.
    let tau_max = errors.bias_correlation_s[1] / 3.0;
    let triad = |name, p: &TriadErrors, samples: &[f64]| {
        let adev = allan_deviation(samples, dt, &clusters);
        let (nd, bi) = white_and_flicker(&adev, tau_max).unwrap_or((f64::NAN, f64::NAN));
        TriadResult {
            triad: name,
            noise_density: p.noise_density,
            noise_density_estimated: nd,
            noise_density_err_rel: nd / p.noise_density - 1.0,
            bias_instability: p.bias_instability,
            bias_instability_estimated: bi,
            bias_instability_err_rel: bi / p.bias_instability - 1.0,
            adev,
        }
    };
    [
        triad("accel", &errors.accel, accel),
        triad("gyro", &errors.gyro, gyro),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The short version of the experiment: flicker from 0.1 s to 10 s, 2000 s at 100 Hz.
    #[test]
    fn the_allan_deviation_recovers_noise_density_and_bias_instability_within_10_percent() {
        let mut errors = example_errors();
        errors.bias_correlation_s = [0.1, 10.0];
        // A bias loud enough to show in 2000 s: its floor meets the white noise near 3 s.
        errors.accel.bias_instability = 4e-3;
        errors.gyro.bias_instability = 1e-4;
        for r in run(&errors, 100.0, 2000.0, 1) {
            eprintln!(
                "{}: N {:+.3}, B {:+.3}",
                r.triad, r.noise_density_err_rel, r.bias_instability_err_rel
            );
            assert!(r.noise_density_err_rel.abs() < 0.1, "{r:?}");
            assert!(r.bias_instability_err_rel.abs() < 0.1, "{r:?}");
        }
    }
}
