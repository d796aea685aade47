//! Table 1 of the reference by Monte-Carlo: per torque-noise level, random poses and pushes
//! on links 3 or 4, the analytical identification's force, direction and point errors and its
//! no-solution rate, and its time per estimate beside the optimiser baseline's on a subset of
//! the same trials.

use crate::depth::{Scanner, self_filter};
use crate::identify::{PointSource, Settings, identify};
use crate::optimiser::optimise;
use crate::planar_arm::PlanarArm;
use crate::push::{PushSpec, sample_angles};
use caravan_sensor::noise::Gaussian;
use nalgebra::Point2;
use std::time::Instant;

/// The experiment. [`Config::reference`] gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    pub arm: PlanarArm,
    /// Joint angle range of the random poses, rad, one (lower, upper) per joint.
    pub joint_limits: Vec<(f64, f64)>,
    /// Every joint but the first bends at least this much, rad ≥ 0: the method needs a
    /// non-singular pose (three joint axes not in line), so near-straight poses, where the
    /// torques barely tell the force, are not drawn.
    pub min_bend: f64,
    pub push: PushSpec,
    pub scanner: Scanner,
    /// Depth returns closer than this to the arm's surface are the arm's own, m.
    pub self_filter_m: f64,
    /// Torque noise levels σ, N·m.
    pub sigmas: Vec<f64>,
    /// Trials per noise level.
    pub trials: usize,
    /// Of these, the first ones also solved by the optimiser.
    pub optimiser_trials: usize,
    pub seed: u64,
}

/// The arm and scanner the scenario ships (the reference publishes no geometry).
pub fn reference_arm() -> PlanarArm {
    PlanarArm::new(Point2::origin(), vec![0.40, 0.40, 0.35, 0.30, 0.15], 0.05)
        .expect("valid geometry")
}

/// The depth sensor: 64 beams over 90° from (−1, −1) m, looking at the arm's workspace.
pub fn reference_scanner() -> Scanner {
    Scanner {
        origin: Point2::new(-1.0, -1.0),
        first_angle: 0.0,
        fov: std::f64::consts::FRAC_PI_2,
        beams: 64,
        max_range: 4.0,
        range_sigma: 0.005,
    }
}

impl Config {
    pub fn reference() -> Self {
        let arm = reference_arm();
        let bend = 2.0 * std::f64::consts::FRAC_PI_3;
        let mut joint_limits = vec![(-bend, bend); arm.links()];
        joint_limits[0] = (-std::f64::consts::PI, std::f64::consts::PI);
        Self {
            arm,
            joint_limits,
            min_bend: 15f64.to_radians(),
            push: PushSpec {
                links: vec![2, 3],
                force_n: (90.0, 110.0),
                mu: 0.5,
                hand_radius: 0.04,
            },
            scanner: reference_scanner(),
            self_filter_m: 0.02,
            sigmas: vec![0.0, 0.1, 0.5, 1.0, 2.0],
            trials: 10_000,
            optimiser_trials: 200,
            seed: 1,
        }
    }
}

/// One trial's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trial {
    /// |F̂ − F|, N; `None` when no force was found.
    pub force_error: Option<f64>,
    /// Angle between F̂ and F, degrees.
    pub direction_error: Option<f64>,
    /// |p̂ − p|, mm, and where p̂ came from.
    pub point_error: Option<(f64, PointSource)>,
    /// The estimate named the pushed link.
    pub right_link: bool,
    /// The depth sensor saw something that is not the arm.
    pub depth_saw: bool,
    pub analytic_ns: u64,
    /// The optimiser's time, its point error (mm) and its distance from the analytical
    /// answer (N, mm), on the first trials.
    pub optimiser: Option<OptimiserTrial>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimiserTrial {
    pub ns: u64,
    pub force_error: Option<f64>,
    pub point_error_mm: Option<f64>,
    /// |F_opt − F̂|, N, and |p_opt − p̂|, mm, when both found a point on the line.
    pub disagreement: Option<(f64, f64)>,
}

/// The trials of one noise level, in order; the same seed gives the same trials.
pub fn run_level(config: &Config, sigma: f64) -> Vec<Trial> {
    let mut g = Gaussian::new(config.seed, sigma.to_bits());
    let settings = Settings {
        mu: config.push.mu,
        torque_sigma: sigma,
        ..Settings::default()
    };
    (0..config.trials)
        .map(|i| {
            let (q, push) = loop {
                let q = sample_angles(&config.joint_limits, &mut g);
                if q[1..].iter().any(|a| a.abs() < config.min_bend) {
                    continue;
                }
                if let Some(p) = config.push.sample(&config.arm.pose(&q), &mut g) {
                    break (q, p);
                }
            };
            let truth = config.arm.pose(&q);
            let mut tau = truth.torques(push.link, &push.point, &push.force);
            for t in &mut tau {
                *t += g.sample(sigma);
            }
            let ranges = config.scanner.scan(&truth.contours, &[push.hand], &mut g);
            let depth = self_filter(
                &config.scanner.points(&ranges),
                &truth.contours,
                config.self_filter_m,
            );
            // Timed: the pose from the joint angles and the identification.
            let started = Instant::now();
            let pose = config.arm.pose(&q);
            let estimate = identify(&pose, &tau, &depth, &settings);
            let analytic_ns = started.elapsed().as_nanos() as u64;
            let estimate = estimate.ok();
            let point_of = |e: &crate::identify::Estimate| {
                e.point
                    .zip(e.source)
                    .map(|(p, s)| ((p - push.point).norm() * 1e3, s))
            };
            let optimiser = (i < config.optimiser_trials).then(|| {
                let started = Instant::now();
                let pose = config.arm.pose(&q);
                let o = optimise(&pose, &tau, &depth, &settings).ok();
                let ns = started.elapsed().as_nanos() as u64;
                let line = estimate
                    .filter(|e| e.source == Some(PointSource::Line))
                    .and_then(|e| e.point.map(|p| (e.force, p)));
                OptimiserTrial {
                    ns,
                    force_error: o.map(|o| (o.force - push.force).norm()),
                    point_error_mm: o.map(|o| (o.point - push.point).norm() * 1e3),
                    disagreement: o
                        .zip(line)
                        .map(|(o, (f, p))| ((o.force - f).norm(), (o.point - p).norm() * 1e3)),
                }
            });
            Trial {
                force_error: estimate.map(|e| (e.force - push.force).norm()),
                direction_error: estimate.map(|e| angle_deg(&e.force, &push.force)),
                point_error: estimate.as_ref().and_then(point_of),
                right_link: estimate.is_some_and(|e| e.link == push.link),
                depth_saw: !depth.is_empty(),
                analytic_ns,
                optimiser,
            }
        })
        .collect()
}

/// The angle between two vectors, degrees; atan2 keeps it exact near 0, where acos of the
/// normalised dot product loses half the digits.
pub fn angle_deg(a: &nalgebra::Vector2<f64>, b: &nalgebra::Vector2<f64>) -> f64 {
    a.perp(b).abs().atan2(a.dot(b)).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_noise_every_trial_is_exact_and_the_optimiser_agrees() {
        let config = Config {
            trials: 300,
            optimiser_trials: 10,
            ..Config::reference()
        };
        let trials = run_level(&config, 0.0);
        for t in &trials {
            assert!(t.force_error.unwrap() < 1e-9, "{t:?}");
            assert!(t.direction_error.unwrap() < 1e-9, "{t:?}");
            let (e, source) = t.point_error.unwrap();
            assert_eq!(source, PointSource::Line, "{t:?}");
            assert!(e < 1e-9, "{t:?}");
            assert!(t.right_link, "{t:?}");
        }
        for o in trials.iter().filter_map(|t| t.optimiser) {
            let (df, dp) = o.disagreement.unwrap();
            assert!(df < 1e-3 && dp < 1e-3, "{o:?}");
        }
        // Same seed, same trials.
        let again = run_level(&config, 0.0);
        assert_eq!(
            trials.iter().map(|t| t.force_error).collect::<Vec<_>>(),
            again.iter().map(|t| t.force_error).collect::<Vec<_>>()
        );
    }

    #[test]
    fn noise_makes_errors_grow_with_sigma() {
        let config = Config {
            trials: 400,
            optimiser_trials: 0,
            ..Config::reference()
        };
        let mean_force_error = |sigma| {
            let t = run_level(&config, sigma);
            let e: Vec<f64> = t.iter().filter_map(|t| t.force_error).collect();
            e.iter().sum::<f64>() / e.len() as f64
        };
        let (low, high) = (mean_force_error(0.1), mean_force_error(1.0));
        assert!(high > 5.0 * low && low > 0.0, "{low} {high}");
    }
}
