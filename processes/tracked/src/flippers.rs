//! The flippers' command path: the operator asks for an angle on
//! [`flipper_command`]; the drive moves each flipper's position target toward it no faster
//! than the joint's speed limit ([`FlipperRamp`]), as a joint trajectory controller would, and
//! the physics' servo follows. Angles are the URDF's: rad above the main track's line, 0 in
//! line, positive raises the tip.

use caravan_schemas::{JointCommand, Topic};

/// The operator's flipper angles for robot `i` (`robot/i/flipper_command`): a position per
/// flipper joint, by name; NaN keeps that flipper's angle.
pub fn flipper_command(i: usize) -> Topic<JointCommand> {
    Topic::new(&format!("robot/{i}/flipper_command"))
}

/// A position target moving toward the asked angle at a bounded speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlipperRamp {
    /// Where the target is now, rad.
    pub position_rad: f64,
    /// Where it is going, rad.
    pub goal_rad: f64,
    /// Largest speed, rad/s, > 0.
    pub speed_rad_s: f64,
    /// The joint's range, rad: goals beyond it stop at its end.
    pub range_rad: [f64; 2],
}

impl FlipperRamp {
    /// A ramp resting at `position_rad` (brought into `range_rad`).
    pub fn at(position_rad: f64, speed_rad_s: f64, range_rad: [f64; 2]) -> Self {
        let position_rad = position_rad.clamp(range_rad[0], range_rad[1]);
        Self {
            position_rad,
            goal_rad: position_rad,
            speed_rad_s,
            range_rad,
        }
    }

    /// Moves the target by at most `speed × dt_s` toward the goal; returns the new target
    /// and its speed (the servo's feed-forward), rad and rad/s.
    pub fn update(&mut self, dt_s: f64) -> (f64, f64) {
        let before = self.position_rad;
        let most = self.speed_rad_s * dt_s.max(0.0);
        let goal = self.goal_rad.clamp(self.range_rad[0], self.range_rad[1]);
        self.position_rad += (goal - before).clamp(-most, most);
        let speed = if dt_s > 0.0 {
            (self.position_rad - before) / dt_s
        } else {
            0.0
        };
        (self.position_rad, speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_target_moves_at_the_speed_limit_and_stops_on_the_goal() {
        let mut r = FlipperRamp::at(0.5, 1.0, [-0.3, 1.0]);
        r.goal_rad = -2.0;
        let (p, v) = r.update(0.5);
        assert!((p - 0.0).abs() < 1e-12 && (v + 1.0).abs() < 1e-12);
        let (p, v) = r.update(0.5);
        assert!(
            (p + 0.3).abs() < 1e-12 && (v + 0.6).abs() < 1e-12,
            "{p} {v}"
        );
        let (p, v) = r.update(0.5);
        assert_eq!((p, v), (-0.3, 0.0));
        assert_eq!(r.update(0.0), (-0.3, 0.0));
    }
}
