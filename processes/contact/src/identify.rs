//! The analytical identification of the reference: from the joint torques of a planar arm,
//! the contact force F and its point p.
//!
//! 1. Torques alone fix only F's line of action. Replacing F at p by a wrench W = (F_x, F_y,
//!    τ_z) at a known point p0 gives a linear system τ = J_eᵀ·W whose least-squares solution
//!    (the pseudo-inverse) is F exactly when at least three joint axes, not collinear, carry
//!    the torque ([`extended_wrench`]).
//! 2. The line of action is where (p − p0) × F = τ_z.
//! 3. The contact point is where that line enters the link's contour with F inside the
//!    friction cone (angle to the inward normal ≤ atan μ).
//! 4. The touched link is ambiguous when the line passes (near) a joint axis: every link from
//!    k_min (the last joint with a torque above the noise) to k_max (the most joints whose
//!    torques one wrench explains) is a candidate, and the depth sensor's view of the obstacle
//!    picks among them ([`candidate_range`]).
//! 5. When the line misses every candidate's surface, F is kept and the point is taken from
//!    the depth sensor.

use crate::planar_arm::{ArmPose, MAX_LINKS};
use nalgebra::{Point2, Vector2, Vector3};

/// What the estimator assumes about its torque sensors and the contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Friction coefficient of the arm's surface, ≥ 0 (reference: 0.5).
    pub mu: f64,
    /// Standard deviation of the torque sensors' noise, N·m, ≥ 0.
    pub torque_sigma: f64,
    /// Torque below which a joint counts as unloaded whatever the noise, N·m, ≥ 0
    /// (round-off, a controller's residual).
    pub torque_floor: f64,
    /// Noise multiple of the thresholds δ_τ = floor + z·σ and δ_ε = floor + z·σ·√(l − 3).
    pub z: f64,
    /// Joint axes spread less than this (m) across their best-fit line are collinear: the
    /// wrench is then undetermined.
    pub min_spread: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mu: 0.5,
            torque_sigma: 0.0,
            torque_floor: 1e-9,
            z: 3.0,
            min_spread: 1e-6,
        }
    }
}

impl Settings {
    /// δ_τ: a joint whose |τ| exceeds it carries the contact's torque.
    pub fn delta_tau(&self) -> f64 {
        self.torque_floor + self.z * self.torque_sigma
    }

    /// δ_ε for `l` equations: the largest residual one wrench may leave.
    pub fn delta_eps(&self, l: usize) -> f64 {
        self.torque_floor + self.z * self.torque_sigma * (l.saturating_sub(3).max(1) as f64).sqrt()
    }

    /// cos(atan μ): the least cosine between F and the inward normal.
    pub fn cone_cos(&self) -> f64 {
        1.0 / (1.0 + self.mu * self.mu).sqrt()
    }
}

/// The wrench at `p0` that best explains the first `tau.len()` torques.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtendedWrench {
    /// Its reference point, m.
    pub p0: Point2<f64>,
    /// (F_x, F_y, τ_z): N, N, N·m.
    pub w: Vector3<f64>,
    /// |τ − J_eᵀ·W|, N·m.
    pub residual: f64,
}

impl ExtendedWrench {
    pub fn force(&self) -> Vector2<f64> {
        Vector2::new(self.w.x, self.w.y)
    }

    /// A point on the line of action: p0 + τ_z·(F_y, −F_x)/|F|².
    pub fn line_point(&self) -> Point2<f64> {
        let f = self.force();
        self.p0 + self.w.z * Vector2::new(f.y, -f.x) / f.norm_squared()
    }
}

/// W = pinv(J_eᵀ)·τ for the joints `joints[..tau.len()]`, with p0 their centroid (which makes
/// J_e·J_eᵀ block-diagonal); `None` when fewer than three joints or their axes are collinear
/// (spread below `min_spread`).
pub fn extended_wrench(
    joints: &[Point2<f64>],
    tau: &[f64],
    min_spread: f64,
) -> Option<ExtendedWrench> {
    let l = tau.len();
    if l < 3 {
        return None;
    }
    let joints = &joints[..l];
    let p0 = Point2::from(joints.iter().map(|j| j.coords).sum::<Vector2<f64>>() / l as f64);
    // Row i of J_eᵀ: (v_i, u_i, 1) with v_i = −(y0 − y_i), u_i = x0 − x_i; Σu = Σv = 0.
    let (mut svv, mut suv, mut suu) = (0.0, 0.0, 0.0);
    let (mut bv, mut bu, mut bt) = (0.0, 0.0, 0.0);
    for (j, t) in joints.iter().zip(tau) {
        let (u, v) = (p0.x - j.x, j.y - p0.y);
        svv += v * v;
        suv += u * v;
        suu += u * u;
        bv += v * t;
        bu += u * t;
        bt += t;
    }
    let det = svv * suu - suv * suv;
    // The smaller eigenvalue of the joints' scatter, per joint: their spread², m².
    let trace = svv + suu;
    let smallest = 0.5 * (trace - (trace * trace - 4.0 * det).max(0.0).sqrt());
    if smallest / l as f64 <= min_spread * min_spread || det <= 0.0 {
        return None;
    }
    let fx = (suu * bv - suv * bu) / det;
    let fy = (svv * bu - suv * bv) / det;
    let tz = bt / l as f64;
    let residual = joints
        .iter()
        .zip(tau)
        .map(|(j, t)| {
            let (u, v) = (p0.x - j.x, j.y - p0.y);
            (t - (v * fx + u * fy + tz)).powi(2)
        })
        .sum::<f64>()
        .sqrt();
    Some(ExtendedWrench {
        p0,
        w: Vector3::new(fx, fy, tz),
        residual,
    })
}

/// The candidate links (0-based, inclusive) and the wrench fitted to joints 0..=k_max.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidates {
    pub k_min: usize,
    pub k_max: usize,
    pub wrench: ExtendedWrench,
}

/// Why no force was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoForce {
    /// No joint's torque is above the noise.
    NoContact,
    /// Fewer than three joints carry torque, or their axes are collinear.
    Underdetermined,
    /// The loaded joints' torques fit no single force (another contact, dynamics).
    Inconsistent,
}

/// k_min: the last joint whose |τ| exceeds δ_τ; k_max: the most joints (at least three, at
/// least k_min + 1) one wrench explains within δ_ε, with that wrench.
pub fn candidate_range(
    joints: &[Point2<f64>],
    tau: &[f64],
    settings: &Settings,
) -> Result<Candidates, NoForce> {
    let delta_tau = settings.delta_tau();
    let k_min = tau
        .iter()
        .rposition(|t| t.abs() > delta_tau)
        .ok_or(NoForce::NoContact)?;
    // The largest l whose equations one wrench explains. In theory a larger l never fits
    // better than a smaller one; in a near-singular pose round-off can make the square
    // 3-joint system look inconsistent, so every l is tried and l = 3 (exactly determined)
    // always fits.
    let mut best = None;
    for l in 3..=tau.len() {
        if let Some(w) = extended_wrench(joints, &tau[..l], settings.min_spread)
            && (l == 3 || w.residual <= settings.delta_eps(l))
        {
            best = Some((l - 1, w));
        }
    }
    match best {
        Some((k_max, wrench)) if k_max >= k_min => Ok(Candidates {
            k_min,
            k_max,
            wrench,
        }),
        Some(_) => Err(NoForce::Inconsistent),
        None => Err(NoForce::Underdetermined),
    }
}

/// Where the estimate's contact point came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointSource {
    /// The line of action's entry into the link's surface.
    Line,
    /// The line missed every candidate's surface: the depth sensor's obstacle point nearest
    /// to the arm, projected onto the link.
    Depth,
}

/// The identified contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// N, in the plane.
    pub force: Vector2<f64>,
    /// On the link's surface, m; `None` when the line missed and the depth sensor saw nothing.
    pub point: Option<Point2<f64>>,
    pub source: Option<PointSource>,
    /// The touched link (0-based).
    pub link: usize,
    pub candidates: Candidates,
}

/// The analytical identification: `tau` holds every joint's external torque (N·m), `depth`
/// the obstacle points the depth sensor sees (already free of the arm itself).
pub fn identify(
    pose: &ArmPose,
    tau: &[f64],
    depth: &[Point2<f64>],
    settings: &Settings,
) -> Result<Estimate, NoForce> {
    let candidates = candidate_range(&pose.joints, tau, settings)?;
    let force = candidates.wrench.force();
    // A pure couple (no force, yet torques): no single contact explains it.
    let reach = pose.joints[..=candidates.k_max]
        .iter()
        .map(|j| (j - candidates.wrench.p0).norm())
        .fold(0.0, f64::max);
    if force.norm() * reach <= settings.delta_tau() {
        return Err(NoForce::Inconsistent);
    }
    let on_line = candidates.wrench.line_point();
    let cone = settings.cone_cos();
    // Candidates whose surface the line enters inside the friction cone, at a point no other
    // link covers.
    let mut valid = [(0usize, Point2::origin()); MAX_LINKS];
    let mut n_valid = 0;
    for link in candidates.k_min..=candidates.k_max {
        if let Some(e) = pose.contours[link].entry(&on_line, &force)
            && e.cos_to_normal >= cone
            && !pose.hidden(link, &e.point, 0.0)
        {
            valid[n_valid] = (link, e.point);
            n_valid += 1;
        }
    }
    let chosen = choose(&valid[..n_valid], depth);
    if let Some((link, point)) = chosen {
        return Ok(Estimate {
            force,
            point: Some(point),
            source: Some(PointSource::Line),
            link,
            candidates,
        });
    }
    // Fall-back: the observed point nearest to a candidate's surface, projected onto it.
    let fallback = (candidates.k_min..=candidates.k_max)
        .flat_map(|link| {
            depth.iter().map(move |d| {
                let (q, dist, _) = pose.contours[link].nearest(d);
                (dist, link, q)
            })
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    Ok(Estimate {
        force,
        point: fallback.map(|f| f.2),
        source: fallback.map(|_| PointSource::Depth),
        link: fallback.map_or(candidates.k_max, |f| f.1),
        candidates,
    })
}

/// Among the candidates the line enters validly (link, point), the one whose point lies
/// nearest to an obstacle point the depth sensor sees; blind, the most distal (the
/// trailing-zero rule's link).
pub fn choose(
    valid: &[(usize, Point2<f64>)],
    depth: &[Point2<f64>],
) -> Option<(usize, Point2<f64>)> {
    let nearest_seen = |p: &Point2<f64>| {
        depth
            .iter()
            .map(|d| (d - p).norm())
            .fold(f64::INFINITY, f64::min)
    };
    match valid {
        [] => None,
        [only] => Some(*only),
        many if depth.is_empty() => many.last().copied(),
        many => many
            .iter()
            .min_by(|a, b| nearest_seen(&a.1).total_cmp(&nearest_seen(&b.1)))
            .copied(),
    }
}

#[cfg(test)]
#[path = "identify_tests.rs"]
mod tests;
