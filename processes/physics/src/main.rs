//! `caravan-physics`: simulates the group's robots and publishes their ground truth.
//!
//! Per robot i it publishes `robot/i/pose_true` and `robot/i/twist_true` every step, and as
//! the robot's params ask `robot/i/wheel_state` (a differential drive, which follows
//! `robot/i/wheel_setpoint`), `robot/i/joint_states` (which takes `robot/i/joint_command`),
//! `robot/i/link_states`, `robot/i/contacts` and `robot/i/force_torque`. It takes
//! `robot/i/cmd_vel` for a kinematic base and every `robot/i/wrench`. Commands are held until
//! changed. Contact events go to `collisions`, and the world's solids to `scene` (once a
//! simulated second, for viewers). The node steps at 100 Hz unless the launch
//! file gives a `rate`; each step runs `substeps` physics steps.
//! Params and inputs are checked before the node joins the group, so bad input never leaves
//! anything behind in shared memory.

use caravan::{Node, NodeIdentity, Publisher, Subscriber, Trigger};
use caravan_physics::messages::{self, CommandReader};
use caravan_physics::{Params, Simulation, setup};
use caravan_schemas::{
    Contacts, ForceTorques, JointCommand, JointState, LinkStates, MAX_ROBOT_STATES, Odometry,
    Pose2D, Pose3D, RobotStates, Twist, WheelSetpoint, WheelState, Wrench, topics,
};
use std::process::ExitCode;
use std::time::Duration;

const DEFAULT_RATE_HZ: f64 = 100.0;
/// A step may catch up at most this many node periods of physics (realtime, after a stall);
/// beyond that, simulated time slips instead of the process spiralling behind.
const MAX_CATCH_UP_PERIODS: u64 = 4;

fn main() -> ExitCode {
    caravan::node_main("caravan-physics", setup, run)
}

/// How often the world's solids are published again, ns of simulated time.
const SCENE_PERIOD_NS: u64 = 1_000_000_000;

/// A simulation built from checked input, and the step it advances by.
struct Ready {
    sim: Simulation,
    /// The world's solids, published on `scene` for viewers.
    scene: Box<caravan::schemas::Scene>,
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
    let checked = setup::check(&params, &identity.launch_dir).map_err(|e| e.0)?;
    let starts = checked.place().map_err(|e| e.0)?;
    let sim = setup::build(&checked, &starts, params.sim_config(dt_ns)).map_err(|e| e.0)?;
    // The launcher finds every other node's `robot` among these.
    identity.simulates_robots(sim.robot_count());
    let mut scene = caravan_world::scene::scene_of(&checked.world);
    // Robots of the one-kind form whose description the differential-drive model fits get
    // their bodies drawn; others (arms, tracks, aircraft) are drawn by their frames alone.
    if let (Some(urdf), Some(count)) = (&params.urdf, params.count)
        && let Ok(robot) = caravan_world::load_robot(&identity.launch_dir.join(urdf))
    {
        caravan_world::scene::add_robot_bodies(&mut scene, &robot, count);
    }
    Ok(Ready {
        sim,
        scene,
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

/// One robot's topics; the optional ones as its `Outputs` say.
struct RobotPorts {
    pose: Publisher<Pose2D>,
    twist: Publisher<Twist>,
    wheels: Option<(Subscriber<WheelSetpoint>, Publisher<WheelState>)>,
    joints: Option<(Subscriber<JointCommand>, Publisher<JointState>)>,
    links: Option<Publisher<LinkStates>>,
    contacts: Option<Publisher<Contacts>>,
    force_torque: Option<Publisher<ForceTorques>>,
    ground_truth: Option<Publisher<Odometry>>,
    cmd_vel: Option<Subscriber<Twist>>,
    set_pose: Option<Subscriber<Pose3D>>,
    wrench: Subscriber<Wrench>,
}

impl RobotPorts {
    fn open(node: &Node, sim: &Simulation, i: usize) -> Result<Self, caravan::Error> {
        let out = sim.outputs(i);
        let wheels = out.wheels.then(|| -> Result<_, caravan::Error> {
            Ok((
                node.subscriber(&topics::wheel_setpoint(i))?,
                node.publisher(&topics::wheel_state(i))?,
            ))
        });
        let joints = out.joint_states.then(|| -> Result<_, caravan::Error> {
            Ok((
                node.subscriber(&topics::joint_command(i))?,
                node.publisher(&topics::joint_states(i))?,
            ))
        });
        let links = out
            .link_states
            .then(|| node.publisher(&topics::link_states(i)));
        let contacts = out.contacts.then(|| node.publisher(&topics::contacts(i)));
        let cmd_vel = out.cmd_vel.then(|| node.subscriber(&topics::cmd_vel(i)));
        let set_pose = out.cmd_vel.then(|| node.subscriber(&topics::set_pose(i)));
        let force_torque = out
            .force_torque
            .then(|| node.publisher(&topics::force_torque(i)));
        let ground_truth = out
            .ground_truth
            .then(|| node.publisher(&topics::ground_truth(i)));
        Ok(Self {
            pose: node.publisher(&topics::pose_true(i))?,
            twist: node.publisher(&topics::twist_true(i))?,
            wheels: wheels.transpose()?,
            joints: joints.transpose()?,
            links: links.transpose()?,
            contacts: contacts.transpose()?,
            force_torque: force_torque.transpose()?,
            ground_truth: ground_truth.transpose()?,
            cmd_vel: cmd_vel.transpose()?,
            set_pose: set_pose.transpose()?,
            wrench: node.subscriber(&topics::wrench(i))?,
        })
    }

    /// Hands robot `i`'s latest commands and every new wrench to the simulation.
    fn take_commands(
        &self,
        sim: &mut Simulation,
        i: usize,
        commands: &mut CommandReader,
    ) -> Result<(), caravan::Error> {
        if let Some((setpoint, _)) = &self.wheels
            && let Some(sp) = setpoint.latest()?
        {
            sim.set_setpoint(i, &sp);
        }
        if let Some((command, _)) = &self.joints {
            while let Some(cmd) = command.receive()? {
                let targets = commands.targets(sim, i, &cmd);
                sim.set_targets(i, &targets);
            }
        }
        if let Some(set_pose) = &self.set_pose {
            while let Some(pose) = set_pose.receive()? {
                sim.set_pose(i, &pose);
            }
        }
        if let Some(cmd_vel) = &self.cmd_vel
            && let Some(cmd) = cmd_vel.latest()?
        {
            sim.set_cmd_vel(i, &cmd);
        }
        while let Some(w) = self.wrench.receive()? {
            let applied = messages::wrench_command(&w).and_then(|w| sim.apply_wrench(i, &w));
            if let Err(e) = applied {
                eprintln!("caravan-physics: robot/{i}/wrench ignored: {e}");
            }
        }
        Ok(())
    }

    /// Publishes robot `i`'s state after a step.
    fn publish(&self, sim: &Simulation, i: usize) -> Result<(), caravan::Error> {
        self.pose.publish(&sim.pose(i))?;
        self.twist.publish(&sim.twist(i))?;
        if let Some((_, state)) = &self.wheels {
            state.publish(&sim.wheel_state(i))?;
        }
        if let Some(p) = &self.ground_truth {
            let (pose, twist) = sim.ground_truth(i);
            p.publish(&Odometry {
                pose,
                twist,
                ..Odometry::default()
            })?;
        }
        let joints = self.joints.as_ref().map(|(_, p)| p);
        send_filled(joints, sim, i, messages::joint_state)?;
        send_filled(self.links.as_ref(), sim, i, messages::link_states)?;
        send_filled(self.contacts.as_ref(), sim, i, messages::contacts)?;
        send_filled(self.force_torque.as_ref(), sim, i, messages::force_torque)?;
        Ok(())
    }
}

/// Has `fill` write robot `i`'s state in place into a message of `out` (if the robot
/// publishes it) and sends it: the large per-robot messages are never copied, nor built for
/// a topic nobody reads.
fn send_filled<T: caravan_schemas::Message>(
    out: Option<&Publisher<T>>,
    sim: &Simulation,
    i: usize,
    fill: fn(&Simulation, usize, &mut T),
) -> Result<(), caravan::Error> {
    let Some(out) = out else { return Ok(()) };
    out.publish_in_place(|m| fill(sim, i, m))
}

/// The publisher of every robot's state in one message, if the team fits in it (sent only
/// while someone reads it, as every topic here).
fn team_states(
    node: &Node,
    sim: &Simulation,
) -> Result<Option<Publisher<RobotStates>>, caravan::Error> {
    if sim.robot_count() > MAX_ROBOT_STATES {
        eprintln!(
            "caravan-physics: {} robots; robots/state_true carries at most {MAX_ROBOT_STATES}, \
             so it is not published (each robot's pose_true and twist_true are)",
            sim.robot_count()
        );
        return Ok(None);
    }
    node.publisher(&topics::robot_states_true()).map(Some)
}

fn run(mut node: Node, ready: Ready) -> Result<(), caravan::Error> {
    let Ready {
        mut sim,
        scene,
        period_ns,
        dt_ns,
        max_steps,
    } = ready;
    let ports = (0..sim.robot_count())
        .map(|i| RobotPorts::open(&node, &sim, i))
        .collect::<Result<Vec<_>, _>>()?;
    let collisions = node.publisher(&topics::collisions())?;
    let scene_out = node.publisher(&topics::scene())?;
    let states_out = team_states(&node, &sim)?;
    let mut next_scene_ns = 0;
    let mut commands = CommandReader::default();

    let mut slip_ns = 0u64;
    node.run(Trigger::Every(Duration::from_nanos(period_ns)), |step| {
        for (i, p) in ports.iter().enumerate() {
            p.take_commands(&mut sim, i, &mut commands)?;
        }
        let target = step.now_ns().saturating_sub(slip_ns);
        sim.advance_to(target, max_steps);
        // Still behind after the catch-up limit: let simulated time slip.
        slip_ns += target.saturating_sub(sim.time_ns()) / dt_ns * dt_ns;
        for (i, p) in ports.iter().enumerate() {
            p.publish(&sim, i)?;
        }
        if let Some(out) = &states_out {
            out.publish_in_place(|m| messages::robot_states(&sim, m))?;
        }
        for c in sim.take_collisions() {
            collisions.publish(&c)?;
        }
        // Static, but sent again every simulated second for viewers that join late.
        if step.now_ns() >= next_scene_ns {
            let mut m = scene_out.loan()?;
            *m = *scene;
            m.send()?;
            next_scene_ns = step.now_ns() + SCENE_PERIOD_NS;
        }
        Ok(())
    })?;
    Ok(())
}
