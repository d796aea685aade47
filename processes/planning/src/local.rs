//! Local planner: Trajectory Rollout, after ROS base_local_planner.
//!
//! Each cycle it samples target velocities (v, ω) within the leader's limits, rolls each out
//! for `sim_time` seconds from the robot's pose and current command, drops those that would
//! bring the robot's centre into an inflated cell, and scores the rest as base_local_planner
//! does: distance of the end point from the global path (`path_distance_bias`), distance from
//! the end point to a local goal `lookahead` metres further along the path
//! (`goal_distance_bias`) and the highest cell cost met (`occdist_scale`).
//!
//! Acceleration: the robot's wheel speed loop is slow (on the floor it settles in about 2.5 s,
//! with overshoot), so the planner never asks for a jump in velocity. Commands move towards
//! their target by at most `acc_lim · control_period` per cycle, and each rollout models
//! exactly that: the command ramps from the current one towards the sample's target, one
//! control period at a time, and then holds it. The command returned is the ramp's first
//! step, so (with a robot that follows its commands) the first period of the chosen rollout
//! is what the robot actually does, and the rollouts never assume an agility the robot lacks.
//! Targets are sampled over everything the ramp can reach within the rollout (`current ±
//! acc·sim_time`, clipped to the limits), which with the defaults is the full range: the
//! window is wide, the acceleration is limited inside each rollout. Pass the command sent in
//! the previous cycle as `current` (not a measured velocity, which lags the command and would
//! slow the ramp down twice).
//!
//! The leader's v_min is 0.1 m/s > 0, so it cannot turn in place; tight turns come from
//! |ω| up to 2 rad/s at 0.1 m/s (a 5 cm radius). The planner never commands anything outside
//! `[v_min, v_max] × [omega_min, omega_max]` (from standstill the first command jumps to
//! v_min); stopping is the caller's job (at the goal, or when [`LocalPlanner::command`]
//! returns `None`).

use crate::costmap::{Costmap, INSCRIBED, LETHAL, MAX_INFLATED};
use crate::trace::segment_cells;
use caravan_schemas::Pose2D;
use serde::{Deserialize, Serialize};

/// Local planner parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct LocalParams {
    /// Slowest forward speed, m/s, finite, ≤ `v_max` (the leader never turns in place).
    pub v_min: f64,
    /// Fastest forward speed, m/s, finite.
    pub v_max: f64,
    /// Most negative (clockwise) turn rate, rad/s, finite, ≤ `omega_max`.
    pub omega_min: f64,
    /// Most positive (counter-clockwise) turn rate, rad/s, finite.
    pub omega_max: f64,
    /// Largest rate of change of the commanded speed, m/s², > 0. Keep it within what the wheel
    /// speed loop can follow. The default is an estimate: a second-order step response that
    /// settles (5 %) in 2.5 s with ~20 % overshoot rises at most ~1.6 × its step per second,
    /// i.e. ~0.3 m/s² for a 0.2 m/s step and ~3 rad/s² for a 2 rad/s step. Refit it to the
    /// motor model.
    pub acc_lim_v: f64,
    /// Largest rate of change of the commanded turn rate, rad/s², > 0.
    pub acc_lim_omega: f64,
    /// Period between commands as the rollouts model it, s, > 0: how often
    /// [`LocalPlanner::command`] is called (the command is held in between). Keep it equal to
    /// the node's period; nothing checks that.
    pub control_period: f64,
    /// How far ahead each rollout is simulated, s, > 0.
    pub sim_time: f64,
    /// Integration step of the rollout, s, > 0, ≤ `sim_time` (at 0.2 m/s, 0.05 s is 1 cm: finer
    /// than a cell).
    pub sim_step: f64,
    /// Number of target speeds sampled across the window, 1 to 1000.
    pub v_samples: usize,
    /// Number of target turn rates sampled across the window, ≥ 1 (ω = 0 is always added).
    pub omega_samples: usize,
    /// Weight of the end point's distance from the global path, per m, ≥ 0.
    pub path_distance_bias: f64,
    /// Weight of the end point's distance from the local goal, per m, ≥ 0.
    pub goal_distance_bias: f64,
    /// Weight of the highest cell cost along the rollout, per 252 cost units, ≥ 0.
    pub occdist_scale: f64,
    /// Distance along the global path from the robot to the local goal, m, > 0. Keep it above
    /// `v_max × sim_time` so that the goal keeps pulling the robot forward.
    pub lookahead: f64,
}

impl Default for LocalParams {
    fn default() -> Self {
        Self {
            v_min: 0.1,
            v_max: 0.2,
            omega_min: -1.5,
            omega_max: 2.0,
            acc_lim_v: 0.3,
            // The convoy's wheels settle in 2.5 s with overshoot: faster turn-rate changes
            // than this make the leader weave, and the followers copy and amplify the weave
            // (measured on launch/convoy/convoy.toml: 3 rad/s² weaves, 0.5 rad/s² does not).
            acc_lim_omega: 0.5,
            control_period: 0.1,
            sim_time: 2.5,
            sim_step: 0.05,
            v_samples: 5,
            omega_samples: 21,
            // base_local_planner's DWA defaults (32, 24, 0.01 per cell and cost unit) keep
            // the path term above the goal term; occdist is stronger here so that the robot
            // prefers the middle of a corridor when the path allows it.
            path_distance_bias: 32.0,
            goal_distance_bias: 24.0,
            occdist_scale: 1.0,
            lookahead: 1.0,
        }
    }
}

impl LocalParams {
    /// Checks that the parameters make sense.
    pub fn validate(&self) -> Result<(), String> {
        let finite = [
            ("v_min", self.v_min),
            ("v_max", self.v_max),
            ("omega_min", self.omega_min),
            ("omega_max", self.omega_max),
        ];
        for (name, v) in finite {
            if !v.is_finite() {
                return Err(format!("{name} must be finite, got {v}"));
            }
        }
        if self.v_min > self.v_max {
            return Err(format!(
                "v_min ({}) must not exceed v_max ({})",
                self.v_min, self.v_max
            ));
        }
        if self.omega_min > self.omega_max {
            return Err(format!(
                "omega_min ({}) must not exceed omega_max ({})",
                self.omega_min, self.omega_max
            ));
        }
        let positive = [
            ("acc_lim_v", self.acc_lim_v),
            ("acc_lim_omega", self.acc_lim_omega),
            ("control_period", self.control_period),
            ("sim_time", self.sim_time),
            ("sim_step", self.sim_step),
            ("lookahead", self.lookahead),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} must be positive, got {v}"));
            }
        }
        if self.sim_step > self.sim_time {
            return Err(format!(
                "sim_step ({}) must not exceed sim_time ({})",
                self.sim_step, self.sim_time
            ));
        }
        // Every step scores v_samples × omega_samples trajectories.
        if !(1..=1000).contains(&self.v_samples) || !(1..=1000).contains(&self.omega_samples) {
            return Err(format!(
                "v_samples and omega_samples must be 1 to 1000, got {} and {}",
                self.v_samples, self.omega_samples
            ));
        }
        let weights = [
            ("path_distance_bias", self.path_distance_bias),
            ("goal_distance_bias", self.goal_distance_bias),
            ("occdist_scale", self.occdist_scale),
        ];
        for (name, v) in weights {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} must be ≥ 0, got {v}"));
            }
        }
        Ok(())
    }
}

/// Trajectory Rollout local planner. Stateless between cycles: everything it needs comes in
/// with each call.
#[derive(Debug, Clone)]
pub struct LocalPlanner {
    params: LocalParams,
}

impl LocalPlanner {
    /// A planner with these parameters; check them first with [`LocalParams::validate`].
    pub fn new(params: LocalParams) -> Self {
        Self { params }
    }

    pub fn params(&self) -> &LocalParams {
        &self.params
    }

    /// The next command `(v, ω)` for the robot at `pose` following the global `path`, given
    /// `current`, the command sent in the previous cycle (`(0, 0)` from standstill). Returns
    /// `None` if the path is empty or every sampled trajectory collides: the caller should
    /// stop and re-plan.
    pub fn command(
        &self,
        costmap: &Costmap,
        pose: Pose2D,
        current: (f64, f64),
        path: &[Pose2D],
    ) -> Option<(f64, f64)> {
        let p = &self.params;
        let local = LocalPath::new(path, (pose.x, pose.y), p.lookahead)?;
        let guard = CollisionGuard::new(costmap, pose);
        // The rollout: `periods` control periods of `substeps` integration steps each.
        let period = p.control_period;
        // Clamped so that unvalidated parameters (a zero step) cannot hang the cycle.
        let periods = ((p.sim_time / period).ceil() as usize).clamp(1, 1000);
        let substeps = ((period / p.sim_step).ceil() as usize).clamp(1, 100);
        let h = period / substeps as f64;
        let (dv, dw) = (p.acc_lim_v * period, p.acc_lim_omega * period);

        let reach_v = p.acc_lim_v * p.sim_time;
        let reach_w = p.acc_lim_omega * p.sim_time;
        let vs = samples(p.v_min, p.v_max, current.0, reach_v, p.v_samples, None);
        let ws = samples(
            p.omega_min,
            p.omega_max,
            current.1,
            reach_w,
            p.omega_samples,
            Some(0.0),
        );
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        let start = (finite(current.0), finite(current.1));

        let mut best: Option<(f64, (f64, f64))> = None;
        // Fastest first, so that among equal scores the faster command wins.
        for &vt in vs.iter().rev() {
            'sample: for &wt in &ws {
                let (mut x, mut y, mut th) = (pose.x, pose.y, pose.theta);
                let (mut v, mut w) = start;
                let mut first = None;
                let mut worst = 0u8;
                for _ in 0..periods {
                    v = approach(v, vt, dv).clamp(p.v_min, p.v_max);
                    w = approach(w, wt, dw).clamp(p.omega_min, p.omega_max);
                    first.get_or_insert((v, w));
                    for _ in 0..substeps {
                        let (px, py) = (x, y);
                        (x, y, th) = arc(x, y, th, v, w, h);
                        // Every cell the step crosses, so that no corner is clipped unseen.
                        let a = costmap.world_to_grid(px, py);
                        let b = costmap.world_to_grid(x, y);
                        let clear = segment_cells(a, b, |ix, iy, _| match guard.cost(ix, iy) {
                            Some(c) => {
                                worst = worst.max(c);
                                true
                            }
                            None => false,
                        });
                        if !clear {
                            continue 'sample;
                        }
                    }
                }
                let score = p.path_distance_bias * local.distance(x, y)
                    + p.goal_distance_bias * (x - local.goal.0).hypot(y - local.goal.1)
                    + p.occdist_scale * f64::from(worst) / f64::from(MAX_INFLATED);
                if best.is_none_or(|(b, _)| score < b) {
                    best = first.map(|cmd| (score, cmd));
                }
            }
        }
        best.map(|(_, cmd)| cmd)
    }
}

/// Pose after driving at (v, ω) for `t` seconds: an exact circular arc (straight line for
/// ω ≈ 0), so that rollouts and a robot that follows its commands agree to rounding.
#[inline]
fn arc(x: f64, y: f64, th: f64, v: f64, w: f64, t: f64) -> (f64, f64, f64) {
    let th1 = th + w * t;
    if w.abs() < 1e-6 {
        let mid = th + 0.5 * w * t;
        (x + v * t * mid.cos(), y + v * t * mid.sin(), th1)
    } else {
        let r = v / w;
        (
            x + r * (th1.sin() - th.sin()),
            y - r * (th1.cos() - th.cos()),
            th1,
        )
    }
}

/// Moves `value` towards `target` by at most `step`.
fn approach(value: f64, target: f64, step: f64) -> f64 {
    value + (target - value).clamp(-step, step)
}

/// `n` evenly spaced targets over what is reachable from `current` within `reach`, clipped to
/// `[min, max]`, plus `extra` if it lies in that window.
fn samples(min: f64, max: f64, current: f64, reach: f64, n: usize, extra: Option<f64>) -> Vec<f64> {
    let current = if current.is_finite() { current } else { 0.0 };
    let lo = (current - reach).clamp(min, max);
    let hi = (current + reach).clamp(min, max);
    let mut out: Vec<f64> = if n <= 1 || hi - lo < 1e-9 {
        vec![0.5 * (lo + hi)]
    } else {
        (0..n)
            .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
            .collect()
    };
    if let Some(e) = extra
        && (lo..=hi).contains(&e)
        && !out.iter().any(|&s| (s - e).abs() < 1e-9)
    {
        out.push(e);
    }
    out
}

/// Decides which rollout points collide. Normally any inflated cell does. When the robot
/// already stands on an inflated cell (it drifted close to a wall), a trajectory may stay
/// there as long as it gets no closer to the obstacle, so the robot can drive out instead of
/// freezing; obstacle cells other than its own stay forbidden.
struct CollisionGuard<'a> {
    costmap: &'a Costmap,
    /// Clearance below which a point collides.
    floor: f64,
    start_cell: Option<(usize, usize)>,
    escaping: bool,
}

impl<'a> CollisionGuard<'a> {
    fn new(costmap: &'a Costmap, pose: Pose2D) -> Self {
        let start_cell = costmap.world_to_cell(pose.x, pose.y);
        let escaping = start_cell.is_some_and(|(x, y)| costmap.cost(x, y) >= INSCRIBED);
        let floor = start_cell.map_or(0.0, |(x, y)| costmap.cell_clearance(x, y));
        Self {
            costmap,
            floor: floor - 1e-6,
            start_cell,
            escaping,
        }
    }

    /// The cost of a cell a rollout crosses, or `None` if it collides.
    #[inline]
    fn cost(&self, ix: i64, iy: i64) -> Option<u8> {
        let c = self.costmap.cost_i(ix, iy);
        if c < INSCRIBED {
            return Some(c);
        }
        let (x, y) = (usize::try_from(ix).ok()?, usize::try_from(iy).ok()?);
        let allowed = self.escaping
            && self.costmap.cell_clearance(x, y) >= self.floor
            && (c != LETHAL || Some((x, y)) == self.start_cell);
        allowed.then_some(MAX_INFLATED)
    }
}

/// The stretch of the global path that matters now: from the point nearest the robot to the
/// local goal `lookahead` metres further on.
struct LocalPath {
    pts: Vec<(f64, f64)>,
    goal: (f64, f64),
}

impl LocalPath {
    fn new(path: &[Pose2D], robot: (f64, f64), lookahead: f64) -> Option<Self> {
        let xy = |p: &Pose2D| (p.x, p.y);
        let first = path.first()?;
        if path.len() == 1 {
            return Some(Self {
                pts: vec![xy(first)],
                goal: xy(first),
            });
        }
        // Nearest point on the polyline.
        let (seg, near) = path
            .windows(2)
            .enumerate()
            .map(|(i, w)| (i, project(robot, xy(&w[0]), xy(&w[1]))))
            .min_by(|a, b| dist2(robot, a.1).total_cmp(&dist2(robot, b.1)))?;
        let mut pts = vec![xy(&path[seg]), near];
        let mut left = lookahead;
        let mut at = near;
        for p in &path[seg + 1..] {
            let next = xy(p);
            let len = dist2(at, next).sqrt();
            if len >= left {
                let t = left / len;
                let goal = (at.0 + (next.0 - at.0) * t, at.1 + (next.1 - at.1) * t);
                pts.push(goal);
                return Some(Self { pts, goal });
            }
            left -= len;
            pts.push(next);
            at = next;
        }
        Some(Self { pts, goal: at })
    }

    /// Distance from a point to this stretch of path.
    fn distance(&self, x: f64, y: f64) -> f64 {
        if self.pts.len() == 1 {
            return dist2((x, y), self.pts[0]).sqrt();
        }
        self.pts
            .windows(2)
            .map(|w| dist2((x, y), project((x, y), w[0], w[1])))
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }
}

fn dist2(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)
}

/// The point of segment `a`–`b` nearest to `p`.
fn project(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    if len2 < 1e-18 {
        return a;
    }
    let t = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0);
    (a.0 + dx * t, a.1 + dy * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_cover_the_window_and_include_zero_turn() {
        let ws = samples(-1.5, 2.0, 0.0, 3.4, 21, Some(0.0));
        assert_eq!(ws.len(), 22);
        assert_eq!(ws[0], -1.5);
        assert_eq!(ws[20], 2.0);
        assert!(ws.contains(&0.0));
        // A small reach narrows the window around the current value.
        let vs = samples(0.1, 0.2, 0.0, 0.12, 3, None);
        assert_eq!(vs, vec![0.1, 0.11, 0.12]);
        assert_eq!(samples(0.1, 0.2, 0.0, 0.05, 3, None), vec![0.1]);
    }

    #[test]
    fn local_path_finds_goal_at_lookahead() {
        let path: Vec<Pose2D> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)]
            .iter()
            .map(|&(x, y)| Pose2D { x, y, theta: 0.0 })
            .collect();
        let lp = LocalPath::new(&path, (0.8, 0.1), 0.5).unwrap();
        assert!(dist2(lp.goal, (1.0, 0.3)) < 1e-12);
        assert!(lp.distance(0.5, 0.2) - 0.2 < 1e-12);
        let end = LocalPath::new(&path, (1.0, 0.9), 0.5).unwrap();
        assert_eq!(end.goal, (1.0, 1.0));
    }

    #[test]
    fn params_deserialise_strictly() {
        let p: LocalParams = toml::from_str("sim_time = 2.0\nv_samples = 7").unwrap();
        assert_eq!(p.sim_time, 2.0);
        assert_eq!(p.v_samples, 7);
        assert_eq!(p.v_max, 0.2);
        assert!(p.validate().is_ok());
        let err = toml::from_str::<LocalParams>("vmax = 0.3").unwrap_err();
        assert!(err.to_string().contains("vmax"), "{err}");
        let bad = LocalParams {
            v_min: 0.3,
            ..LocalParams::default()
        };
        assert!(bad.validate().unwrap_err().contains("v_min"));
    }
}
