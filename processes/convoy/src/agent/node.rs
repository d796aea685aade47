//! The agent as a node: the leader drives through its goals (straight at them, or passing a
//! planner's commands on) and publishes the current one on `goal`; a follower runs the
//! reference follower law on its predecessor's pose history. Both turn (v, ω) into wheel
//! set-points.

use crate::agent::history::PoseHistory;
use crate::agent::params::{Mode, Params};
use crate::agent::poses::Poses;
use crate::agent::{follower, leader};
use caravan::{Error, Node, Publisher, Topic, Trigger};
use caravan_schemas::{Goal, Pose2D, Twist, WheelSetpoint, topics};
use caravan_world::kinematics::wheel_speeds;

/// Both agents step at 20 Hz unless the launch file says otherwise.
const RATE_HZ: f64 = 20.0;

/// The robot's wheel radius and separation, m.
#[derive(Debug, Clone, Copy)]
pub struct Geometry {
    pub wheel_radius_m: f64,
    pub wheel_separation_m: f64,
}

/// Checks `p` and reads the robot's geometry from its URDF, before the node joins the group.
pub fn setup(
    mut p: Params,
    identity: &caravan::NodeIdentity,
) -> Result<(Params, Geometry), String> {
    p.validate()?;
    identity.serves_robot(p.robot);
    let robot = caravan_world::load_robot(&identity.resolve_path(&p.urdf))
        .map_err(|e| format!("key 'urdf': robot description {e}"))?;
    p.follower.footprint_half_m = [robot.chassis_half_extents[0], robot.chassis_half_extents[1]];
    p.follower.footprint_offset_m = robot.chassis_center[0];
    if let Some(file) = &p.world {
        let world = caravan_world::load_world(&identity.resolve_path(file))
            .map_err(|e| format!("key 'world': world file {e}"))?;
        // A world that lists [[start]] poses names its robots: this agent's is one of them.
        world.check_robot(file, p.robot)?;
        if p.mode == Mode::Leader && p.leader.goals.is_empty() {
            if world.goals.is_empty() {
                return Err(format!(
                    "key 'leader.goals': none given, and world file {file} has no [[goal]]s"
                ));
            }
            p.leader.goals = world.goals.iter().map(|g| g.at).collect();
        }
    }
    let geometry = Geometry {
        wheel_radius_m: robot.wheel_radius,
        wheel_separation_m: robot.wheel_separation(),
    };
    Ok((p, geometry))
}

/// Runs the agent `p` describes until the group stops.
pub fn run(mut node: Node, (p, geometry): (Params, Geometry)) -> Result<(), Error> {
    let i = p.robot;
    let setpoint = node.publisher(&topics::wheel_setpoint(i))?;
    let wheels = Wheels {
        setpoint,
        radius_m: geometry.wheel_radius_m,
        separation_m: geometry.wheel_separation_m,
    };
    // A drive reads no pose.
    match p.mode {
        Mode::Leader => {
            let poses = Poses::open(&node, &p)?;
            run_leader(&mut node, &p, poses, wheels)
        }
        Mode::Follower => {
            let poses = Poses::open(&node, &p)?;
            run_follower(&mut node, &p, poses, wheels)
        }
        Mode::Drive => run_drive(&mut node, &p, wheels),
    }
}

/// Where (v, ω) commands go: the robot's wheel set-points.
struct Wheels {
    setpoint: Publisher<WheelSetpoint>,
    radius_m: f64,
    separation_m: f64,
}

impl Wheels {
    fn drive(&self, (v, omega): (f64, f64)) -> Result<(), Error> {
        let (left, right) = wheel_speeds(v, omega, self.radius_m, self.separation_m);
        self.setpoint.publish(&WheelSetpoint {
            left_rad_s: left,
            right_rad_s: right,
        })
    }
}

fn run_leader(node: &mut Node, p: &Params, poses: Poses, wheels: Wheels) -> Result<(), Error> {
    let goal_pub = node.publisher(&topics::goal())?;
    let planner = match &p.cmd_vel_topic {
        Some(topic) => Some(node.subscriber(&Topic::<Twist>::new(topic))?),
        None => None,
    };
    let mut pose = None;
    let mut planned: Option<(f64, (f64, f64))> = None;
    let mut progress = leader::Progress::default();
    let mut announced = None;
    node.run(Trigger::every_hz(RATE_HZ), |step| {
        if let Some((_, newest)) = poses.read(|_, _| {})? {
            pose = Some(newest);
        }
        let now = step.now().as_secs_f64();
        let Some(current) = pose else { return Ok(()) };
        let cmd = match &planner {
            None => leader::command(current, &mut progress, &p.leader),
            Some(sub) => {
                if let Some(msg) = sub.latest()? {
                    let t = msg.header().stamp_ns as f64 * 1e-9;
                    planned = Some((t, (msg.linear.x, msg.angular.z)));
                }
                let fresh = planned
                    .filter(|(t, _)| now - t <= p.cmd_vel_timeout_s)
                    .map(|(_, c)| c);
                match leader::advance(current, &mut progress, &p.leader) {
                    Some(_) => leader::limit(fresh, &p.leader),
                    None => (0.0, 0.0),
                }
            }
        };
        // Announce goal changes, and once a second for late subscribers.
        if announced != Some(progress.current) || step.index() % 20 == 0 {
            announced = Some(progress.current);
            let target = p
                .leader
                .goals
                .get(progress.current)
                .copied()
                .unwrap_or([current.x, current.y]);
            goal_pub.publish(&Goal {
                index: progress.current as u32,
                total: p.leader.goals.len() as u32,
                pose: Pose2D {
                    x: target[0],
                    y: target[1],
                    theta: 0.0,
                },
                tolerance_m: p.leader.tolerance_m,
            })?;
        }
        wheels.drive(cmd)
    })?;
    Ok(())
}

/// Drives the newest fresh command within the leader's limits; a stale one stops the robot.
fn run_drive(node: &mut Node, p: &Params, wheels: Wheels) -> Result<(), Error> {
    let topic = match &p.cmd_vel_topic {
        Some(name) => Topic::new(name),
        None => topics::cmd_vel(p.robot),
    };
    let commands = node.subscriber(&topic)?;
    let mut last: Option<(f64, (f64, f64))> = None;
    node.run(Trigger::every_hz(RATE_HZ), |step| {
        if let Some(msg) = commands.latest()? {
            let t = msg.header().stamp_ns as f64 * 1e-9;
            last = Some((t, (msg.linear.x, msg.angular.z)));
        }
        let now = step.now().as_secs_f64();
        let fresh = last
            .filter(|(t, _)| now - t <= p.cmd_vel_timeout_s)
            .map(|(_, c)| c);
        wheels.drive(leader::limit(fresh, &p.leader))
    })?;
    Ok(())
}

fn run_follower(node: &mut Node, p: &Params, poses: Poses, wheels: Wheels) -> Result<(), Error> {
    let mut history = PoseHistory::new(p.follower.tau_s + 2.0);
    // The own pose's recent past, for the robot's speed; a step sees the newest pose only.
    let mut own_history = PoseHistory::new(p.follower.speed_window_s + 1.0);
    node.run(Trigger::every_hz(RATE_HZ), |step| {
        if let Some((t, pose)) = poses.read(|t, pose| history.push(t, pose))? {
            own_history.push(t, pose);
        }
        if own_history.latest().is_none() {
            return Ok(());
        }
        let (v, omega, _) = follower::command(
            &own_history,
            &history,
            step.now().as_secs_f64(),
            &p.follower,
        );
        wheels.drive((v, omega))
    })?;
    Ok(())
}
