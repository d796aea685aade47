//! Checks shared by the tracked processes' params: an error names the key as the user wrote
//! it, under its table. Every numeric key has a [`Range`]: finite, of the right sign, and
//! within bounds tied to the world (at most 10 km across, a robot's part at most 100 m) and to
//! the tick the processes step at (50 Hz for the drive and the driver, 250 Hz for the
//! scenario's physics). [`DOCUMENTED`] lists them all; docs/tracked.md states each one (a
//! test keeps the two equal).

use crate::diff_drive::ranges as drive;
use crate::keep_line::ranges as keep_line;

/// A param's physical range: finite, at least `min` (above it when `open_min`) and at most
/// `max`, in `unit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub min: f64,
    pub max: f64,
    /// Whether `min` itself is excluded (a length must be above 0, not 0).
    pub open_min: bool,
    /// The unit as the docs write it after the bounds ("m/s"), or empty.
    pub unit: &'static str,
}

impl Range {
    /// [`min`, `max`].
    pub const fn closed(min: f64, max: f64, unit: &'static str) -> Self {
        Self {
            min,
            max,
            open_min: false,
            unit,
        }
    }

    /// (0, `max`]: a positive quantity.
    pub const fn positive(max: f64, unit: &'static str) -> Self {
        Self {
            min: 0.0,
            max,
            open_min: true,
            unit,
        }
    }

    /// Whether `v` lies in the range (never for NaN or ±∞).
    pub fn contains(&self, v: f64) -> bool {
        let above = if self.open_min {
            v > self.min
        } else {
            v >= self.min
        };
        v.is_finite() && above && v <= self.max
    }

    /// `v` when it lies in the range, else the error naming `key`, in the style of every
    /// Caravan param check (`caravan::range`): `key 'k': must be between 1 and 100 m, got 0`.
    pub fn check(&self, key: &str, v: f64) -> Result<f64, String> {
        if self.open_min {
            caravan::range::above(key, v, self.min, self.max, self.unit)
        } else {
            caravan::range::between(key, v, self.min, self.max, self.unit)
        }
    }

    /// The range as docs/tracked.md writes it: `(0, 5] m/s`, `[-90, 90] °`.
    pub fn describe(&self) -> String {
        let open = if self.open_min { '(' } else { '[' };
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!("{open}{}, {}]{unit}", show(self.min), show(self.max))
    }
}

/// Whether `v` is written in exponent form: tiny or huge (1e-300, not three hundred zeros).
fn exponent_form(v: f64) -> bool {
    v != 0.0 && v.is_finite() && !(1e-4..1e15).contains(&v.abs())
}

/// A value given, for a message: every digit, in exponent form when tiny or huge.
pub fn show_exact(v: f64) -> String {
    if exponent_form(v) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A bound, for a message and the docs: at most four decimals (±π/2 as 1.5708), in
/// exponent form when tiny or huge.
pub fn show(v: f64) -> String {
    if exponent_form(v) {
        return format!("{v:e}");
    }
    let text = format!("{v:.4}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    match text {
        "-0" => "0".into(),
        t => t.into(),
    }
}

/// Every value finite and > 0, else an error naming the first that is not, as
/// `'{prefix}{key}'` (the prefix is the key's table, e.g. `keep_line.`, or empty).
pub fn all_positive(prefix: &str, values: &[(&str, f64)]) -> Result<(), String> {
    match values.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        Some((key, v)) => Err(format!(
            "key '{prefix}{key}': must be a positive number, got {v}"
        )),
        None => Ok(()),
    }
}

/// Most robots in a group: the physics simulates at most this many (its `MAX_ROBOTS`: three
/// topics each within a lockstep step's `MAX_TOPICS`), so no robot index reaches it.
pub const MAX_ROBOTS: usize = (caravan_schemas::lockstep::MAX_TOPICS - 1) / 3;

/// The drive's and the driver's `count`: the robots the physics simulates, 1 to
/// [`MAX_ROBOTS`]. The tracked scenario has one (default 1).
pub fn robot_count(count: usize) -> Result<(), String> {
    if (1..=MAX_ROBOTS).contains(&count) {
        Ok(())
    } else {
        Err(format!(
            "key 'count': must be between 1 and {MAX_ROBOTS} (the robots the physics \
             simulates), got {count}"
        ))
    }
}

/// `robot` must name one of the `count` robots, 0 to `count` − 1: an index beyond them
/// drives a robot that does not exist, and the real one never moves.
pub fn robot_index(robot: usize, count: usize) -> Result<(), String> {
    robot_count(count)?;
    if robot < count {
        Ok(())
    } else {
        Err(format!(
            "key 'robot': robot {robot} is not one of the group's {count} (robots are \
             numbered 0 to {}; give 'count' when the physics simulates more)",
            count - 1
        ))
    }
}

/// The drive's `flipper_angle_rad`: within a movable flipper's range
/// ([`crate::urdf::FLIPPER_RANGE_DEG`], ±90°: tip straight down to upright), rad.
pub const FLIPPER_ANGLE_RAD: Range = Range::closed(
    -std::f64::consts::FRAC_PI_2,
    std::f64::consts::FRAC_PI_2,
    "rad",
);

/// The driver's `speed_m_s`, either way: within the drive's largest `max_v_m_s` (the drive
/// limits it further to its own).
pub const SPEED_M_S: Range = Range::closed(-drive::MAX_V_M_S.max, drive::MAX_V_M_S.max, "m/s");

/// The driver's `start_s` (and a finite `stop_s`): simulated time from 0 to a day. The
/// shipped runs last at most 30 s; a day at the scenario's 250 Hz physics is 21.6 million
/// steps, hours of wall time, so a later time is a typo (as the contact and IMU scenarios
/// bound theirs).
pub const TIME_S: Range = Range::closed(0.0, 86_400.0, "s");

/// The report's `goal_x_m`: a line on a world's floor (at most 10 km across); with `world`
/// given, also within its floor (checked against the file).
pub const GOAL_X_M: Range = Range::closed(
    -caravan_world::limits::MAX_WORLD_EXTENT_M,
    caravan_world::limits::MAX_WORLD_EXTENT_M,
    "m",
);

/// Every numeric key of the tracked processes with a fixed range, as (process, key, range):
/// the table docs/tracked.md shows (`climb`'s angles are bounded by each other, `robot` by
/// `count`, `keep_line.line` by the world; the docs say so in words).
pub const DOCUMENTED: &[(&str, &str, Range)] = &[
    ("drive", "flipper_angle_rad", FLIPPER_ANGLE_RAD),
    ("drive", "limits.max_v_m_s", drive::MAX_V_M_S),
    ("drive", "limits.max_w_rad_s", drive::MAX_W_RAD_S),
    ("drive", "limits.max_accel_m_s2", drive::MAX_ACCEL_M_S2),
    ("drive", "limits.max_alpha_rad_s2", drive::MAX_ALPHA_RAD_S2),
    ("drive", "limits.wheel_radius_m", drive::WHEEL_RADIUS_M),
    (
        "drive",
        "limits.wheel_separation_m",
        drive::WHEEL_SEPARATION_M,
    ),
    ("driver", "speed_m_s", SPEED_M_S),
    ("driver", "start_s", TIME_S),
    ("driver", "stop_s", TIME_S),
    ("driver", "keep_line.gain_per_s", keep_line::GAIN_PER_S),
    ("driver", "keep_line.lookahead_m", keep_line::LOOKAHEAD_M),
    (
        "driver",
        "keep_line.max_turn_rad_s",
        keep_line::MAX_TURN_RAD_S,
    ),
    ("report", "goal_x_m", GOAL_X_M),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_value_not_positive_and_finite_is_named_with_its_table() {
        assert!(all_positive("", &[("a", 1.0), ("b", 0.5)]).is_ok());
        let e = all_positive("t.", &[("a", 1.0), ("b", 0.0), ("c", -1.0)]).unwrap_err();
        assert_eq!(e, "key 't.b': must be a positive number, got 0");
        assert!(
            all_positive("", &[("n", f64::NAN)])
                .unwrap_err()
                .contains("'n'")
        );
        assert!(all_positive("", &[("i", f64::INFINITY)]).is_err());
    }

    #[test]
    fn a_range_takes_its_bounds_and_refuses_the_rest_naming_the_key() {
        let closed = Range::closed(1.0, 100.0, "m");
        assert_eq!(closed.check("k", 1.0), Ok(1.0));
        assert_eq!(closed.check("k", 100.0), Ok(100.0));
        assert_eq!(
            closed.check("t.k", 0.0).unwrap_err(),
            "key 't.k': must be between 1 and 100 m, got 0"
        );
        let open = Range::positive(5.0, "m/s");
        assert!(open.check("v", 5.0).is_ok() && open.check("v", 1e-300).is_ok());
        assert_eq!(
            open.check("v", 0.0).unwrap_err(),
            "key 'v': must be above 0 and at most 5 m/s, got 0"
        );
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 5.000001, -1.0] {
            assert!(open.check("v", bad).is_err(), "{bad}");
        }
        assert_eq!(open.describe(), "(0, 5] m/s");
        assert_eq!(FLIPPER_ANGLE_RAD.describe(), "[-1.5708, 1.5708] rad");
        assert_eq!(TIME_S.describe(), "[0, 86400] s");
        assert_eq!(Range::closed(-1.0, 1.0, "").describe(), "[-1, 1]");
    }

    #[test]
    fn numbers_are_shown_short() {
        assert_eq!(show(0.0), "0");
        assert_eq!(show(-1.0), "-1");
        assert_eq!(show(0.225), "0.225");
        assert_eq!(show(1e-300), "1e-300");
        assert_eq!(show(-2.5e20), "-2.5e20");
        assert_eq!(show(std::f64::consts::FRAC_PI_2), "1.5708");
        assert_eq!(show_exact(5.000001), "5.000001");
        assert_eq!(show_exact(1e-300), "1e-300");
        assert_eq!(show_exact(f64::NAN), "NaN");
        assert_eq!(show_exact(f64::NEG_INFINITY), "-inf");
    }

    #[test]
    fn a_robot_index_names_one_of_the_robots() {
        assert!(robot_index(0, 1).is_ok() && robot_index(4, 5).is_ok());
        let e = robot_index(9, 1).unwrap_err();
        assert!(
            e.starts_with("key 'robot': robot 9 is not one of the group's 1"),
            "{e}"
        );
        assert!(robot_index(0, 0).unwrap_err().starts_with("key 'count'"));
        assert!(robot_index(0, MAX_ROBOTS + 1).is_err());
        assert!(robot_index(MAX_ROBOTS - 1, MAX_ROBOTS).is_ok());
    }

    #[test]
    fn every_shipped_value_lies_in_its_range() {
        // The defaults and the launch files' values (launch/tracked, docs/tracked): each must
        // pass, or a shipped run would be refused.
        assert!(FLIPPER_ANGLE_RAD.contains(crate::urdf::FLIPPER_ANGLE_DEG.to_radians()));
        assert!(FLIPPER_ANGLE_RAD.contains(0.26) && FLIPPER_ANGLE_RAD.contains(0.79));
        for v in [0.225, 0.3, 0.4, -0.3] {
            assert!(SPEED_M_S.contains(v), "{v}");
        }
        for goal in [3.0, 3.5, 5.0, 5.5] {
            assert!(GOAL_X_M.contains(goal), "{goal}");
        }
        assert!(TIME_S.contains(0.5) && TIME_S.contains(3.0) && TIME_S.contains(6.0));
    }

    #[test]
    fn the_docs_state_every_range() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/tracked.md");
        let docs = std::fs::read_to_string(path).unwrap();
        for (process, key, range) in DOCUMENTED {
            let row = docs
                .lines()
                .find(|l| l.starts_with(&format!("| `{key}` |")))
                .unwrap_or_else(|| panic!("docs/tracked.md has no row for {process}'s `{key}`"));
            assert!(
                row.contains(&range.describe()),
                "docs/tracked.md: {process}'s `{key}` must say {}: {row}",
                range.describe()
            );
        }
    }
}
