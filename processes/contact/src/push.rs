//! Random pushes as the reference's Monte-Carlo draws them and the scripted person applies
//! them: a random pose, a point on the surface of a chosen link that a hand can reach, a
//! direction inside the friction cone and a magnitude near 100 N.

use crate::depth::Disc;
use crate::planar_arm::{ArmPose, PlanarArm};
use caravan_sensor::noise::Gaussian;
use nalgebra::{Point2, Rotation2, Vector2};

/// How pushes are drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct PushSpec {
    /// Links that may be pushed (0-based), drawn uniformly; the reference pushes its links 3
    /// and 4, indices 2 and 3.
    pub links: Vec<usize>,
    /// Force magnitude range, N, 0 < min ≤ max.
    pub force_n: (f64, f64),
    /// Friction coefficient: the direction is uniform in angle within atan μ of the inward
    /// normal.
    pub mu: f64,
    /// Radius of the hand pushing, m: it touches the surface from outside and may not
    /// overlap another link.
    pub hand_radius: f64,
}

/// One push.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Push {
    pub link: usize,
    /// On the link's surface, world frame, m.
    pub point: Point2<f64>,
    /// N, world frame.
    pub force: Vector2<f64>,
    /// The same in the link's frame.
    pub local_point: Point2<f64>,
    pub local_force: Vector2<f64>,
    /// The hand, touching the surface at `point`.
    pub hand: Disc,
}

impl PushSpec {
    pub fn validate(&self, arm: &PlanarArm) -> Result<(), String> {
        if self.links.is_empty() {
            return Err("'links' is empty".into());
        }
        if let Some(l) = self.links.iter().find(|l| **l >= arm.links()) {
            return Err(format!(
                "'links': link {} does not exist (the arm has {} links, numbered from 1)",
                l + 1,
                arm.links()
            ));
        }
        let (lo, hi) = self.force_n;
        if !(lo > 0.0 && lo <= hi && hi.is_finite()) {
            return Err(format!("'force_n' must be 0 < min ≤ max, got [{lo}, {hi}]"));
        }
        if !(self.mu.is_finite() && self.mu >= 0.0) {
            return Err(format!("'mu' must be ≥ 0, got {}", self.mu));
        }
        if !(self.hand_radius.is_finite() && self.hand_radius > 0.0) {
            return Err(format!(
                "'hand_radius' must be positive, got {} m",
                self.hand_radius
            ));
        }
        Ok(())
    }

    /// A push on `pose`, or `None` if 1000 draws found no reachable point (a pose folded
    /// onto itself).
    pub fn sample(&self, pose: &ArmPose, g: &mut Gaussian) -> Option<Push> {
        for _ in 0..1000 {
            let link = self.links
                [((g.uniform() * self.links.len() as f64) as usize).min(self.links.len() - 1)];
            let contour = &pose.contours[link];
            let (point, segment) = contour.point_at(g.uniform() * contour.perimeter());
            let outward = contour.outward_normal(segment);
            let hand = Disc {
                center: point + outward * self.hand_radius,
                radius: self.hand_radius,
            };
            let reachable = !pose.hidden(link, &point, 0.0)
                && pose.contours.iter().enumerate().all(|(i, c)| {
                    i == link
                        || (!c.contains(&hand.center, 0.0)
                            && c.nearest(&hand.center).1 > hand.radius)
                });
            if !reachable {
                continue;
            }
            let cone = self.mu.atan();
            let angle = (2.0 * g.uniform() - 1.0) * cone;
            let magnitude = self.force_n.0 + g.uniform() * (self.force_n.1 - self.force_n.0);
            let force = Rotation2::new(angle) * (-outward) * magnitude;
            let frame = pose.frames[link];
            return Some(Push {
                link,
                point,
                force,
                local_point: frame.inverse_transform_point(&point),
                local_force: frame.inverse_transform_vector(&force),
                hand,
            });
        }
        None
    }
}

/// The largest push on `links` (0-based) that every joint of the arm in `pose` holds, N, with
/// the joint that limits it and its lever (m): joint i holds `efforts[i]` (N·m), and a push
/// acts on it at most as far as the farthest point of a pushed link beyond it. A harder push
/// saturates the joint's actuator, the arm gives way, and the static identification has no
/// pose to hold the push in. `f64::INFINITY` (and joint 0) where no effort is finite.
pub fn holding_force_n(pose: &ArmPose, efforts: &[f64], links: &[usize]) -> (f64, usize, f64) {
    let mut best = (f64::INFINITY, 0, 0.0);
    for (i, (joint, effort)) in pose.joints.iter().zip(efforts).enumerate() {
        let lever = links
            .iter()
            .filter(|&&l| l >= i)
            .flat_map(|&l| pose.contours[l].vertices.iter())
            .map(|v| (v - joint).norm())
            .fold(0.0, f64::max);
        if lever > 0.0 && effort / lever < best.0 {
            best = (effort / lever, i, lever);
        }
    }
    best
}

/// Joint angles drawn uniformly within `limits` (rad, one (lower, upper) per joint).
pub fn sample_angles(limits: &[(f64, f64)], g: &mut Gaussian) -> Vec<f64> {
    limits
        .iter()
        .map(|(lo, hi)| lo + g.uniform() * (hi - lo))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushes_touch_the_chosen_links_from_outside_inside_the_cone() {
        let arm = PlanarArm::new(Point2::origin(), vec![0.4, 0.35, 0.3, 0.25, 0.2], 0.04).unwrap();
        let spec = PushSpec {
            links: vec![2, 3],
            force_n: (90.0, 110.0),
            mu: 0.5,
            hand_radius: 0.03,
        };
        let mut g = Gaussian::new(3, 0);
        let limits = vec![(-2.0, 2.0); 5];
        let mut seen = [0; 5];
        for _ in 0..500 {
            let pose = arm.pose(&sample_angles(&limits, &mut g));
            let Some(p) = spec.sample(&pose, &mut g) else {
                continue;
            };
            seen[p.link] += 1;
            let (_, dist, segment) = pose.contours[p.link].nearest(&p.point);
            assert!(dist < 1e-12);
            let inward = -pose.contours[p.link].outward_normal(segment);
            let cos = inward.dot(&p.force.normalize());
            assert!(
                cos >= 1.0 / 1.25f64.sqrt() - 1e-12,
                "outside the cone: {cos}"
            );
            assert!((90.0..=110.0).contains(&p.force.norm()));
            assert!((pose.frames[p.link] * p.local_point - p.point).norm() < 1e-12);
        }
        assert_eq!(seen[0] + seen[1] + seen[4], 0);
        assert!(seen[2] > 150 && seen[3] > 150, "{seen:?}");
    }

    #[test]
    fn the_holding_force_is_the_weakest_joints_effort_over_its_longest_lever() {
        let arm = PlanarArm::new(Point2::origin(), vec![1.0, 1.0, 1.0], 0.1).unwrap();
        let pose = arm.pose(&[0.0; 3]);
        // A push on link 2 (index 1) reaches 2.1 m from joint 0 (its tip plus the radius,
        // the contour's farthest vertex) and 1.1 m from joint 1; joint 2 carries none.
        let (f, joint, lever) = holding_force_n(&pose, &[400.0, 100.0, 1.0], &[1]);
        assert_eq!(joint, 1);
        assert!((lever - 1.1).abs() < 5e-3, "{lever}");
        assert!((f - 100.0 / lever).abs() < 1e-9, "{f}");
        let (f, joint, _) = holding_force_n(&pose, &[f64::INFINITY; 3], &[1]);
        assert_eq!((f, joint), (f64::INFINITY, 0));
    }
}
