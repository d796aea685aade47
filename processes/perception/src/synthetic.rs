//! Synthetic laser scans of a simple room, for tests and benchmarks.
//!
//! The room is an axis-aligned rectangle of walls with axis-aligned boxes inside; the scanner
//! is the simulated URG-04LX (682 beams over 240°, 0.02–5.6 m, σ = 10 mm up to 1 m then 1 % of
//! the range), with the same conventions for invalid readings as the sensor node: no surface in
//! range reads `range_max + 1`. The noise comes from a small seeded generator so that the
//! scans are reproducible without a random-number crate.

use caravan_schemas::{LaserScan, Pose2D, SCAN_MAX_BEAMS};

/// URG-04LX-UG01 geometry, as the sensor node's defaults.
pub const BEAMS: usize = 682;
pub const FIELD_OF_VIEW: f64 = 240.0 * std::f64::consts::PI / 180.0;
pub const RANGE_MIN: f64 = 0.02;
pub const RANGE_MAX: f64 = 5.6;

/// An axis-aligned rectangular room (inner wall faces at `min` and `max`) with boxes inside.
#[derive(Debug, Clone, PartialEq)]
pub struct Room {
    pub min: [f64; 2],
    pub max: [f64; 2],
    /// Boxes as (lower corner, upper corner).
    pub boxes: Vec<([f64; 2], [f64; 2])>,
}

impl Default for Room {
    /// A 4 m × 3 m room with a 0.4 m × 0.3 m box, so that no direction is unconstrained.
    fn default() -> Self {
        Self {
            min: [0.0, 0.0],
            max: [4.0, 3.0],
            boxes: vec![([2.6, 1.9], [3.0, 2.2])],
        }
    }
}

impl Room {
    /// Distance from `o` along unit direction `d` to the first surface.
    pub fn ray(&self, o: [f64; 2], d: [f64; 2]) -> f64 {
        let mut t = f64::INFINITY;
        for k in 0..2 {
            if d[k] > 0.0 {
                t = t.min((self.max[k] - o[k]) / d[k]);
            } else if d[k] < 0.0 {
                t = t.min((self.min[k] - o[k]) / d[k]);
            }
        }
        for (lo, hi) in &self.boxes {
            let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
            for k in 0..2 {
                if d[k] == 0.0 {
                    if o[k] < lo[k] || o[k] > hi[k] {
                        t1 = -1.0;
                    }
                } else {
                    let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
            }
            if t0 <= t1 {
                t = t.min(t0);
            }
        }
        t
    }

    /// A scan from a robot at `pose` whose scanner sits `laser_x_offset` ahead of base_link;
    /// with Gaussian range noise when `noise_seed` is given.
    pub fn scan(&self, pose: &Pose2D, laser_x_offset: f64, noise_seed: Option<u64>) -> LaserScan {
        let mut scan = LaserScan::default();
        let increment = FIELD_OF_VIEW / (BEAMS - 1) as f64;
        scan.angle_min = (-FIELD_OF_VIEW / 2.0) as f32;
        scan.angle_max = (FIELD_OF_VIEW / 2.0) as f32;
        scan.angle_increment = increment as f32;
        scan.scan_time = 0.1;
        scan.range_min = RANGE_MIN as f32;
        scan.range_max = RANGE_MAX as f32;
        scan.beam_count = BEAMS as u32;
        let (s, c) = pose.theta.sin_cos();
        let o = [pose.x + c * laser_x_offset, pose.y + s * laser_x_offset];
        let mut rng = noise_seed.map(Normal::new);
        for (i, r) in scan.ranges[..BEAMS.min(SCAN_MAX_BEAMS)]
            .iter_mut()
            .enumerate()
        {
            // The angle a consumer computes from the message's f32 fields.
            let a = pose.theta + scan.angle_min as f64 + i as f64 * scan.angle_increment as f64;
            let truth = self.ray(o, [a.cos(), a.sin()]);
            let draw = rng.as_mut().map_or(0.0, Normal::sample);
            *r = if truth > RANGE_MAX {
                (RANGE_MAX + 1.0) as f32
            } else {
                let sigma = if truth <= 1.0 { 0.01 } else { 0.01 * truth };
                (truth + sigma * draw).clamp(RANGE_MIN, RANGE_MAX) as f32
            };
        }
        scan
    }
}

/// Standard normal numbers from splitmix64 and Box–Muller.
#[derive(Debug, Clone)]
pub struct Normal(u64);

impl Normal {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// One N(0, 1) draw.
    pub fn sample(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_hit_walls_and_boxes() {
        let room = Room::default();
        assert!((room.ray([1.0, 1.0], [1.0, 0.0]) - 3.0).abs() < 1e-12);
        assert!((room.ray([1.0, 1.0], [0.0, -1.0]) - 1.0).abs() < 1e-12);
        assert!((room.ray([2.0, 2.0], [1.0, 0.0]) - 0.6).abs() < 1e-12);
        let d = std::f64::consts::FRAC_1_SQRT_2;
        assert!((room.ray([1.0, 1.0], [-d, -d]) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn scans_look_like_the_sensor() {
        let room = Room::default();
        let pose = Pose2D {
            x: 1.0,
            y: 1.0,
            theta: 0.0,
        };
        let clean = room.scan(&pose, 0.0, None);
        assert_eq!(clean.ranges().len(), 682);
        // The middle beams look along +x at the far wall (3 m away).
        let mid = clean.ranges()[340];
        assert!((mid - 3.0).abs() < 0.01, "{mid}");
        let noisy = room.scan(&pose, 0.0, Some(3));
        let errors: Vec<f64> = (0..682)
            .map(|i| (noisy.ranges[i] - clean.ranges[i]) as f64 / clean.ranges[i].max(1.0) as f64)
            .collect();
        let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
        assert!((rms - 0.01).abs() < 0.002, "{rms}");
        let mut n = Normal::new(5);
        let xs: Vec<f64> = (0..20_000).map(|_| n.sample()).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
    }
}
