//! `caravan-tracked-driver`: the experiment's operator. It drives robot `robot` straight
//! ahead: `robot/i/cmd_vel` asks for `speed_m_s` from `start_s` until `stop_s`, then for a
//! stop. Params: `robot`, `speed_m_s` (default 0.3), `start_s` (0.5), `stop_s` (never), and
//! `climb`: with `climb = { enabled = true }` it also works the flippers through the
//! step-climbing sequence of `caravan_tracked::climb` (its angles are keys of the same table)
//! from the robot's pitch (`robot/i/ground_truth`), on `robot/i/flipper_command`.
//! `keep_line` (on by default) steers back to the line the robot was on when it set off (or
//! to `keep_line.line`), from its true pose, as an operator with a joystick would
//! (`caravan_tracked::keep_line`); with `keep_line.straight_above_tilt_deg` it pushes straight
//! on while the body leans more than that; `keep_line = { enabled = false }` never turns.
//! `count` (default 1) is the robots the physics simulates, which `robot` must be one of.
//! Each number's range is in `caravan_tracked::params` and docs/tracked.md.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_schemas::{JointCommand, JointValue, Name, Twist, topics};
use caravan_tracked::climb::{Climb, ClimbParams, nose_up_deg};
use caravan_tracked::crossing::tilt_deg;
use caravan_tracked::flippers::flipper_command;
use caravan_tracked::keep_line::{Attitude, KeepLineParams, Line, turn_rate};
use caravan_tracked::urdf::{FLIPPER_RANGE_DEG, flipper_joints};
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-tracked-driver", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    /// The robot's index: one of the group's `count` robots.
    #[serde(default)]
    robot: usize,
    /// The robots the physics simulates (default 1), as the drive's `count`.
    #[serde(default = "one")]
    count: usize,
    /// Forward speed asked for, m/s, in `params::SPEED_M_S` (negative reverses).
    #[serde(default = "speed")]
    speed_m_s: f64,
    /// When to start, s, in `params::TIME_S`.
    #[serde(default = "start")]
    start_s: f64,
    /// When to ask for a stop, s > `start_s`, in `params::TIME_S`, or never (the default).
    #[serde(default = "never")]
    stop_s: f64,
    /// Work the flippers to climb steps (angles in degrees; see `caravan_tracked::climb`).
    #[serde(default)]
    climb: ClimbParams,
    /// Steer back to the starting line (see `caravan_tracked::keep_line`).
    #[serde(default)]
    keep_line: KeepLineParams,
}

fn one() -> usize {
    1
}
fn speed() -> f64 {
    0.3
}
fn start() -> f64 {
    0.5
}
fn never() -> f64 {
    f64::INFINITY
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Params, String> {
    use caravan_tracked::params::{SPEED_M_S, TIME_S, robot_index, show_exact};
    robot_index(p.robot, p.count)?;
    identity.serves_robot(p.robot);
    SPEED_M_S.check("speed_m_s", p.speed_m_s)?;
    TIME_S.check("start_s", p.start_s)?;
    if p.stop_s != f64::INFINITY {
        TIME_S.check("stop_s", p.stop_s)?;
    }
    if p.stop_s <= p.start_s {
        return Err(format!(
            "key 'stop_s': must be after start_s ({}), got {}",
            show_exact(p.start_s),
            show_exact(p.stop_s)
        ));
    }
    p.climb.validate(FLIPPER_RANGE_DEG)?;
    p.keep_line.validate()?;
    Ok(p)
}

fn run(mut node: Node, p: Params) -> Result<(), caravan::Error> {
    let cmd_vel = node.publisher(&topics::cmd_vel(p.robot))?;
    let truth = if p.climb.enabled || p.keep_line.enabled {
        Some(node.subscriber(&topics::ground_truth(p.robot))?)
    } else {
        None
    };
    let mut flippers = if p.climb.enabled {
        Some((
            Climb::new(p.climb),
            node.publisher(&flipper_command(p.robot))?,
        ))
    } else {
        None
    };
    let mut line: Option<Line> = None;
    let names = flipper_joints();
    let trigger = node.trigger(Trigger::every_hz(50.0))?;
    node.run(trigger, |step| {
        let t = step.now().as_secs_f64();
        let driving = t >= p.start_s && t < p.stop_s;
        let pose = match &truth {
            Some(truth) => truth.latest()?.map(|odometry| odometry.pose),
            None => None,
        };
        if let Some((climb, out)) = &mut flippers
            && let Some(pose) = &pose
        {
            let angle = climb.update(nose_up_deg(&pose.orientation)).to_radians();
            let mut cmd = caravan_schemas::placement_new::<JointCommand>();
            for name in &names {
                let _ = cmd.joints.push(JointValue {
                    name: Name::new(name),
                    position: angle,
                    velocity: f64::NAN,
                    effort: f64::NAN,
                });
            }
            out.publish(&cmd)?;
        }
        let (v, w) = match (driving, &pose) {
            (false, _) => (0.0, 0.0),
            (true, None) => (p.speed_m_s, 0.0),
            (true, Some(pose)) => {
                let q = &pose.orientation;
                let at = Attitude {
                    position: [pose.position.x, pose.position.y],
                    yaw_rad: q.yaw(),
                    tilt_deg: tilt_deg([q.x, q.y, q.z, q.w]),
                };
                let line =
                    *line.get_or_insert_with(|| p.keep_line.line_from(at.position, at.yaw_rad));
                (
                    p.speed_m_s,
                    turn_rate(&p.keep_line, &line, &at, p.speed_m_s),
                )
            }
        };
        cmd_vel.publish(&Twist::planar(v, w))
    })?;
    Ok(())
}
