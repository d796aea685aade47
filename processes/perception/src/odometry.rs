//! Follower dead reckoning from wheel encoder counts.
//!
//! Between two readings each wheel turned Δφ = 2π·Δticks / ticks_per_rev, so base_link moved
//! Δs = r·(Δφ_R + Δφ_L)/2 along its path and turned Δθ = r·(Δφ_R − Δφ_L)/l. Taking the wheel
//! speeds as constant between readings, the path is a circular arc, whose chord has length
//! Δs·sinc(Δθ/2) in the direction θ + Δθ/2. This is exact for constant wheel speeds, and
//! reduces to the midpoint rule (and stays well conditioned) as Δθ → 0. Slip and encoder
//! quantisation are not corrected: the estimate drifts, as the reference's followers did.

use crate::matcher::wrap_angle;
use caravan_schemas::{EncoderTicks, Pose2D};

/// A dead-reckoning pose and the mean velocities over the last interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryEstimate {
    pub pose: Pose2D,
    /// Forward speed, m/s.
    pub v: f64,
    /// Turn rate, rad/s (counter-clockwise positive).
    pub omega: f64,
}

/// Differential-drive dead reckoning.
#[derive(Debug, Clone)]
pub struct WheelOdometry {
    pose: Pose2D,
    wheel_radius: f64,
    wheel_separation: f64,
    /// Time and counts of the previous reading.
    last: Option<(f64, EncoderTicks)>,
}

impl WheelOdometry {
    /// Odometry starting at `initial` for wheels of radius `wheel_radius_m` spaced
    /// `wheel_separation_m` apart (the robot's URDF has both).
    pub fn new(initial: Pose2D, wheel_radius_m: f64, wheel_separation_m: f64) -> Self {
        assert!(
            wheel_radius_m > 0.0 && wheel_separation_m > 0.0,
            "wheel radius and separation must be positive"
        );
        Self {
            pose: initial,
            wheel_radius: wheel_radius_m,
            wheel_separation: wheel_separation_m,
            last: None,
        }
    }

    pub fn pose(&self) -> Pose2D {
        self.pose
    }

    /// Integrates the counts read at time `t_s` (s). The first reading only sets the reference
    /// counts and returns `None`, as does a reading with `ticks_per_rev` = 0 (ignored). Speeds
    /// are 0 when the time did not advance.
    pub fn update(&mut self, t_s: f64, ticks: &EncoderTicks) -> Option<OdometryEstimate> {
        if ticks.ticks_per_rev == 0 {
            return None;
        }
        let (t0, before) = self.last.replace((t_s, *ticks))?;
        let rad_per_tick = std::f64::consts::TAU / ticks.ticks_per_rev as f64;
        let left = ticks.left.wrapping_sub(before.left) as f64 * rad_per_tick;
        let right = ticks.right.wrapping_sub(before.right) as f64 * rad_per_tick;
        let ds = self.wheel_radius * (right + left) / 2.0;
        let dtheta = self.wheel_radius * (right - left) / self.wheel_separation;
        let half = dtheta / 2.0;
        let chord = ds * sinc(half);
        let heading = self.pose.theta + half;
        self.pose.x += chord * heading.cos();
        self.pose.y += chord * heading.sin();
        self.pose.theta = wrap_angle(self.pose.theta + dtheta);
        let dt = t_s - t0;
        let (v, omega) = if dt > 0.0 {
            (ds / dt, dtheta / dt)
        } else {
            (0.0, 0.0)
        };
        Some(OdometryEstimate {
            pose: self.pose,
            v,
            omega,
        })
    }
}

/// sin(x)/x, by its series near 0.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // The convoy robot's wheels.
    const R: f64 = 0.067;
    const L: f64 = 0.172;

    /// Drives at constant (v, ω) from `start` for `duration` s, with encoder readings at 50 Hz
    /// from the exact wheel angles; returns the last estimate.
    fn drive(start: Pose2D, v: f64, omega: f64, duration: f64, tpr: u32) -> OdometryEstimate {
        let right = (2.0 * v + L * omega) / (2.0 * R);
        let left = (2.0 * v - L * omega) / (2.0 * R);
        let mut odo = WheelOdometry::new(start, R, L);
        let ticks = |t: f64| EncoderTicks {
            left: (left * t / std::f64::consts::TAU * tpr as f64).floor() as i64,
            right: (right * t / std::f64::consts::TAU * tpr as f64).floor() as i64,
            ticks_per_rev: tpr,
            _reserved: 0,
        };
        assert!(odo.update(0.0, &ticks(0.0)).is_none());
        let steps = (duration * 50.0).round() as usize;
        let mut last = None;
        for k in 1..=steps {
            let t = k as f64 / 50.0;
            last = odo.update(t, &ticks(t));
        }
        last.unwrap()
    }

    fn assert_pose(got: Pose2D, want: Pose2D, tol: f64) {
        assert!(
            (got.x - want.x).abs() < tol
                && (got.y - want.y).abs() < tol
                && wrap_angle(got.theta - want.theta).abs() < tol,
            "{got:?} vs {want:?}"
        );
    }

    fn pose(x: f64, y: f64, theta: f64) -> Pose2D {
        Pose2D { x, y, theta }
    }

    #[test]
    fn straight_line() {
        let e = drive(pose(1.0, 2.0, 0.5), 0.2, 0.0, 5.0, 1 << 20);
        assert_pose(
            e.pose,
            pose(1.0 + 0.5f64.cos(), 2.0 + 0.5f64.sin(), 0.5),
            1e-5,
        );
        assert!((e.v - 0.2).abs() < 1e-3 && e.omega.abs() < 1e-3);
    }

    #[test]
    fn rotation_in_place() {
        let e = drive(pose(0.0, 0.0, 0.0), 0.0, 1.5, 2.0, 1 << 20);
        assert_pose(e.pose, pose(0.0, 0.0, 3.0), 1e-5);
        assert!(e.v.abs() < 1e-3 && (e.omega - 1.5).abs() < 1e-3);
    }

    #[test]
    fn arc() {
        // v = 0.2, ω = 0.5: a circle of radius 0.4 m about (0, 0.4), for 4 s (2 rad).
        let (v, w, t): (f64, f64, f64) = (0.2, 0.5, 4.0);
        let want = pose((w * t).sin() * v / w, (1.0 - (w * t).cos()) * v / w, w * t);
        assert_pose(
            drive(pose(0.0, 0.0, 0.0), v, w, t, 1 << 20).pose,
            want,
            1e-5,
        );
        // With a coarse 360-tick encoder the error is the quantisation: at most one tick per
        // wheel, 1.2 mm of wheel travel, 6.8 mrad of heading at the end.
        let coarse = drive(pose(0.0, 0.0, 0.0), v, w, t, 360);
        assert_pose(coarse.pose, want, 0.01);
    }

    #[test]
    fn first_reading_and_bad_readings_are_not_integrated() {
        let mut odo = WheelOdometry::new(pose(0.0, 0.0, 0.0), R, L);
        let t = |l, r, tpr| EncoderTicks {
            left: l,
            right: r,
            ticks_per_rev: tpr,
            _reserved: 0,
        };
        assert!(odo.update(0.0, &t(1000, 1000, 360)).is_none());
        assert!(odo.update(0.1, &t(1360, 1360, 0)).is_none());
        let e = odo.update(0.1, &t(1360, 1360, 360)).unwrap();
        assert!((e.pose.x - std::f64::consts::TAU * R).abs() < 1e-12);
        assert!((e.v - std::f64::consts::TAU * R / 0.1).abs() < 1e-9);
        let e = odo.update(0.1, &t(1360, 1360, 360)).unwrap();
        assert_eq!((e.v, e.omega), (0.0, 0.0));
    }
}
