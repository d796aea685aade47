//! An inertial sensor's error model beyond white noise, per triad (accelerometer or
//! gyroscope), in the terms of IEEE Std 952 and a datasheet:
//!
//! reading = q((1 + s)·truth + white + bias + walk), with
//! - **white noise** of density N (units/√Hz): σ = N/√dt per reading of interval dt; the
//!   Allan deviation falls as N/√τ;
//! - **bias instability** B (units): a flicker bias, the sum of first-order Gauss–Markov
//!   processes with correlation times spread evenly in log between `bias_correlation_s`
//!   (two per decade), scaled so that the Allan deviation's floor between them is 0.664·B,
//!   the floor flicker noise of instability B gives;
//! - **rate random walk** K (units·√Hz, i.e. units/√s): a random-walk bias; the Allan
//!   deviation rises as K·√(τ/3);
//! - **scale factor** s, and **quantisation** q to steps of `quantum` (0: none).
//!
//! Every draw comes from the sensor's seeded stream, so runs repeat.

use crate::noise::Gaussian;
use nalgebra::Vector3;
use serde::Deserialize;

/// The Allan deviation's floor of flicker noise of bias instability B is this times B.
pub const FLICKER_FLOOR: f64 = 0.664;

/// One triad's error parameters; all zero by default (an ideal sensor).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct TriadErrors {
    /// White noise density N, units/√Hz (m/s²/√Hz, rad/s/√Hz), ≥ 0.
    pub noise_density: f64,
    /// Bias instability B, units (m/s², rad/s), ≥ 0.
    pub bias_instability: f64,
    /// Rate random walk K, units/√s, ≥ 0.
    pub random_walk: f64,
    /// Scale-factor error s (a reading is (1 + s)·truth), > −1.
    pub scale_factor: f64,
    /// Quantisation step, units, ≥ 0; 0 for none.
    pub quantum: f64,
}

/// The error model of both triads (the sensor's `imu_errors` table).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImuErrors {
    #[serde(default)]
    pub accel: TriadErrors,
    #[serde(default)]
    pub gyro: TriadErrors,
    /// Shortest and longest correlation time of the flicker bias, s; its Allan deviation is
    /// flat from about three times the first to a third of the second.
    #[serde(default = "default_correlation")]
    pub bias_correlation_s: [f64; 2],
}

fn default_correlation() -> [f64; 2] {
    [1.0, 1000.0]
}

impl TriadErrors {
    /// Checks ranges; the error names the key, below `prefix`.
    pub fn validate(&self, prefix: &str) -> Result<(), String> {
        for (key, v) in [
            ("noise_density", self.noise_density),
            ("bias_instability", self.bias_instability),
            ("random_walk", self.random_walk),
            ("quantum", self.quantum),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!(
                    "'{prefix}.{key}' must be zero or positive, got {v}"
                ));
            }
        }
        if !(self.scale_factor.is_finite() && self.scale_factor > -1.0) {
            return Err(format!(
                "'{prefix}.scale_factor' must be a number above −1, got {}",
                self.scale_factor
            ));
        }
        Ok(())
    }
}

impl ImuErrors {
    /// Checks ranges; the error names the key below `imu_errors`.
    pub fn validate(&self) -> Result<(), String> {
        self.accel.validate("accel")?;
        self.gyro.validate("gyro")?;
        let [lo, hi] = self.bias_correlation_s;
        // Two processes per decade: 1 ms to 10⁶ s spans 18 of them.
        if !(lo >= 1e-3 && hi <= 1e6 && hi >= lo) {
            return Err(format!(
                "'bias_correlation_s': give [shortest, longest] in s, \
                 0.001 ≤ shortest ≤ longest ≤ 1e6, got [{lo}, {hi}]"
            ));
        }
        Ok(())
    }
}

/// The correlation times of the flicker bias: two per decade from `lo` to `hi`.
pub fn correlation_times([lo, hi]: [f64; 2]) -> Vec<f64> {
    let decades = (hi / lo).log10();
    let n = (decades * 2.0).round() as usize + 1;
    (0..n)
        .map(|k| lo * 10f64.powf(k as f64 / 2.0).min(hi / lo))
        .collect()
}

/// Allan variance at averaging time `tau` of a first-order Gauss–Markov process of unit
/// variance and correlation time `t`.
pub fn gauss_markov_avar(tau: f64, t: f64) -> f64 {
    let x = tau / t;
    if x < 1e-4 {
        return 2.0 * tau / (3.0 * t); // the series, where the closed form cancels
    }
    2.0 * t / tau * (1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x))
}

/// Averaging times over which the flicker bias's Allan deviation is flat: four per decade
/// from 3× the shortest correlation time to a third of the longest.
pub fn floor_taus([lo, hi]: [f64; 2]) -> Vec<f64> {
    let (a, b) = (3.0 * lo, (hi / 3.0).max(3.0 * lo));
    let n = ((b / a).log10() * 4.0).round() as usize + 1;
    (0..n).map(|k| a * 10f64.powf(k as f64 / 4.0)).collect()
}

/// The standard deviation each Gauss–Markov level gets for bias instability `b`: the median
/// over [`floor_taus`] of the bank's Allan deviation is then 0.664·b.
pub fn level_stddev(b: f64, correlation: [f64; 2]) -> f64 {
    let times = correlation_times(correlation);
    let mut unit: Vec<f64> = floor_taus(correlation)
        .iter()
        .map(|&tau| {
            times
                .iter()
                .map(|&t| gauss_markov_avar(tau, t))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    unit.sort_by(f64::total_cmp);
    FLICKER_FLOOR * b / unit[unit.len() / 2]
}

/// One triad's error state.
#[derive(Debug, Clone)]
pub struct TriadModel {
    params: TriadErrors,
    /// Correlation time of each Gauss–Markov level, s, and its stationary deviation.
    levels: Vec<f64>,
    level_stddev: f64,
    bias: Vec<Vector3<f64>>,
    walk: Vector3<f64>,
    started: bool,
}

impl TriadModel {
    pub fn new(params: TriadErrors, correlation: [f64; 2]) -> Self {
        let levels = if params.bias_instability > 0.0 {
            correlation_times(correlation)
        } else {
            Vec::new()
        };
        Self {
            level_stddev: level_stddev(params.bias_instability, correlation),
            bias: vec![Vector3::zeros(); levels.len()],
            levels,
            params,
            walk: Vector3::zeros(),
            started: false,
        }
    }

    /// The reading of `truth` over an interval of `dt` s.
    pub fn apply(&mut self, truth: Vector3<f64>, dt: f64, rng: &mut Gaussian) -> Vector3<f64> {
        let p = self.params;
        let mut draw = |s: f64| {
            if s == 0.0 {
                Vector3::zeros()
            } else {
                Vector3::new(rng.sample(s), rng.sample(s), rng.sample(s))
            }
        };
        if !self.started {
            // Each level starts from its stationary distribution: no warm-up transient.
            for b in &mut self.bias {
                *b = draw(self.level_stddev);
            }
            self.started = true;
        }
        for (b, t) in self.bias.iter_mut().zip(&self.levels) {
            let a = (-dt / t).exp();
            *b = *b * a + draw(self.level_stddev * (1.0 - a * a).sqrt());
        }
        self.walk += draw(p.random_walk * dt.sqrt());
        let white = draw(p.noise_density / dt.sqrt());
        let bias: Vector3<f64> = self.bias.iter().sum();
        let out = truth * (1.0 + p.scale_factor) + white + bias + self.walk;
        if p.quantum > 0.0 {
            out.map(|v| (v / p.quantum).round() * p.quantum)
        } else {
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ideal_triad_reads_the_truth_and_scale_and_quantum_apply() {
        let mut rng = Gaussian::new(1, 9);
        let truth = Vector3::new(1.0, -2.0, 9.81);
        let mut ideal = TriadModel::new(TriadErrors::default(), [1.0, 1000.0]);
        assert_eq!(ideal.apply(truth, 0.01, &mut rng), truth);
        let p = TriadErrors {
            scale_factor: 0.01,
            quantum: 0.5,
            ..TriadErrors::default()
        };
        let out = TriadModel::new(p, [1.0, 1000.0]).apply(truth, 0.01, &mut rng);
        assert_eq!(out, Vector3::new(1.0, -2.0, 10.0));
    }

    #[test]
    fn the_gauss_markov_allan_variance_has_its_known_limits() {
        // τ ≪ T: a random walk, 2τ/(3T); τ ≫ T: white, 2T/τ.
        assert!((gauss_markov_avar(1e-3, 10.0) / (2.0 * 1e-3 / 30.0) - 1.0).abs() < 1e-3);
        assert!((gauss_markov_avar(1e5, 1.0) / (2.0 / 1e5) - 1.0).abs() < 1e-3);
        assert_eq!(correlation_times([1.0, 100.0]).len(), 5);
    }

    #[test]
    fn bad_values_name_their_key() {
        let mut e = ImuErrors {
            accel: TriadErrors::default(),
            gyro: TriadErrors::default(),
            bias_correlation_s: [1.0, 1000.0],
        };
        e.gyro.noise_density = -1.0;
        assert!(e.validate().unwrap_err().contains("'gyro.noise_density'"));
        e.gyro.noise_density = 0.0;
        e.bias_correlation_s = [10.0, 1.0];
        assert!(e.validate().unwrap_err().contains("bias_correlation_s"));
    }
}
