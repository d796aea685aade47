//! The planar serial arm: n revolute joints with parallel axes (z), link i turning about
//! joint i and carrying joint i + 1 at its far end; each link's surface is a stadium contour
//! around its centre line. Its kinematics, and the torques a force at a point produces.

use crate::contour::Contour;
use nalgebra::{Isometry2, Point2, Vector2};

/// Most links an arm may have (the identification keeps its work on the stack).
pub const MAX_LINKS: usize = 8;

/// The arm's geometry. Links and joints are numbered from 0 here; the reference's link k is
/// index k − 1.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanarArm {
    /// Joint 0's axis in the plane, m.
    pub base: Point2<f64>,
    /// Length of each link, m, > 0: joint i to joint i + 1, the last one joint to tip.
    pub lengths: Vec<f64>,
    /// Half-width of every link's surface (the stadium's radius), m, > 0.
    pub radius: f64,
    /// Each link's surface in its own frame, built once.
    local_contours: Vec<Contour>,
}

/// The arm at one set of joint angles.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmPose {
    /// Joint axes in the plane, m.
    pub joints: Vec<Point2<f64>>,
    /// Each link's frame: origin on its joint, x along the link.
    pub frames: Vec<Isometry2<f64>>,
    /// Each link's surface in the plane.
    pub contours: Vec<Contour>,
}

impl PlanarArm {
    pub fn new(base: Point2<f64>, lengths: Vec<f64>, radius: f64) -> Result<Self, String> {
        if lengths.len() < 3 || lengths.len() > MAX_LINKS {
            return Err(format!(
                "an arm needs 3 to {MAX_LINKS} links, got {}",
                lengths.len()
            ));
        }
        if let Some(l) = lengths.iter().find(|l| !(l.is_finite() && **l > 0.0)) {
            return Err(format!("link lengths must be positive, got {l} m"));
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(format!("the link radius must be positive, got {radius} m"));
        }
        let local_contours = lengths
            .iter()
            .map(|l| Contour::stadium(Point2::origin(), Point2::new(*l, 0.0), radius))
            .collect();
        Ok(Self {
            base,
            lengths,
            radius,
            local_contours,
        })
    }

    pub fn links(&self) -> usize {
        self.lengths.len()
    }

    /// Link `i`'s surface in its own frame.
    pub fn local_contour(&self, i: usize) -> &Contour {
        &self.local_contours[i]
    }

    /// The arm at joint angles `q` (rad, one per link; each relative to the previous link).
    pub fn pose(&self, q: &[f64]) -> ArmPose {
        assert_eq!(q.len(), self.links(), "one angle per joint");
        let mut joints = Vec::with_capacity(q.len());
        let mut frames = Vec::with_capacity(q.len());
        let mut contours = Vec::with_capacity(q.len());
        let (mut at, mut heading) = (self.base, 0.0);
        for (i, qi) in q.iter().enumerate() {
            heading += qi;
            let frame = Isometry2::new(at.coords, heading);
            joints.push(at);
            contours.push(self.local_contour(i).transformed(&frame));
            frames.push(frame);
            at += self.lengths[i] * Vector2::new(heading.cos(), heading.sin());
        }
        ArmPose {
            joints,
            frames,
            contours,
        }
    }
}

impl ArmPose {
    /// The torque about each joint (N·m) of force `force` (N) acting at `point` (m) on link
    /// `link`: τ_i = (x_p − x_i)·F_y − (y_p − y_i)·F_x for i ≤ link, 0 beyond.
    pub fn torques(&self, link: usize, point: &Point2<f64>, force: &Vector2<f64>) -> Vec<f64> {
        self.joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                if i <= link {
                    (point - j).perp(force)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Whether `point` lies inside some link other than `link`, deeper than `margin` (m): a
    /// place no one can touch.
    pub fn hidden(&self, link: usize, point: &Point2<f64>, margin: f64) -> bool {
        self.contours
            .iter()
            .enumerate()
            .any(|(i, c)| i != link && c.contains(point, margin))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joints_follow_the_summed_angles() {
        let arm = PlanarArm::new(Point2::new(1.0, 0.0), vec![1.0, 0.5, 0.25], 0.05).unwrap();
        let pose = arm.pose(&[
            std::f64::consts::FRAC_PI_2,
            -std::f64::consts::FRAC_PI_2,
            0.0,
        ]);
        let expected = [(1.0, 0.0), (1.0, 1.0), (1.5, 1.0)];
        for (j, (x, y)) in pose.joints.iter().zip(expected) {
            assert!((j - Point2::new(x, y)).norm() < 1e-12, "{j}");
        }
        // The last link's surface reaches its tip plus the radius (the polygon is inscribed
        // in the half circle, whose middle falls on a segment's midpoint).
        let tip = pose.contours[2]
            .vertices
            .iter()
            .map(|v| v.x)
            .fold(f64::MIN, f64::max);
        assert!((tip - (1.75 + 0.05 * (std::f64::consts::PI / 14.0).cos())).abs() < 1e-12);
    }

    #[test]
    fn torques_are_the_moments_about_the_joints_up_to_the_touched_link() {
        let arm = PlanarArm::new(Point2::origin(), vec![1.0, 1.0, 1.0, 1.0], 0.05).unwrap();
        let pose = arm.pose(&[0.0; 4]);
        // 10 N along +y at x = 2.5 on link 2: lever arms 2.5, 1.5, 0.5.
        let tau = pose.torques(2, &Point2::new(2.5, 0.05), &Vector2::new(0.0, 10.0));
        assert_eq!(tau, vec![25.0, 15.0, 5.0, 0.0]);
    }

    #[test]
    fn bad_geometry_is_named() {
        assert!(PlanarArm::new(Point2::origin(), vec![1.0, 1.0], 0.1).is_err());
        assert!(PlanarArm::new(Point2::origin(), vec![1.0, -1.0, 1.0], 0.1).is_err());
        assert!(PlanarArm::new(Point2::origin(), vec![1.0; 3], 0.0).is_err());
    }
}
