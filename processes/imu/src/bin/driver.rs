//! `caravan-imu-driver`: moves robot 0 as its scenario says (see `caravan_imu::scenario`):
//! the platform's angular velocity on `robot/0/cmd_vel` (world frame) every step, one
//! upward push on `robot/0/wrench` at the cube's centre of mass, or the bar's joint to its
//! velocity limit on `robot/0/joint_command`, or the arm's elbow to its bend and its
//! shoulder to its rate there. Params: the scenario table,
//! e.g. `{ scenario = "tilt", rate_deg_s = 3.0 }`. Give it a `rate` whose period divides the
//! scenario's switching times, so that every switch falls on a step.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_imu::arm::Arm;
use caravan_imu::scenario::{Command, Scenario};
use caravan_imu::spin_up::Bar;
use caravan_schemas::{JointCommand, JointValue, Name, Twist, Vector3, Wrench, topics};
use caravan_world::description::load_description;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-imu-driver", setup, run)
}

/// The scenario, and for a spin-up the joint and its target rate (rad/s).
struct Ready {
    scenario: Scenario,
    spin: Option<(String, f64)>,
}

fn setup(scenario: Scenario, identity: &NodeIdentity) -> Result<Ready, String> {
    scenario.validate()?;
    let load = |urdf: &str| {
        load_description(&identity.resolve_path(urdf))
            .map_err(|e| format!("key 'urdf': robot description {e}"))
    };
    let spin = match &scenario {
        Scenario::SpinUp { urdf, joint, .. } => {
            let bar = Bar::from_description(&load(urdf)?, joint)?;
            Some((joint.clone(), bar.rate_rad_s))
        }
        // The pushes are bounded by the cube's mass (16 g at most).
        Scenario::Lift { urdf, .. } => {
            scenario.validate_forces(load(urdf)?.mass())?;
            None
        }
        Scenario::Arm(_) => {
            Arm::load(&scenario, load)?;
            None
        }
        _ => None,
    };
    Ok(Ready { scenario, spin })
}

fn run(mut node: Node, ready: Ready) -> Result<(), caravan::Error> {
    let Ready { scenario, spin } = ready;
    let cmd_vel = node.publisher(&topics::cmd_vel(0))?;
    let joints = node.publisher(&topics::joint_command(0))?;
    let wrench = node.publisher(&topics::wrench(0))?;
    let mut pushed = 0;
    let trigger = node.trigger(Trigger::every_hz(100.0))?;
    node.run(trigger, |step| {
        match scenario.command(step.now().as_secs_f64(), pushed) {
            Command::Turn([x, y, z]) => {
                cmd_vel.publish(&Twist {
                    angular: Vector3 { x, y, z },
                    ..Twist::default()
                })?;
            }
            Command::Push {
                force_n,
                duration_s,
            } => {
                pushed += 1;
                wrench.publish(&Wrench {
                    link: Name::new("cube"),
                    frame: Wrench::LINK,
                    force: Vector3 {
                        x: 0.0,
                        y: 0.0,
                        z: force_n,
                    },
                    duration_s,
                    ..Wrench::default()
                })?;
            }
            Command::Spin => {
                let (joint, rate) = spin.as_ref().expect("a spin-up has its joint");
                joints.publish(&joint_command(&[(joint.as_str(), f64::NAN, *rate)]))?;
            }
            Command::Arm {
                elbow_rad,
                shoulder_rad_s,
            } => {
                let Scenario::Arm(arm) = &scenario else {
                    unreachable!("only the arm commands an arm")
                };
                // Each joint is held still (velocity 0) until its phase: the elbow until it
                // bends to its angle, the shoulder until it turns.
                joints.publish(&joint_command(&[
                    (arm.elbow.as_str(), elbow_rad.unwrap_or(f64::NAN), 0.0),
                    (
                        arm.shoulder.as_str(),
                        f64::NAN,
                        shoulder_rad_s.unwrap_or(0.0),
                    ),
                ]))?;
            }
            Command::Idle => {}
        }
        Ok(())
    })?;
    Ok(())
}

/// A joint command of (joint, position target or NaN, velocity target) for each joint.
fn joint_command(targets: &[(&str, f64, f64)]) -> JointCommand {
    let mut cmd = caravan_schemas::placement_new::<JointCommand>();
    for &(joint, position, velocity) in targets {
        let _ = cmd.joints.push(JointValue {
            name: Name::new(joint),
            position,
            velocity,
            effort: f64::NAN,
        });
    }
    cmd
}
