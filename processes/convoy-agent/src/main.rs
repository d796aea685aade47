//! caravan-convoy-agent: a convoy robot's controller, as a node. Leader: drives through the
//! goals and publishes the current one on `goal`. Follower: the reference follower law on its
//! predecessor's pose history. Both turn (v, ω) into wheel set-points.

use caravan::{Error, Node, Topic, Trigger};
use caravan_convoy_agent::history::PoseHistory;
use caravan_convoy_agent::params::{Mode, Params};
use caravan_convoy_agent::{follower, leader};
use caravan_schemas::{Goal, Pose2D, Twist, WheelSetpoint, topics};
use caravan_world::kinematics::wheel_speeds;

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caravan-convoy-agent: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Error> {
    let mut node = Node::from_env()?;
    let p: Params = node.params()?;
    p.validate().map_err(|message| Error::Params {
        node: node.name().to_string(),
        message,
    })?;
    let i = p.robot;
    let own = node.subscriber(&Topic::<Pose2D>::new(
        &p.pose_topic.clone().unwrap_or_else(|| topics::pose_true(i)),
    ))?;
    let setpoint = node.publisher(&Topic::<WheelSetpoint>::new(&topics::wheel_setpoint(i)))?;
    let publish = |(v, omega): (f64, f64)| {
        let (left, right) = wheel_speeds(v, omega, p.wheel_radius_m, p.wheel_separation_m);
        setpoint.publish(&WheelSetpoint {
            left_rad_s: left,
            right_rad_s: right,
        })
    };
    let mut pose = None;
    match p.mode {
        Mode::Leader => {
            let goal_pub = node.publisher(&Topic::<Goal>::new(topics::GOAL))?;
            let planner = match &p.cmd_vel_topic {
                Some(topic) => Some(node.subscriber(&Topic::<Twist>::new(topic))?),
                None => None,
            };
            let mut planned: Option<(f64, (f64, f64))> = None;
            let mut progress = leader::Progress::default();
            let mut announced = None;
            node.run(Trigger::every_hz(20.0), |step| {
                if let Some(msg) = own.latest()? {
                    pose = Some(*msg);
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
                publish(cmd)
            })?;
        }
        Mode::Follower => {
            let predecessor_topic = p
                .predecessor_topic
                .clone()
                .unwrap_or_else(|| topics::pose_true(i - 1));
            let predecessor = node.subscriber(&Topic::<Pose2D>::new(&predecessor_topic))?;
            let mut history = PoseHistory::new(p.follower.tau_s + 2.0);
            node.run(Trigger::every_hz(20.0), |step| {
                while let Some(msg) = predecessor.receive()? {
                    history.push(msg.header().stamp_ns as f64 * 1e-9, *msg);
                }
                if let Some(msg) = own.latest()? {
                    pose = Some(*msg);
                }
                let Some(current) = pose else { return Ok(()) };
                let (v, omega, _) =
                    follower::command(current, &history, step.now().as_secs_f64(), &p.follower);
                publish((v, omega))
            })?;
        }
    }
    Ok(())
}
