//! The convoy's measures, one definition for the live monitor ([`crate::monitor`]) and the
//! report ([`crate::report`]):
//! - **gap**: distance between two robots' footprint rectangles (the URDF's chassis box), from
//!   their true poses; 0 when they touch;
//! - **cross-track error**: distance from a follower's position to another robot's path, the
//!   path extended 5 m backwards along its start heading so the start line counts ([`path`]).

use caravan_world::geometry::{Polyline, footprint, rect_distance};

/// How far a path is extended behind its start, m.
pub const RUN_UP_M: f64 = 5.0;

/// Spacing of the points a path keeps, m.
const PATH_SPACING_M: f64 = 0.02;

/// The robot's footprint rectangle: half extents and the offset of its centre along x from
/// base_link, m (from the URDF's chassis box).
#[derive(Debug, Clone, Copy)]
pub struct Footprint {
    pub half: [f64; 2],
    pub offset: f64,
}

impl Footprint {
    pub fn of(robot: &caravan_world::RobotModel) -> Self {
        Self {
            half: [robot.chassis_half_extents[0], robot.chassis_half_extents[1]],
            offset: robot.chassis_center[0],
        }
    }
}

/// Gaps between every pair of robots at poses `poses` (x, y, θ): `(neighbours, smallest)`,
/// where `neighbours[i]` is the gap from robot i + 1 to robot i and `smallest` the least gap
/// between any two robots.
pub fn gaps(poses: &[[f64; 3]], fp: &Footprint) -> (Vec<f64>, f64) {
    let rects: Vec<_> = poses
        .iter()
        .map(|p| footprint(*p, fp.half, fp.offset))
        .collect();
    let mut neighbours = Vec::with_capacity(rects.len().saturating_sub(1));
    let mut smallest = f64::INFINITY;
    for a in 0..rects.len() {
        for b in a + 1..rects.len() {
            let gap = rect_distance(&rects[a], &rects[b]);
            smallest = smallest.min(gap);
            if b == a + 1 {
                neighbours.push(gap);
            }
        }
    }
    (neighbours, smallest)
}

/// A robot's path through `poses` (x, y, θ); with `run_up`, [`RUN_UP_M`] is prepended behind
/// the first pose along its heading.
pub fn path<'a>(poses: impl IntoIterator<Item = &'a [f64; 3]>, run_up: bool) -> Polyline {
    let mut points: Vec<[f64; 2]> = Vec::new();
    for p in poses {
        if run_up && points.is_empty() {
            points.push([p[0] - RUN_UP_M * p[2].cos(), p[1] - RUN_UP_M * p[2].sin()]);
        }
        points.push([p[0], p[1]]);
    }
    Polyline::from_trajectory(&points, PATH_SPACING_M)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FP: Footprint = Footprint {
        half: [0.1, 0.09],
        offset: -0.02,
    };

    #[test]
    fn robots_in_a_row_have_their_spacing_less_their_length_as_gaps() {
        let poses = [[2.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.5, 0.0, 0.0]];
        let (neighbours, smallest) = gaps(&poses, &FP);
        assert!((neighbours[0] - 0.3).abs() < 1e-12, "{neighbours:?}");
        assert!((neighbours[1] - 0.8).abs() < 1e-12, "{neighbours:?}");
        assert!((smallest - 0.3).abs() < 1e-12);
        let (_, touching) = gaps(&[[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]], &FP);
        assert_eq!(touching, 0.0);
    }

    #[test]
    fn the_path_runs_up_behind_its_start() {
        let poses = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let path = super::path(&poses, true);
        // A point on the run-up is on the path; one beside it is as far as it is beside.
        assert!(path.project([-3.0, 0.0]).0 < 1e-9);
        assert!((path.project([0.5, 0.25]).0 - 0.25).abs() < 1e-9);
    }
}
