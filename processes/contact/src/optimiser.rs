//! The baseline the reference compares against: the same identification as a constrained
//! optimisation, min |τ − J_kᵀ(p)·F|² over the point p on the link's contour and the force F
//! in the friction cone, solved by sequential quadratic programming (the `slsqp` crate, a
//! port of NLopt's SLSQP, with exact gradients; the reference used MATLAB's fmincon).
//!
//! The contour is piecewise linear, so each of its 16 segments is one smooth problem in
//! (t, F_x, F_y), t ∈ [0, 1] along the segment; every segment of every candidate link is
//! solved and the least residual wins. The candidate links and the depth sensor's choice are
//! the analytical method's ([`crate::identify`]), so the two differ only in how they find p and F.

use crate::contour::SEGMENTS;
use crate::identify::{Candidates, NoForce, PointSource, Settings, candidate_range, choose};
use crate::planar_arm::ArmPose;
use nalgebra::{Point2, Vector2};
use slsqp::{StopTols, minimize};

/// The optimiser's answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optimum {
    pub force: Vector2<f64>,
    pub point: Point2<f64>,
    pub link: usize,
    /// |τ − model|, N·m.
    pub residual: f64,
    pub source: PointSource,
    pub candidates: Candidates,
    /// Objective evaluations, all segments together.
    pub evaluations: usize,
}

/// Bounds of each force component, N.
const FORCE_BOUND: f64 = 1e4;
/// The force variables are in units of this, N.
const FORCE_SCALE: f64 = 100.0;
/// Objective evaluations per segment at most.
const MAX_EVALUATIONS: usize = 1000;

struct Problem<'a> {
    joints: &'a [Point2<f64>],
    tau: &'a [f64],
    link: usize,
    a: Point2<f64>,
    b: Point2<f64>,
}

impl Problem<'_> {
    fn point(&self, t: f64) -> Point2<f64> {
        self.a + (self.b - self.a) * t
    }

    /// The force of variables `x` (t, F_x/S, F_y/S): scaled so every variable is of order 1.
    fn force(x: &[f64]) -> Vector2<f64> {
        Vector2::new(x[1], x[2]) * FORCE_SCALE
    }

    /// Σ (τ_i − (p − x_i) × F)² over the joints up to the link, Σ τ_i² beyond, and its
    /// gradient.
    fn cost(&self, x: &[f64], gradient: Option<&mut [f64]>) -> f64 {
        let p = self.point(x[0]);
        let f = Self::force(x);
        let d = self.b - self.a;
        let (mut cost, mut g) = (0.0, [0.0; 3]);
        for (i, (j, t)) in self.joints.iter().zip(self.tau).enumerate() {
            if i > self.link {
                cost += t * t;
                continue;
            }
            let r = t - (p - j).perp(&f);
            cost += r * r;
            // ∂m/∂t = d × F, ∂m/∂F_x = −(p_y − y_i)·S, ∂m/∂F_y = (p_x − x_i)·S.
            g[0] -= 2.0 * r * d.perp(&f);
            g[1] += 2.0 * r * (p.y - j.y) * FORCE_SCALE;
            g[2] -= 2.0 * r * (p.x - j.x) * FORCE_SCALE;
        }
        if let Some(out) = gradient {
            out.copy_from_slice(&g);
        }
        cost
    }
}

/// Solves every segment of every candidate link; `None` when the torques name no force.
pub fn optimise(
    pose: &ArmPose,
    tau: &[f64],
    depth: &[Point2<f64>],
    settings: &Settings,
) -> Result<Optimum, NoForce> {
    let candidates = candidate_range(&pose.joints, tau, settings)?;
    let cone = settings.cone_cos();
    let mut best: Vec<(f64, usize, Point2<f64>, Vector2<f64>)> = Vec::new();
    let mut evaluations = 0;
    for link in candidates.k_min..=candidates.k_max {
        let contour = &pose.contours[link];
        let mut link_best: Option<(f64, Point2<f64>, Vector2<f64>)> = None;
        for segment in 0..SEGMENTS {
            let (a, b) = contour.segment(segment);
            let inward = -contour.outward_normal(segment);
            let problem = Problem {
                joints: &pose.joints,
                tau,
                link,
                a,
                b,
            };
            let count = std::cell::Cell::new(0usize);
            let objective = |x: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
                count.set(count.get() + 1);
                problem.cost(x, g)
            };
            // Inside the cone: the component along the inward normal covers cos(atan μ)·|F|
            // (SLSQP wants g(x) ≤ 0).
            let outside_cone = |x: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
                let f = Vector2::new(x[1], x[2]);
                let norm = f.norm().max(1e-300);
                if let Some(g) = g {
                    g[0] = 0.0;
                    g[1] = cone * f.x / norm - inward.x;
                    g[2] = cone * f.y / norm - inward.y;
                }
                cone * f.norm() - inward.dot(&f)
            };
            let start = [0.5, inward.x, inward.y];
            let bound = FORCE_BOUND / FORCE_SCALE;
            let bounds = [(0.0, 1.0), (-bound, bound), (-bound, bound)];
            let tols = StopTols {
                ftol_abs: 1e-24,
                xtol_abs: vec![1e-14; 3],
                ..StopTols::default()
            };
            let result = minimize(
                objective,
                &start,
                &bounds,
                &[&outside_cone],
                (),
                MAX_EVALUATIONS,
                Some(tols),
            );
            evaluations += count.get();
            let (x, cost) = match result {
                Ok((_, x, cost)) | Err((_, x, cost)) => (x, cost),
            };
            // The solver may end a hair outside the cone; only feasible answers count.
            if outside_cone(&x, None, &mut ()) > 1e-9 {
                continue;
            }
            if link_best.is_none_or(|(c, _, _)| cost < c) {
                link_best = Some((cost, problem.point(x[0]), Problem::force(&x)));
            }
        }
        if let Some((cost, p, f)) = link_best {
            best.push((cost, link, p, f));
        }
    }
    let least = best.iter().map(|b| b.0).fold(f64::INFINITY, f64::min);
    if !least.is_finite() {
        return Err(NoForce::Inconsistent);
    }
    // Links explaining the torques as well as the best (within the noise) are ties the depth
    // sensor breaks, as in the analytical method.
    let tie = least + settings.delta_eps(tau.len()).powi(2);
    let tied: Vec<(usize, Point2<f64>)> = best
        .iter()
        .filter(|b| b.0 <= tie)
        .map(|b| (b.1, b.2))
        .collect();
    let (link, point) = choose(&tied, depth).expect("the least-cost link ties with itself");
    let &(cost, _, _, force) = best.iter().find(|b| b.1 == link).expect("chosen from best");
    Ok(Optimum {
        force,
        point,
        link,
        residual: cost.sqrt(),
        source: PointSource::Line,
        candidates,
        evaluations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::identify;
    use crate::planar_arm::PlanarArm;

    #[test]
    fn the_optimiser_agrees_with_the_analytical_answer_without_noise() {
        let pose = PlanarArm::new(Point2::origin(), vec![1.0; 4], 0.05)
            .unwrap()
            .pose(&[0.3, 1.2, -0.9, 0.4]);
        let contour = &pose.contours[2];
        let (point, segment) = contour.point_at(0.37 * contour.perimeter());
        let inward = -contour.outward_normal(segment);
        let force = nalgebra::Rotation2::new(0.2) * inward * 100.0;
        let tau = pose.torques(2, &point, &force);
        let settings = Settings::default();
        let exact = identify(&pose, &tau, &[], &settings).unwrap();
        assert!((exact.point.unwrap() - point).norm() < 1e-12);
        let o = optimise(&pose, &tau, &[], &settings).unwrap();
        assert_eq!(o.link, 2);
        assert!((o.force - force).norm() < 1e-4, "{o:?} vs {force}");
        assert!((o.point - point).norm() < 1e-6, "{o:?} vs {point}");
    }
}
