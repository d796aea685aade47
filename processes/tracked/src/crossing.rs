//! One crossing's outcome from the robot's true 3-D pose over time, as the reference's
//! passability runs count them: **passed** (its base reached the goal line without tipping
//! over), **flipped** (it tipped past [`FLIP_TILT_DEG`] at any time), **off the world** (its
//! base left the world's floor plan, in practice sideways: a run driven straight that veered
//! off the terrain, which the reference's operator would have steered back) or **stuck**
//! (none of these, by the end of the run). The first of them to happen decides; in one sample
//! tipping over comes first. The figures (furthest x, largest tilt, highest climb) describe
//! the crossing up to that decision: a robot that has passed drives on until the run ends,
//! off the terrain's far end and over the floor's edge (1 m past the world's `size`), and
//! that fall is not the crossing's.

use serde::Serialize;

/// Tilt of the body's up axis from the vertical beyond which the robot counts as flipped,
/// degrees (on its side or worse; chosen).
pub const FLIP_TILT_DEG: f64 = 90.0;

/// One ground-truth sample: time s, position m (map), orientation quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub t_s: f64,
    pub position: [f64; 3],
    pub orientation: [f64; 4],
}

impl Sample {
    /// Angle between the body's z axis and the world's, degrees.
    pub fn tilt_deg(&self) -> f64 {
        tilt_deg(self.orientation)
    }
}

/// Angle between the z axis of a body with orientation `[x, y, z, w]` (a quaternion, any
/// norm) and the world's, degrees: how far it leans from level, whichever way.
pub fn tilt_deg([x, y, z, w]: [f64; 4]) -> f64 {
    // The body z axis' world z component: 1 − 2(x² + y²) for a unit quaternion.
    let n = x * x + y * y + z * z + w * w;
    let up = 1.0 - 2.0 * (x * x + y * y) / n;
    up.clamp(-1.0, 1.0).acos().to_degrees()
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    Passed,
    Stuck,
    Flipped,
    /// The base left the world's floor plan (onto the physics' floor margin, then over it).
    #[serde(rename = "off_world")]
    OffWorld,
}

/// What a crossing did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Crossing {
    pub outcome: Outcome,
    /// When the base crossed the goal line, s (passed only).
    pub passed_at_s: Option<f64>,
    /// Furthest x the base reached until the outcome was decided, m.
    pub max_x_m: f64,
    /// Largest tilt until the outcome was decided, degrees.
    pub max_tilt_deg: f64,
    /// Highest the base rose above its start until the outcome was decided, m.
    pub max_climb_m: f64,
}

/// Classifies a run's samples (time order) against the goal line x = `goal_x_m`, on a world
/// whose floor plan is [0, `size`.0] × [0, `size`.1] m when `size` is given.
pub fn classify(samples: &[Sample], goal_x_m: f64, size: Option<[f64; 2]>) -> Option<Crossing> {
    let off = |p: [f64; 3]| {
        size.is_some_and(|[sx, sy]| !(0.0..=sx).contains(&p[0]) || !(0.0..=sy).contains(&p[1]))
    };
    let first = samples.first()?;
    let mut c = Crossing {
        outcome: Outcome::Stuck,
        passed_at_s: None,
        max_x_m: f64::NEG_INFINITY,
        max_tilt_deg: 0.0,
        max_climb_m: 0.0,
    };
    for s in samples {
        c.max_x_m = c.max_x_m.max(s.position[0]);
        c.max_tilt_deg = c.max_tilt_deg.max(s.tilt_deg());
        c.max_climb_m = c.max_climb_m.max(s.position[2] - first.position[2]);
        if s.tilt_deg() > FLIP_TILT_DEG {
            c.outcome = Outcome::Flipped;
        } else if off(s.position) {
            c.outcome = Outcome::OffWorld;
        } else if s.position[0] >= goal_x_m {
            c.outcome = Outcome::Passed;
            c.passed_at_s = Some(s.t_s);
        }
        if c.outcome != Outcome::Stuck {
            break;
        }
    }
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t_s: f64, x: f64, pitch_deg: f64) -> Sample {
        let (s, c) = (pitch_deg.to_radians() / 2.0).sin_cos();
        Sample {
            t_s,
            position: [x, 1.0, 0.1],
            orientation: [0.0, s, 0.0, c],
        }
    }

    #[test]
    fn tilt_is_the_angle_of_the_body_up_axis() {
        assert!(at(0.0, 0.0, 0.0).tilt_deg().abs() < 1e-9);
        assert!((at(0.0, 0.0, 30.0).tilt_deg() - 30.0).abs() < 1e-9);
        assert!((at(0.0, 0.0, 180.0).tilt_deg() - 180.0).abs() < 1e-6);
    }

    #[test]
    fn outcomes() {
        // Passed at 1 s, then off the far end and over the floor's edge, falling.
        let run = [at(0.0, 1.0, 0.0), at(1.0, 5.1, 20.0), at(2.0, 8.1, 165.0)];
        let passed = classify(&run, 5.0, Some([7.0, 3.0])).unwrap();
        assert_eq!(passed.outcome, Outcome::Passed);
        assert_eq!(passed.passed_at_s, Some(1.0));
        assert_eq!((passed.max_x_m, passed.max_tilt_deg.round()), (5.1, 20.0));
        let stuck = classify(&[at(0.0, 1.0, 0.0), at(1.0, 3.0, 40.0)], 5.0, None).unwrap();
        assert_eq!(stuck.outcome, Outcome::Stuck);
        assert_eq!(stuck.max_x_m, 3.0);
        // Tipping over first counts, even if the body later slides past the line.
        let flipped = classify(&[at(0.0, 3.0, 100.0), at(1.0, 5.5, 170.0)], 5.0, None).unwrap();
        assert_eq!(flipped.outcome, Outcome::Flipped);
        assert!(classify(&[], 5.0, None).is_none());
    }

    #[test]
    fn veering_off_the_worlds_side_is_neither_passed_nor_flipped() {
        let veer = |y: f64, x: f64, pitch: f64| Sample {
            position: [x, y, 0.1],
            ..at(0.0, x, pitch)
        };
        // On a 7 × 3 m world, goal line x = 5 m.
        let on_world = |run: &[Sample]| classify(run, 5.0, Some([7.0, 3.0])).unwrap();
        // Off the side at x = 4, then falling and tumbling past the goal line.
        let run = [
            veer(1.5, 1.0, 0.0),
            veer(3.2, 4.0, 10.0),
            veer(3.5, 5.6, 150.0),
        ];
        let c = on_world(&run);
        assert_eq!((c.outcome, c.passed_at_s), (Outcome::OffWorld, None));
        // The figures stop where the outcome was decided: the tumble is not the crossing.
        assert_eq!((c.max_x_m, c.max_tilt_deg.round()), (4.0, 10.0));
        // Tipped over and off in the same sample: flipped.
        let both = [veer(1.5, 1.0, 0.0), veer(3.2, 4.0, 120.0)];
        assert_eq!(on_world(&both).outcome, Outcome::Flipped);
        // Backwards off the near end counts too.
        let back = [veer(1.5, 1.0, 0.0), veer(1.5, -0.1, 0.0)];
        assert_eq!(on_world(&back).outcome, Outcome::OffWorld);
        // Without a floor plan the first run counts as flipped, as before.
        assert_eq!(classify(&run, 5.0, None).unwrap().outcome, Outcome::Flipped);
        // Running off the far end after passing keeps the pass.
        let on = [
            veer(1.5, 1.0, 0.0),
            veer(1.5, 5.5, 0.0),
            veer(1.5, 7.5, 120.0),
        ];
        assert_eq!(on_world(&on).outcome, Outcome::Passed);
        assert_eq!(
            serde_json::to_value(Outcome::OffWorld).unwrap(),
            serde_json::json!("off_world")
        );
    }
}
