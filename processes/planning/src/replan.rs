//! When the leader re-plans: the planning node's rules around the global and local planners,
//! step by step, with no runtime in the way (the node feeds it its topics and publishes what
//! it decides).
//!
//! - A map with a sequence number not seen before rebuilds the costmap and marks the map
//!   changed; a repeat of the last one is ignored.
//! - A goal with another index or pose than the current one replaces it and asks for a new
//!   plan (a change of its tolerance alone does not).
//! - Nothing happens until a costmap, a goal and a pose are known, nor once every goal is
//!   reached (the goal's index equals its total).
//! - A changed map, once there is a path, re-plans if the path from the pose nearest the
//!   robot on is now blocked, or if `replan_period_s` has passed since the last plan (the
//!   world is discovered as the leader drives, so a path may be improved upon without being
//!   blocked).
//! - With no path (none yet, or the last plan failed) the planner plans every step.
//! - A failed plan is reported once per distinct reason and commands nothing: the leader
//!   stops when its commands go stale. A success clears the report, so that a failure that
//!   comes back is reported again.
//! - With a path, the local planner commands (v, ω) from the last command sent. When every
//!   rollout collides it commands nothing, starts again from standstill and re-plans next step.

use crate::costmap::{Costmap, CostmapParams};
use crate::global::{GlobalParams, GlobalPlanner};
use crate::local::{LocalParams, LocalPlanner};
use crate::path::{nearest_pose_index, path_blocked};
use caravan_schemas::{Goal, OccupancyGrid, Pose2D};

/// What one step decided, for the node to publish: the path first, then the command.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Decision {
    /// Whether the global plan was redone this step, successfully: publish
    /// [`Replanner::path`].
    pub new_path: bool,
    /// The velocity command to publish: forward speed v (m/s, within the local planner's
    /// `[v_min, v_max]`) and turn rate ω (rad/s, within `[omega_min, omega_max]`, positive
    /// counter-clockwise). `None`: command nothing this step.
    pub command: Option<(f64, f64)>,
    /// A planning failure not reported since the last success, as "goal i of n: reason"
    /// (goals counted from 1), for the node to tell the operator.
    pub failure: Option<String>,
}

/// The planning node's state between steps: the costmap, the goal, the current path and
/// when to redo it.
pub struct Replanner {
    replan_period_s: f64,
    costmap_params: CostmapParams,
    global: GlobalPlanner,
    local: LocalPlanner,
    costmap: Option<Costmap>,
    map_seq: Option<u64>,
    /// Whether a new map arrived since the path was last checked against one.
    map_changed: bool,
    goal: Option<Goal>,
    path: Vec<Pose2D>,
    /// Simulated time of the last plan, s.
    last_plan_s: f64,
    /// Whether the next step must plan afresh.
    replan: bool,
    /// The last command sent, the local planner's starting point.
    command: (f64, f64),
    /// The last planning failure reported, to report each once.
    reported: Option<String>,
}

impl Replanner {
    /// A planner with no map, goal or path yet. `replan_period_s` (s, > 0) is how often at
    /// least a changing map re-plans.
    pub fn new(
        replan_period_s: f64,
        costmap: CostmapParams,
        global: GlobalParams,
        local: LocalParams,
    ) -> Self {
        Self {
            replan_period_s,
            costmap_params: costmap,
            global: GlobalPlanner::new(global),
            local: LocalPlanner::new(local),
            costmap: None,
            map_seq: None,
            map_changed: false,
            goal: None,
            path: Vec::new(),
            last_plan_s: 0.0,
            replan: false,
            command: (0.0, 0.0),
            reported: None,
        }
    }

    /// Takes the latest map, numbered `seq` by its publisher; a repeat of the last one is
    /// ignored.
    pub fn map(&mut self, seq: u64, grid: &OccupancyGrid) {
        if self.map_seq == Some(seq) {
            return;
        }
        self.map_seq = Some(seq);
        match &mut self.costmap {
            Some(c) => c.update(grid),
            None => self.costmap = Some(Costmap::from_grid(grid, &self.costmap_params)),
        }
        self.map_changed = true;
    }

    /// Takes the latest goal; one with the current goal's index and pose is no change.
    pub fn goal(&mut self, goal: Goal) {
        if self.goal.map(|g| (g.index, g.pose)) != Some((goal.index, goal.pose)) {
            self.goal = Some(goal);
            self.replan = true;
        }
    }

    /// One step at simulated time `now_s` (s), with the robot's latest pose (map frame), after
    /// this step's [`Replanner::map`] and [`Replanner::goal`].
    pub fn step(&mut self, now_s: f64, pose: Option<Pose2D>) -> Decision {
        let mut out = Decision::default();
        let (Some(costmap), Some(goal), Some(pose)) = (&self.costmap, self.goal, pose) else {
            return out;
        };
        if goal.index >= goal.total {
            return out; // every goal reached
        }
        if self.map_changed && !self.path.is_empty() {
            let from = nearest_pose_index(&self.path, pose.x, pose.y).unwrap_or(0);
            if path_blocked(costmap, &self.path, from)
                || now_s - self.last_plan_s >= self.replan_period_s
            {
                self.replan = true;
            }
            self.map_changed = false;
        }
        if self.replan || self.path.is_empty() {
            self.last_plan_s = now_s;
            self.replan = false;
            match self.global.plan(costmap, pose, goal.pose) {
                Ok(path) => {
                    self.path = path;
                    self.reported = None;
                    out.new_path = true;
                }
                Err(e) => {
                    let text = format!("goal {} of {}: {e}", goal.index + 1, goal.total);
                    if self.reported.as_deref() != Some(text.as_str()) {
                        out.failure = Some(text.clone());
                        self.reported = Some(text);
                    }
                    self.path.clear();
                    return out;
                }
            }
        }
        match self.local.command(costmap, pose, self.command, &self.path) {
            Some((v, omega)) => {
                self.command = (v, omega);
                out.command = Some((v, omega));
            }
            // Every rollout collides: stop (no command) and plan afresh next step.
            None => {
                self.command = (0.0, 0.0);
                self.replan = true;
            }
        }
        out
    }

    /// The current global plan (map frame); empty before the first plan and after a failed
    /// one.
    pub fn path(&self) -> &[Pose2D] {
        &self.path
    }
}

#[cfg(test)]
#[path = "replan_tests.rs"]
mod tests;
