//! `caravan-imu-driver`: moves robot 0 as its scenario says (see `caravan_imu::scenario`):
//! the platform's angular velocity on `robot/0/cmd_vel` (world frame) every step, or one
//! upward push on `robot/0/wrench` at the cube's centre of mass. Params: the scenario table,
//! e.g. `{ scenario = "tilt", rate_deg_s = 3.0 }`. Give it a `rate` whose period divides the
//! scenario's switching times, so that every switch falls on a step.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_imu::scenario::{Command, Scenario};
use caravan_schemas::{Name, Twist, Vector3, Wrench, topics};
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-imu-driver", setup, run)
}

fn setup(scenario: Scenario, _: &NodeIdentity) -> Result<Scenario, String> {
    scenario.validate()?;
    Ok(scenario)
}

fn run(mut node: Node, scenario: Scenario) -> Result<(), caravan::Error> {
    let cmd_vel = node.publisher(&topics::cmd_vel(0))?;
    let wrench = node.publisher(&topics::wrench(0))?;
    let mut pushed = false;
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
                pushed = true;
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
            Command::Idle => {}
        }
        Ok(())
    })?;
    Ok(())
}
