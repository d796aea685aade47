//! The leader's goal sequence and its simplest driver. With a planner (`cmd_vel_topic`), the
//! leader only tracks goal progress and passes the planner's command on within the limits;
//! without one it turns toward the current goal and drives within the reference limits (heading gain 0.7 s⁻¹: the wheels' slow, overshooting
//! speed loop makes higher gains weave) v ∈ [0.1, 0.2] m/s, ω ∈ [−1.5, 2.0] rad/s, advancing
//! to the next goal within the tolerance and stopping at the last.

use crate::agent::angle::wrap;
use caravan_schemas::Pose2D;
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct LeaderParams {
    /// Goals A, B, C, D… in order, as [x, y] in the map frame, m, each coordinate within ±10
    /// 000. Empty: the `world` file's `[[goal]]`s; a leader needs at least one.
    pub goals: Vec<[f64; 2]>,
    /// A goal is reached within this distance, m, above 0, at most 10.
    pub tolerance_m: f64,
    /// Slowest forward speed while driving, m/s, 0 to `leader.v_max` (planner commands are
    /// clamped up to it).
    pub v_min: f64,
    /// Fastest forward speed, m/s, above 0, at most 2.5.
    pub v_max: f64,
    /// Most clockwise turn rate, rad/s, −20 to 0.
    pub omega_min: f64,
    /// Most counter-clockwise turn rate, rad/s, above 0, at most 20.
    pub omega_max: f64,
    /// Heading gain of the straight-to-goal driver, 1/s, above 0, at most 20.
    pub k_heading: f64,
}

impl Default for LeaderParams {
    fn default() -> Self {
        Self {
            goals: Vec::new(),
            tolerance_m: 0.15,
            v_min: 0.1,
            v_max: 0.2,
            omega_min: -1.5,
            omega_max: 2.0,
            k_heading: 0.7,
        }
    }
}

/// Progress through the goal sequence.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Index of the goal being driven to; `goals.len()` once all were reached.
    pub current: usize,
}

impl Progress {
    pub fn finished(&self, p: &LeaderParams) -> bool {
        self.current >= p.goals.len()
    }
}

/// Moves `progress` past every goal within the tolerance of `pose`; returns the goal to drive
/// to, or `None` once all were reached.
pub fn advance(pose: Pose2D, progress: &mut Progress, p: &LeaderParams) -> Option<[f64; 2]> {
    while let Some(goal) = p.goals.get(progress.current) {
        if (goal[0] - pose.x).hypot(goal[1] - pose.y) > p.tolerance_m {
            return Some(*goal);
        }
        progress.current += 1;
    }
    None
}

/// A planner's command held to the leader's limits; `None` (no fresh command) stops.
pub fn limit(cmd: Option<(f64, f64)>, p: &LeaderParams) -> (f64, f64) {
    match cmd {
        Some((v, omega)) => (
            v.clamp(p.v_min, p.v_max),
            omega.clamp(p.omega_min, p.omega_max),
        ),
        None => (0.0, 0.0),
    }
}

/// Updates `progress` for the pose and returns the straight-to-goal command (v, ω).
pub fn command(pose: Pose2D, progress: &mut Progress, p: &LeaderParams) -> (f64, f64) {
    let Some(goal) = advance(pose, progress, p) else {
        return (0.0, 0.0);
    };
    let heading_error = wrap((goal[1] - pose.y).atan2(goal[0] - pose.x) - pose.theta);
    let omega = (p.k_heading * heading_error).clamp(p.omega_min, p.omega_max);
    // Slow down while facing away from the goal, but never under the planner's minimum speed.
    let v = (p.v_max * heading_error.cos().max(0.0)).clamp(p.v_min, p.v_max);
    (v, omega)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> LeaderParams {
        LeaderParams {
            goals: vec![[2.0, 0.0], [2.0, 2.0]],
            ..Default::default()
        }
    }

    #[test]
    fn drives_straight_at_full_speed_toward_the_goal() {
        let mut pr = Progress::default();
        let (v, w) = command(
            Pose2D {
                x: 0.0,
                y: 0.0,
                theta: 0.0,
            },
            &mut pr,
            &params(),
        );
        assert_eq!((v, w), (0.2, 0.0));
    }

    #[test]
    fn turns_within_limits_at_minimum_speed() {
        let mut pr = Progress::default();
        let (v, w) = command(
            Pose2D {
                x: 0.0,
                y: 0.0,
                theta: std::f64::consts::PI,
            },
            &mut pr,
            &params(),
        );
        assert_eq!(v, 0.1);
        assert!(w == -1.5 || w == 2.0, "{w}");
    }

    #[test]
    fn planner_commands_are_held_to_the_limits_and_a_missing_one_stops() {
        let p = params();
        assert_eq!(limit(Some((0.5, -3.0)), &p), (0.2, -1.5));
        assert_eq!(limit(Some((0.0, 3.0)), &p), (0.1, 2.0));
        assert_eq!(limit(None, &p), (0.0, 0.0));
    }

    #[test]
    fn advances_through_goals_and_stops_after_the_last() {
        let p = params();
        let mut pr = Progress::default();
        command(
            Pose2D {
                x: 1.9,
                y: 0.05,
                theta: 0.0,
            },
            &mut pr,
            &p,
        );
        assert_eq!(pr.current, 1);
        let (v, w) = command(
            Pose2D {
                x: 2.0,
                y: 1.95,
                theta: 1.57,
            },
            &mut pr,
            &p,
        );
        assert!(pr.finished(&p));
        assert_eq!((v, w), (0.0, 0.0));
    }
}
