//! Scoring a live run: every estimate the perception published, against the push the person
//! was applying then (its point and force carried into the world by the link's true pose),
//! once the arm holds still again (`settle_s` after the push began).

use crate::messages::ContactEstimate;
use crate::monte_carlo::angle_deg;
use crate::table::{Mean, mean_of};
use nalgebra::{Isometry2, Point2, Vector2};
use serde::Serialize;
use std::collections::BTreeMap;

/// A push as the person applied it, in its link's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct AppliedPush {
    pub start_s: f64,
    /// When a zero wrench ended it (∞ if the run ended first).
    pub end_s: f64,
    pub link: String,
    pub local_point: Point2<f64>,
    pub local_force: Vector2<f64>,
}

/// The true planar pose of every link at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkPoses {
    pub t_s: f64,
    pub poses: BTreeMap<String, Isometry2<f64>>,
}

/// One published estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimateAt {
    pub t_s: f64,
    pub status: u32,
    pub link: String,
    pub force: Option<Vector2<f64>>,
    pub point: Option<Point2<f64>>,
}

/// One scored estimate, for the plot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoredEstimate {
    pub t_s: f64,
    pub true_force: Vector2<f64>,
    pub force: Option<Vector2<f64>>,
    pub point_error_mm: Option<f64>,
}

/// The live run's score, beside the Monte-Carlo at the same pose and noise.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct LiveScore {
    pub pushes: usize,
    /// Estimates made while a push acted and the arm had settled.
    pub scored: usize,
    pub force_error_n: Option<Mean>,
    pub direction_error_deg: Option<Mean>,
    /// Where the point came from the line of action.
    pub point_error_mm: Option<Mean>,
    /// Scored estimates without a point from the line of action, %.
    pub no_solution_pct: f64,
    /// Points from the line that named another link than the pushed one, %.
    pub wrong_link_pct: f64,
    /// Estimates between pushes (settled) that reported a contact, %.
    pub false_contact_pct: f64,
    pub between_pushes: usize,
}

/// Scores `estimates` against `pushes`, with the links' true poses from `poses` (in time
/// order); estimates within `settle_s` of a push's start or end are left out.
pub fn score(
    pushes: &[AppliedPush],
    poses: &[LinkPoses],
    estimates: &[EstimateAt],
    settle_s: f64,
) -> (LiveScore, Vec<ScoredEstimate>) {
    let (mut force, mut direction, mut point) = (Vec::new(), Vec::new(), Vec::new());
    let (mut scored, mut no_solution, mut wrong, mut on_line) = (0, 0, 0, 0);
    let (mut between, mut false_contact) = (0, 0);
    let mut plotted = Vec::new();
    let pose_at = |t: f64| {
        let i = poses.partition_point(|p| p.t_s <= t);
        (i > 0).then(|| &poses[i - 1])
    };
    for e in estimates {
        let push = pushes
            .iter()
            .find(|p| p.start_s <= e.t_s && e.t_s < p.end_s);
        let Some(push) = push else {
            // Between pushes, once the last push ended settle_s ago (before the first push
            // the arm is still moving into its pose).
            let last_end = pushes
                .iter()
                .filter(|p| p.end_s <= e.t_s)
                .map(|p| p.end_s)
                .fold(f64::NEG_INFINITY, f64::max);
            if last_end.is_finite() && e.t_s >= last_end + settle_s {
                between += 1;
                if e.status != ContactEstimate::NO_CONTACT {
                    false_contact += 1;
                }
            }
            continue;
        };
        if e.t_s < push.start_s + settle_s {
            continue;
        }
        let Some(frame) = pose_at(e.t_s).and_then(|p| p.poses.get(&push.link)) else {
            continue;
        };
        let true_point = frame * push.local_point;
        let true_force = frame * push.local_force;
        scored += 1;
        if let Some(f) = e.force {
            force.push((f - true_force).norm());
            direction.push(angle_deg(&f, &true_force));
        }
        let mut point_error_mm = None;
        match (e.status, e.point) {
            (ContactEstimate::FOUND, Some(p)) => {
                on_line += 1;
                let err = (p - true_point).norm() * 1e3;
                point.push(err);
                point_error_mm = Some(err);
                if e.link != push.link {
                    wrong += 1;
                }
            }
            _ => no_solution += 1,
        }
        plotted.push(ScoredEstimate {
            t_s: e.t_s,
            true_force,
            force: e.force,
            point_error_mm,
        });
    }
    let pct = |k: usize, n: usize| 100.0 * k as f64 / n.max(1) as f64;
    (
        LiveScore {
            pushes: pushes.len(),
            scored,
            force_error_n: mean_of(&force),
            direction_error_deg: mean_of(&direction),
            point_error_mm: mean_of(&point),
            no_solution_pct: pct(no_solution, scored),
            wrong_link_pct: pct(wrong, on_line),
            false_contact_pct: pct(false_contact, between),
            between_pushes: between,
        },
        plotted,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(t_s: f64, status: u32, force: [f64; 2], point: [f64; 2]) -> EstimateAt {
        EstimateAt {
            t_s,
            status,
            link: "link3".into(),
            force: Some(Vector2::new(force[0], force[1])),
            point: Some(Point2::new(point[0], point[1])),
        }
    }

    #[test]
    fn estimates_are_scored_in_the_world_after_the_settling_time() {
        // Link 3 stands at (1, 0) turned 90°: its local (0.2, 0.05) is the world's (0.95, 0.2),
        // its local force (0, −10) the world's (10, 0).
        let push = AppliedPush {
            start_s: 1.0,
            end_s: 3.0,
            link: "link3".into(),
            local_point: Point2::new(0.2, 0.05),
            local_force: Vector2::new(0.0, -10.0),
        };
        let poses = [LinkPoses {
            t_s: 0.0,
            poses: [(
                "link3".to_string(),
                Isometry2::new(Vector2::new(1.0, 0.0), std::f64::consts::FRAC_PI_2),
            )]
            .into(),
        }];
        let found = ContactEstimate::FOUND;
        let estimates = [
            // While settling: left out.
            estimate(1.2, found, [0.0, 50.0], [0.0, 0.0]),
            // 1 N and 3 mm off.
            estimate(2.0, found, [10.0, 1.0], [0.95, 0.203]),
            // No point.
            estimate(
                2.5,
                ContactEstimate::NO_SOLUTION,
                [10.0, 0.0],
                [f64::NAN, f64::NAN],
            ),
            // Between pushes, settled: one says contact, one does not.
            estimate(3.6, ContactEstimate::NO_CONTACT, [0.0, 0.0], [0.0, 0.0]),
            estimate(3.7, found, [1.0, 0.0], [0.0, 0.0]),
        ];
        let (s, plotted) = score(&[push], &poses, &estimates, 0.5);
        assert_eq!((s.pushes, s.scored, s.between_pushes), (1, 2, 2));
        let f = s.force_error_n.unwrap();
        assert!((f.max - 1.0).abs() < 1e-12 && f.n == 2, "{f:?}");
        let p = s.point_error_mm.unwrap();
        assert!((p.mean - 3.0).abs() < 1e-9 && p.n == 1, "{p:?}");
        assert_eq!((s.no_solution_pct, s.false_contact_pct), (50.0, 50.0));
        assert_eq!(plotted.len(), 2);
        assert!((plotted[0].true_force - Vector2::new(10.0, 0.0)).norm() < 1e-12);
    }
}
