//! Hector scan-to-map matching: Gauss–Newton on an interpolated map field.
//!
//! For scan end points p_i (robot frame) the pose ξ = (x, y, θ) minimises
//! Σ_i [1 − M(S_i(ξ))]², S_i(ξ) = R(θ)·p_i + (x, y), where M is a bilinearly interpolated map
//! field in 0..1. As in Hector's `estimateTransformationLogLh` / `getCompleteHessianDerivs`,
//! each iteration linearises M around the current estimate, J_i = ∇M(S_i)·∂S_i/∂ξ, accumulates
//! H = Σ J_iᵀJ_i and g = Σ J_iᵀ(1 − M(S_i)), and steps by Δξ = H⁻¹g, the rotation step clamped
//! to ±0.2 rad. Points whose interpolation stencil leaves the map do not contribute.
//!
//! Two departures from Hector, both found necessary on synthetic URG scans:
//! - **The field.** Hector's M is the occupancy probability (the reference's `100 − M`, in
//!   percent). Across a wall seen from one side it is a plateau that starts a little in front
//!   of the face and runs on behind it, so the noisy end points in front are pulled in while
//!   those behind are not: the pose slides toward the walls in view. With a 360° scanner the
//!   pulls cancel (≤ 7 mm over 1 m in the synthetic room); with the URG's 240° they do not
//!   (4–5 cm over 1 m, and the map is built from the biased poses). [`MatchField::Reflection`]
//!   (the default in [`crate::Slam`]) matches to the reflection rate instead, a ridge centred
//!   on the face (see [`OccupancyMap`]); [`MatchField::Occupancy`] is Hector's.
//! - **Step control.** A step that raises the cost is halved (up to four times), and steps are
//!   capped at one cell: on a field that is flat under most points (a saturated coarse level,
//!   a single-scan map) H is nearly singular and a full step can throw the pose off the map.
//!
//! The minimum is local: the guess must be within a few cells of the truth at the level
//! matched, which is why the SLAM front end runs coarse levels first.

use crate::grid::OccupancyMap;
use caravan_schemas::Pose2D;

/// Largest rotation step of one iteration, rad (Hector's clamp).
const MAX_ROTATION_STEP: f64 = 0.2;

/// Which map field the end points are matched to.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    serde::Deserialize,
    serde::Serialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum MatchField {
    /// Hector's choice: the occupancy probability. End points are drawn into occupied space,
    /// which with a scanner that sees walls mostly from one side biases the pose toward them
    /// by about the range noise (see the module documentation).
    Occupancy,
    /// The reflection rate, a ridge centred on the surfaces (see [`OccupancyMap`]).
    #[default]
    Reflection,
}

/// The outcome of [`match_scan`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchResult {
    pub pose: Pose2D,
    /// Points whose interpolation stencil lies inside the map at the returned pose.
    pub points: usize,
    /// Mean of 1 − M over those points at the returned pose: near 0 when the
    /// scan lies on occupied cells, 0.5 on unknown ones, near 1 on free ones.
    pub mean_residual: f64,
    /// Gauss–Newton steps tried.
    pub iterations: usize,
}

/// Matches `points` (robot frame, m) against `map` from `guess`, with at most `iterations`
/// Gauss–Newton steps. A step that would raise the cost is halved (up to four times) and the
/// search stops if none helps: on a map whose field is flat over most points (a saturated
/// coarse level, a single-scan map) the normal equations are nearly singular and a full step
/// can throw the pose far off. Steps are also capped at one cell and 0.2 rad. Stops early
/// once a step is below 1e-5 m and 1e-5 rad, or when no point lies on structure.
pub fn match_scan(
    map: &OccupancyMap,
    field: MatchField,
    points: &[[f64; 2]],
    guess: Pose2D,
    iterations: usize,
) -> MatchResult {
    let evaluate = |pose: &Pose2D| match field {
        MatchField::Occupancy => normal_equations(points, pose, |x, y| map.interpolated(x, y)),
        MatchField::Reflection => {
            normal_equations(points, pose, |x, y| map.interpolated_reflection(x, y))
        }
    };
    let mut pose = guess;
    let mut current = evaluate(&pose);
    let mut steps = 0;
    'steps: while steps < iterations {
        let Some(mut step) = solve(&current.h, &current.g) else {
            break;
        };
        step[2] = step[2].clamp(-MAX_ROTATION_STEP, MAX_ROTATION_STEP);
        let len = step[0].hypot(step[1]);
        let cap = map.resolution();
        if len > cap {
            step[0] *= cap / len;
            step[1] *= cap / len;
        }
        steps += 1;
        let mut scale = 1.0;
        loop {
            let candidate = Pose2D {
                x: pose.x + scale * step[0],
                y: pose.y + scale * step[1],
                theta: wrap_angle(pose.theta + scale * step[2]),
            };
            let next = evaluate(&candidate);
            if next.cost(points.len()) <= current.cost(points.len()) {
                pose = candidate;
                current = next;
                break;
            }
            scale *= 0.5;
            if scale < 0.1 {
                break 'steps;
            }
        }
        if scale * step[0].hypot(step[1]) < 1e-5 && (scale * step[2]).abs() < 1e-5 {
            break;
        }
    }
    MatchResult {
        pose,
        points: current.used,
        mean_residual: if current.used > 0 {
            current.residual / current.used as f64
        } else {
            1.0
        },
        iterations: steps,
    }
}

/// The linearised problem at one pose.
struct Normal {
    /// H, upper triangle: h00 h01 h02 h11 h12 h22.
    h: [f64; 6],
    g: [f64; 3],
    /// Points inside the map, Σ(1 − M) and Σ(1 − M)² over them.
    used: usize,
    residual: f64,
    squares: f64,
}

impl Normal {
    /// Mean squared residual, points off the map counting as 1.
    fn cost(&self, points: usize) -> f64 {
        (self.squares + (points - self.used) as f64) / points.max(1) as f64
    }
}

#[inline]
fn normal_equations(
    points: &[[f64; 2]],
    pose: &Pose2D,
    field: impl Fn(f64, f64) -> Option<(f64, f64, f64)>,
) -> Normal {
    let (s, c) = pose.theta.sin_cos();
    let mut h = [0.0; 6];
    let mut g = [0.0; 3];
    let (mut used, mut residual, mut squares) = (0usize, 0.0, 0.0);
    for p in points {
        let x = c * p[0] - s * p[1] + pose.x;
        let y = s * p[0] + c * p[1] + pose.y;
        let Some((m, dx, dy)) = field(x, y) else {
            continue;
        };
        let r = 1.0 - m;
        // ∂S/∂θ = (−s·px − c·py, c·px − s·py)
        let dt = (-s * p[0] - c * p[1]) * dx + (c * p[0] - s * p[1]) * dy;
        g[0] += dx * r;
        g[1] += dy * r;
        g[2] += dt * r;
        h[0] += dx * dx;
        h[1] += dx * dy;
        h[2] += dx * dt;
        h[3] += dy * dy;
        h[4] += dy * dt;
        h[5] += dt * dt;
        used += 1;
        residual += r;
        squares += r * r;
    }
    Normal {
        h,
        g,
        used,
        residual,
        squares,
    }
}

/// Solves the symmetric 3×3 system H·x = g by Cramer's rule; `None` if H is (nearly)
/// singular.
fn solve(h: &[f64; 6], g: &[f64; 3]) -> Option<[f64; 3]> {
    let [a, b, c, d, e, f] = *h;
    // H = [[a b c] [b d e] [c e f]]
    let (m00, m01, m02) = (d * f - e * e, c * e - b * f, b * e - c * d);
    let det = a * m00 + b * m01 + c * m02;
    let scale = a * d * f;
    if a <= 0.0 || d <= 0.0 || det.is_nan() || det <= 1e-12 * scale {
        return None;
    }
    let (m11, m12, m22) = (a * f - c * c, b * c - a * e, a * d - b * b);
    let x = [
        (m00 * g[0] + m01 * g[1] + m02 * g[2]) / det,
        (m01 * g[0] + m11 * g[1] + m12 * g[2]) / det,
        (m02 * g[0] + m12 * g[1] + m22 * g[2]) / det,
    ];
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Angle wrapped to (−π, π] (the schemas' one wrap).
pub use caravan_schemas::wrap_angle;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slam::scan_to_points;
    use crate::synthetic::Room;

    #[test]
    fn solve_inverts_a_symmetric_matrix() {
        let h = [4.0, 1.0, 0.5, 3.0, 0.2, 2.0];
        let x = [0.3, -1.2, 2.0];
        let g = [
            4.0 * x[0] + 1.0 * x[1] + 0.5 * x[2],
            1.0 * x[0] + 3.0 * x[1] + 0.2 * x[2],
            0.5 * x[0] + 0.2 * x[1] + 2.0 * x[2],
        ];
        let got = solve(&h, &g).unwrap();
        assert!(got.iter().zip(x).all(|(a, b)| (a - b).abs() < 1e-12));
        assert!(solve(&[1.0, 1.0, 0.0, 1.0, 0.0, 1.0], &g).is_none());
    }

    #[test]
    fn wraps_angles() {
        assert!((wrap_angle(3.5) - (3.5 - std::f64::consts::TAU)).abs() < 1e-12);
        assert_eq!(wrap_angle(-0.25), -0.25);
    }

    /// Builds a three-level map from `map_scans` scans (the first at `truth`, the others 0.1 m
    /// or 0.1 rad around it), then matches a scan taken at `truth + offset` coarse to fine
    /// starting from `truth`; returns the position and heading errors of the recovered pose.
    fn recover(field: MatchField, noise: Option<u64>, map_scans: usize) -> (f64, f64) {
        let room = Room::default();
        let pose = |x, y, theta| Pose2D { x, y, theta };
        let truth = pose(1.2, 1.1, 0.3);
        let finest = OccupancyMap::new(0.025, [-1.0, -1.0], 256, 256);
        let mut maps = vec![finest.coarser(1), finest.coarser(2), finest.coarser(4)];
        let around = [
            pose(0.0, 0.0, 0.0),
            pose(0.1, 0.0, 0.0),
            pose(-0.1, 0.0, 0.0),
            pose(0.0, 0.1, 0.1),
            pose(0.0, -0.1, -0.1),
        ];
        for (k, d) in around.iter().take(map_scans).enumerate() {
            let at = pose(truth.x + d.x, truth.y + d.y, truth.theta + d.theta);
            let scan = room.scan(&at, 0.0, noise.map(|s| s + 10 * k as u64));
            let (s, c) = at.theta.sin_cos();
            let ends: Vec<[f64; 2]> = scan_to_points(&scan, 0.0, 0.05, 5.6)
                .iter()
                .map(|p| [at.x + c * p[0] - s * p[1], at.y + s * p[0] + c * p[1]])
                .collect();
            for m in &mut maps {
                m.update([at.x, at.y], &ends, &vec![true; ends.len()]);
            }
        }
        let moved = pose(truth.x + 0.05, truth.y - 0.03, truth.theta + 0.05);
        let scan = room.scan(&moved, 0.0, noise.map(|s| s + 1));
        let points = scan_to_points(&scan, 0.0, 0.05, 5.6);
        let mut est = truth;
        for (level, m) in maps.iter().enumerate().rev() {
            let r = match_scan(m, field, &points, est, if level == 0 { 5 } else { 3 });
            assert!(r.points > 600, "{r:?}");
            est = r.pose;
        }
        (
            (est.x - moved.x).hypot(est.y - moved.y),
            wrap_angle(est.theta - moved.theta).abs(),
        )
    }

    /// Largest errors over the noise-free case and five noisy ones.
    fn worst(field: MatchField, map_scans: usize) -> (f64, f64) {
        let cases = [None, Some(10), Some(20), Some(30), Some(40), Some(50)];
        cases.iter().fold((0.0, 0.0), |(d, a), &noise| {
            let (dd, aa) = recover(field, noise, map_scans);
            (dd.max(d), aa.max(a))
        })
    }

    #[test]
    fn recovers_a_known_offset_on_a_one_scan_map() {
        let (d, a) = worst(MatchField::Occupancy, 1);
        println!("occupancy, 1 scan: ≤ {d:.4} m, {:.3}°", a.to_degrees());
        assert!(d < 0.01 && a < 0.5f64.to_radians(), "{d} m {a} rad");
        // The reflection field of a single scan is a thin, bumpy ridge: a little less precise.
        let (d, a) = worst(MatchField::Reflection, 1);
        println!("reflection, 1 scan: ≤ {d:.4} m, {:.3}°", a.to_degrees());
        assert!(d < 0.015 && a < 0.5f64.to_radians(), "{d} m {a} rad");
    }

    #[test]
    fn recovers_a_known_offset_on_a_five_scan_map() {
        let results = [MatchField::Occupancy, MatchField::Reflection].map(|f| worst(f, 5));
        for (field, (d, a)) in ["occupancy", "reflection"].iter().zip(results) {
            println!("{field}, 5 scans: ≤ {d:.4} m, {:.3}°", a.to_degrees());
        }
        for (d, a) in results {
            assert!(d < 0.015 && a < 0.5f64.to_radians(), "{d} m {a} rad");
        }
    }
}
