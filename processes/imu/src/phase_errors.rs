//! Errors of IMU readings against a phase's ideal reading: per axis, the largest absolute
//! error and the root mean square over the readings stamped inside the phase's window.

use crate::scenario::{Expect, Phase};
use serde::Serialize;

/// One IMU reading: its stamp (s), specific force (m/s²) and angular rate (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    pub t_s: f64,
    pub accel: [f64; 3],
    pub gyro: [f64; 3],
}

/// Max and RMS of a set of errors.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Stat {
    pub max: f64,
    pub rms: f64,
}

#[derive(Debug, Default)]
struct Accumulator {
    max: f64,
    sum_sq: f64,
    n: usize,
}

impl Accumulator {
    fn add(&mut self, e: f64) {
        self.max = self.max.max(e.abs());
        self.sum_sq += e * e;
        self.n += 1;
    }

    fn stat(&self) -> Stat {
        Stat {
            max: self.max,
            rms: if self.n == 0 {
                0.0
            } else {
                (self.sum_sq / self.n as f64).sqrt()
            },
        }
    }
}

/// The errors of one phase. `accel` holds x, y, z, or one entry (the magnitude) when the
/// phase expects only the magnitude.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseErrors {
    pub phase: String,
    pub from_s: f64,
    pub to_s: f64,
    pub readings: usize,
    /// The ideal reading: a vector, or `[magnitude]`.
    pub expected_accel_m_s2: Vec<f64>,
    pub expected_gyro_rad_s: [f64; 3],
    pub accel_err_m_s2: Vec<Stat>,
    pub gyro_err_rad_s: [Stat; 3],
}

impl PhaseErrors {
    /// Largest accelerometer error over the axes, m/s².
    pub fn accel_max(&self) -> f64 {
        self.accel_err_m_s2
            .iter()
            .map(|s| s.max)
            .fold(0.0, f64::max)
    }

    /// Largest gyroscope error over the axes, rad/s.
    pub fn gyro_max(&self) -> f64 {
        self.gyro_err_rad_s
            .iter()
            .map(|s| s.max)
            .fold(0.0, f64::max)
    }
}

/// Scores the readings stamped in `[from_s, to_s]` of `phase`.
pub fn score(phase: &Phase, readings: &[Reading]) -> PhaseErrors {
    let inside = readings
        .iter()
        .filter(|r| r.t_s >= phase.from_s && r.t_s <= phase.to_s);
    let (expected, axes) = match phase.accel {
        Expect::Vector(v) => (v.to_vec(), 3),
        Expect::Norm(n) => (vec![n], 1),
    };
    let mut accel: Vec<Accumulator> = (0..axes).map(|_| Accumulator::default()).collect();
    let mut gyro: [Accumulator; 3] = Default::default();
    let mut n = 0;
    for r in inside {
        n += 1;
        match phase.accel {
            Expect::Vector(v) => {
                for ((acc, a), e) in accel.iter_mut().zip(r.accel).zip(v) {
                    acc.add(a - e);
                }
            }
            Expect::Norm(norm) => {
                let m = r.accel.iter().map(|a| a * a).sum::<f64>().sqrt();
                accel[0].add(m - norm);
            }
        }
        for ((acc, w), e) in gyro.iter_mut().zip(r.gyro).zip(phase.gyro) {
            acc.add(w - e);
        }
    }
    PhaseErrors {
        phase: phase.name.to_string(),
        from_s: phase.from_s,
        to_s: phase.to_s,
        readings: n,
        expected_accel_m_s2: expected,
        expected_gyro_rad_s: phase.gyro,
        accel_err_m_s2: accel.iter().map(Accumulator::stat).collect(),
        gyro_err_rad_s: [gyro[0].stat(), gyro[1].stat(), gyro[2].stat()],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phase(accel: Expect) -> Phase {
        Phase {
            name: "p",
            from_s: 1.0,
            to_s: 2.0,
            accel,
            gyro: [0.0, 0.0, 1.0],
        }
    }

    fn reading(t_s: f64, accel: [f64; 3], gz: f64) -> Reading {
        Reading {
            t_s,
            accel,
            gyro: [0.0, 0.0, gz],
        }
    }

    #[test]
    fn only_readings_in_the_window_count_with_max_and_rms_per_axis() {
        let readings = [
            reading(0.5, [9.0, 9.0, 9.0], 5.0), // outside
            reading(1.0, [0.0, 0.0, 9.81 + 3e-6], 1.0),
            reading(2.0, [4e-6, 0.0, 9.81 - 3e-6], 1.0 + 2e-7),
            reading(2.5, [9.0, 9.0, 9.0], 5.0), // outside
        ];
        let e = score(&phase(Expect::Vector([0.0, 0.0, 9.81])), &readings);
        assert_eq!(e.readings, 2);
        assert!((e.accel_err_m_s2[0].max - 4e-6).abs() < 1e-12);
        assert!((e.accel_err_m_s2[0].rms - 4e-6 / 2f64.sqrt()).abs() < 1e-12);
        assert!((e.accel_err_m_s2[2].max - 3e-6).abs() < 1e-9);
        assert!((e.gyro_max() - 2e-7).abs() < 1e-12);
        assert!((e.accel_max() - 4e-6).abs() < 1e-12);
    }

    #[test]
    fn a_magnitude_phase_scores_the_norm() {
        let readings = [reading(1.5, [0.0, 6.0, 8.0], 1.0)];
        let e = score(&phase(Expect::Norm(10.0)), &readings);
        assert_eq!(e.accel_err_m_s2.len(), 1);
        assert!(e.accel_max() < 1e-12);
    }
}
