//! `caravan-planning`: the leader's move_base, as a node at 10 Hz.
//!
//! In:  `map` (SLAM's occupancy grid), `robot/i/pose` (the leader's localisation), `goal`.
//! Out: `robot/i/path` (the global plan, whenever it changes) and `robot/i/cmd_vel` (the
//!      local planner's (v, ω) each step while there is a goal and a collision-free rollout).
//!
//! The global plan is redone when the goal changes, when a new map shows the remaining path
//! blocked, when the local planner finds no safe rollout, and at least every
//! `replan_period_s` while the map changes (the world is discovered as the leader drives). An
//! unreachable goal is reported once, with the planner's reason, and nothing is commanded:
//! the leader stops when its commands go stale.

use caravan::{Error, Node, Trigger};
use caravan_planning::{
    Costmap, CostmapParams, GlobalParams, GlobalPlanner, LocalParams, LocalPlanner, fill_path2d,
    nearest_pose_index, path_blocked,
};
use caravan_schemas::{Goal, Pose2D, Twist, topics};
use serde::Deserialize;
use std::process::ExitCode;

#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct Params {
    /// The robot that plans (the leader).
    robot: usize,
    /// The robot's URDF, relative to the launch file: its footprint for the costmap (required).
    urdf: String,
    /// Re-plan at least this often while the map keeps changing, s.
    replan_period_s: f64,
    costmap: CostmapParams,
    global: GlobalParams,
    local: LocalParams,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            robot: 0,
            urdf: String::new(),
            replan_period_s: 1.0,
            costmap: CostmapParams::default(),
            global: GlobalParams::default(),
            local: LocalParams::default(),
        }
    }
}

impl Params {
    fn validate(&self) -> Result<(), String> {
        if !(self.replan_period_s > 0.0 && self.replan_period_s.is_finite()) {
            return Err(format!(
                "key 'replan_period_s': must be positive, got {}",
                self.replan_period_s
            ));
        }
        self.costmap
            .validate()
            .map_err(|e| format!("key 'costmap': {e}"))?;
        self.global
            .validate()
            .map_err(|e| format!("key 'global': {e}"))?;
        self.local
            .validate()
            .map_err(|e| format!("key 'local': {e}"))
    }
}

fn main() -> ExitCode {
    caravan::node_main(
        "caravan-planning",
        |mut p: Params, identity| {
            p.validate()?;
            if p.urdf.is_empty() {
                return Err("key 'urdf': give the robot's URDF (its footprint)".into());
            }
            let robot = caravan_world::load_robot(&identity.resolve_path(&p.urdf))
                .map_err(|e| format!("key 'urdf': robot description {e}"))?;
            p.costmap.footprint_length = 2.0 * robot.chassis_half_extents[0];
            p.costmap.footprint_width = 2.0 * robot.chassis_half_extents[1];
            Ok(p)
        },
        |node, p| plan(node, &p),
    )
}

/// What the planner is working on.
#[derive(Default)]
struct State {
    costmap: Option<Costmap>,
    map_seq: Option<u64>,
    map_changed: bool,
    goal: Option<Goal>,
    path: Vec<Pose2D>,
    last_plan_s: f64,
    replan: bool,
    /// The last command sent, the local planner's starting point.
    command: (f64, f64),
    /// The last planning failure reported, to report each once.
    reported: Option<String>,
}

fn plan(mut node: Node, p: &Params) -> Result<(), Error> {
    let i = p.robot;
    let map_sub = node.subscriber(&topics::map())?;
    let pose_sub = node.subscriber(&topics::pose(i))?;
    let goal_sub = node.subscriber(&topics::goal())?;
    let path_pub = node.publisher(&topics::path(i))?;
    let cmd_pub = node.publisher(&topics::cmd_vel(i))?;
    let mut global = GlobalPlanner::new(p.global.clone());
    let local = LocalPlanner::new(p.local.clone());
    let mut s = State::default();
    let name = node.name().to_string();
    node.run(Trigger::every_hz(10.0), |step| {
        let now = step.now().as_secs_f64();
        if let Some(map) = map_sub.latest()?
            && s.map_seq != Some(map.header().seq)
        {
            s.map_seq = Some(map.header().seq);
            match &mut s.costmap {
                Some(c) => c.update(&map),
                None => s.costmap = Some(Costmap::from_grid(&map, &p.costmap)),
            }
            s.map_changed = true;
        }
        if let Some(goal) = goal_sub.latest()?
            && s.goal.map(|g| (g.index, g.pose)) != Some((goal.index, goal.pose))
        {
            s.goal = Some(*goal);
            s.replan = true;
        }
        let (Some(costmap), Some(goal), Some(pose)) =
            (&s.costmap, s.goal, pose_sub.latest()?.map(|m| *m))
        else {
            return Ok(());
        };
        if goal.index >= goal.total {
            return Ok(()); // every goal reached
        }
        if s.map_changed && !s.path.is_empty() {
            let from = nearest_pose_index(&s.path, pose.x, pose.y).unwrap_or(0);
            if path_blocked(costmap, &s.path, from) || now - s.last_plan_s >= p.replan_period_s {
                s.replan = true;
            }
            s.map_changed = false;
        }
        if s.replan || s.path.is_empty() {
            s.last_plan_s = now;
            s.replan = false;
            match global.plan(costmap, pose, goal.pose) {
                Ok(path) => {
                    s.path = path;
                    s.reported = None;
                    let mut msg = path_pub.loan()?;
                    fill_path2d(&mut msg, &s.path);
                    msg.send()?;
                }
                Err(e) => {
                    let text = format!("goal {} of {}: {e}", goal.index + 1, goal.total);
                    if s.reported.as_deref() != Some(text.as_str()) {
                        eprintln!("{name}: cannot plan to {text}");
                        s.reported = Some(text);
                    }
                    s.path.clear();
                    return Ok(());
                }
            }
        }
        match local.command(costmap, pose, s.command, &s.path) {
            Some((v, omega)) => {
                s.command = (v, omega);
                cmd_pub.publish(&Twist::planar(v, omega))?;
            }
            // Every rollout collides: stop (no command) and plan afresh next step.
            None => {
                s.command = (0.0, 0.0);
                s.replan = true;
            }
        }
        Ok(())
    })?;
    Ok(())
}
