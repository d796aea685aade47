//! The operator's flipper sequence for climbing a step, from the body's pitch alone (what an
//! operator reads off the robot's IMU): approach with the flippers raised so that their tips
//! land on the step; once the nose has risen by `lift_deg`, turn them down so they carry the
//! front across the edge while the main tracks follow; once the pitch has passed `crest_deg`
//! and come back down by `settle_deg` (the body is tipping onto the step), or has fallen back
//! below `lift_deg` by `settle_deg` (a low step, already climbed), raise them again, and
//! watch for the next step once the body is level (below `lift_deg` by `settle_deg`). The
//! reference's real robot climbs 20 cm this way; fixed flippers cannot.

use caravan_schemas::Quaternion;
use serde::Deserialize;

/// The body's nose-up pitch, degrees, from its orientation (x forward, z up; a rotation
/// about y that lifts x is positive, the opposite of ROS's pitch sign).
pub fn nose_up_deg(q: &Quaternion) -> f64 {
    let q = nalgebra::Quaternion::new(q.w, q.x, q.y, q.z);
    let (_, pitch, _) = nalgebra::UnitQuaternion::new_normalize(q).euler_angles();
    -pitch.to_degrees()
}

/// The sequence's angles, degrees. Flipper angles are above the main track's line (positive
/// raises the tip); pitch is nose-up positive.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ClimbParams {
    /// Work the flippers (default false: they stay at the drive's angle).
    #[serde(default)]
    pub enabled: bool,
    /// Flipper angle while approaching, degrees in the flipper's range (default 45).
    #[serde(default = "approach")]
    pub approach_deg: f64,
    /// Flipper angle while the front is carried over the edge, degrees in the flipper's range
    /// (default −45).
    #[serde(default = "push")]
    pub push_deg: f64,
    /// Nose-up pitch that starts the push, degrees > 0 (default 15).
    #[serde(default = "lift")]
    pub lift_deg: f64,
    /// Pitch above which the body is on the edge, degrees > `lift_deg` (default 30).
    #[serde(default = "crest")]
    pub crest_deg: f64,
    /// How far the pitch must fall back to end the push, degrees in (0, `lift_deg`)
    /// (default 10).
    #[serde(default = "settle")]
    pub settle_deg: f64,
}

// The middle of the band where v4 climbs 20 cm with either wheel model (docs/tracked.md).
fn approach() -> f64 {
    45.0
}
fn push() -> f64 {
    -45.0
}
fn lift() -> f64 {
    15.0
}
fn crest() -> f64 {
    30.0
}
fn settle() -> f64 {
    10.0
}

impl Default for ClimbParams {
    fn default() -> Self {
        Self {
            enabled: false,
            approach_deg: approach(),
            push_deg: push(),
            lift_deg: lift(),
            crest_deg: crest(),
            settle_deg: settle(),
        }
    }
}

impl ClimbParams {
    /// Checks the angles against each other and against the flippers' range (degrees).
    pub fn validate(&self, range_deg: [f64; 2]) -> Result<(), String> {
        for (key, v) in [
            ("approach_deg", self.approach_deg),
            ("push_deg", self.push_deg),
        ] {
            if !(v.is_finite() && range_deg[0] <= v && v <= range_deg[1]) {
                return Err(format!(
                    "key 'climb.{key}': {v} is outside the flippers' range [{}, {}] degrees",
                    range_deg[0], range_deg[1]
                ));
            }
        }
        // 0 < settle < lift < crest < 90, each checked against the one below it.
        let chain = [
            ("settle_deg", self.settle_deg, 0.0),
            ("lift_deg", self.lift_deg, self.settle_deg),
            ("crest_deg", self.crest_deg, self.lift_deg),
        ];
        for (key, v, below) in chain {
            if !(v.is_finite() && below < v && v < 90.0) {
                return Err(format!(
                    "key 'climb.{key}': {v} must lie between {below} and 90 degrees \
                     (0 < settle_deg < lift_deg < crest_deg < 90)"
                ));
            }
        }
        Ok(())
    }
}

/// Where in the sequence the robot is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Phase {
    /// Flippers raised, waiting for the nose to rise.
    Approach,
    /// Flippers down; the highest pitch seen so far, degrees.
    Push { peak_deg: f64 },
    /// Flippers raised again, waiting for the body to level before watching for a step.
    Settle,
}

/// The sequence's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Climb {
    /// Its angles.
    pub params: ClimbParams,
    /// Where it is.
    pub phase: Phase,
}

impl Climb {
    pub fn new(params: ClimbParams) -> Self {
        Self {
            params,
            phase: Phase::Approach,
        }
    }

    /// The flipper angle to ask for, degrees, given the body's nose-up pitch, degrees.
    pub fn update(&mut self, pitch_deg: f64) -> f64 {
        let p = self.params;
        let level = pitch_deg < p.lift_deg - p.settle_deg;
        self.phase = match self.phase {
            Phase::Approach if pitch_deg > p.lift_deg => Phase::Push {
                peak_deg: pitch_deg,
            },
            Phase::Push { peak_deg } => {
                let peak_deg = peak_deg.max(pitch_deg);
                let over = peak_deg > p.crest_deg && pitch_deg < p.crest_deg - p.settle_deg;
                if level {
                    Phase::Approach
                } else if over {
                    Phase::Settle
                } else {
                    Phase::Push { peak_deg }
                }
            }
            Phase::Settle if level => Phase::Approach,
            phase => phase,
        };
        match self.phase {
            Phase::Approach | Phase::Settle => p.approach_deg,
            Phase::Push { .. } => p.push_deg,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Round numbers for the sequence's tests: approach at 50°.
    fn params() -> ClimbParams {
        ClimbParams {
            approach_deg: 50.0,
            ..ClimbParams::default()
        }
    }

    #[test]
    fn flippers_go_down_when_the_nose_rises_and_up_again_past_the_crest() {
        let mut c = Climb::new(params());
        assert_eq!(c.update(0.0), 50.0);
        assert_eq!(c.update(14.0), 50.0);
        assert_eq!(c.update(16.0), -45.0);
        // Climbing the edge: the pitch rises past the crest and wobbles.
        for pitch in [25.0, 38.0, 45.0, 36.0, 41.0, 21.0] {
            assert_eq!(c.update(pitch), -45.0, "{pitch}");
        }
        // Tipping onto the step: flippers up, and they stay up while the body levels.
        for pitch in [19.0, 17.0, 16.0, 8.0] {
            assert_eq!(c.update(pitch), 50.0, "{pitch}");
            assert_eq!(c.phase, Phase::Settle);
        }
        // Level: watching for the next step.
        assert_eq!(c.update(3.0), 50.0);
        assert_eq!(c.phase, Phase::Approach);
        assert_eq!(c.update(16.0), -45.0);
    }

    #[test]
    fn pitch_is_positive_nose_up() {
        // Nose up by 30°: a rotation of −30° about y.
        let (s, c) = (-15f64.to_radians()).sin_cos();
        let q = Quaternion {
            x: 0.0,
            y: s,
            z: 0.0,
            w: c,
        };
        assert!((nose_up_deg(&q) - 30.0).abs() < 1e-9);
        let yawed = Quaternion::from_yaw(1.0);
        assert!(nose_up_deg(&yawed).abs() < 1e-9);
    }

    #[test]
    fn a_low_step_ends_the_push_once_the_body_is_level_again() {
        let mut c = Climb::new(params());
        c.update(18.0);
        assert_eq!(c.update(22.0), -45.0);
        assert_eq!(c.update(6.0), -45.0);
        assert_eq!(c.update(4.0), 50.0);
    }

    #[test]
    fn angles_out_of_order_or_out_of_range_are_refused_with_their_key() {
        let range = [-90.0, 90.0];
        assert!(ClimbParams::default().validate(range).is_ok());
        let bad = ClimbParams {
            push_deg: -100.0,
            ..ClimbParams::default()
        };
        assert!(bad.validate(range).unwrap_err().contains("climb.push_deg"));
        let bad = ClimbParams {
            crest_deg: 10.0,
            ..ClimbParams::default()
        };
        let e = bad.validate(range).unwrap_err();
        assert!(
            e.contains("'climb.crest_deg'") && !e.contains("'climb.lift_deg'"),
            "{e}"
        );
        let bad = ClimbParams {
            approach_deg: f64::NAN,
            ..ClimbParams::default()
        };
        assert!(bad.validate(range).is_err());
    }
}
