//! The operator's steering while driving "straight across": keep to the line the robot
//! started on. An operator with a joystick steers back when a track drops into a hole and the
//! robot yaws; without this the robot wanders off the 3 m field's side. The turn rate asked
//! for is proportional to the heading error toward a point `lookahead_m` ahead on the line
//! (a pure-pursuit-like line follower), bounded by `max_turn_rad_s`; the drive's own limits
//! (|ω| ≤ 0.5 rad/s, 0.5 rad/s²) still apply after it.

use serde::Deserialize;

/// How the operator keeps to the line.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KeepLineParams {
    /// Steer back to the line (default true); off, the turn rate asked for is always 0.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Turn rate per radian of heading error, 1/s, in [`ranges::GAIN_PER_S`] (default 2).
    #[serde(default = "gain")]
    pub gain_per_s: f64,
    /// How far ahead on the line the operator aims, m, in [`ranges::LOOKAHEAD_M`] (default
    /// 0.5): shorter steers
    /// back harder.
    #[serde(default = "lookahead")]
    pub lookahead_m: f64,
    /// The largest turn rate asked for, rad/s, in [`ranges::MAX_TURN_RAD_S`] (default 0.5,
    /// the drive's limit).
    #[serde(default = "max_turn")]
    pub max_turn_rad_s: f64,
    /// The line to keep, `[x m, y m, heading rad]` on the floor; default the robot's own
    /// position and heading when it sets off.
    #[serde(default)]
    pub line: Option<[f64; 3]>,
    /// While the body leans more than this from level (pitch or roll), degrees in (0, 90),
    /// the operator pushes straight on and steers back once it is under again, as one does
    /// over an obstacle; default none: it always steers.
    #[serde(default)]
    pub straight_above_tilt_deg: Option<f64>,
}

fn yes() -> bool {
    true
}
fn gain() -> f64 {
    2.0
}
fn lookahead() -> f64 {
    0.5
}
fn max_turn() -> f64 {
    0.5
}

impl Default for KeepLineParams {
    fn default() -> Self {
        Self {
            enabled: yes(),
            gain_per_s: gain(),
            lookahead_m: lookahead(),
            max_turn_rad_s: max_turn(),
            line: None,
            straight_above_tilt_deg: None,
        }
    }
}

/// The physical range of each of [`KeepLineParams`]' numbers, and why.
pub mod ranges {
    use crate::params::Range;

    /// Turn rate per radian of heading error: at the driver's 50 Hz, gain × tick ≤ 1. A
    /// larger gain turns the heading past the line within one tick and the steering chatters.
    pub const GAIN_PER_S: Range = Range::positive(50.0, "1/s");
    /// The aim point: 1 cm at least (closer, a centimetre off the line aims the robot across
    /// it at 45°), at most 10 km, the largest world.
    pub const LOOKAHEAD_M: Range =
        Range::closed(0.01, caravan_world::limits::MAX_WORLD_EXTENT_M, "m");
    /// The largest turn rate asked for: the drive's largest `max_w_rad_s` bound.
    pub const MAX_TURN_RAD_S: Range =
        Range::positive(crate::diff_drive::ranges::MAX_W_RAD_S.max, "rad/s");
}

impl KeepLineParams {
    /// Every number within its range ([`ranges`]), or an error naming the key (under
    /// `keep_line`).
    pub fn validate(&self) -> Result<(), String> {
        use caravan_world::limits::{MAX_ANGLE_RAD, MAX_WORLD_EXTENT_M, coordinate};
        ranges::GAIN_PER_S.check("keep_line.gain_per_s", self.gain_per_s)?;
        ranges::LOOKAHEAD_M.check("keep_line.lookahead_m", self.lookahead_m)?;
        ranges::MAX_TURN_RAD_S.check("keep_line.max_turn_rad_s", self.max_turn_rad_s)?;
        if let Some(t) = self
            .straight_above_tilt_deg
            .filter(|t| !(*t > 0.0 && *t < 90.0))
        {
            return Err(format!(
                "key 'keep_line.straight_above_tilt_deg': must be above 0 and below 90 degrees, got {t}"
            ));
        }
        // A point on a world's floor (at most 10 km out) and a heading of at most a thousand
        // turns, where the trigonometry still holds the angle.
        if let Some([x, y, heading]) = self.line {
            coordinate("key 'keep_line.line[0]': x", x, MAX_WORLD_EXTENT_M)?;
            coordinate("key 'keep_line.line[1]': y", y, MAX_WORLD_EXTENT_M)?;
            coordinate("key 'keep_line.line[2]': heading", heading, MAX_ANGLE_RAD)?;
        }
        Ok(())
    }

    /// The line to keep for a robot setting off at `position` (m) heading `yaw_rad`.
    pub fn line_from(&self, position: [f64; 2], yaw_rad: f64) -> Line {
        match self.line {
            Some([x, y, heading_rad]) => Line {
                origin: [x, y],
                heading_rad,
            },
            None => Line {
                origin: position,
                heading_rad: yaw_rad,
            },
        }
    }
}

/// A line on the floor: through `origin` (x, y, m) along heading `heading_rad`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    pub origin: [f64; 2],
    pub heading_rad: f64,
}

impl Line {
    /// The robot's signed distance to the left of the line, m.
    pub fn left_of(&self, position: [f64; 2]) -> f64 {
        let (s, c) = self.heading_rad.sin_cos();
        let d = [position[0] - self.origin[0], position[1] - self.origin[1]];
        c * d[1] - s * d[0]
    }
}

/// Where the robot is: position on the floor (m), heading (rad) and lean from level (deg).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attitude {
    pub position: [f64; 2],
    pub yaw_rad: f64,
    pub tilt_deg: f64,
}

/// The turn rate to ask for, rad/s (positive turns left), for a robot at `at` driving at
/// `speed_m_s` (its sign says which way the aim point lies: reversing, the robot closes on
/// the line by turning the other way).
pub fn turn_rate(p: &KeepLineParams, line: &Line, at: &Attitude, speed_m_s: f64) -> f64 {
    let leaning = p.straight_above_tilt_deg.is_some_and(|t| at.tilt_deg > t);
    if !p.enabled || leaning {
        return 0.0;
    }
    let (position, yaw_rad) = (at.position, at.yaw_rad);
    let toward = if speed_m_s < 0.0 { -1.0 } else { 1.0 };
    let aim = line.heading_rad - toward * (line.left_of(position) / p.lookahead_m).atan();
    let error = caravan_schemas::wrap_angle(aim - yaw_rad);
    (p.gain_per_s * error).clamp(-p.max_turn_rad_s, p.max_turn_rad_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALONG_X_AT_0: Line = Line {
        origin: [0.0, 1.5],
        heading_rad: 0.0,
    };
    const ALONG_X: Line = Line {
        origin: [1.0, 1.5],
        heading_rad: 0.0,
    };

    /// Level, at `position` heading `yaw_rad`.
    fn at(position: [f64; 2], yaw_rad: f64) -> Attitude {
        Attitude {
            position,
            yaw_rad,
            tilt_deg: 0.0,
        }
    }

    #[test]
    fn on_the_line_and_heading_along_it_asks_for_no_turn() {
        let p = KeepLineParams::default();
        assert_eq!(turn_rate(&p, &ALONG_X, &at([3.0, 1.5], 0.0), 0.3), 0.0);
    }

    #[test]
    fn a_robot_yawed_right_turns_left_and_the_turn_is_bounded() {
        let p = KeepLineParams::default();
        let w = turn_rate(&p, &ALONG_X, &at([2.0, 1.5], -0.1), 0.3);
        assert!((w - 0.2).abs() < 1e-12, "{w}");
        assert_eq!(turn_rate(&p, &ALONG_X, &at([2.0, 1.5], -1.0), 0.3), 0.5);
        assert_eq!(turn_rate(&p, &ALONG_X, &at([2.0, 1.5], 1.0), 0.3), -0.5);
    }

    #[test]
    fn a_robot_left_of_the_line_heading_along_it_turns_right_toward_it() {
        let p = KeepLineParams::default();
        // 0.1 m left, 0.5 m look-ahead: aim atan(0.2) to the right.
        let w = turn_rate(&p, &ALONG_X, &at([2.0, 1.6], 0.0), 0.3);
        assert!((w + 2.0 * 0.2f64.atan()).abs() < 1e-12, "{w}");
        // Reversing, the aim point lies behind: turn left, so the tail swings toward it.
        let back = turn_rate(&p, &ALONG_X, &at([2.0, 1.6], 0.0), -0.3);
        assert!((back - 2.0 * 0.2f64.atan()).abs() < 1e-12, "{back}");
        // Already pointing at the aim point: no turn.
        assert!(turn_rate(&p, &ALONG_X, &at([2.0, 1.6], -(0.2f64.atan())), 0.3).abs() < 1e-12);
    }

    #[test]
    fn headings_wrap_so_the_turn_is_the_short_way_round() {
        let p = KeepLineParams::default();
        let line = Line {
            origin: [0.0, 0.0],
            heading_rad: std::f64::consts::PI,
        };
        // Heading −179° on a line of 180°: 1° to the right of it, so turn right.
        let w = turn_rate(&p, &line, &at([-1.0, 0.0], -179f64.to_radians()), 0.3);
        assert!((w + 2.0 * 1f64.to_radians()).abs() < 1e-9, "{w}");
        assert!((line.left_of([-1.0, -0.2]) - 0.2).abs() < 1e-12);
    }

    #[test]
    fn disabled_asks_for_no_turn_and_bad_numbers_name_their_key() {
        let off = KeepLineParams {
            enabled: false,
            ..KeepLineParams::default()
        };
        assert_eq!(turn_rate(&off, &ALONG_X, &at([2.0, 2.5], 1.0), 0.3), 0.0);
        let bad = KeepLineParams {
            lookahead_m: 0.0,
            ..KeepLineParams::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .contains("keep_line.lookahead_m")
        );
        let bad = KeepLineParams {
            line: Some([0.0, f64::NAN, 0.0]),
            ..KeepLineParams::default()
        };
        assert!(bad.validate().unwrap_err().contains("keep_line.line"));
        for t in [0.0, 90.0, f64::NAN] {
            let bad = KeepLineParams {
                straight_above_tilt_deg: Some(t),
                ..KeepLineParams::default()
            };
            let err = bad.validate().unwrap_err();
            assert!(err.contains("keep_line.straight_above_tilt_deg"), "{err}");
        }
        assert!(KeepLineParams::default().validate().is_ok());
    }

    #[test]
    fn numbers_past_their_physical_range_name_their_key() {
        let bad = |f: &dyn Fn(&mut KeepLineParams)| {
            let mut p = KeepLineParams::default();
            f(&mut p);
            p.validate().unwrap_err()
        };
        assert_eq!(
            bad(&|p| p.gain_per_s = 1e300),
            "key 'keep_line.gain_per_s': must be above 0 and at most 50 1/s, got 1e300"
        );
        assert!(bad(&|p| p.lookahead_m = 0.001).contains("'keep_line.lookahead_m'"));
        assert!(bad(&|p| p.lookahead_m = 2e4).contains("'keep_line.lookahead_m'"));
        assert!(bad(&|p| p.max_turn_rad_s = 11.0).contains("'keep_line.max_turn_rad_s'"));
        let e = bad(&|p| p.line = Some([1e5, 1.5, 0.0]));
        assert!(e.starts_with("key 'keep_line.line[0]': x must be"), "{e}");
        let e = bad(&|p| p.line = Some([0.0, 1.5, 1e9]));
        assert!(e.starts_with("key 'keep_line.line[2]': heading"), "{e}");
    }

    #[test]
    fn leaning_past_the_threshold_it_drives_straight_on_and_steers_again_when_under() {
        let p = KeepLineParams {
            straight_above_tilt_deg: Some(12.0),
            ..KeepLineParams::default()
        };
        let yawed = |tilt_deg| Attitude {
            tilt_deg,
            ..at([2.0, 1.5], -0.1)
        };
        assert_eq!(turn_rate(&p, &ALONG_X, &yawed(20.0), 0.3), 0.0);
        let level = turn_rate(&p, &ALONG_X, &yawed(5.0), 0.3);
        assert!((level - 0.2).abs() < 1e-12, "{level}");
        // Without the threshold it steers however it leans.
        let always = turn_rate(&KeepLineParams::default(), &ALONG_X, &yawed(20.0), 0.3);
        assert_eq!(always, level);
    }

    #[test]
    fn the_line_is_the_start_pose_unless_one_is_given() {
        let p = KeepLineParams::default();
        assert_eq!(
            p.line_from([2.0, 1.0], 0.3),
            Line {
                origin: [2.0, 1.0],
                heading_rad: 0.3
            }
        );
        let given = KeepLineParams {
            line: Some([0.0, 1.5, 0.0]),
            ..p
        };
        assert_eq!(given.line_from([2.0, 1.0], 0.3), ALONG_X_AT_0);
    }
}
