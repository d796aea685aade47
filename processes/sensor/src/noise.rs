//! Seeded Gaussian noise shared by the sensor models.
//!
//! Every stream is a ChaCha8 generator seeded from the node's seed (`NodeIdentity::node_seed`),
//! one ChaCha stream per sensor, so a lockstep run with the same group seed draws the same
//! numbers, and switching one sensor's noise on or off does not shift another's.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// ChaCha stream numbers, one per sensor.
pub const LASER_STREAM: u64 = 1;
pub const IMU_STREAM: u64 = 2;

/// A reproducible source of standard normal (and uniform) numbers.
pub struct Gaussian {
    rng: ChaCha8Rng,
}

impl Gaussian {
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Self { rng }
    }

    /// One N(0, 1) draw (Box–Muller; uses one pair of uniforms per draw, so the number of
    /// uniforms consumed per reading is fixed and runs stay aligned).
    pub fn standard(&mut self) -> f64 {
        // 1 − U lies in (0, 1], so the logarithm is finite.
        let u1 = 1.0 - self.rng.random::<f64>();
        let u2 = self.rng.random::<f64>();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// One U[0, 1) draw.
    pub fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// One N(0, σ²) draw.
    pub fn sample(&mut self, stddev: f64) -> f64 {
        stddev * self.standard()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_numbers_and_unit_variance() {
        let (mut a, mut b) = (
            Gaussian::new(7, LASER_STREAM),
            Gaussian::new(7, LASER_STREAM),
        );
        let xs: Vec<f64> = (0..20_000).map(|_| a.standard()).collect();
        assert!(xs.iter().all(|&x| x == b.standard()));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
        let mut other = Gaussian::new(7, IMU_STREAM);
        assert_ne!(xs[0], other.standard());
    }
}
