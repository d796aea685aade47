//! `caravan-physics`: simulates the group's robots and publishes their ground truth.
//!
//! Per robot i it subscribes `robot/i/wheel_setpoint` (the latest value is held; zero before
//! the first) and publishes `robot/i/pose_true`, `robot/i/twist_true` and
//! `robot/i/wheel_state` every step; contact events go to `collisions`. The node steps at
//! 100 Hz unless the launch file gives a `rate`; each step runs `substeps` physics steps.
//! Params and inputs are checked before the node joins the group, so bad input never leaves
//! anything behind in shared memory.

use caravan::{Node, NodeIdentity, Publisher, Subscriber, Trigger};
use caravan_physics::{Params, Simulation};
use caravan_schemas::{Pose2D, Twist, WheelSetpoint, WheelState, topics};
use std::process::ExitCode;
use std::time::Duration;

const DEFAULT_RATE_HZ: f64 = 100.0;
/// A step may catch up at most this many node periods of physics (realtime, after a stall);
/// beyond that, simulated time slips instead of the process spiralling behind.
const MAX_CATCH_UP_PERIODS: u64 = 4;

fn main() -> ExitCode {
    caravan::node_main("caravan-physics", setup, run)
}

/// A simulation built from checked input, and the step it advances by.
struct Ready {
    sim: Simulation,
    period_ns: u64,
    dt_ns: u64,
    max_steps: u64,
}

/// Checks the params, loads the world and robot and builds the simulation, before the node
/// joins the group.
fn setup(params: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    let period_ns = period(identity)?.as_nanos() as u64;
    let dt_ns = period_ns / params.substeps.max(1) as u64;
    if dt_ns == 0 {
        return Err(format!(
            "key 'substeps' = {}: more physics steps than nanoseconds in a node period",
            params.substeps
        ));
    }
    let sim = caravan_physics::load(&params, &identity.launch_dir, dt_ns).map_err(|e| e.0)?;
    Ok(Ready {
        sim,
        period_ns,
        dt_ns,
        max_steps: params.substeps as u64 * MAX_CATCH_UP_PERIODS,
    })
}

/// The node period: the launch file's `rate`, else 100 Hz. Physics needs a fixed step, so a
/// message trigger (`on`) is refused.
fn period(identity: &NodeIdentity) -> Result<Duration, String> {
    if let Some(topic) = &identity.on_override {
        return Err(format!(
            "`on = \"{topic}\"`: physics steps at a fixed rate; give `rate` (e.g. \"100Hz\") instead"
        ));
    }
    match &identity.rate_override {
        Some(rate) => caravan::parse_rate(rate).map_err(|e| e.to_string()),
        None => Ok(Trigger::every_hz(DEFAULT_RATE_HZ)
            .period()
            .expect("periodic")),
    }
}

/// One robot's topics.
struct RobotPorts {
    setpoint: Subscriber<WheelSetpoint>,
    pose: Publisher<Pose2D>,
    twist: Publisher<Twist>,
    wheels: Publisher<WheelState>,
}

impl RobotPorts {
    fn open(node: &Node, i: usize) -> Result<Self, caravan::Error> {
        Ok(Self {
            setpoint: node.subscriber(&topics::wheel_setpoint(i))?,
            pose: node.publisher(&topics::pose_true(i))?,
            twist: node.publisher(&topics::twist_true(i))?,
            wheels: node.publisher(&topics::wheel_state(i))?,
        })
    }
}

fn run(mut node: Node, ready: Ready) -> Result<(), caravan::Error> {
    let Ready {
        mut sim,
        period_ns,
        dt_ns,
        max_steps,
    } = ready;
    let ports = (0..sim.robot_count())
        .map(|i| RobotPorts::open(&node, i))
        .collect::<Result<Vec<_>, _>>()?;
    let collisions = node.publisher(&topics::collisions())?;

    let mut slip_ns = 0u64;
    node.run(Trigger::Every(Duration::from_nanos(period_ns)), |step| {
        for (i, p) in ports.iter().enumerate() {
            if let Some(sp) = p.setpoint.latest()? {
                sim.set_setpoint(i, &sp);
            }
        }
        let target = step.now_ns().saturating_sub(slip_ns);
        sim.advance_to(target, max_steps);
        // Still behind after the catch-up limit: let simulated time slip.
        slip_ns += target.saturating_sub(sim.time_ns()) / dt_ns * dt_ns;
        for (i, p) in ports.iter().enumerate() {
            p.pose.publish(&sim.pose(i))?;
            p.twist.publish(&sim.twist(i))?;
            p.wheels.publish(&sim.wheel_state(i))?;
        }
        for c in sim.take_collisions() {
            collisions.publish(&c)?;
        }
        Ok(())
    })?;
    Ok(())
}
