//! A custom convoy follower: pure pursuit on the path its predecessor drove.
//! See docs/agents.md for a walk through this file.

use caravan::{Error, Node, Trigger};
use caravan_schemas::{Pose2D, WheelSetpoint, topics};
use caravan_world::{RobotModel, kinematics::wheel_speeds};
use serde::Deserialize;

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
struct Params {
    /// This robot's index; it follows `robot − 1` (0 is not rejected).
    robot: usize,
    /// How far ahead on the path to aim, m.
    lookahead_m: f64,
    /// Cruise speed, m/s.
    speed: f64,
    /// Centre distance to the predecessor at which it stops, m.
    keep_back_m: f64,
    /// The robot's URDF, relative to the launch file: wheel radius and separation (the
    /// default `""` fails to load, so in effect required).
    urdf: String,
    /// The world file, relative to the launch file (optional): when it lists `[[start]]`
    /// poses, `robot` must be one of the robots they name.
    world: Option<String>,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            robot: 1,
            lookahead_m: 0.25,
            speed: 0.2,
            keep_back_m: 0.5,
            urdf: String::new(),
            world: None,
        }
    }
}

fn main() -> std::process::ExitCode {
    caravan::node_main("pure-pursuit-follower", setup, run)
}

/// Before joining the group: the robot among the world's, the wheels from its URDF.
fn setup(p: Params, identity: &caravan::NodeIdentity) -> Result<(Params, RobotModel), String> {
    if p.robot == 0 {
        return Err("key 'robot': robot 0 leads; a follower is robot 1 or later".into());
    }
    if p.urdf.is_empty() {
        return Err("key 'urdf': give the robot's URDF (its wheel radius and separation)".into());
    }
    if let Some(file) = &p.world {
        caravan_world::load_world(&identity.resolve_path(file))
            .map_err(|e| format!("key 'world': world file {e}"))?
            .check_robot(file, p.robot)?;
    }
    let robot = caravan_world::load_robot(&identity.resolve_path(&p.urdf))
        .map_err(|e| format!("key 'urdf': {e}"))?;
    Ok((p, robot))
}

fn run(mut node: Node, (p, robot): (Params, RobotModel)) -> Result<(), Error> {
    let me = node.subscriber(&topics::pose_true(p.robot))?;
    let ahead = node.subscriber(&topics::pose_true(p.robot - 1))?;
    let wheels = node.publisher(&topics::wheel_setpoint(p.robot))?;
    let mut path = std::collections::VecDeque::new();
    node.run(Trigger::every_hz(20.0), |_| {
        while let Some(pose) = ahead.receive()? {
            path.push_back(*pose);
        }
        let (Some(me), Some(lead)) = (me.latest()?.map(|m| *m), path.back().copied()) else {
            return Ok(());
        };
        let dist = |q: &Pose2D| (q.x - me.x).hypot(q.y - me.y);
        while path.len() > 1 && dist(&path[0]) < p.lookahead_m {
            path.pop_front(); // reached: aim further along
        }
        // Pure pursuit: the arc through the aim point has curvature 2·y / d² (robot frame).
        let (s, c) = me.theta.sin_cos();
        let (dx, dy) = (path[0].x - me.x, path[0].y - me.y);
        let curvature = 2.0 * (-s * dx + c * dy) / (dx * dx + dy * dy).max(1e-6);
        let v = p.speed.min(1.5 * (dist(&lead) - p.keep_back_m)).max(0.0);
        let (left, right) = wheel_speeds(
            v,
            v * curvature,
            robot.wheel_radius,
            robot.wheel_separation(),
        );
        wheels.publish(&WheelSetpoint {
            left_rad_s: left,
            right_rad_s: right,
        })
    })?;
    Ok(())
}
