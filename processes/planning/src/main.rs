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
//! the leader stops when its commands go stale. The rules are the library's `Replanner`
//! (`replan.rs`); this file wires it to the topics.

use caravan::{Error, Node, Trigger};
use caravan_planning::{CostmapParams, GlobalParams, LocalParams, Replanner, fill_path2d};
use caravan_schemas::{Twist, topics};
use serde::Deserialize;
use std::process::ExitCode;

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
struct Params {
    /// The robot that plans (the leader); with a `world` that lists `[[start]]` poses, one of
    /// its robots.
    robot: usize,
    /// The world file, relative to the launch file, whose `[[start]]` poses name the robots
    /// (optional: only `robot` is checked against it; the planner maps from `map`).
    world: Option<String>,
    /// The robot's URDF, relative to the launch file: its chassis box is the footprint for the
    /// costmap (required).
    urdf: String,
    /// Re-plan at least this often while the map keeps changing, s, > 0.
    replan_period_s: f64,
    costmap: CostmapParams,
    global: GlobalParams,
    local: LocalParams,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            robot: 0,
            world: None,
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
            identity.serves_robot(p.robot);
            if let Some(file) = &p.world {
                caravan_world::load_world(&identity.resolve_path(file))
                    .map_err(|e| format!("key 'world': world file {e}"))?
                    .check_robot(file, p.robot)?;
            }
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

fn plan(mut node: Node, p: &Params) -> Result<(), Error> {
    let i = p.robot;
    let map_sub = node.subscriber(&topics::map())?;
    let pose_sub = node.subscriber(&topics::pose(i))?;
    let goal_sub = node.subscriber(&topics::goal())?;
    let path_pub = node.publisher(&topics::path(i))?;
    let cmd_pub = node.publisher(&topics::cmd_vel(i))?;
    let mut r = Replanner::new(
        p.replan_period_s,
        p.costmap.clone(),
        p.global.clone(),
        p.local.clone(),
    );
    let name = node.name().to_string();
    node.run(Trigger::every_hz(10.0), |step| {
        let now = step.now().as_secs_f64();
        if let Some(map) = map_sub.latest()? {
            r.map(map.header().seq, &map);
        }
        if let Some(goal) = goal_sub.latest()? {
            r.goal(*goal);
        }
        let decision = r.step(now, pose_sub.latest()?.map(|m| *m));
        if let Some(text) = &decision.failure {
            eprintln!("{name}: cannot plan to {text}");
        }
        if decision.new_path {
            let mut msg = path_pub.loan()?;
            fill_path2d(&mut msg, r.path());
            msg.send()?;
        }
        if let Some((v, omega)) = decision.command {
            cmd_pub.publish(&Twist::planar(v, omega))?;
        }
        Ok(())
    })?;
    Ok(())
}
