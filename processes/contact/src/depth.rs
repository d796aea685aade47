//! The sparse depth sensor: a planar scanner of a few beams in the arm's plane that sees the
//! obstacle touching the arm (the person's hand, a disc), and the self-filter that removes
//! the arm's own returns, as a robot's self-filter does with its model.

use crate::contour::Contour;
use caravan_sensor::noise::Gaussian;
use nalgebra::{Point2, Vector2};

/// A planar scanner. Beam `i` points at `first_angle + i·fov/(beams − 1)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Scanner {
    /// Where it sits in the arm's plane, m.
    pub origin: Point2<f64>,
    /// Direction of the first beam, rad from +x.
    pub first_angle: f64,
    /// Angle from the first beam to the last, rad, in (0, 2π].
    pub fov: f64,
    /// Number of beams, ≥ 2.
    pub beams: usize,
    /// Longest range it reports, m, > 0.
    pub max_range: f64,
    /// Standard deviation of a range, m, ≥ 0.
    pub range_sigma: f64,
}

/// A disc in the plane: the person's hand or fingertip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    pub center: Point2<f64>,
    /// m, > 0.
    pub radius: f64,
}

impl Disc {
    /// Distance along the unit ray to where it enters the disc.
    fn ray_hit(&self, origin: &Point2<f64>, direction: &Vector2<f64>) -> Option<f64> {
        let to = self.center - origin;
        let along = to.dot(direction);
        let miss2 = to.norm_squared() - along * along;
        let r2 = self.radius * self.radius;
        if miss2 > r2 {
            return None;
        }
        let t = along - (r2 - miss2).sqrt();
        (t >= 0.0).then_some(t)
    }
}

impl Scanner {
    pub fn validate(&self) -> Result<(), String> {
        if self.beams < 2 {
            return Err(format!("'beams' must be at least 2, got {}", self.beams));
        }
        if !(self.fov > 0.0 && self.fov <= std::f64::consts::TAU) {
            return Err(format!(
                "'fov' must be in (0, 360]°, got {}°",
                self.fov.to_degrees()
            ));
        }
        if !(self.max_range.is_finite() && self.max_range > 0.0) {
            return Err(format!(
                "'max_range' must be positive, got {} m",
                self.max_range
            ));
        }
        if !(self.range_sigma.is_finite() && self.range_sigma >= 0.0) {
            return Err(format!(
                "'range_sigma' must be ≥ 0, got {} m",
                self.range_sigma
            ));
        }
        Ok(())
    }

    /// Angle between neighbouring beams, rad.
    pub fn increment(&self) -> f64 {
        self.fov / (self.beams - 1) as f64
    }

    fn direction(&self, beam: usize) -> Vector2<f64> {
        let a = self.first_angle + beam as f64 * self.increment();
        Vector2::new(a.cos(), a.sin())
    }

    /// One scan: each beam's range to the nearest surface (the arm's links or a disc), with
    /// Gaussian noise; +∞ where nothing lies within `max_range`.
    pub fn scan(&self, arm: &[Contour], discs: &[Disc], noise: &mut Gaussian) -> Vec<f64> {
        (0..self.beams)
            .map(|beam| {
                let d = self.direction(beam);
                let hit = arm
                    .iter()
                    .filter_map(|c| c.ray_hit(&self.origin, &d))
                    .chain(discs.iter().filter_map(|c| c.ray_hit(&self.origin, &d)))
                    .fold(f64::INFINITY, f64::min);
                let noise = noise.sample(self.range_sigma);
                if hit <= self.max_range {
                    hit + noise
                } else {
                    f64::INFINITY
                }
            })
            .collect()
    }

    /// The returns of `ranges` as points in the plane.
    pub fn points(&self, ranges: &[f64]) -> Vec<Point2<f64>> {
        ranges
            .iter()
            .enumerate()
            .filter(|(_, r)| r.is_finite())
            .map(|(beam, r)| self.origin + self.direction(beam) * *r)
            .collect()
    }
}

/// The points farther than `margin` (m) from every link's surface and outside every link:
/// what the sensor sees that is not the arm.
pub fn self_filter(points: &[Point2<f64>], arm: &[Contour], margin: f64) -> Vec<Point2<f64>> {
    points
        .iter()
        .filter(|p| {
            arm.iter()
                .all(|c| !c.contains(p, 0.0) && c.nearest(p).1 > margin)
        })
        .copied()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scanner(beams: usize) -> Scanner {
        Scanner {
            origin: Point2::new(0.0, -1.0),
            first_angle: 0.0,
            fov: std::f64::consts::PI,
            beams,
            max_range: 5.0,
            range_sigma: 0.0,
        }
    }

    #[test]
    fn beams_hit_the_nearest_surface_and_the_filter_keeps_the_hand_only() {
        let arm = [Contour::stadium(
            Point2::new(-1.0, 0.0),
            Point2::new(1.0, 0.0),
            0.05,
        )];
        let hand = Disc {
            center: Point2::new(0.0, -0.15),
            radius: 0.1,
        };
        let s = scanner(181);
        let mut noise = Gaussian::new(1, 9);
        let ranges = s.scan(&arm, &[hand], &mut noise);
        // Straight up (beam 90) the hand's near side at y = −0.25.
        assert!((ranges[90] - 0.75).abs() < 1e-12, "{}", ranges[90]);
        // 45° to the right the arm's lower side at y = −0.05.
        assert!(
            (ranges[45] - 0.95 * 2f64.sqrt()).abs() < 1e-9,
            "{}",
            ranges[45]
        );
        // Nothing along the horizon within 5 m.
        assert!(ranges[0].is_infinite());
        let seen = self_filter(&s.points(&ranges), &arm, 0.02);
        assert!(!seen.is_empty());
        for p in &seen {
            assert!(((p - hand.center).norm() - hand.radius).abs() < 1e-9, "{p}");
        }
    }

    #[test]
    fn bad_settings_are_named() {
        let mut s = scanner(1);
        assert!(s.validate().unwrap_err().contains("beams"));
        s.beams = 8;
        s.range_sigma = -1.0;
        assert!(s.validate().unwrap_err().contains("range_sigma"));
    }
}
