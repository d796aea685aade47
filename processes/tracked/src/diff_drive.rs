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
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DriveLimits {
    /// |v| bound, m/s, in [`ranges::MAX_V_M_S`].
    #[serde(default = "max_v")]
    pub max_v_m_s: f64,
    /// |ω| bound, rad/s, in [`ranges::MAX_W_RAD_S`].
    #[serde(default = "max_w")]
    pub max_w_rad_s: f64,
    /// |dv/dt| bound, m/s², in [`ranges::MAX_ACCEL_M_S2`].
    #[serde(default = "max_a")]
    pub max_accel_m_s2: f64,
    /// |dω/dt| bound, rad/s², in [`ranges::MAX_ALPHA_RAD_S2`].
    #[serde(default = "max_alpha")]
    pub max_alpha_rad_s2: f64,
    /// Wheel radius for the speeds and odometry, m, in [`ranges::WHEEL_RADIUS_M`]. Default (0 here): the first wheel's
    /// circumscribed radius from the robot description (a gear's tip circle, as the
    /// reference's 0.06256 m).
    #[serde(default)]
    pub wheel_radius_m: f64,
    /// Distance between the two tracks, m, in [`ranges::WHEEL_SEPARATION_M`].
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

/// The physical range of each of [`DriveLimits`]' keys, and why.
pub mod ranges {
    use crate::params::Range;

    /// |v| bound: 12 × the reference's 0.4 m/s at most. At 5 m/s the robot moves 2 cm in one
    /// 4 ms physics step (the scenario's 250 Hz), a fifth of a terrain block: faster, a wheel
    /// crosses a block's edge between two steps.
    pub const MAX_V_M_S: Range = Range::positive(5.0, "m/s");
    /// |ω| bound: 20 × the reference's 0.5 rad/s at most; at the drive's 50 Hz that is 0.2 rad
    /// (11°) a tick, more than any operator turns a tracked robot.
    pub const MAX_W_RAD_S: Range = Range::positive(10.0, "rad/s");
    /// |dv/dt| bound: about g at most. A track's grip gives at most μ·g, and no world here
    /// has μ above 1: asking more only spins the wheels. At 50 Hz, 0.2 m/s a tick.
    pub const MAX_ACCEL_M_S2: Range = Range::positive(10.0, "m/s²");
    /// |dω/dt| bound: the tracks' acceleration α·separation/2 at the reference's 0.2 m
    /// separation then reaches max_accel's 10 m/s² bound.
    pub const MAX_ALPHA_RAD_S2: Range = Range::positive(100.0, "rad/s²");
    /// Wheel radius: 1 mm (the variants' smallest wheel is 12 mm) to 100 m, the launcher's
    /// largest part of a robot. The drive also checks the wheel speeds it can then ask for
    /// against the URDF's velocity limits ([`super::DriveLimits::top_wheel_speed`]), the
    /// tighter bound: a radius far below the wheels' asks for speeds the physics clips.
    pub const WHEEL_RADIUS_M: Range = Range::closed(0.001, 100.0, "m");
    /// Distance between the tracks: a centimetre to 100 m, the launcher's largest part of a
    /// robot.
    pub const WHEEL_SEPARATION_M: Range = Range::closed(0.01, 100.0, "m");
}

impl DriveLimits {
    /// Checks every value against its range ([`ranges`]); the error names the key.
    pub fn validate(&self) -> Result<(), String> {
        use ranges::*;
        MAX_V_M_S.check("max_v_m_s", self.max_v_m_s)?;
        MAX_W_RAD_S.check("max_w_rad_s", self.max_w_rad_s)?;
        MAX_ACCEL_M_S2.check("max_accel_m_s2", self.max_accel_m_s2)?;
        MAX_ALPHA_RAD_S2.check("max_alpha_rad_s2", self.max_alpha_rad_s2)?;
        WHEEL_RADIUS_M.check("wheel_radius_m", self.wheel_radius_m)?;
        WHEEL_SEPARATION_M.check("wheel_separation_m", self.wheel_separation_m)?;
        Ok(())
    }

    /// The fastest wheel speed the drive can ask for, rad/s: one side at the speed limit
    /// while the robot turns at the turn limit.
    pub fn top_wheel_speed(&self) -> f64 {
        (self.max_v_m_s + self.max_w_rad_s * self.wheel_separation_m / 2.0) / self.wheel_radius_m
    }

    /// Checks [`Self::top_wheel_speed`] against the slowest wheel joint's velocity limit
    /// (rad/s, from the URDF `file`; ∞ where it gives none): the physics holds a wheel at
    /// its limit, so a faster ask would not drive the robot at the speeds commanded (a
    /// radius of 1e-300 m asked for 4e299 rad/s and the robot went at its wheels' 0.9 m/s
    /// against the 0.4 m/s limit). The error names `wheel_radius_m` when it was given
    /// (`radius_given`), else `max_v_m_s`.
    pub fn check_wheel_speed(
        &self,
        limit_rad_s: f64,
        file: &str,
        radius_given: bool,
    ) -> Result<(), String> {
        let top = self.top_wheel_speed();
        if top <= limit_rad_s * (1.0 + 1e-9) {
            return Ok(());
        }
        let key = if radius_given {
            "wheel_radius_m"
        } else {
            "max_v_m_s"
        };
        Err(format!(
            "key '{key}': the drive would ask the wheels for up to {top:.3} rad/s \
             ((max_v_m_s + max_w_rad_s·wheel_separation_m/2) / wheel_radius_m with \
             wheel_radius_m = {} m), above their joints' velocity limit of {} rad/s in {file}; \
             the physics would hold them there and the robot would not go at the speeds \
             commanded",
            crate::params::show_exact(self.wheel_radius_m),
            crate::params::show(limit_rad_s)
        ))
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
        assert!(reference().validate().is_ok());
        let with = |f: &dyn Fn(&mut DriveLimits)| {
            let mut l = reference();
            f(&mut l);
            l.validate().unwrap_err()
        };
        assert_eq!(
            with(&|l| l.wheel_radius_m = 1e-300),
            "key 'wheel_radius_m': must be between 0.001 and 100 m, got 1e-300"
        );
        assert!(
            with(&|l| l.max_v_m_s = 6.0).contains("'max_v_m_s': must be above 0 and at most 5 m/s")
        );
        assert!(with(&|l| l.max_w_rad_s = f64::NAN).contains("'max_w_rad_s'"));
        assert!(with(&|l| l.max_accel_m_s2 = 0.0).contains("'max_accel_m_s2'"));
        assert!(with(&|l| l.max_alpha_rad_s2 = 1e3).contains("'max_alpha_rad_s2'"));
        assert!(with(&|l| l.wheel_separation_m = -0.2).contains("'wheel_separation_m'"));
    }

    #[test]
    fn a_wheel_radius_far_below_the_wheels_asks_for_speeds_past_their_limit() {
        // The reference: 0.45 m/s on the outer track at full speed and turn, 7.2 rad/s of 14.
        let l = reference();
        assert!((l.top_wheel_speed() - 0.45 / 0.06256).abs() < 1e-12);
        assert!(l.check_wheel_speed(14.0, "v4.urdf", true).is_ok());
        assert!(l.check_wheel_speed(f64::INFINITY, "v4.urdf", true).is_ok());
        let tiny = DriveLimits {
            wheel_radius_m: 0.01,
            ..l
        };
        let e = tiny.check_wheel_speed(14.0, "v4.urdf", true).unwrap_err();
        assert!(
            e.starts_with(
                "key 'wheel_radius_m': the drive would ask the wheels for up to 45.000 rad/s"
            ) && e.contains("14 rad/s in v4.urdf"),
            "{e}"
        );
        let fast = DriveLimits {
            max_v_m_s: 1.0,
            ..l
        };
        let e = fast.check_wheel_speed(14.0, "v4.urdf", false).unwrap_err();
        assert!(e.starts_with("key 'max_v_m_s'"), "{e}");
    }
}
