//! The tracked robot's differential-drive controller, as the reference's (ros_control's
//! `diff_drive_controller`): a commanded body velocity (v, ω) is limited in magnitude and
//! rate, then turned into one wheel speed per side, the same for every wheel of that side;
//! wheel odometry integrates the mean joint angle of each side.

use caravan_world::description::{Geometry, Link};
use serde::Deserialize;

/// The radius of the circle about a wheel link's axis (its y axis) that holds all its
/// collision shapes: a round wheel's radius, a gear's tip circle. Cylinders, capsules and
/// boxes only.
pub fn circumscribed_radius(link: &Link) -> f64 {
    link.collisions
        .iter()
        .map(|c| {
            let p = c.origin.translation.vector;
            match c.geometry {
                Geometry::Cylinder { radius, .. } => p.x.hypot(p.z) + radius,
                Geometry::Capsule { radius, length } => {
                    // Both ends of its segment.
                    let axis = c.origin.rotation * nalgebra::Vector3::z() * (length / 2.0);
                    let (a, b) = (p + axis, p - axis);
                    a.x.hypot(a.z).max(b.x.hypot(b.z)) + radius
                }
                Geometry::Box { half_extents } => {
                    // The farthest corner from the y axis, in the link's x–z plane.
                    let r = c.origin.rotation;
                    let mut far: f64 = 0.0;
                    for sx in [-1.0, 1.0] {
                        for sy in [-1.0, 1.0] {
                            for sz in [-1.0, 1.0] {
                                let corner = nalgebra::Vector3::new(
                                    sx * half_extents[0],
                                    sy * half_extents[1],
                                    sz * half_extents[2],
                                );
                                let q = p + r * corner;
                                far = far.max(q.x.hypot(q.z));
                            }
                        }
                    }
                    far
                }
                _ => 0.0,
            }
        })
        .fold(0.0, f64::max)
}

/// The reference's limits and geometry; every field has the reference's value as default.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveLimits {
    /// |v| bound, m/s, > 0.
    #[serde(default = "max_v")]
    pub max_v_m_s: f64,
    /// |ω| bound, rad/s, > 0.
    #[serde(default = "max_w")]
    pub max_w_rad_s: f64,
    /// |dv/dt| bound, m/s², > 0.
    #[serde(default = "max_a")]
    pub max_accel_m_s2: f64,
    /// |dω/dt| bound, rad/s², > 0.
    #[serde(default = "max_alpha")]
    pub max_alpha_rad_s2: f64,
    /// Wheel radius for the speeds and odometry, m, > 0. Default (0 here): the first wheel's
    /// circumscribed radius from the robot description (a gear's tip circle, as the
    /// reference's 0.06256 m).
    #[serde(default)]
    pub wheel_radius_m: f64,
    /// Distance between the two tracks, m, > 0.
    #[serde(default = "separation")]
    pub wheel_separation_m: f64,
}

fn max_v() -> f64 {
    0.4
}
fn max_w() -> f64 {
    0.5
}
fn max_a() -> f64 {
    0.2
}
fn max_alpha() -> f64 {
    0.5
}
fn separation() -> f64 {
    2.0 * crate::running_gear::MAIN_Y_M
}

impl Default for DriveLimits {
    fn default() -> Self {
        Self {
            max_v_m_s: max_v(),
            max_w_rad_s: max_w(),
            max_accel_m_s2: max_a(),
            max_alpha_rad_s2: max_alpha(),
            wheel_radius_m: 0.0,
            wheel_separation_m: separation(),
        }
    }
}

impl DriveLimits {
    /// Checks every value is positive; the error names the key.
    pub fn validate(&self) -> Result<(), String> {
        crate::params::all_positive(
            "",
            &[
                ("max_v_m_s", self.max_v_m_s),
                ("max_w_rad_s", self.max_w_rad_s),
                ("max_accel_m_s2", self.max_accel_m_s2),
                ("max_alpha_rad_s2", self.max_alpha_rad_s2),
                ("wheel_radius_m", self.wheel_radius_m),
                ("wheel_separation_m", self.wheel_separation_m),
            ],
        )
    }
}

/// The controller's state: the last (v, ω) it sent.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DiffDrive {
    pub v_m_s: f64,
    pub w_rad_s: f64,
}

impl DiffDrive {
    /// Moves towards the commanded (v, ω) within the limits over `dt_s`; returns the wheel
    /// speeds (left, right), rad/s.
    pub fn update(&mut self, limits: &DriveLimits, v: f64, w: f64, dt_s: f64) -> (f64, f64) {
        let toward = |now: f64, target: f64, bound: f64, rate: f64| {
            let target = if target.is_finite() {
                target.clamp(-bound, bound)
            } else {
                0.0
            };
            now + (target - now).clamp(-rate * dt_s, rate * dt_s)
        };
        self.v_m_s = toward(self.v_m_s, v, limits.max_v_m_s, limits.max_accel_m_s2);
        self.w_rad_s = toward(self.w_rad_s, w, limits.max_w_rad_s, limits.max_alpha_rad_s2);
        let half = limits.wheel_separation_m / 2.0;
        (
            (self.v_m_s - self.w_rad_s * half) / limits.wheel_radius_m,
            (self.v_m_s + self.w_rad_s * half) / limits.wheel_radius_m,
        )
    }
}

/// Wheel odometry: a planar pose integrated from the change of each side's mean wheel angle.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WheelOdometry {
    pub x_m: f64,
    pub y_m: f64,
    pub yaw_rad: f64,
    /// Body velocity from the last update: forward m/s, turn rad/s.
    pub v_m_s: f64,
    pub w_rad_s: f64,
    last: Option<(f64, f64)>,
}

impl WheelOdometry {
    /// Takes each side's mean wheel angle (rad) `dt_s` after the last call.
    pub fn update(&mut self, limits: &DriveLimits, left_rad: f64, right_rad: f64, dt_s: f64) {
        if let Some((l0, r0)) = self.last {
            let r = limits.wheel_radius_m;
            let (dl, dr) = ((left_rad - l0) * r, (right_rad - r0) * r);
            let ds = (dl + dr) / 2.0;
            let dyaw = (dr - dl) / limits.wheel_separation_m;
            // Midpoint heading: exact for a constant-curvature step.
            let mid = self.yaw_rad + dyaw / 2.0;
            self.x_m += ds * mid.cos();
            self.y_m += ds * mid.sin();
            self.yaw_rad += dyaw;
            if dt_s > 0.0 {
                self.v_m_s = ds / dt_s;
                self.w_rad_s = dyaw / dt_s;
            }
        }
        self.last = Some((left_rad, right_rad));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference's limits with its big gear's radius.
    fn reference() -> DriveLimits {
        DriveLimits {
            wheel_radius_m: 0.06256,
            ..DriveLimits::default()
        }
    }

    #[test]
    fn speed_ramps_at_the_acceleration_limit_and_stops_at_the_speed_limit() {
        let l = reference();
        let mut d = DiffDrive::default();
        // 50 Hz for 3 s towards 1 m/s: 0.2 m/s² until 0.4 m/s at 2 s.
        let mut at_1s = 0.0;
        for k in 1..=150 {
            d.update(&l, 1.0, 0.0, 0.02);
            if k == 50 {
                at_1s = d.v_m_s;
            }
        }
        assert!((at_1s - 0.2).abs() < 1e-12, "{at_1s}");
        assert!((d.v_m_s - 0.4).abs() < 1e-12);
        let (left, right) = d.update(&l, 1.0, 0.0, 0.02);
        assert_eq!(left, right);
        assert!((left - 0.4 / 0.06256).abs() < 1e-12);
    }

    #[test]
    fn turning_splits_the_sides_by_the_separation() {
        let l = reference();
        let mut d = DiffDrive {
            v_m_s: 0.0,
            w_rad_s: 0.5,
        };
        let (left, right) = d.update(&l, 0.0, 2.0, 0.02);
        assert!((right - 0.5 * 0.1 / 0.06256).abs() < 1e-12);
        assert_eq!(left, -right);
        // NaN commands stop the robot, gently.
        d.update(&l, f64::NAN, f64::NAN, 0.02);
        assert!((d.w_rad_s - 0.49).abs() < 1e-12);
    }

    #[test]
    fn odometry_follows_a_circle() {
        let l = reference();
        let mut o = WheelOdometry::default();
        // v = 0.2 m/s, ω = 0.5 rad/s for 2π/ω s: one full circle back to the start.
        let (v, w) = (0.2, 0.5);
        let steps = 1000;
        let dt = std::f64::consts::TAU / w / steps as f64;
        let (wl, wr) = (
            (v - w * 0.1) / l.wheel_radius_m,
            (v + w * 0.1) / l.wheel_radius_m,
        );
        for k in 0..=steps {
            let t = k as f64 * dt;
            o.update(&l, wl * t, wr * t, dt);
        }
        assert!(o.x_m.abs() < 1e-9 && o.y_m.abs() < 1e-9, "{o:?}");
        assert!((o.yaw_rad - std::f64::consts::TAU).abs() < 1e-9);
        assert!((o.v_m_s - v).abs() < 1e-9 && (o.w_rad_s - w).abs() < 1e-9);
    }

    #[test]
    fn bad_limits_name_their_key() {
        let bad = DriveLimits::default();
        assert!(bad.validate().unwrap_err().contains("'wheel_radius_m'"));
    }
}
